//! The paper's plate through femu's FE core: the mixed hex/wedge/tet steel plate sized like the
//! one in Hemez's study (1,845 nodes, 5,535 DOFs), checked (geometry, conformity), assembled with
//! consistent and lumped mass, and its lowest free-free frequencies from the dense reference
//! eigensolver, with the six rigid-body modes accounted for.
//!
//! `cargo run --release --example plate`

use femu::prelude::*;
use femu::sparse::csc::{bilinear, to_dense};
use femu::sparse::dense::generalized_symmetric_eigenvalues;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spec = PlateSpec::default();
    let t = Instant::now();
    let mesh = mixed_plate(&spec)?;
    let conformity = mesh.check_conformity();
    println!(
        "plate {:?} m: {} nodes, {} elements {:?}, volume {:.3e} m^3, conforming: {} ({} interior faces)",
        spec.lengths,
        mesh.node_count(),
        mesh.element_count(),
        mesh.kind_counts(),
        mesh.volume()?,
        conformity.is_conforming(),
        conformity.interior_faces
    );
    let mut model = Model::new(mesh)?;
    model.set_material(None, Material::steel())?;
    let asm = Assembler::new(&model)?;
    let consistent = asm.assemble(&model, MassKind::Consistent)?;
    let lumped = asm.assemble(&model, MassKind::Lumped)?;
    println!(
        "assembled K and M: {} DOF, nnz(K) = {}, {:.1} ms",
        consistent.dofs.free_count(),
        consistent.k.nnz(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let n = consistent.dofs.free_count();
    let ux: Vec<f64> = (0..n)
        .map(|f| {
            if consistent.dofs.full_of_free(f) % 3 == 0 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    println!(
        "mass: rho V = {:.6} kg, u^T M u (rigid x) consistent {:.6} kg, lumped {:.6} kg",
        model.total_mass()?,
        bilinear(&consistent.m, &ux, &ux)?,
        bilinear(&lumped.m, &ux, &ux)?
    );
    let t = Instant::now();
    println!(
        "dense eigenvalues of the {n}-DOF pencil (reference path; the sparse eigensolver is femu-sparse's next step)..."
    );
    let values = generalized_symmetric_eigenvalues(
        to_dense(&consistent.k).as_ref(),
        to_dense(&consistent.m).as_ref(),
    )?;
    println!("{:.1} s", t.elapsed().as_secs_f64());
    println!("\n mode | eigenvalue (s^-2) | frequency (Hz)");
    for (i, l) in values.iter().take(12).enumerate() {
        let f = l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
        let tag = if i < 6 { "  rigid body" } else { "" };
        println!("{:5} | {l:17.6e} | {f:14.2}{tag}", i + 1);
    }
    Ok(())
}
