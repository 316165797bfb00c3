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
    /// uncertainty and the model's discretisation error, and the parameters are plausible.
    Agrees,
    /// The held-out modes improved, but at least one is still outside that tolerance, and the
    /// parameters are plausible: an error the chosen parameters cannot represent (model form).
    ModelFormError,
    /// The parameters are not credible (at a bound, beyond +-50 %, or in regions without localised
    /// evidence), whatever the held-out modes do: the correction compensates rather than corrects.
    Compensates,
    /// The held-out modes did not improve.
    NotImproved,
    /// Nothing to judge on (no held-out mode), or the held-out modes agree only within the
    /// model's own discretisation error, which is larger than the test's uncertainty.
    Inconclusive,
}

impl Verdict {
    /// The answer to the paper's question in words.
    pub fn answer(self) -> &'static str {
        match self {
            Verdict::Agrees => "yes: agrees within the test's uncertainty",
            Verdict::ModelFormError => {
                "no: improved, but still off by more than the test's uncertainty allows (an error the parameters cannot represent, or a biased estimate)"
            }
            Verdict::Compensates => "no: the correction compensates rather than corrects",
            Verdict::NotImproved => "no: the held-out modes did not improve",
            Verdict::Inconclusive => "cannot tell",
        }
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
    /// Whether localisation found evidence in its region (selected it).
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
}

/// A parameter change beyond this (50 %) is implausible for a model that was built with care.
pub const IMPLAUSIBLE_CHANGE: f64 = 0.5;

/// How many standard deviations a held-out error may be and still agree.
pub const AGREEMENT_SIGMAS: f64 = 3.0;

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
    ///    any verdict;
    /// 3. a parameter at a bound, beyond +-50 %, or without localised evidence: compensates (a
    ///    parameter whose 95 % interval is wider than its change is named as not determined, a
    ///    caveat to any verdict);
    /// 4. every held-out error within `3 sigma_f`: agrees;
    /// 5. within `3 sqrt(sigma_f^2 + d_i^2)` only: inconclusive;
    /// 6. held-out RMS error lower than before: model-form error;
    /// 7. otherwise: not improved.
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
    let mut reasons = Vec::new();
    if !inputs.uncertainty.given {
        reasons.push(format!(
            "test uncertainty not given: assumed {} on frequencies",
            pct(sf)
        ));
    }
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
    if !swamped.is_empty() {
        reasons.push(format!(
            "before updating: the model's own discretisation error is as large as what updating would correct ({}); parameters fitted to such a mesh are effective values of the mesh, not of the structure",
            swamped.join("; ")
        ));
    }
    // 3: the parameters
    let mut doubts = Vec::new();
    let mut undetermined = Vec::new();
    for p in &inputs.parameters {
        let span = (p.bounds.1 - p.bounds.0).abs().max(1e-12);
        if (p.value - p.bounds.0).abs() <= 1e-6 * span
            || (p.value - p.bounds.1).abs() <= 1e-6 * span
        {
            doubts.push(format!("{} = {:+.3} is at a bound", p.name, p.value));
        } else if p.value.abs() > IMPLAUSIBLE_CHANGE {
            doubts.push(format!(
                "{} = {:+.3} changes its region by more than 50 %",
                p.name, p.value
            ));
        }
        if !p.evidence && p.value.abs() > 0.05 {
            doubts.push(format!(
                "{} = {:+.3} corrects a region where localisation found no evidence",
                p.name, p.value
            ));
        }
        if let Some(h) = p.half_width_95
            && p.value.abs() > 0.05
            && h > p.value.abs()
        {
            // a caveat, not a verdict: the data are consistent with no change there
            undetermined.push(format!("{} = {:+.3} +- {:.3}", p.name, p.value, h));
        }
    }
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
    reasons.push(format!(
        "held-out RMS frequency error {:.2} % before, {:.2} % after ({} modes)",
        100.0 * b,
        100.0 * a,
        held.len()
    ));
    if !undetermined.is_empty() {
        reasons.push(format!(
            "not determined by the data (95 % interval wider than the change; consistent with no change): {}",
            undetermined.join(", ")
        ));
    }
    if !doubts.is_empty() {
        reasons.extend(doubts);
        return verdict(
            Verdict::Compensates,
            "3: a parameter at a bound, beyond 50 %, or without localised evidence",
            reasons,
        );
    }
    if outside.is_empty() && unpaired == 0 {
        reasons.push(format!(
            "every held-out mode within {AGREEMENT_SIGMAS} standard deviations of the test's frequency uncertainty ({})",
            pct(AGREEMENT_SIGMAS * sf)
        ));
        return verdict(
            Verdict::Agrees,
            "4: every held-out error within 3 sigma of the test",
            reasons,
        );
    }
    if outside_mesh.is_empty() && unpaired == 0 {
        reasons.push(format!(
            "the held-out modes agree only within the model's discretisation error, not within the test's uncertainty: {}",
            outside.join(", ")
        ));
        return verdict(
            Verdict::Inconclusive,
            "5: held-out errors within the discretisation error only",
            reasons,
        );
    }
    if a < b {
        reasons.push(format!(
            "still outside the tolerance: {}{}",
            outside.join(", "),
            if unpaired > 0 {
                format!("; {unpaired} held-out mode(s) unpaired")
            } else {
                String::new()
            }
        ));
        return verdict(
            Verdict::ModelFormError,
            "6: improved, but a held-out error above 3 sigma",
            reasons,
        );
    }
    reasons.push(format!(
        "{} of {} held-out modes improved",
        held.iter().filter(|m| m.improved() == Some(true)).count(),
        held.len()
    ));
    verdict(
        Verdict::NotImproved,
        "7: held-out RMS error not lower",
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
                mac_before: b.map(|p| p.mac),
                f_after: a.map(|p| p.f_model),
                mac_after: a.map(|p| p.mac),
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
        // 4: within 3 sigma (sigma 0.1 %: 0.3 %)
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.002), Some(-0.0029)]);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::Agrees);
        // 6: improved, one held-out at 0.5 % > 0.3 %
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.005), Some(0.001)]);
        let j = c.judge(&given(1e-3)).clone();
        assert_eq!(j.verdict, Verdict::ModelFormError);
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("mode 3 +0.50 % (tolerance 0.30 %)")),
            "{j:?}"
        );
        // 5: within 3 sqrt(sigma^2 + d^2) only, d = 1 %
        let mut inputs = given(1e-3);
        inputs.discretisation = vec![Some(0.01); 4];
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.005), Some(0.001)]);
        assert_eq!(c.judge(&inputs).verdict, Verdict::Inconclusive);
        // 7: not improved
        let mut c = check(errs, [Some(0.0), Some(0.0), Some(0.03), Some(0.02)]);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::NotImproved);
        // 1: no held-out mode
        let mut c = check(errs, [Some(0.0); 4]);
        c.modes.iter_mut().for_each(|m| m.tuned = true);
        assert_eq!(c.judge(&given(1e-3)).verdict, Verdict::Inconclusive);
        // 3: at a bound, beyond 50 %, without evidence -- even when the held-out modes agree
        for p in [
            finding(-0.9, true, None),
            finding(0.6, true, None),
            finding(0.2, false, None),
        ] {
            let mut c = check(errs, [Some(0.0); 4]);
            let mut inputs = given(1e-3);
            inputs.parameters = vec![p.clone()];
            assert_eq!(c.judge(&inputs).verdict, Verdict::Compensates, "{p:?}");
        }
        // a parameter not determined by the data is a caveat, not a verdict
        let mut c = check(errs, [Some(0.0); 4]);
        let mut inputs = given(1e-3);
        inputs.parameters = vec![finding(0.1, true, Some(0.3))];
        let j = c.judge(&inputs).clone();
        assert_eq!(j.verdict, Verdict::Agrees);
        assert!(
            j.reasons
                .iter()
                .any(|r| r.contains("not determined by the data"))
        );
        // the mesh's own error as large as the signal is said before anything else
        let mut inputs = given(1e-3);
        inputs.discretisation = vec![Some(0.015), None, None, None];
        let mut c = check(errs, [Some(0.0); 4]);
        let j = c.judge(&inputs).clone();
        assert!(j.reasons[0].starts_with("before updating"), "{j:?}");
        // an assumed uncertainty is said
        let mut c = check(errs, [Some(0.0); 4]);
        let j = c.judge(&JudgeInputs::default()).clone();
        assert!(
            j.reasons[0].starts_with("test uncertainty not given"),
            "{j:?}"
        );
    }
}
