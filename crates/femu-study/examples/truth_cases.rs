//! Measures updating and the truth check on "real" structures that are not the model (the cases
//! of `tests/truth.rs`), printing what femu identifies and says:
//! `cargo run --release -p femu-study --example truth_cases`.

#[path = "../tests/common/real.rs"]
mod real;

use femu_correlate::prelude::*;
use femu_fem::prelude::Model;
use femu_study::updating::{UpdateStudyOptions, localise_update_check};
use femu_update::prelude::*;

fn main() {
    let mut theta = vec![0.0; real::REGIONS];
    theta[3] = -0.25;
    let cases: Vec<(&str, Model, Model, &[f64])> = vec![
        (
            "same mesh hex8",
            real::plate([20, 7, 2], false),
            real::plate([20, 7, 2], false),
            &[0.0, 0.005, 0.01, 0.02],
        ),
        (
            "hex20 model vs tet10 real",
            real::plate([20, 7, 2], true),
            real::plate_of([20, 7, 2], femu_fem::prelude::BoxCells::Tet6, true),
            &[0.0, 0.01],
        ),
        (
            "locked hex8 vs hex20",
            real::plate([20, 7, 1], false),
            real::plate([20, 7, 2], true),
            &[0.0],
        ),
    ];
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    for (name, model, realm, noises) in cases {
        for &noise in noises {
            let (test, sensors) = real::measure(&realm, &theta, &model, 10, noise, noise / 10.0, 7);
            let dofs = model.dof_map().unwrap();
            let layout = SensorLayout::new(model.mesh(), &dofs, sensors).unwrap();
            for (method, shapes, all) in [
                (UpdateMethod::SbEbe, false, false),
                (UpdateMethod::InverseEigensensitivity, true, false),
                (UpdateMethod::InverseEigensensitivity, true, true),
            ] {
                let options = UpdateStudyOptions {
                    method,
                    shapes,
                    all,
                    uncertainty: TestUncertainty {
                        frequency: (noise / 10.0).max(1e-3),
                        shape: noise.max(1e-2),
                        given: true,
                    },
                    ..UpdateStudyOptions::new(4, 10)
                };
                let t = std::time::Instant::now();
                match localise_update_check(
                    &model,
                    &sets,
                    &layout,
                    &test,
                    None,
                    None,
                    &options,
                    |_| {},
                ) {
                    Ok(s) => {
                        let rank: Vec<&str> = s
                            .localisation
                            .ranking
                            .iter()
                            .take(3)
                            .map(|g| g.name.as_str())
                            .collect();
                        let th: Vec<String> = s
                            .result
                            .names
                            .iter()
                            .zip(&s.result.theta)
                            .map(|(n, v)| format!("{n} {v:+.3}"))
                            .collect();
                        let ci = s
                            .result
                            .confidence
                            .as_ref()
                            .map(|c| {
                                format!(
                                    "{:?}",
                                    c.half_width_95
                                        .iter()
                                        .map(|v| (v * 1000.0).round() / 1000.0)
                                        .collect::<Vec<_>>()
                                )
                            })
                            .unwrap_or_default();
                        let (b, a) = s.truth_check.held_out_rms();
                        println!(
                            "{name} | noise {noise} | {method} | ranking {rank:?} | {} {ci} | held-out {:.2}% -> {:.2}% | {:?} ({}) | {:.1} s",
                            th.join(", "),
                            100.0 * b,
                            100.0 * a,
                            s.truth_check.judgement.verdict,
                            s.truth_check.judgement.rule,
                            t.elapsed().as_secs_f64()
                        );
                    }
                    Err(e) => println!("{name} | noise {noise} | {method} | error {e}"),
                }
            }
        }
    }
}
