//! The speed of the model's frequency responses (docs/SCALING.md, "Frequency responses"), timed
//! side by side in one run on a cantilevered steel plate (`FEMU_BENCH_FRF=16`: 5n x 3n x 3 hex8
//! cells, 47,628 DOF less the clamped face; `33` for the 200k case):
//!
//! - **modal synthesis**: 1,000 lines at 60 response and 3 excitation DOFs from the 40 lowest
//!   modes plus the residual flexibility of those above, against the time of the modes it uses;
//!   the residual flexibility solved with the eigensolver's kept factor (the workflow's route)
//!   and, beside it, with a factorization of `K`;
//! - **direct**: one sparse complex `LDL^T` of the dynamic stiffness per line (with its solves for
//!   the 3 excitations, refined where needed), against femu's real `LDL^T` of `K - sigma M` on
//!   the same pattern; the process's peak resident memory before and after.
//!
//! Run: `cargo bench --bench frf`. A timing script (no criterion): each phase is run `FEMU_BENCH_REPS`
//! times (default 3) and its median printed.

use femu::correlate::frf::{
    Damping, DirectSystem, FrfOptions, ResponseKind, direct_frf, direct_frf_at_once, modal_frf,
    residual_flexibility_analysed, residual_flexibility_factored,
};
use femu::correlate::{Sensor, SensorLayout};
use femu::prelude::*;
use femu::sparse::eigen::{EigenOptions, Pencil, Which};
use femu::sparse::ordering::Ordering;
use std::time::Instant;

mod common;

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn time<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::with_capacity(reps);
    let mut last = None;
    for _ in 0..reps {
        let t0 = Instant::now();
        last = Some(f());
        times.push(t0.elapsed().as_secs_f64());
    }
    (median(times), last.unwrap())
}

/// The process's peak resident set (VmHWM), MB.
fn peak_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    // criterion's flags (`--bench`) are ignored
    let n: usize = std::env::var("FEMU_BENCH_FRF")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(16);
    let reps: usize = std::env::var("FEMU_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let model = common::clamped(BoxSpec::new(
        [1.0, 0.6, 0.02],
        [5 * n, 3 * n, 3],
        BoxCells::Hex,
        false,
    ));
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let dofs = sys.k.rows();
    let mesh = model.mesh();
    // 60 responses along z on the top face, 3 excitations among them
    let top: Vec<usize> = (0..mesh.node_count())
        .filter(|&i| (mesh.coords()[i][2] - 0.02).abs() < 1e-9 && mesh.coords()[i][0] > 1e-9)
        .collect();
    let outputs: Vec<Sensor> = (0..60)
        .map(|k| Sensor::axis(mesh.node_id(top[k * top.len() / 60]), 2))
        .collect();
    let inputs: Vec<Sensor> = [7, 29, 53].iter().map(|k| outputs[*k].clone()).collect();
    let outputs = SensorLayout::new(mesh, &sys.dofs, outputs).unwrap();
    let inputs = SensorLayout::new(mesh, &sys.dofs, inputs).unwrap();
    println!(
        "plate {n}: {dofs} DOF, {} threads",
        rayon::current_num_threads()
    );

    // modal synthesis
    let eigen = EigenOptions::default();
    let (t_plain, _) = time(reps, || sys.modes(Which::Lowest(40), &eigen).unwrap());
    let keep = EigenOptions {
        keep_factor: true,
        ..Default::default()
    };
    let (t_modes, modes) = time(reps, || sys.modes(Which::Lowest(40), &keep).unwrap());
    let factor = modes.factor.as_ref().expect("kept");
    let top_hz = modes.values.last().unwrap().sqrt() / (2.0 * std::f64::consts::PI);
    let lines: Vec<f64> = (1..=1000)
        .map(|l| l as f64 * 0.5 * top_hz / 1000.0)
        .collect();
    let (t_res_k, r_k) = time(reps, || {
        residual_flexibility_analysed(
            &sys.k,
            sys.analysis(),
            &modes.values,
            modes.vectors.as_ref(),
            &outputs,
            &inputs,
        )
        .unwrap()
    });
    let (t_res, r) = time(reps, || {
        residual_flexibility_factored(
            &sys.k,
            &sys.m,
            factor,
            &modes.values,
            modes.vectors.as_ref(),
            &outputs,
            &inputs,
        )
        .unwrap()
    });
    let differ = (&r - &r_k).norm_max() / r_k.norm_max();
    let options = FrfOptions {
        damping: Damping::Ratio(0.01),
        kind: ResponseKind::Accelerance,
    };
    let (t_sum, _) = time(reps, || {
        modal_frf(
            &modes.values,
            modes.vectors.as_ref(),
            Some(r.as_ref()),
            &outputs,
            &inputs,
            &lines,
            &options,
        )
        .unwrap()
    });
    println!(
        "modes (40, to {top_hz:.1} Hz): {t_modes:.3} s with the factor kept, {t_plain:.3} s without; residual flexibility by the kept factor {t_res:.3} s, by a factorization of K {t_res_k:.3} s (differ by {differ:.1e}); 1,000 lines x 60 x 3 {t_sum:.3} s; synthesis / modes = {:.1} % (by the factorization of K {:.1} %)",
        100.0 * (t_res + t_sum) / t_modes,
        100.0 * (t_res_k + t_sum) / t_plain
    );

    // direct: per line, against the real LDL^T at the same pattern
    let pencil = Pencil::new(&sys.k, &sys.m, Ordering::NestedDissection).unwrap();
    let sigma = (2.0 * std::f64::consts::PI * 0.3 * top_hz).powi(2);
    let (t_ldlt, _) = time(reps, || pencil.factor_shifted(sigma).unwrap());
    let before = peak_mb();
    let system = DirectSystem {
        k: &sys.k,
        m: &sys.m,
        viscous: None,
        structural: None,
    };
    let direct_lines = [0.3 * top_hz];
    let loss = FrfOptions {
        damping: Damping::LossFactor(0.02),
        kind: ResponseKind::Receptance,
    };
    let (t_line, d) = time(reps, || {
        direct_frf(&system, &outputs, &inputs, &direct_lines, &loss).unwrap()
    });
    println!(
        "real LDL^T of K - sigma M {t_ldlt:.3} s; direct line (analysis, complex LDL^T, 3 solves) {t_line:.3} s = {:.2} x; backward error {:.1e}; peak RSS {before:.0} -> {:.0} MB",
        t_line / t_ldlt,
        d.backward_errors[0],
        peak_mb()
    );
    {
        use femu::sparse::complex::Combination;
        use femu::sparse::faer::{Mat, c64};
        let t0 = Instant::now();
        let comb = Combination::new(&[&sys.k, &sys.m], &["K", "M"]).unwrap();
        let t_new = t0.elapsed().as_secs_f64();
        let w2 = sigma;
        let (t_factor, _) = time(reps, || {
            comb.factor(&[c64::new(1.0, 0.02), c64::new(-w2, 0.0)])
                .unwrap()
                .pivoted()
        });
        let mut f = comb
            .factor(&[c64::new(1.0, 0.02), c64::new(-w2, 0.0)])
            .unwrap();
        let (t_solve, _) = time(reps, || {
            let mut b = Mat::<c64>::from_fn(dofs, 3, |i, j| c64::new(((i + j) % 7) as f64, 0.0));
            f.solve_in_place(b.as_mut()).unwrap()
        });
        println!(
            "  analysis {t_new:.3} s ({} complex values in L: {:.0} MB); LDL^T {t_factor:.3} s = {:.2} x the real one; 3 refined solves {t_solve:.3} s; pivoted: {}",
            comb.factor_len(),
            comb.factor_len() as f64 * 16.0 / 1e6,
            t_factor / t_ldlt,
            f.pivoted()
        );
    }
    let four: Vec<f64> = (1..=4).map(|l| l as f64 * 0.2 * top_hz).collect();
    let (t_four, _) = time(reps, || {
        direct_frf(&system, &outputs, &inputs, &four, &loss).unwrap()
    });
    println!(
        "four lines {t_four:.3} s: {:.3} s per further line = {:.2} x the real LDL^T",
        (t_four - t_line) / 3.0,
        (t_four - t_line) / 3.0 / t_ldlt
    );
    // sixteen lines one at a time (each factorization all the threads) against several at once
    let sixteen: Vec<f64> = (1..=16).map(|l| l as f64 * 0.06 * top_hz).collect();
    let before = peak_mb();
    let (t_one, one) = time(reps, || {
        direct_frf_at_once(&system, &outputs, &inputs, &sixteen, &loss, Some(1)).unwrap()
    });
    let peak_one = peak_mb();
    let (t_many, many) = time(reps, || {
        direct_frf(&system, &outputs, &inputs, &sixteen, &loss).unwrap()
    });
    let same = one
        .frf
        .h
        .iter()
        .zip(&many.frf.h)
        .map(|(a, b)| (a - b).norm_max() / a.norm_max())
        .fold(0.0, f64::max);
    println!(
        "sixteen lines on {} threads: one at a time {t_one:.3} s, several at once {t_many:.3} s ({:.2} x; the same to {same:.1e}); peak RSS {before:.0} -> {peak_one:.0} -> {:.0} MB",
        rayon::current_num_threads(),
        t_one / t_many,
        peak_mb()
    );
}
