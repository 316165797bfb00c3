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
//! - `peer_modes gemm [N [REPS]]`: faer's dense `N x N` GEMM on all threads (default 1536, 10
//!   repetitions after a warm-up), its best and median GFLOP/s: the GEMM limit a factorization's
//!   rate is set against.

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

/// The dense GEMM limit of the goal "within 3x of the dense GEMM limit" (docs/SCALING.md): faer's
/// product of two `n x n` matrices on all threads, `reps` times after one warm-up, printed as one
/// JSON line with the best and the median rate (`2 n^3` flops each). `benches/peers/run.py` runs
/// it in every round beside femu's solve, so that a factorization's rate is set against the limit
/// the machine reached that minute (this machine's two-thread rate was measured at 61 and at
/// 127 GFLOP/s ten minutes apart).
fn gemm(n: usize, reps: usize) -> Result<(), Box<dyn std::error::Error>> {
    if n == 0 || reps == 0 {
        return Err("gemm: N and REPS must be positive".into());
    }
    let a = faer::Mat::<f64>::from_fn(n, n, |i, j| ((i * 3 + j * 5) % 11) as f64 - 5.0);
    let b = faer::Mat::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 2) % 13) as f64 - 6.0);
    let mut c = faer::Mat::<f64>::zeros(n, n);
    let mut rates = Vec::with_capacity(reps);
    for rep in 0..=reps {
        let t = Instant::now();
        faer::linalg::matmul::matmul(
            c.as_mut(),
            faer::Accum::Replace,
            a.as_ref(),
            b.as_ref(),
            1.0,
            faer::Par::rayon(0),
        );
        let seconds = t.elapsed().as_secs_f64();
        if rep > 0 {
            rates.push(2.0 * (n as f64).powi(3) / seconds * 1e-9);
        }
    }
    // one entry against its sum by hand: the product was computed, not optimised away
    let check: f64 = (0..n).map(|k| a[(n - 1, k)] * b[(k, 0)]).sum();
    if (c[(n - 1, 0)] - check).abs() > 1e-9 * check.abs().max(1.0) {
        return Err(format!("gemm: entry (n-1, 0) is {}, by hand {check}", c[(n - 1, 0)]).into());
    }
    rates.sort_by(f64::total_cmp);
    println!(
        "{{\"n\": {n}, \"threads\": {}, \"gflops_best\": {:.1}, \"gflops_median\": {:.1}}}",
        rayon::current_num_threads(),
        rates[rates.len() - 1],
        rates[rates.len() / 2]
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: peer_modes (export KIND N COUNT DIR | solve KIND N COUNT | factor KIND N \
                 REPS | gemm [N [REPS]])";
    // the whole number at `args[i]` (named `name` in the error), or `default` when it is absent
    let number = |i: usize, name: &str, default: Option<usize>| match (args.get(i), default) {
        (Some(a), _) => a
            .parse::<usize>()
            .map_err(|e| format!("{name} {a:?} is not a whole number ({e}); {usage}")),
        (None, Some(d)) => Ok(d),
        (None, None) => Err(usage.to_string()),
    };
    if args.get(1).map(String::as_str) == Some("gemm") {
        return gemm(number(2, "N", Some(1536))?, number(3, "REPS", Some(10))?);
    }
    if args.len() < 5 {
        return Err(usage.into());
    }
    let (kind, n, count): (&str, usize, usize) = (
        &args[2],
        number(3, "N", None)?,
        number(4, "COUNT (REPS of factor)", None)?,
    );
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
