//! Times the pattern and the assembly of K and M of a flat square plate of 4-node shells against
//! a hex8 cube of about as many DOFs, in one run, and prints the time per million DOF of each and
//! their ratio (docs/SCALING.md, "Shells").
//!
//! `cargo run --release --example shell_assembly -- [SHELLS_PER_SIDE]` (default 400: 966,000
//! DOF against a 68^3 cube of 985,000).

use femu::fem::shell::Shell;
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
    let mut mesh = Mesh::new();
    for j in 0..=n {
        for i in 0..=n {
            mesh.add_node(
                (1 + i + (n + 1) * j) as u64,
                [i as f64 / n as f64, j as f64 / n as f64, 0.0],
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
    };
    for j in 0..n {
        for i in 0..n {
            let g = |i: usize, j: usize| i + (n + 1) * j;
            plate.add_structural(StructuralElement {
                id: (1 + i + n * j) as u64,
                nodes: vec![g(i, j), g(i + 1, j), g(i + 1, j + 1), g(i, j + 1)],
                kind: StructuralKind::Shell(shell),
            })?;
        }
    }
    for j in 0..=n {
        plate.fix_node_dofs((1 + (n + 1) * j) as u64, &[0, 1, 2, 3, 4, 5])?;
    }
    // a cube of about as many DOFs: 3 (c + 1)^3 = 6 (n + 1)^2
    let c = ((2.0 * ((n + 1) * (n + 1)) as f64).cbrt().round() as usize).max(2) - 1;
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
        "shells {n}x{n}: {sd} DOF, pattern {sp:.2} s, assembly {sa:.2} s ({:.2} s per million DOF)",
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
