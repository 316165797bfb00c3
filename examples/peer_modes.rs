//! The model of the eigensolver comparison (`benches/peers/run.sh`): a steel block 2 x 1 x 1 m,
//! clamped at x = 0, meshed with hex8, hex20 or tet10 (`n` cells across, `2n` along); or (`plate`)
//! a free-free hex8 steel plate 1.0 x 0.6 x 0.02 m of `5n x 3n x 3` cells.
//!
//! - `peer_modes export KIND N COUNT DIR`: writes `DIR/model.inp` (CalculiX, `*FREQUENCY` step
//!   with COUNT modes) and `DIR/K.mtx`, `DIR/M.mtx` (scipy).
//! - `peer_modes solve KIND N COUNT`: assembles and solves with femu, prints one JSON line with
//!   the frequencies, the Sturm check and where the time went (`assembly_s` includes the ordering
//!   and symbolic analysis made beside it, whose own time is `analysis_s`). `FEMU_ENGINE=slepc:R` solves with
//!   SLEPc on `R` MPI ranks instead (`benches/scaling.sh`).
//! - `peer_modes factor KIND N REPS`: the numeric factorization of `K - sigma M` alone at the
//!   peers' shift (10 Hz below zero) with the analysis the eigensolver uses, `REPS` stored
//!   factorizations then `REPS` Sturm counts (no factor kept), one after the other; prints their
//!   times and the analysis's flop count. `export` writes that analysis's permutation to
//!   `DIR/ordering.txt` (the original index of each pivot, one per line, from 0), so that
//!   `benches/peers/pardiso_factor.py` factors the same `L` with PARDISO
//!   (docs/SCALING.md, "PARDISO's flop count").

use femu::io::inp::{FrequencyStep, write_inp};
use femu::prelude::*;
use femu::sparse::eigen::{EigenOptions, Which};
use std::time::Instant;

fn model(kind: &str, n: usize) -> Result<Model, Box<dyn std::error::Error>> {
    if kind == "plate" {
        // a free-free hex8 steel plate 1.0 x 0.6 x 0.02 m, 5n x 3n x 3 cells (n = 33: 199k DOF)
        let mut model = Model::new(box_mesh(&BoxSpec::new(
            [1.0, 0.6, 0.02],
            [5 * n, 3 * n, 3],
            BoxCells::Hex,
            false,
        ))?)?;
        model.set_material(None, Material::steel())?;
        return Ok(model);
    }
    let (cells, quadratic) = match kind {
        "hex8" => (BoxCells::Hex, false),
        "hex20" => (BoxCells::Hex, true),
        "tet10" => (BoxCells::Tet6, true),
        other => return Err(format!("unknown kind {other} (hex8, hex20, tet10)").into()),
    };
    let mut model = Model::new(box_mesh(&BoxSpec::new(
        [2.0, 1.0, 1.0],
        [2 * n, n, n],
        cells,
        quadratic,
    ))?)?;
    model.set_material(None, Material::steel())?;
    model.fix_set("xmin", &[0, 1, 2])?;
    Ok(model)
}

/// The pencil of the model's matrices with the analysis its eigensolve uses (the one made beside
/// the assembly).
fn pencil(
    sys: &SystemMatrices,
) -> Result<femu::sparse::eigen::Pencil<'_>, Box<dyn std::error::Error>> {
    use femu::sparse::eigen::Pencil;
    Ok(match sys.analysis() {
        Some(symbolic) => Pencil::with_symbolic(&sys.k, &sys.m, symbolic)?,
        None => Pencil::new(
            &sys.k,
            &sys.m,
            femu::sparse::ordering::Ordering::NestedDissection,
        )?,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage =
        "usage: peer_modes (export KIND N COUNT DIR | solve KIND N COUNT | factor KIND N REPS)";
    if args.len() < 5 {
        return Err(usage.into());
    }
    let (kind, n, count): (&str, usize, usize) = (&args[2], args[3].parse()?, args[4].parse()?);
    let t = Instant::now();
    let model = model(kind, n)?;
    let sys = model.assemble(MassKind::Consistent)?;
    let t_assembly = t.elapsed().as_secs_f64();
    match args[1].as_str() {
        "export" => {
            let dir = std::path::Path::new(args.get(5).ok_or(usage)?);
            std::fs::create_dir_all(dir)?;
            let step = FrequencyStep {
                count,
                shift_cycles2: None,
            };
            write_inp(&model, Some(&step), dir.join("model.inp"))?;
            femu::sparse::mtx::write_matrix_market(dir.join("K.mtx"), &sys.k, true)?;
            femu::sparse::mtx::write_matrix_market(dir.join("M.mtx"), &sys.m, true)?;
            let pencil = pencil(&sys)?;
            if let Some(fwd) = pencil.symbolic().permutation() {
                let lines: Vec<String> = fwd.iter().map(|i| i.to_string()).collect();
                std::fs::write(dir.join("ordering.txt"), lines.join("\n") + "\n")?;
            }
            println!(
                "{{\"dofs\": {}, \"elements\": {}}}",
                sys.dofs.free_count(),
                model.mesh().element_count()
            );
        }
        "solve" => {
            let t = Instant::now();
            let mut params = EigenOptions::default();
            if let Some(b) = std::env::var("FEMU_BLOCK")
                .ok()
                .and_then(|v| v.parse().ok())
            {
                params.block_size = b; // for tuning runs
            }
            if let Some(m) = std::env::var("FEMU_MAX_BASIS")
                .ok()
                .and_then(|v| v.parse().ok())
            {
                params.max_basis = m; // for tuning runs
            }
            if let Some(t) = std::env::var("FEMU_TOL").ok().and_then(|v| v.parse().ok()) {
                params.tol = t; // to compare at a peer's residual
            }
            if let Some(ranks) = std::env::var("FEMU_ENGINE")
                .ok()
                .and_then(|v| v.strip_prefix("slepc:").and_then(|r| r.parse().ok()))
            {
                // SLEPc with MUMPS under MPI (benches/scaling.sh)
                params.engine =
                    femu::sparse::slepc::Engine::Slepc(femu::sparse::slepc::SlepcOptions {
                        ranks,
                        ..Default::default()
                    });
            }
            let modes = sys.modes(Which::Lowest(count), &params)?;
            let t_eigen = t.elapsed().as_secs_f64();
            let s = &modes.stats;
            let f: Vec<String> = modes
                .frequencies_hz()
                .iter()
                .take(count)
                .map(|v| format!("{v:.15e}"))
                .collect();
            let worst = modes
                .residuals
                .iter()
                .take(count)
                .fold(0.0_f64, |m, r| m.max(*r));
            println!(
                "{{\"dofs\": {}, \"assembly_s\": {t_assembly:.3}, \"analysis_s\": {:.3}, \"eigen_s\": {t_eigen:.3}, \"check_s\": {:.3}, \"symbolic_s\": {:.3}, \"factor_s\": {:.3}, \"solve_s\": {:.3}, \"orth_s\": {:.3}, \"ritz_s\": {:.3}, \"other_s\": {:.3}, \"factorizations\": {}, \"solved_vectors\": {}, \"restarts\": {}, \"reorthogonalized_blocks\": {}, \"factor_len\": {}, \"factor_flops\": {:.4e}, \"sturm_verified\": {}, \"max_residual\": {worst:.2e}, \"frequencies_hz\": [{}]}}",
                sys.dofs.free_count(),
                sys.analysis().map_or(0.0, |a| a.seconds()),
                s.check_seconds,
                s.symbolic_seconds,
                s.factor_seconds,
                s.solve_seconds,
                s.orthogonalization_seconds,
                s.ritz_seconds,
                s.other_seconds(),
                s.factorizations,
                s.solved_vectors,
                s.restarts,
                s.reorthogonalized_blocks,
                s.factor_len,
                s.factor_flops,
                modes.sturm.verified(),
                f.join(", ")
            );
        }
        "factor" => {
            let pencil = pencil(&sys)?;
            // the peers' shift (benches/peers/run.py): 10 Hz below zero
            let sigma = -(2.0 * std::f64::consts::PI * 10.0_f64).powi(2);
            let time = |f: &dyn Fn() -> Result<(), femu::sparse::SparseError>| {
                (0..count)
                    .map(|_| {
                        let t = Instant::now();
                        f().map(|()| format!("{:.4}", t.elapsed().as_secs_f64()))
                    })
                    .collect::<Result<Vec<_>, _>>()
            };
            let stored = time(&|| pencil.factor_shifted(sigma).map(drop))?;
            let counts = time(&|| pencil.count_below(sigma).map(drop))?;
            println!(
                "{{\"dofs\": {}, \"factor_len\": {}, \"factor_flops\": {:.6e}, \"factor_s\": [{}], \"count_s\": [{}]}}",
                sys.dofs.free_count(),
                pencil.symbolic().factor_len(),
                pencil.symbolic().flops(),
                stored.join(", "),
                counts.join(", ")
            );
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
