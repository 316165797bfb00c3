//! Can updating tell the truth when the model is not the structure? Each case's "real" plate is
//! built apart from the model (another mesh, quadratic elements; `common/real.rs`), one or two
//! regions softer, measured at the model's 15 sensor nodes in y and z with noise; the truth is
//! known. With default settings, where the data hold the answer femu selects the damaged region
//! first and recovers it within 0.05, other regions stay within 0.1 or are named not determined,
//! and the verdict is not "compensates"; where they do not, the verdict says why and is never
//! "agrees". Each case's numbers are in `docs/VERIFICATION.md`, "Updating by default".

mod common;

use common::real;
use femu_correlate::prelude::*;
use femu_fem::prelude::*;
use femu_study::updating::{Select, UpdateStudy, UpdateStudyOptions, localise_update_check};
use femu_update::prelude::*;
use femu_update::{JudgeInputs, ParameterFinding, Verdict, select_parameters};
use rayon::prelude::*;

const TRUTH: f64 = -0.25;

fn truth() -> Vec<f64> {
    let mut t = vec![0.0; real::REGIONS];
    t[3] = TRUTH;
    t
}

/// The default workflow (forward selection, inverse eigensensitivity on frequencies and shapes)
/// on a test of `realm` with region factors `theta`, measured at `model`'s sensors with `noise` on
/// shapes and a tenth of it on frequencies, the first `tuned` of ten modes tuned; `adjust` changes
/// the options.
fn study(
    model: &Model,
    realm: &Model,
    theta: &[f64],
    noise: f64,
    seed: u64,
    adjust: impl FnOnce(&mut UpdateStudyOptions),
) -> UpdateStudy {
    let (test, sensors) = real::measure(realm, theta, model, 10, noise, noise / 10.0, seed);
    let layout = SensorLayout::new(model.mesh(), &model.dof_map().unwrap(), sensors).unwrap();
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut options = UpdateStudyOptions {
        uncertainty: TestUncertainty {
            frequency: (noise / 10.0).max(1e-3),
            shape: noise.max(1e-2),
            given: true,
        },
        ..UpdateStudyOptions::new(4, 10)
    };
    adjust(&mut options);
    localise_update_check(model, &sets, &layout, &test, None, None, &options, |_| {}).unwrap()
}

/// The defaults with the test's uncertainty given (0.1 % on frequencies, 1 % on shapes), `tuned`
/// of ten modes.
fn given_options(tuned: usize) -> UpdateStudyOptions {
    UpdateStudyOptions {
        uncertainty: TestUncertainty {
            frequency: 1e-3,
            shape: 1e-2,
            given: true,
        },
        ..UpdateStudyOptions::new(tuned, 10)
    }
}

/// The workflow on the plate's regions `r0`..`r9`.
fn on_regions(
    model: &Model,
    layout: &SensorLayout,
    test: &TestModes,
    options: &UpdateStudyOptions,
) -> Result<UpdateStudy, femu_study::StudyError> {
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    localise_update_check(model, &sets, layout, test, None, None, options, |_| {})
}

fn value(s: &UpdateStudy, name: &str) -> Option<f64> {
    s.result
        .names
        .iter()
        .position(|n| n == name)
        .map(|k| s.result.theta[k])
}

/// Every updated parameter other than `damaged` is within 0.1 of zero or not determined (its
/// 95 % interval contains zero).
fn others_small_or_undetermined(s: &UpdateStudy, damaged: &[&str]) {
    let c = s.result.confidence.as_ref().unwrap();
    for (k, (n, v)) in s.result.names.iter().zip(&s.result.theta).enumerate() {
        if !damaged.contains(&n.as_str()) {
            assert!(
                v.abs() < 0.1 || c.half_width_95[k] >= v.abs(),
                "{n} = {v} +- {}\n{}",
                c.half_width_95[k],
                s.result
            );
        }
    }
}

/// The user's mesh is the real structure's (noise 0 to 2 %): with default settings the
/// selection takes r3 first (and only), inverse eigensensitivity recovers it within 0.01 (measured
/// -0.250, -0.245, -0.241 at 0, 1 and 2 %), every held-out mode improves and the verdict agrees;
/// the fit's residuals imply the shape noise that was put in, within 15 %.
/// The paper's route (residual ranking and SB-EBE) at 2 % noise is not judged to agree.
#[test]
fn same_mesh_at_every_noise_level() {
    let model = real::plate([20, 7, 2], false);
    let studies: Vec<(f64, UpdateStudy)> = [0.0, 0.005, 0.01, 0.02]
        .par_iter()
        .map(|&noise| (noise, study(&model, &model, &truth(), noise, 7, |_| {})))
        .collect();
    for (noise, s) in &studies {
        assert_eq!(
            s.selection.names(),
            ["k:r3"],
            "noise {noise}\n{}",
            s.selection
        );
        assert_eq!(s.updated_sets, ["r3"]);
        let r3 = value(s, "k:r3").unwrap();
        assert!((r3 - TRUTH).abs() < 0.01, "noise {noise}: r3 {r3}");
        assert!(
            s.truth_check.held_out().all(|m| m.improved() == Some(true)),
            "noise {noise}\n{}",
            s.truth_check
        );
        assert_eq!(
            s.truth_check.judgement.verdict,
            Verdict::Agrees,
            "noise {noise}\n{}",
            s.truth_check
        );
        // the shape noise the fit's residuals imply, against the noise put in (one standard
        // deviation of each reading relative to the mode's largest)
        let (_, shape) = s
            .result
            .confidence
            .as_ref()
            .unwrap()
            .implied_uncertainty
            .unwrap();
        let shape = shape.unwrap();
        if *noise > 0.0 {
            assert!(
                (shape / noise - 1.0).abs() < 0.15,
                "noise {noise}: implied {shape}"
            );
        }
    }
    let s = study(&model, &model, &truth(), 0.02, 7, |o| {
        o.method = UpdateMethod::SbEbe;
        o.select = Select::Residual;
    });
    assert!(
        !s.truth_check.judgement.verdict.agrees(),
        "{}",
        s.truth_check
    );
}

/// The realisations of the converged-model case: without noise (seed 7), and at 1 % noise.
const CASES: [(f64, u64); 5] = [(0.0, 7), (0.01, 1), (0.01, 3), (0.01, 5), (0.01, 7)];

/// A converged model (hex20, two through the thickness) against a "real" plate of another
/// element kind (tet10 on the same grid), so that the test carries a model-form difference of a
/// few tenths of a percent.
///
/// - What the data hold, by the least-squares fit with every region free (noise-free): r3 is the
///   largest change, -0.282 +- 0.061, every other region within 0.08 and not determined.
/// - With default settings, in every realisation: r3 selected first and alone (the end regions
///   that lower the objective in some realisations are selected in 10-73 % of the resamples
///   only, and not kept), r3 within 0.02 of -0.25 (measured -0.231 to -0.237), the held-out RMS
///   error cut by at least three (about 1.4 % to 0.35 %). The element difference leaves held-out
///   modes 7 and 10 0.4-0.7 % off, which no stiffness factor represents, and the model's own
///   discretisation error (the hex20 mesh split once: up to 0.28 % on these modes) is of that
///   size: noise-free the verdict is "agrees within the test's uncertainty and the model's
///   discretisation error"; at 1 % noise either that or "improved, but still off", by
///   realisation, never "agrees" alone. Mode 10 overshoots (+0.62 % to -0.66 % at seed 1,
///   measured), so one held-out mode may end up no better, by less than 0.1 point.
#[test]
fn converged_model_against_another_discretisation() {
    let model = real::plate([20, 7, 2], true);
    let realm = real::plate_of([20, 7, 2], BoxCells::Tet6, true);
    let (all, studies) = rayon::join(
        || study(&model, &realm, &truth(), 0.0, 7, |o| o.select = Select::All),
        || {
            CASES
                .par_iter()
                .map(|&(noise, seed)| study(&model, &realm, &truth(), noise, seed, |_| {}))
                .collect::<Vec<UpdateStudy>>()
        },
    );
    let r3 = value(&all, "k:r3").unwrap();
    assert!((r3 - TRUTH).abs() < 0.05, "r3 {r3}\n{}", all.result);
    let largest = all
        .result
        .theta
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .unwrap()
        .0;
    assert_eq!(all.result.names[largest], "k:r3", "{}", all.result);
    others_small_or_undetermined(&all, &["k:r3"]);
    for (&(noise, seed), s) in CASES.iter().zip(&studies) {
        let at = format!("noise {noise} seed {seed}");
        assert_eq!(
            s.selection.steps[0].parameter, "k:r3",
            "{at}\n{}",
            s.selection
        );
        assert_eq!(s.updated_sets, ["r3"], "{at}\n{}", s.selection);
        let r3 = value(s, "k:r3").unwrap();
        assert!((r3 - TRUTH).abs() < 0.02, "{at}: r3 {r3}");
        let (before, after) = s.truth_check.held_out_rms();
        assert!(after < before / 3.0, "{at}: {before} -> {after}");
        let worse: Vec<f64> = s
            .truth_check
            .held_out()
            .filter(|m| m.improved() == Some(false))
            .map(|m| m.error_after().unwrap().abs() - m.error_before().unwrap().abs())
            .collect();
        assert!(
            worse.len() <= 1 && worse.iter().all(|w| *w < 1e-3),
            "{at}: {worse:?}\n{}",
            s.truth_check
        );
        // the hex20 model split once: its own error is a few tenths of a percent, what the
        // element difference leaves on the held-out modes; which of the two verdicts holds
        // depends on the realisation, never "agrees" within the test's uncertainty alone
        let d = s
            .discretisation
            .as_ref()
            .expect("a hex20 mesh is split once");
        let worst = d
            .relative
            .iter()
            .flatten()
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        assert!(worst < 0.01, "{at}: {worst}");
        let j = &s.truth_check.judgement;
        match j.verdict {
            Verdict::AgreesWithinDiscretisation => assert!(
                j.reasons
                    .iter()
                    .any(|r| r.contains("the model's discretisation error together")),
                "{at}\n{}",
                s.truth_check
            ),
            Verdict::ModelFormError => assert!(
                j.reasons
                    .iter()
                    .any(|r| r.starts_with("still outside the tolerance")),
                "{at}\n{}",
                s.truth_check
            ),
            other => panic!("{at}: {other:?}\n{}", s.truth_check),
        }
        if noise == 0.0 {
            assert_eq!(
                j.verdict,
                Verdict::AgreesWithinDiscretisation,
                "{}",
                s.truth_check
            );
        }
    }
}

/// The residual ranking against the selection on the converged-model case at 1 % noise, eight
/// realisations: the selection puts r3 first in every one, and keeps it in every resample; the
/// ranking reads the expanded shapes and, in the measurement this test was written from, put r3
/// first in four of the eight (seeds 3, 5, 6 and 8 ranked r6, r9, r0 and r4 first). Where they
/// disagree the workflow says so.
#[test]
fn the_selection_is_stable_where_the_residual_ranking_follows_the_noise() {
    let model = real::plate([20, 7, 2], true);
    let realm = real::plate_of([20, 7, 2], BoxCells::Tet6, true);
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let ranked_first: Vec<bool> = (1..=8u64)
        .into_par_iter()
        .map(|seed| {
            let (test, sensors) = real::measure(&realm, &truth(), &model, 10, 0.01, 0.001, seed);
            let layout =
                SensorLayout::new(model.mesh(), &model.dof_map().unwrap(), sensors).unwrap();
            let tuned = TestModes::new(
                test.frequencies_hz[..4].to_vec(),
                None,
                test.shapes.as_ref().subcols(0, 4).to_owned(),
            )
            .unwrap();
            let mut up = UpdateModel::from_element_sets(
                &model,
                &sets,
                MassKind::Consistent,
                Corrections::Stiffness,
            )
            .unwrap();
            let options = SensitivityOptions {
                shapes: true,
                uncertainty: TestUncertainty {
                    frequency: 1e-3,
                    shape: 1e-2,
                    given: true,
                },
                ..Default::default()
            };
            let s =
                select_parameters(&mut up, &layout, &tuned, &options, &Default::default()).unwrap();
            assert_eq!(s.steps[0].parameter, "k:r3", "seed {seed}\n{s}");
            let r3 = s.stability_of("k:r3").unwrap();
            assert_eq!((r3.selected, r3.first), (1.0, 1.0), "seed {seed}\n{s}");
            let loc = localise_expanded(&up, &layout, &tuned, &SelectionRule::default()).unwrap();
            loc.ranking[0].name == "r3"
        })
        .collect();
    let first = ranked_first.iter().filter(|b| **b).count();
    assert!(
        first < 8,
        "the residual ranking put r3 first in every realisation"
    );
    // the workflow names the disagreement
    let s = study(&model, &realm, &truth(), 0.01, 3, |_| {});
    assert!(
        s.notes
            .iter()
            .any(|n| n.starts_with("the residual ranking puts r6 first")),
        "{:?}",
        s.notes
    );
}

/// Two damaged regions (r3 -25 %, r7 -15 %) at 1 % noise: on the same mesh and on the converged
/// model of another element kind, the selection keeps both and only them, each within 0.02 of its
/// value (measured -0.244/-0.152 and -0.240/-0.135), every held-out mode improves; the verdict
/// agrees on the same mesh and is "improved, but still off" on the other.
#[test]
fn two_damaged_regions() {
    let mut theta = truth();
    theta[7] = -0.15;
    let same = real::plate([20, 7, 2], false);
    let model = real::plate([20, 7, 2], true);
    let realm = real::plate_of([20, 7, 2], BoxCells::Tet6, true);
    let (a, b) = rayon::join(
        || study(&same, &same, &theta, 0.01, 7, |_| {}),
        || study(&model, &realm, &theta, 0.01, 7, |_| {}),
    );
    for (s, verdict) in [(&a, Verdict::Agrees), (&b, Verdict::ModelFormError)] {
        assert_eq!(s.updated_sets, ["r3", "r7"], "{}", s.selection);
        for (name, v) in [("k:r3", TRUTH), ("k:r7", -0.15)] {
            let got = value(s, name).unwrap();
            assert!((got - v).abs() < 0.02, "{name} {got}");
        }
        assert!(s.truth_check.held_out().all(|m| m.improved() == Some(true)));
        assert_eq!(
            s.truth_check.judgement.verdict, verdict,
            "{}",
            s.truth_check
        );
    }
}

/// Where the data do not hold the answer the verdict says so, never "agrees": r0 (a free end,
/// little strain energy in the two lowest modes) 25 % softer, tuned on those two modes. With
/// shapes the best candidate (r0) misses the Bonferroni level (measured F = 6.7, p = 0.012 against
/// 0.005); on frequencies alone the free-free plate's mirror symmetry makes r9 look the same as r0.
/// Either way no candidate is kept and the verdict is "cannot tell", naming the best candidate's
/// test.
#[test]
fn a_region_the_tuned_modes_barely_strain_cannot_be_told() {
    let model = real::plate([20, 7, 2], false);
    let mut theta = vec![0.0; real::REGIONS];
    theta[0] = TRUTH;
    let studies: Vec<UpdateStudy> = [true, false]
        .par_iter()
        .map(|&shapes| {
            study(&model, &model, &theta, 0.01, 7, |o| {
                o.tuned = 2;
                o.shapes = shapes;
            })
        })
        .collect();
    for s in &studies {
        assert!(s.selection.selected.is_empty(), "{}", s.selection);
        let j = &s.truth_check.judgement;
        assert_eq!(j.verdict, Verdict::Inconclusive, "{}", s.truth_check);
        assert!(j.rule.starts_with("3:"), "{j:?}");
        assert!(
            j.reasons
                .iter()
                .any(|r| r.starts_with("the tuned modes support no correction")),
            "{j:?}"
        );
    }
}

/// Sensors along directions turned 30 degrees about x (neither is a global axis): the residual
/// ranking, which expands the shapes, cannot run and says so; the default workflow selects r3,
/// recovers it within 0.01 (measured -0.245) and agrees.
#[test]
fn sensors_off_the_global_axes() {
    let model = real::plate([20, 7, 2], false);
    let c = 30f64.to_radians();
    let directions = [[0.0, c.cos(), c.sin()], [0.0, -c.sin(), c.cos()]];
    let (test, sensors) =
        real::measure_along(&model, &truth(), &model, 10, (0.01, 0.001), 7, &directions);
    let layout = SensorLayout::new(model.mesh(), &model.dof_map().unwrap(), sensors).unwrap();
    assert!(layout.measured_dofs().is_none());
    let options = given_options(4);
    let s = on_regions(&model, &layout, &test, &options).unwrap();
    assert!(s.localisation.is_none() && s.reach.is_none());
    assert!(s.notes[0].contains("needs every sensor along a global axis"));
    assert_eq!(s.updated_sets, ["r3"]);
    assert!((value(&s, "k:r3").unwrap() - TRUTH).abs() < 0.01);
    assert_eq!(
        s.truth_check.judgement.verdict,
        Verdict::Agrees,
        "{}",
        s.truth_check
    );
    // the paper's residual ranking is refused by name
    let residual = UpdateStudyOptions {
        select: Select::Residual,
        ..options
    };
    let e = on_regions(&model, &layout, &test, &residual).unwrap_err();
    assert!(e.to_string().contains("forward selection"), "{e}");
}

/// A locked model (one hex8 through the thickness) against a hex20 plate: its discretisation
/// error is measured and said before updating, and whatever the method, the corrections needed
/// to fit it are beyond 50 %: compensates, never "agrees".
#[test]
fn locked_model_is_said_and_never_agrees() {
    let model = real::plate([20, 7, 1], false);
    let realm = real::plate([20, 7, 2], true);
    for (method, select) in [
        (UpdateMethod::SbEbe, Select::Residual),
        (UpdateMethod::InverseEigensensitivity, Select::Forward),
    ] {
        let s = study(&model, &realm, &truth(), 0.0, 7, |o| {
            o.method = method;
            o.select = select;
        });
        let d = s.discretisation.as_ref().expect("a linear mesh is checked");
        let worst = d
            .relative
            .iter()
            .flatten()
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        assert!(worst > 0.1, "locking: {worst}");
        let j = &s.truth_check.judgement;
        assert_eq!(
            j.verdict,
            Verdict::Compensates,
            "{method}\n{}",
            s.truth_check
        );
        assert!(
            j.reasons
                .iter()
                .any(|r| r.starts_with("before updating: the model's own discretisation error")),
            "{:?}",
            j.reasons
        );
    }
}

/// A compensating parameter set: regions r0 and r9, where localisation finds no evidence,
/// updated on frequencies alone: the fit drives r0 beyond -50 % and r9 to its bound (the
/// tuned frequencies can be matched that way), and the verdict is that the correction compensates.
#[test]
fn a_correction_away_from_the_evidence_compensates() {
    let model = real::plate([20, 7, 2], false);
    let (test, sensors) = real::measure(&model, &truth(), &model, 10, 0.0, 0.0, 7);
    let dofs = model.dof_map().unwrap();
    let layout = SensorLayout::new(model.mesh(), &dofs, sensors).unwrap();
    let names = real::regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut nominal =
        UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent, Corrections::Stiffness)
            .unwrap();
    let tuned = TestModes::new(
        test.frequencies_hz[..4].to_vec(),
        None,
        test.shapes.as_ref().subcols(0, 4).to_owned(),
    )
    .unwrap();
    let loc = localise_expanded(&nominal, &layout, &tuned, &SelectionRule::default()).unwrap();
    assert!(!loc.selected.contains(&0) && !loc.selected.contains(&9));
    let before = model_modes(&mut nominal, 20, &Default::default()).unwrap();
    let mut up = UpdateModel::from_element_sets(
        &model,
        &["r0", "r9"],
        MassKind::Consistent,
        Corrections::Stiffness,
    )
    .unwrap();
    let r =
        inverse_eigensensitivity(&mut up, &layout, &tuned, &Default::default(), |_| {}).unwrap();
    let after = model_modes(&mut up, 20, &Default::default()).unwrap();
    let mut check = truth_check(
        &before,
        &after,
        &test,
        &layout,
        &[0, 1, 2, 3],
        &Default::default(),
    )
    .unwrap();
    let parameters: Vec<ParameterFinding> = up
        .parameters()
        .iter()
        .zip(&r.theta)
        .map(|(p, v)| ParameterFinding {
            name: p.name.clone(),
            value: *v,
            bounds: (p.lower, p.upper),
            half_width_95: None,
            evidence: false,
        })
        .collect();
    let j = check
        .judge(&JudgeInputs {
            parameters,
            ..Default::default()
        })
        .clone();
    assert_eq!(j.verdict, Verdict::Compensates, "{check}");
    // measured: r0 -0.77 (beyond 50 %) and r9 at its upper bound, said with how far the tuned
    // frequencies moved
    assert!(
        j.reasons
            .iter()
            .any(|r| r.starts_with("k:r9 = +2.000 is at a bound"))
            && j.reasons
                .iter()
                .any(|r| r.contains("moved the tuned frequencies")),
        "{:?}",
        j.reasons
    );
}

/// A test of frequencies alone (the plate's ten frequencies, 0.1 % noise, no shapes, six tuned):
/// the modes are paired by frequency, the selection and inverse eigensensitivity fit the
/// frequencies, r3 comes out -0.250 (measured -0.2498 +- 0.012), and the held-out frequencies
/// agree. Frequencies alone cannot tell r3 from its mirror image r6 on the free-free plate: the
/// selection reports them as equivalent (counting a resample that picks r6 for r3: 100 %, 72 %
/// without), and the verdict says that only measurements that see the difference can say which.
#[test]
fn frequencies_alone() {
    let model = real::plate([20, 7, 2], false);
    let (test, _) = real::measure(&model, &truth(), &model, 10, 0.0, 0.001, 7);
    let test = TestModes::frequencies_only(test.frequencies_hz.clone(), None).unwrap();
    assert!(!test.has_shapes());
    let layout = SensorLayout::new(model.mesh(), &model.dof_map().unwrap(), Vec::new()).unwrap();
    let options = given_options(6);
    let s = on_regions(&model, &layout, &test, &options).unwrap();
    assert!(s.localisation.is_none());
    assert!(
        s.notes[0].starts_with("the test gives frequencies alone"),
        "{:?}",
        s.notes
    );
    assert_eq!(s.updated_sets, ["r3"], "{}", s.selection);
    assert!(
        (value(&s, "k:r3").unwrap() - TRUTH).abs() < 0.01,
        "{}",
        s.result
    );
    assert_eq!(
        s.selection.equivalents,
        vec![("k:r3".to_string(), vec!["k:r6".to_string()])]
    );
    let check = &s.truth_check;
    assert!(
        check
            .modes
            .iter()
            .all(|m| m.mac_before.is_none() && m.f_before.is_some())
    );
    assert_eq!(check.judgement.verdict, Verdict::Agrees, "{check}");
    assert!(
        check
            .judgement
            .reasons
            .iter()
            .any(|r| r.starts_with("k:r3 cannot be told from k:r6")),
        "{check}"
    );
    // SB-EBE expands shapes: refused by name
    let sbebe = UpdateStudyOptions {
        method: UpdateMethod::SbEbe,
        ..options
    };
    let e = on_regions(&model, &layout, &test, &sbebe).unwrap_err();
    assert!(e.to_string().contains("frequencies alone"), "{e}");
}
