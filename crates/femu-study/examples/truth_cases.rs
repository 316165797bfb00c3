//! Measures updating and the truth check on "real" structures that are not the model (the cases
//! of `tests/truth.rs`), printing, per case and route, what femu selects, identifies and says:
//! `cargo run --release -p femu-study --example truth_cases`. The routes: the default workflow
//! (forward selection, inverse eigensensitivity on frequencies and shapes), the paper's (residual
//! ranking, SB-EBE), and every region free (the least-squares fit that decides what the data
//! hold). The table of `docs/VERIFICATION.md`, "Updating by default", is its output.

#[path = "../tests/common/real.rs"]
mod real;

use femu_correlate::prelude::*;
use femu_fem::prelude::{BoxCells, Model};
use femu_study::updating::{Select, UpdateStudyOptions, localise_update_check};
use femu_update::prelude::*;

struct Case {
    name: &'static str,
    model: Model,
    realm: Model,
    theta: Vec<f64>,
    noises: &'static [f64],
    tuned: usize,
}

fn main() {
    let damaged = |pairs: &[(usize, f64)]| {
        let mut t = vec![0.0; real::REGIONS];
        for (r, v) in pairs {
            t[*r] = *v;
        }
        t
    };
    let hex8 = || real::plate([20, 7, 2], false);
    let hex20 = || real::plate([20, 7, 2], true);
    let tet10 = || real::plate_of([20, 7, 2], BoxCells::Tet6, true);
    let cases = vec![
        Case {
            name: "same mesh (hex8), r3 -25 %",
            model: hex8(),
            realm: hex8(),
            theta: damaged(&[(3, -0.25)]),
            noises: &[0.0, 0.005, 0.01, 0.02],
            tuned: 4,
        },
        Case {
            name: "hex20 model, tet10 structure, r3 -25 %",
            model: hex20(),
            realm: tet10(),
            theta: damaged(&[(3, -0.25)]),
            noises: &[0.0, 0.01],
            tuned: 4,
        },
        Case {
            name: "locked hex8 (one through the thickness), hex20 structure, r3 -25 %",
            model: real::plate([20, 7, 1], false),
            realm: hex20(),
            theta: damaged(&[(3, -0.25)]),
            noises: &[0.0],
            tuned: 4,
        },
        Case {
            name: "same mesh, r0 -25 %, tuned on 2 modes (little strain energy there)",
            model: hex8(),
            realm: hex8(),
            theta: damaged(&[(0, -0.25)]),
            noises: &[0.01],
            tuned: 2,
        },
        Case {
            name: "same mesh, r3 -25 % and r7 -15 %",
            model: hex8(),
            realm: hex8(),
            theta: damaged(&[(3, -0.25), (7, -0.15)]),
            noises: &[0.01],
            tuned: 4,
        },
        Case {
            name: "hex20 model, tet10 structure, r3 -25 % and r7 -15 %",
            model: hex20(),
            realm: tet10(),
            theta: damaged(&[(3, -0.25), (7, -0.15)]),
            noises: &[0.01],
            tuned: 4,
        },
    ];
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    println!(
        "| case | noise | route | residual ranking's first | selected | identified (95 %) | held-out RMS before -> after | held-out better | verdict (rule) |\n|---|---|---|---|---|---|---|---|---|"
    );
    for case in &cases {
        for &noise in case.noises {
            let (test, sensors) = real::measure(
                &case.realm,
                &case.theta,
                &case.model,
                10,
                noise,
                noise / 10.0,
                7,
            );
            let dofs = case.model.dof_map().unwrap();
            let layout = SensorLayout::new(case.model.mesh(), &dofs, sensors).unwrap();
            for (route, method, select) in [
                (
                    "default",
                    UpdateMethod::InverseEigensensitivity,
                    Select::Forward,
                ),
                ("paper (SB-EBE)", UpdateMethod::SbEbe, Select::Residual),
                (
                    "every region free",
                    UpdateMethod::InverseEigensensitivity,
                    Select::All,
                ),
            ] {
                let options = UpdateStudyOptions {
                    method,
                    select,
                    uncertainty: TestUncertainty {
                        frequency: (noise / 10.0).max(1e-3),
                        shape: noise.max(1e-2),
                        given: true,
                    },
                    ..UpdateStudyOptions::new(case.tuned, 10)
                };
                let s = match localise_update_check(
                    &case.model,
                    &sets,
                    &layout,
                    &test,
                    None,
                    None,
                    &options,
                    |_| {},
                ) {
                    Ok(s) => s,
                    Err(e) => {
                        println!("| {} | {noise} | {route} | error: {e} |", case.name);
                        continue;
                    }
                };
                let first = s
                    .localisation
                    .as_ref()
                    .and_then(|l| l.ranking.first())
                    .map_or("-".to_string(), |g| g.name.clone());
                let half = |k: usize| {
                    s.result
                        .confidence
                        .as_ref()
                        .map_or(f64::NAN, |c| c.half_width_95[k])
                };
                let identified: Vec<String> = s
                    .result
                    .names
                    .iter()
                    .zip(&s.result.theta)
                    .enumerate()
                    .filter(|(k, (_, v))| {
                        select != Select::All || v.abs() >= half(*k) || v.abs() > 0.1
                    })
                    .map(|(k, (n, v))| {
                        let h = half(k);
                        if h.is_finite() {
                            format!("{n} {v:+.3} +- {h:.3}")
                        } else {
                            format!("{n} {v:+.3}")
                        }
                    })
                    .collect();
                let (b, a) = s.truth_check.held_out_rms();
                let held = s.truth_check.held_out().count();
                let better = s
                    .truth_check
                    .held_out()
                    .filter(|m| m.improved() == Some(true))
                    .count();
                println!(
                    "| {} | {:.1} % | {route} | {first} | {} | {}{} | {:.2} % -> {:.2} % | {better} of {held} | {:?} ({}) |",
                    case.name,
                    100.0 * noise,
                    s.updated_sets.join(", "),
                    identified.join(", "),
                    if select == Select::All {
                        " (every other region within 0.1 and not determined)"
                    } else {
                        ""
                    },
                    100.0 * b,
                    100.0 * a,
                    s.truth_check.judgement.verdict,
                    s.truth_check.judgement.rule.split(':').next().unwrap_or("")
                );
            }
        }
    }
}
