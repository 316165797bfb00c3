//! SB-EBE's bias against its trust in the test: the weight `gamma` of the test-error term of the
//! expansion (`SbebeOptions::test_error`; `None` imposes the readings), swept on the plate cases
//! of `tests/truth.rs` (r3 25 % softer), updating r3 alone and r2-r4:
//! `cargo run --release -p femu-study --example sbebe_test_error`. Its output is in
//! `docs/VERIFICATION.md`, "Updating by default".

#[path = "../tests/common/real.rs"]
mod real;
use femu_correlate::prelude::*;
use femu_fem::prelude::*;
use femu_update::prelude::*;
use rayon::prelude::*;

fn main() {
    let same = real::plate([20, 7, 2], false);
    let conv = real::plate([20, 7, 2], true);
    let tet = real::plate_of([20, 7, 2], BoxCells::Tet6, true);
    let mut t = vec![0.0; 10];
    t[3] = -0.25;
    let cases: Vec<(&str, &Model, &Model, f64)> = vec![
        ("same", &same, &same, 0.01),
        ("same", &same, &same, 0.02),
        ("conv", &conv, &tet, 0.01),
    ];
    let gammas = [
        None,
        Some(1e-5),
        Some(1e-4),
        Some(1e-3),
        Some(1e-2),
        Some(1e-1),
        Some(1.0),
    ];
    let out: Vec<String> = cases
        .par_iter()
        .flat_map(|(name, model, realm, noise)| {
            let (test, sensors) = real::measure(realm, &t, model, 10, *noise, noise / 10.0, 7);
            let layout =
                SensorLayout::new(model.mesh(), &model.dof_map().unwrap(), sensors).unwrap();
            let tuned = TestModes::new(
                test.frequencies_hz[..4].to_vec(),
                None,
                test.shapes.as_ref().subcols(0, 4).to_owned(),
            )
            .unwrap();
            gammas
                .par_iter()
                .map(|g| {
                    let mut res = String::new();
                    for sets in [vec!["r3"], vec!["r2", "r3", "r4"]] {
                        let mut up = UpdateModel::from_element_sets(
                            model,
                            &sets,
                            MassKind::Consistent,
                            Corrections::Stiffness,
                        )
                        .unwrap();
                        let o = SbebeOptions {
                            test_error: *g,
                            ..Default::default()
                        };
                        match sb_ebe(&mut up, &layout, &tuned, &o, |_| {}) {
                            Ok(r) => {
                                res += &format!(
                                    " {:?}={:?}",
                                    sets,
                                    r.theta
                                        .iter()
                                        .map(|v| (v * 1000.0).round() / 1000.0)
                                        .collect::<Vec<_>>()
                                )
                            }
                            Err(e) => res += &format!(" {:?}=err {e}", sets),
                        }
                    }
                    format!("{name} noise {noise} gamma {g:?}:{res}")
                })
                .collect::<Vec<_>>()
        })
        .collect();
    for o in out {
        println!("{o}");
    }
}
