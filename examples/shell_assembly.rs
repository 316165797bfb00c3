//! Times the pattern and the assembly of K and M of a flat square plate of 4-node shells (or,
//! with `8` after the count, 8-node shells) against a hex8 cube of about as many DOFs, in one
//! run, and prints the time per million DOF of each and their ratio (docs/SCALING.md, "Shells").
//!
//! `cargo run --release --example shell_assembly -- [SHELLS_PER_SIDE] [4|8]` (default 400 4-node:
//! 966,000 DOF against a 68^3 cube of 985,000; 230 8-node shells a side: about 950,000 DOF).

use femu::fem::shell::{Membrane, Shell};
use femu::fem::structural::{StructuralElement, StructuralKind};
use femu::prelude::*;
use std::time::Instant;

fn time(model: &Model) -> Result<(usize, f64, f64), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let asm = Assembler::new(model)?;
    let pattern = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sys = asm.assemble(model, MassKind::Consistent)?;
    let assembly = t.elapsed().as_secs_f64();
    Ok((sys.dofs.free_count(), pattern, assembly))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(400);
    let eight = std::env::args().nth(2).as_deref() == Some("8");
    // the node grid: (n + 1)^2 corners, or (2n + 1)^2 points less the cells' centres
    let m = if eight { 2 * n } else { n };
    let mut mesh = Mesh::new();
    for j in 0..=m {
        for i in 0..=m {
            if eight && i % 2 == 1 && j % 2 == 1 {
                continue;
            }
            mesh.add_node(
                (1 + i + (m + 1) * j) as u64,
                [i as f64 / m as f64, j as f64 / m as f64, 0.0],
            )?;
        }
    }
    let mut plate = Model::new(mesh)?;
    let shell = Shell {
        e: 2.1e11,
        nu: 0.3,
        rho: 7850.0,
        t: 0.005,
        bending: 1.0,
        shear: Some(5.0 / 6.0),
        nsm: 0.0,
        material: None,
        offset: 0.0,
        membrane: Membrane::Incompatible,
    };
    for j in 0..n {
        for i in 0..n {
            let nodes = if eight {
                let g = |i: usize, j: usize| plate.mesh().node_index((1 + i + (m + 1) * j) as u64);
                let (a, b) = (2 * i, 2 * j);
                [
                    (a, b),
                    (a + 2, b),
                    (a + 2, b + 2),
                    (a, b + 2),
                    (a + 1, b),
                    (a + 2, b + 1),
                    (a + 1, b + 2),
                    (a, b + 1),
                ]
                .iter()
                .map(|&(p, q)| g(p, q).ok_or("a grid point"))
                .collect::<Result<Vec<_>, _>>()?
            } else {
                let g = |i: usize, j: usize| i + (n + 1) * j;
                vec![g(i, j), g(i + 1, j), g(i + 1, j + 1), g(i, j + 1)]
            };
            plate.add_structural(StructuralElement {
                id: (1 + i + n * j) as u64,
                nodes,
                kind: StructuralKind::Shell(shell),
            })?;
        }
    }
    for j in 0..=m {
        plate.fix_node_dofs((1 + (m + 1) * j) as u64, &[0, 1, 2, 3, 4, 5])?;
    }
    // a cube of about as many DOFs: 3 (c + 1)^3 = 6 nodes
    let nodes = plate.mesh().node_count();
    let c = ((2.0 * nodes as f64).cbrt().round() as usize).max(2) - 1;
    let mut cube = Model::new(box_mesh(&BoxSpec::new(
        [1.0; 3],
        [c; 3],
        BoxCells::Hex,
        false,
    ))?)?;
    cube.set_material(None, Material::steel())?;
    cube.fix_set("xmin", &[0, 1, 2])?;
    let (sd, sp, sa) = time(&plate)?;
    let (hd, hp, ha) = time(&cube)?;
    let per = |dofs: usize, s: f64| s / (dofs as f64 / 1e6);
    println!(
        "{}-node shells {n}x{n}: {sd} DOF, pattern {sp:.2} s, assembly {sa:.2} s ({:.2} s per million DOF)",
        if eight { 8 } else { 4 },
        per(sd, sa)
    );
    println!(
        "hex8 {c}^3: {hd} DOF, pattern {hp:.2} s, assembly {ha:.2} s ({:.2} s per million DOF)",
        per(hd, ha)
    );
    println!(
        "assembly per DOF, shells over hex8: {:.2}; pattern per DOF: {:.2}",
        per(sd, sa) / per(hd, ha),
        per(sd, sp) / per(hd, hp)
    );
    Ok(())
}
