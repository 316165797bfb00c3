//! The paper's plate through femu's FE core and sparse eigensolver: the mixed hex/wedge/tet steel
//! plate sized like the one in Hemez's study (1,845 nodes, 5,535 DOFs), checked (geometry,
//! conformity), assembled with consistent and lumped mass, and its lowest free-free modes from the
//! shift-invert eigensolver, with residuals and the Sturm check that proves no mode was skipped.
//!
//! Then the paper's question on it: a "real" plate, 20 % less stiff in its first 4 cm, is "tested"
//! (its first four elastic modes, measured at 15 nodes of the upper surface in y and z: 30
//! measurements, as in the paper), correlated with the model (Table 1: pairs, frequency errors,
//! MAC), and the a priori estimator is computed with every DOF measured (Table 2: the eigenvalue
//! gap against `rho_M` and the paper's `rho_2`), without any eigen extraction of the model.
//!
//! `cargo run --release --example plate`

use femu::correlate::modes::hz_of_eigenvalue;
use femu::prelude::*;
use femu::sparse::csc::bilinear;
use femu::sparse::eigen::{EigenOptions, Which, eigs};
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
    let mut results = Vec::new();
    for (name, sys) in [("consistent", &consistent), ("lumped", &lumped)] {
        let t = Instant::now();
        let modes = eigs(&sys.k, &sys.m, Which::Lowest(16), &EigenOptions::default())?;
        println!(
            "{name} mass: {} modes in {:.2} s (shift {:.3e} s^-2); Sturm check: {} eigenvalues below {:.4e} s^-2, {} returned: {}",
            modes.values.len(),
            t.elapsed().as_secs_f64(),
            modes.shift,
            modes.sturm.count,
            modes.sturm.upper,
            modes.sturm.returned,
            if modes.sturm.verified() {
                "verified"
            } else {
                "MISSED MODES"
            }
        );
        results.push(modes);
    }
    println!("\n mode | f consistent (Hz) | residual | f lumped (Hz) | residual");
    let (c, l) = (&results[0], &results[1]);
    let (fc, fl) = (c.frequencies_hz(), l.frequencies_hz());
    for i in 0..16 {
        let tag = if i < 6 {
            "  rigid body (residual relative to the shifted operator)"
        } else {
            ""
        };
        let (rc, rl) = if i < 6 {
            (c.shifted_residuals[i], l.shifted_residuals[i])
        } else {
            (c.residuals[i], l.residuals[i])
        };
        println!(
            "{:5} | {:17.2} | {rc:8.1e} | {:13.2} | {rl:8.1e}{tag}",
            i + 1,
            fc[i],
            fl[i]
        );
    }

    // The "real" plate: 20 % less stiff where x < 4 cm.
    let mesh = model.mesh();
    let mut soft = Vec::new();
    let mut xy = Vec::new();
    for e in 0..mesh.element_count() {
        mesh.element_coords(e, &mut xy);
        if xy.iter().map(|p| p[0]).sum::<f64>() / (xy.len() as f64) < 0.04 {
            soft.push(mesh.element(e).id);
        }
    }
    let mut real_mesh = mesh.clone();
    real_mesh.add_element_set("damaged", &soft)?;
    let mut real = Model::new(real_mesh)?;
    real.set_material(None, Material::steel())?;
    let steel = Material::steel();
    let e = match steel.elasticity {
        femu::fem::material::Elasticity::Isotropic { e, .. } => e,
        _ => unreachable!("steel is isotropic"),
    };
    real.set_material(
        Some("damaged"),
        Material::isotropic("damaged steel", 0.8 * e, 0.3, steel.density)?,
    )?;
    let real_sys = real.assemble(MassKind::Consistent)?;
    let truth = eigs(
        &real_sys.k,
        &real_sys.m,
        Which::Lowest(10),
        &EigenOptions::default(),
    )?;
    // test: elastic modes 7-10 of the real plate, at 15 upper-surface nodes (a 5 x 3 grid), y and z
    let sensors = femu::correlate::placement::grid_nodes(mesh, "zmax", [5, 3])?
        .into_iter()
        .flat_map(|id| [Sensor::axis(id, 1), Sensor::axis(id, 2)])
        .collect();
    let layout = SensorLayout::new(mesh, &consistent.dofs, sensors)?;
    let x = truth.vectors.as_ref().subcols(6, 4).to_owned();
    let f_test: Vec<f64> = truth.values[6..10]
        .iter()
        .map(|l| hz_of_eigenvalue(*l))
        .collect();
    let test = TestModes::new(f_test.clone(), None, layout.measure_all(x.as_ref())?)?;
    let report = correlate(
        &ModeSet::from_modes(c),
        &test,
        &layout,
        &PairingOptions::default(),
    )?;
    println!(
        "\nTable 1 (the plate 20 % softer over its first 4 cm, {} sensors):",
        layout.len()
    );
    print!("{report}");
    // Table 2: full measurement set, the estimator from K, M and the test pair only
    let est = Estimator::new(&consistent.k, &consistent.m)?;
    let lambdas: Vec<f64> = truth.values[6..10].to_vec();
    let (norms, report_m) = est.residual_norms(&lambdas, x.as_ref())?;
    println!(
        "\nTable 2 (every DOF measured; M^-1 by Jacobi CG, {} iterations):",
        report_m.iterations
    );
    println!(
        "| test | |lambda_id - lambda_j| (s^-2) | rho_M (rigorous) | rho_2 (paper, M != I) | a model mode lies in (Hz) |"
    );
    println!("|---|---|---|---|---|");
    for (t, n) in norms.iter().enumerate() {
        let gap = report
            .pairing
            .of_test(t)
            .map_or("unpaired".to_string(), |p| {
                format!("{:.3e}", p.eigenvalue_gap)
            });
        let (lo, hi) = n.frequency_interval_hz();
        println!(
            "| {} | {gap} | {:.3e} | {:.3e} | {lo:.1} .. {hi:.1} |",
            t + 1,
            n.rho_m,
            n.rho_2
        );
    }
    println!(
        "rho_M is at least the smallest gap |lambda_id - lambda_j| (Theorem 2, rigorous); rho_2 is the paper's\n\
         Euclidean ratio, not a bound when M != I (here it falls below the gap of mode 1, like the\n\
         paper's Table 2). rho_M is large because x has small components on the model's\n\
         high-frequency modes, weighted by (lambda_id - lambda_j)^2 in (25)."
    );
    Ok(())
}
