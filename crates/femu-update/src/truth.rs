//! The truth check: does the updated model predict the modes it was not tuned on?
//!
//! The paper's question. Tuned modes improve by construction; the held-out modes (test modes not
//! used in updating) show whether the correction is physical or a compensation. When the test was
//! simulated from a known model the identified parameters are compared with the true ones too.

use crate::UpdateError;
use femu_correlate::{ModeSet, PairingOptions, SensorLayout, TestModes, correlate};
use serde::{Deserialize, Serialize};

/// One test mode before and after updating.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeCheck {
    /// Test mode (1-based).
    pub test: usize,
    /// Whether it was used in updating.
    pub tuned: bool,
    /// Test frequency, Hz.
    pub f_test: f64,
    /// Paired model frequency before updating, Hz (`None`: unpaired).
    pub f_before: Option<f64>,
    /// MAC before.
    pub mac_before: Option<f64>,
    /// Paired model frequency after updating, Hz.
    pub f_after: Option<f64>,
    /// MAC after.
    pub mac_after: Option<f64>,
}

impl ModeCheck {
    /// Relative frequency error before updating.
    pub fn error_before(&self) -> Option<f64> {
        self.f_before.map(|f| (f - self.f_test) / self.f_test)
    }

    /// Relative frequency error after updating.
    pub fn error_after(&self) -> Option<f64> {
        self.f_after.map(|f| (f - self.f_test) / self.f_test)
    }

    /// Whether the absolute frequency error decreased (and the mode stayed paired).
    pub fn improved(&self) -> Option<bool> {
        match (self.error_before(), self.error_after()) {
            (Some(b), Some(a)) => Some(a.abs() < b.abs()),
            (None, Some(_)) => Some(true),
            (Some(_), None) => Some(false),
            (None, None) => None,
        }
    }
}

/// An identified parameter against its true value (simulated tests).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterCheck {
    /// Parameter name.
    pub name: String,
    /// The identified value.
    pub identified: f64,
    /// The true value.
    pub truth: f64,
}

/// The truth check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthCheck {
    /// Every test mode, tuned and held out.
    pub modes: Vec<ModeCheck>,
    /// Identified against true parameters (empty when the truth is unknown).
    pub parameters: Vec<ParameterCheck>,
    /// The verdict with its reasons ([`TruthCheck::judge`]).
    pub judgement: Judgement,
}

/// The verdict of the truth check, one of a few well-defined answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Every held-out mode agrees within three standard deviations of the test's frequency
    /// uncertainty, no held-out shape got worse, the held-out modes are not worse than the nominal
    /// model's, and the parameters are plausible.
    Agrees,
    /// As [`Verdict::Agrees`], but some held-out modes agree only once the model's own
    /// discretisation error is added to the test's uncertainty: the updated model is as close as
    /// its mesh allows.
    AgreesWithinDiscretisation,
    /// The held-out modes improved, but at least one is still outside that tolerance (or its shape
    /// got worse), and the parameters are plausible: an error the chosen parameters cannot
    /// represent (model form).
    ModelFormError,
    /// A determined parameter is not credible (at a bound, beyond +-50 %, or a change the data's
    /// selection did not support), whatever the held-out modes do: the correction compensates
    /// rather than corrects.
    Compensates,
    /// The held-out modes did not improve (their RMS frequency error is not lower than the
    /// nominal model's).
    NotImproved,
    /// Nothing to judge on: no held-out mode, or the data support no correction among the
    /// candidates.
    Inconclusive,
}

impl Verdict {
    /// The answer to the paper's question in words.
    pub fn answer(self) -> &'static str {
        match self {
            Verdict::Agrees => "yes: agrees within the test's uncertainty",
            Verdict::AgreesWithinDiscretisation => {
                "yes: agrees within the test's uncertainty and the model's discretisation error"
            }
            Verdict::ModelFormError => {
                "no: improved, but still off by more than the test's uncertainty allows (an error the parameters cannot represent, or a biased estimate)"
            }
            Verdict::Compensates => "no: the correction compensates rather than corrects",
            Verdict::NotImproved => "no: the held-out modes did not improve",
            Verdict::Inconclusive => "cannot tell",
        }
    }

    /// Whether the verdict says the updated model tells the truth.
    pub fn agrees(self) -> bool {
        matches!(self, Verdict::Agrees | Verdict::AgreesWithinDiscretisation)
    }
}

/// The verdict, the rule that produced it and the reasons with their numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Judgement {
    /// The verdict.
    pub verdict: Verdict,
    /// The rule that decided, in words.
    pub rule: String,
    /// The findings behind it, one sentence each.
    pub reasons: Vec<String>,
}

/// One identified parameter as the judgement sees it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterFinding {
    /// Its name (`k:r3`).
    pub name: String,
    /// The identified value.
    pub value: f64,
    /// Its bounds.
    pub bounds: (f64, f64),
    /// The half-width of its 95 % interval, when known.
    pub half_width_95: Option<f64>,
    /// Whether the data support a change of it: the parameter selection (or, when asked for,
    /// the residual localisation) chose it.
    pub evidence: bool,
}

/// What the judgement weighs the held-out errors against.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct JudgeInputs {
    /// The test's uncertainty (`given: false` is said in the reasons).
    pub uncertainty: crate::sensitivity::TestUncertainty,
    /// The model's own relative frequency error per test mode (discretisation), when estimated.
    pub discretisation: Vec<Option<f64>>,
    /// The identified parameters (empty: not reviewed).
    pub parameters: Vec<ParameterFinding>,
    /// `sqrt(chi^2 / nu)` of the fit, when known: the scatter the fit leaves in units of the
    /// test's uncertainty (1: the uncertainty explains it).
    pub fit_scale: Option<f64>,
    /// Why the data support no correction among the candidates, when the selection kept none
    /// (the parameters were then fitted for the record only).
    pub unsupported: Option<String>,
    /// The test's uncertainty as the fit's residuals imply it, `(frequency, shape)` relative
    /// ([`crate::Confidence::implied_uncertainty`]); said beside an assumed uncertainty.
    pub implied: Option<(f64, Option<f64>)>,
}

/// A parameter change beyond this (50 %) is implausible for a model that was built with care.
pub const IMPLAUSIBLE_CHANGE: f64 = 0.5;

/// How many standard deviations a held-out error may be and still agree.
pub const AGREEMENT_SIGMAS: f64 = 3.0;

/// A held-out mode's shape got worse when its MAC fell by more than this.
pub const MAC_DROP: f64 = 0.02;

/// A change below this (5 %) is small enough not to need the data's support.
pub const SMALL_CHANGE: f64 = 0.05;

impl TruthCheck {
    /// The held-out modes.
    pub fn held_out(&self) -> impl Iterator<Item = &ModeCheck> {
        self.modes.iter().filter(|m| !m.tuned)
    }

    /// RMS relative frequency error of the held-out modes before and after (paired ones only).
    pub fn held_out_rms(&self) -> (f64, f64) {
        let rms = |f: &dyn Fn(&ModeCheck) -> Option<f64>| {
            let v: Vec<f64> = self.held_out().filter_map(f).collect();
            if v.is_empty() {
                f64::NAN
            } else {
                (v.iter().map(|e| e * e).sum::<f64>() / v.len() as f64).sqrt()
            }
        };
        (rms(&|m| m.error_before()), rms(&|m| m.error_after()))
    }

    /// The answer in one sentence: the verdict and its first reasons.
    pub fn verdict(&self) -> String {
        let j = &self.judgement;
        format!("{}: {}", j.verdict.answer(), j.reasons.join("; "))
    }

    /// Judges the held-out modes against the test's uncertainty and the model's discretisation
    /// error, and the parameters for plausibility (`docs/MATH.md`, "The truth check"); stores and
    /// returns the judgement. The rules, in order:
    /// 1. no held-out mode: inconclusive;
    /// 2. each tuned mode whose discretisation error is at least half its test-analysis error is
    ///    named (parameters fitted to such a mesh are effective values of the mesh), a caveat to
    ///    any verdict; so is a parameter whose 95 % interval contains zero ("not determined":
    ///    the data are consistent with no change there), whatever its size;
    /// 3. the data's selection kept no candidate ([`JudgeInputs::unsupported`]): inconclusive;
    /// 4. a parameter at a bound, or a determined one (interval excluding zero, or unknown)
    ///    beyond +-50 %, or a determined change above 5 % that the data's selection did not
    ///    support: compensates;
    /// 5. held-out RMS frequency error not lower than before: not improved (even inside the
    ///    tolerance: a nominal model that already agreed is said so);
    /// 6. every held-out error within `3 sigma_f`, every held-out MAC within 0.02 of its nominal
    ///    value: agrees;
    /// 7. the same within `3 sqrt(sigma_f^2 + d_i^2)`: agrees within the discretisation error;
    /// 8. otherwise: model-form error (improved, still outside).
    pub fn judge(&mut self, inputs: &JudgeInputs) -> &Judgement {
        self.judgement = judge(self, inputs);
        &self.judgement
    }
}

/// A percentage with two decimals, or two significant digits below 0.01 %.
fn pct(v: f64) -> String {
    if v.abs() >= 1e-4 || v == 0.0 {
        format!("{:.2} %", 100.0 * v)
    } else {
        format!("{:.1e} %", 100.0 * v)
    }
}

fn judge(check: &TruthCheck, inputs: &JudgeInputs) -> Judgement {
    let sf = inputs.uncertainty.frequency;
    let mut reasons = uncertainty_caveats(inputs);
    let held: Vec<&ModeCheck> = check.held_out().collect();
    let (b, a) = check.held_out_rms();
    let d = |t: usize| inputs.discretisation.get(t - 1).copied().flatten();
    let verdict = |v: Verdict, rule: &str, reasons: Vec<String>| Judgement {
        verdict: v,
        rule: rule.to_string(),
        reasons,
    };
    if held.is_empty() {
        reasons.push(
            "no held-out mode: the updated model cannot be checked on modes it was not tuned on"
                .into(),
        );
        return verdict(Verdict::Inconclusive, "1: no held-out mode", reasons);
    }
    reasons.extend(discretisation_caveat(check, inputs));
    let (doubts, undetermined) = parameter_doubts(check, inputs);
    let outside_with = |with_mesh: bool| -> Vec<String> {
        held.iter()
            .filter_map(|m| {
                let e = m.error_after()?;
                let di = if with_mesh {
                    d(m.test).unwrap_or(0.0)
                } else {
                    0.0
                };
                let tol = AGREEMENT_SIGMAS * (sf * sf + di * di).sqrt();
                (e.abs() > tol).then(|| {
                    format!(
                        "mode {} {:+.2} % (tolerance {:.2} %)",
                        m.test,
                        100.0 * e,
                        100.0 * tol
                    )
                })
            })
            .collect()
    };
    let outside = outside_with(false);
    let outside_mesh = outside_with(true);
    let unpaired = held.iter().filter(|m| m.f_after.is_none()).count();
    let shape_worse: Vec<String> = held
        .iter()
        .filter_map(|m| {
            let (mb, ma) = (m.mac_before?, m.mac_after?);
            (ma < mb - MAC_DROP).then(|| format!("mode {} MAC {mb:.3} -> {ma:.3}", m.test))
        })
        .collect();
    let mean_mac = |f: &dyn Fn(&ModeCheck) -> Option<f64>| {
        let v: Vec<f64> = held.iter().filter_map(|m| f(m)).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    reasons.push(format!(
        "held-out RMS frequency error {:.2} % before, {:.2} % after ({} modes){}",
        100.0 * b,
        100.0 * a,
        held.len(),
        match (mean_mac(&|m| m.mac_before), mean_mac(&|m| m.mac_after)) {
            (Some(x), Some(y)) => format!("; mean held-out MAC {x:.3} before, {y:.3} after"),
            _ => String::new(),
        }
    ));
    if !undetermined.is_empty() {
        reasons.push(format!(
            "not determined by the data (95 % interval contains zero: consistent with no change): {}",
            undetermined.join(", ")
        ));
    }
    if let Some(why) = &inputs.unsupported {
        reasons.push(why.clone());
        return verdict(
            Verdict::Inconclusive,
            "3: the data support no correction among the candidates",
            reasons,
        );
    }
    if !doubts.is_empty() {
        reasons.extend(doubts);
        return verdict(
            Verdict::Compensates,
            "4: a parameter at a bound, or a determined one beyond 50 % or without the data's support",
            reasons,
        );
    }
    let nominal_agreed = held.iter().all(|m| {
        m.error_before()
            .is_some_and(|e| e.abs() <= AGREEMENT_SIGMAS * sf)
    });
    if !(a < b) {
        reasons.push(format!(
            "{} of {} held-out modes improved{}",
            held.iter().filter(|m| m.improved() == Some(true)).count(),
            held.len(),
            if nominal_agreed {
                "; the nominal model already agreed within the test's uncertainty: there was nothing for the data to correct"
            } else {
                ""
            }
        ));
        return verdict(
            Verdict::NotImproved,
            "5: held-out RMS error not lower than the nominal model's",
            reasons,
        );
    }
    if !shape_worse.is_empty() {
        reasons.push(format!(
            "held-out shapes got worse (MAC fell by more than {MAC_DROP}): {}",
            shape_worse.join(", ")
        ));
    }
    if outside.is_empty() && unpaired == 0 && shape_worse.is_empty() {
        reasons.push(format!(
            "every held-out mode within {AGREEMENT_SIGMAS} standard deviations of the test's frequency uncertainty ({}), no held-out shape worse",
            pct(AGREEMENT_SIGMAS * sf)
        ));
        return verdict(
            Verdict::Agrees,
            "6: every held-out error within 3 sigma of the test, no held-out shape worse",
            reasons,
        );
    }
    if outside_mesh.is_empty() && unpaired == 0 && shape_worse.is_empty() {
        reasons.push(format!(
            "the held-out modes agree within the test's uncertainty and the model's discretisation error together: {}",
            outside.join(", ")
        ));
        return verdict(
            Verdict::AgreesWithinDiscretisation,
            "7: held-out errors within 3 sigma of the test and the discretisation error",
            reasons,
        );
    }
    reasons.push(format!(
        "still outside the tolerance: {}{}",
        if outside_mesh.is_empty() {
            "no frequency".to_string()
        } else {
            outside_mesh.join(", ")
        },
        if unpaired > 0 {
            format!("; {unpaired} held-out mode(s) unpaired")
        } else {
            String::new()
        }
    ));
    verdict(
        Verdict::ModelFormError,
        "8: improved, but a held-out error above 3 sigma or a held-out shape worse",
        reasons,
    )
}

impl std::fmt::Display for TruthCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let pct =
            |v: Option<f64>| v.map_or("unpaired".to_string(), |e| format!("{:+.2} %", 100.0 * e));
        let mac = |v: Option<f64>| v.map_or("-".to_string(), |m| format!("{m:.3}"));
        writeln!(
            f,
            "| test | role | f test (Hz) | error before | MAC before | error after | MAC after | better |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|")?;
        for m in &self.modes {
            writeln!(
                f,
                "| {} | {} | {:.2} | {} | {} | {} | {} | {} |",
                m.test,
                if m.tuned { "tuned" } else { "held out" },
                m.f_test,
                pct(m.error_before()),
                mac(m.mac_before),
                pct(m.error_after()),
                mac(m.mac_after),
                match m.improved() {
                    Some(true) => "yes",
                    Some(false) => "no",
                    None => "-",
                }
            )?;
        }
        if !self.parameters.is_empty() {
            writeln!(f, "\n| parameter | identified | true |")?;
            writeln!(f, "|---|---|---|")?;
            for p in &self.parameters {
                writeln!(f, "| {} | {:+.4} | {:+.4} |", p.name, p.identified, p.truth)?;
            }
        }
        writeln!(
            f,
            "\nDoes the updated model tell the truth? {}",
            self.judgement.verdict.answer()
        )?;
        for r in &self.judgement.reasons {
            writeln!(f, "- {r}")?;
        }
        writeln!(f, "\n(rule {})", self.judgement.rule)
    }
}

/// Correlates the model before and after updating with every test mode; `tuned` lists the test
/// modes (0-based) used in updating, the others are held out.
///
/// `docs/MATH.md`, "Updating": the truth check on held-out modes.
///
/// # Errors
/// The correlation's errors (sizes, zero shapes), a tuned index out of range.
pub fn truth_check(
    before: &ModeSet,
    after: &ModeSet,
    test: &TestModes,
    layout: &SensorLayout,
    tuned: &[usize],
    pairing: &PairingOptions,
) -> Result<TruthCheck, UpdateError> {
    if let Some(t) = tuned.iter().find(|t| **t >= test.len()) {
        return Err(UpdateError::Invalid {
            what: "tuned test modes",
            reason: format!("index {t} but only {} test modes", test.len()),
        });
    }
    let rb = correlate(before, test, layout, pairing)?;
    let ra = correlate(after, test, layout, pairing)?;
    let modes = (0..test.len())
        .map(|t| {
            let b = rb.pairing.of_test(t);
            let a = ra.pairing.of_test(t);
            ModeCheck {
                test: t + 1,
                tuned: tuned.contains(&t),
                f_test: test.frequencies_hz[t],
                f_before: b.map(|p| p.f_model),
                mac_before: b.and_then(|p| p.mac),
                f_after: a.map(|p| p.f_model),
                mac_after: a.and_then(|p| p.mac),
            }
        })
        .collect();
    let mut check = TruthCheck {
        modes,
        parameters: Vec::new(),
        judgement: Judgement {
            verdict: Verdict::Inconclusive,
            rule: String::new(),
            reasons: Vec::new(),
        },
    };
    check.judge(&JudgeInputs::default());
    Ok(check)
}

/// Rule 2's caveats on the test's uncertainty: assumed rather than given (with the scatter the
/// fit's residuals imply), and a fit that leaves more scatter than it explains.
fn uncertainty_caveats(inputs: &JudgeInputs) -> Vec<String> {
    let sf = inputs.uncertainty.frequency;
    let mut reasons = Vec::new();
    if !inputs.uncertainty.given {
        reasons.push(format!(
            "test uncertainty not given: assumed {} on frequencies and {} on shapes{}",
            pct(sf),
            pct(inputs.uncertainty.shape),
            match inputs.implied {
                Some((f, s)) => format!(
                    "; the fit's residuals scatter as {} on the tuned frequencies{} (a lower estimate: the fit absorbs part of it); give --frequency-uncertainty and --shape-uncertainty from the identification",
                    pct(f),
                    s.map_or(String::new(), |s| format!(" and {} on the readings", pct(s)))
                ),
                None => String::new(),
            }
        ));
    }
    if let Some(scale) = inputs.fit_scale.filter(|s| *s > 1.5) {
        reasons.push(format!(
            "the fit leaves {scale:.1} times the scatter the test's uncertainty explains (chi-square per degree of freedom {:.1}): noise larger than {}, or what the parameters cannot represent; the intervals are widened by that factor",
            scale * scale,
            if inputs.uncertainty.given { "given" } else { "assumed" }
        ));
    }
    reasons
}

/// Rule 2's caveat on the mesh: a tuned mode whose discretisation error is at least half the
/// test-analysis difference.
fn discretisation_caveat(check: &TruthCheck, inputs: &JudgeInputs) -> Option<String> {
    let d = |t: usize| inputs.discretisation.get(t - 1).copied().flatten();
    // 2: the mesh's own error against the signal
    let swamped: Vec<String> = check
        .modes
        .iter()
        .filter(|m| m.tuned)
        .filter_map(|m| {
            let (e, di) = (m.error_before()?, d(m.test)?);
            (di.abs() >= 0.5 * e.abs()).then(|| {
                format!(
                    "mode {}: discretisation error {:+.2} % against a test-analysis difference of {:+.2} %",
                    m.test,
                    100.0 * di,
                    100.0 * e
                )
            })
        })
        .collect();
    (!swamped.is_empty()).then(|| {
        format!(
            "before updating: the model's own discretisation error is as large as what updating would correct ({}); parameters fitted to such a mesh are effective values of the mesh, not of the structure",
            swamped.join("; ")
        )
    })
}

/// Rule 4's doubts on the fitted parameters (at a bound, beyond 50 %, or a determined change the
/// selection did not support, with how far the tuned frequencies moved), and the parameters the
/// data do not determine.
fn parameter_doubts(check: &TruthCheck, inputs: &JudgeInputs) -> (Vec<String>, Vec<String>) {
    // 2 and 3: the parameters
    let mut doubts = Vec::new();
    let mut undetermined = Vec::new();
    let mut at_bound = false;
    for p in &inputs.parameters {
        let span = (p.bounds.1 - p.bounds.0).abs().max(1e-12);
        let determined = p.half_width_95.is_none_or(|h| h < p.value.abs());
        if let Some(h) = p.half_width_95
            && !determined
        {
            undetermined.push(format!("{} = {:+.3} +- {:.3}", p.name, p.value, h));
        }
        if (p.value - p.bounds.0).abs() <= 1e-6 * span
            || (p.value - p.bounds.1).abs() <= 1e-6 * span
        {
            at_bound = true;
            doubts.push(format!(
                "{} = {:+.3} is at a bound: the correction left the range a stiffness factor can physically take",
                p.name, p.value
            ));
        } else if determined && p.value.abs() > IMPLAUSIBLE_CHANGE {
            doubts.push(format!(
                "{} = {:+.3} changes its region by more than 50 %",
                p.name, p.value
            ));
        } else if determined && !p.evidence && p.value.abs() > SMALL_CHANGE {
            doubts.push(format!(
                "{} = {:+.3}{} is a determined change the data's selection did not support",
                p.name,
                p.value,
                p.half_width_95
                    .map_or(String::new(), |h| format!(" +- {h:.3}"))
            ));
        }
    }
    if at_bound {
        let moved: Vec<f64> = check
            .modes
            .iter()
            .filter(|m| m.tuned)
            .filter_map(|m| Some(m.f_after? / m.f_before? - 1.0))
            .collect();
        if let (Some(lo), Some(hi)) = (
            moved.iter().copied().reduce(f64::min),
            moved.iter().copied().reduce(f64::max),
        ) {
            doubts.push(format!(
                "the update moved the tuned frequencies by {:+.1} to {:+.1} %",
                100.0 * lo,
                100.0 * hi
            ));
        }
    }
    (doubts, undetermined)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensitivity::TestUncertainty;

    /// A check of two tuned and two held-out modes at 100 Hz with the given relative errors
    /// before and after.
    fn check(before: [f64; 4], after: [Option<f64>; 4]) -> TruthCheck {
        let modes = (0..4)
            .map(|i| ModeCheck {
                test: i + 1,
                tuned: i < 2,
                f_test: 100.0,
                f_before: Some(100.0 * (1.0 + before[i])),
                mac_before: Some(0.99),
                f_after: after[i].map(|e| 100.0 * (1.0 + e)),
                mac_after: after[i].map(|_| 0.99),
            })
            .collect();
        TruthCheck {
            modes,
            parameters: Vec::new(),
            judgement: Judgement {
                verdict: Verdict::Inconclusive,
                rule: String::new(),
                reasons: Vec::new(),
            },
        }
    }

    fn given(frequency: f64) -> JudgeInputs {
        JudgeInputs {
            uncertainty: TestUncertainty {
                frequency,
                shape: 0.01,
                given: true,
            },
            ..Default::default()
        }
    }

    fn finding(value: f64, evidence: bool, half_width_95: Option<f64>) -> ParameterFinding {
        ParameterFinding {
            name: "k:a".into(),
            value,
            bounds: (-0.9, 2.0),
            half_width_95,
            evidence,
        }
    }

    #[test]
    fn each_rule_by_hand() {
        let errs = [0.02, 0.02, 0.02, 0.02];
        // 6: within 3 sigma (sigma 0.1 %: 0.3 %)
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.002), Some(-0.0029)]);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::Agrees);
        // 8: improved, one held-out at 0.5 % > 0.3 %
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.005), Some(0.001)]);
        let j = c.judge(&given(1e-3)).clone();
        assert_eq!(j.verdict, Verdict::ModelFormError);
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("mode 3 +0.50 % (tolerance 0.30 %)")),
            "{j:?}"
        );
        // 7: within 3 sqrt(sigma^2 + d^2) only, d = 1 %: 3.02 % tolerance
        let mut inputs = given(1e-3);
        inputs.discretisation = vec![Some(0.01); 4];
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.005), Some(0.001)]);
        assert_eq!(
            c.judge(&inputs).verdict,
            Verdict::AgreesWithinDiscretisation
        );
        assert!(Verdict::AgreesWithinDiscretisation.agrees());
        // 5: not improved
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.03), Some(0.02)]);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::NotImproved);
        // 5 before 6: a nominal model that already agreed within a 1 % uncertainty (3 %
        // tolerance), made worse inside the tolerance, is not improved, and said so
        let mut c = check(
            [0.02, 0.02, 0.0086, -0.0086],
            [Some(0.0), Some(0.0), Some(0.0099), Some(-0.0099)],
        );
        let j = c.judge(&given(1e-2)).clone();
        assert_eq!(j.verdict, Verdict::NotImproved, "{j:?}");
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("the nominal model already agreed")),
            "{j:?}"
        );
        // 1: no held-out mode
        let mut c = check(errs, [Some(0.0); 4]);
        c.modes.iter_mut().for_each(|m| m.tuned = true);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::Inconclusive);
        // 3: no candidate supported by the data, whatever the held-out modes do
        let mut c = check(errs, [Some(0.0); 4]);
        let mut inputs = given(1e-3);
        inputs.unsupported = Some("no candidate passed".into());
        let j = c.judge(&inputs).clone();
        assert_eq!(j.verdict, Verdict::Inconclusive);
        assert!(j.rule.starts_with("3:"), "{j:?}");
        // 4: at a bound; determined beyond 50 %; a determined change without the data's support
        // -- even when the held-out modes agree
        for p in [
            finding(-0.9, true, Some(0.01)),
            finding(0.6, true, None),
            finding(0.6, true, Some(0.1)),
            finding(0.2, false, Some(0.05)),
        ] {
            let mut c = check(errs, [Some(0.0); 4]);
            let mut inputs = given(1e-3);
            inputs.parameters = vec![p.clone()];
            assert_eq!(c.judge(&inputs).verdict, Verdict::Compensates, "{p:?}");
        }
        // at a bound: how far the tuned frequencies moved is said (2 % to 0 %: -1.96 %)
        let mut c = check(errs, [Some(0.0); 4]);
        let mut inputs = given(1e-3);
        inputs.parameters = vec![finding(-0.9, true, None)];
        let j = c.judge(&inputs).clone();
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("moved the tuned frequencies by -2.0 to -2.0 %")),
            "{j:?}"
        );
        // an interval containing zero is "not determined", never compensation, whatever its size
        // and whether or not the selection chose it; small changes are named too
        let mut c = check(errs, [Some(0.0); 4]);
        let mut inputs = given(1e-3);
        inputs.parameters = vec![
            finding(0.073, false, Some(0.162)),
            finding(0.6, true, Some(0.8)),
            finding(0.02, true, Some(0.24)),
        ];
        let j = c.judge(&inputs).clone();
        assert_eq!(j.verdict, Verdict::Agrees, "{j:?}");
        let caveat = j
            .reasons
            .iter()
            .find(|r| r.contains("not determined by the data"))
            .expect("caveat");
        for v in ["+0.073 +- 0.162", "+0.600 +- 0.800", "+0.020 +- 0.240"] {
            assert!(caveat.contains(v), "{caveat}");
        }
        // a held-out shape worse by more than 0.02 in MAC keeps the verdict from agreeing
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.001), Some(0.001)]);
        c.modes[2].mac_after = Some(0.95);
        let j = c.judge(&given(1e-3)).clone();
        assert_eq!(j.verdict, Verdict::ModelFormError, "{j:?}");
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("mode 3 MAC 0.990 -> 0.950")),
            "{j:?}"
        );
        // the mesh's own error as large as the signal is said before anything else
        let mut inputs = given(1e-3);
        inputs.discretisation = vec![Some(0.015), None, None, None];
        let mut c = check(errs, [Some(0.0); 4]);
        let j = c.judge(&inputs).clone();
        assert!(j.reasons[0].starts_with("before updating"), "{j:?}");
        // an assumed uncertainty is said, and a fit that leaves more scatter than it explains
        let mut c = check(errs, [Some(0.0); 4]);
        let j = c
            .judge(&JudgeInputs {
                fit_scale: Some(3.0),
                implied: Some((4e-4, Some(0.025))),
                ..Default::default()
            })
            .clone();
        assert!(
            j.reasons[0]
                .contains("scatter as 0.04 % on the tuned frequencies and 2.50 % on the readings"),
            "{j:?}"
        );
        assert!(
            j.reasons[0].starts_with("test uncertainty not given"),
            "{j:?}"
        );
        assert!(j.reasons[1].contains("3.0 times the scatter"), "{j:?}");
    }
}
