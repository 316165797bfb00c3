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
}

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

    /// The answer in one sentence.
    pub fn verdict(&self) -> String {
        let held: Vec<&ModeCheck> = self.held_out().collect();
        if held.is_empty() {
            return "no held-out mode: the updated model cannot be checked on modes it was not tuned on".into();
        }
        let better = held.iter().filter(|m| m.improved() == Some(true)).count();
        let (b, a) = self.held_out_rms();
        if better == held.len() {
            format!(
                "yes: every held-out mode ({}) is predicted better after updating (RMS frequency error {:.2} % -> {:.2} %)",
                held.len(),
                100.0 * b,
                100.0 * a
            )
        } else if a < b {
            format!(
                "partly: {better} of {} held-out modes improved (RMS frequency error {:.2} % -> {:.2} %)",
                held.len(),
                100.0 * b,
                100.0 * a
            )
        } else {
            format!(
                "no: the held-out modes got worse or did not improve ({better} of {} improved; RMS frequency error {:.2} % -> {:.2} %): the correction compensates rather than corrects",
                held.len(),
                100.0 * b,
                100.0 * a
            )
        }
    }
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
            self.verdict()
        )
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
    Ok(TruthCheck {
        modes,
        parameters: Vec::new(),
    })
}
