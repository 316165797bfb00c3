//! One-call workflows over the building blocks, with serialisable results: what `femu correlate`
//! and `femu estimate` print and write.

use crate::CorrelateError;
use crate::correlation::{align_repeated, comac, mac_matrix, msd};
use crate::estimators::{Bound, Estimator, ModelSpectrum, PairedModel, ResidualNorms, assess};
use crate::modes::{ModeSet, TestModes};
use crate::pairing::{Pairing, PairingOptions, pair_modes};
use crate::sensors::SensorLayout;
use faer::MatRef;
use femu_sparse::SparseMatrix;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Test-analysis correlation on the sensors: MAC matrix, pairs, MSD per pair, COMAC per sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CorrelationReport {
    /// Test frequencies, Hz.
    pub f_test: Vec<f64>,
    /// Model frequencies, Hz.
    pub f_model: Vec<f64>,
    /// MAC on the sensors, `mac[test][model]` (empty for a test of frequencies alone).
    pub mac: Vec<Vec<f64>>,
    /// The pairing (optimal assignment above the threshold).
    pub pairing: Pairing,
    /// MSD on the sensors with the modal scale factor (17), per pair in pairing order (empty for
    /// a test of frequencies alone).
    pub msd: Vec<f64>,
    /// COMAC per sensor over the pairs (empty when nothing paired).
    pub comac: Vec<f64>,
    /// Whether each pair's complex MAC compares with the model's damped (complex) modes
    /// ([`PairingOptions::damped`]) rather than its real ones.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub damped: bool,
}

/// What a test of frequencies alone cannot give, said with its correlation.
pub const FREQUENCIES_ONLY: &str = "the test gives frequencies without mode shapes: the modes are paired by frequency alone (nearest, in order), with no MAC, MSD or COMAC; the estimators and expansion need shapes, and updating fits the frequencies only (it cannot tell mirror regions apart)";

/// Correlates model modes with test modes measured on `layout`. The basis of each repeated model
/// eigenvalue is first turned towards the test ([`align_repeated`]), so that pairs, MACs and MSDs
/// do not depend on the basis the eigensolver happened to return. A test of frequencies alone
/// (no sensor) is paired by frequency ([`pair_by_frequency`](crate::pair_by_frequency)), with no
/// MAC, MSD or COMAC, and a warning that says so.
///
/// # Errors
/// Mismatched sizes (model shapes against the layout, test shapes against the sensors), zero
/// vectors, a bad threshold.
pub fn correlate(
    model: &ModeSet,
    test: &TestModes,
    layout: &SensorLayout,
    options: &PairingOptions,
) -> Result<CorrelationReport, CorrelateError> {
    if test.shapes.nrows() != layout.len() {
        return Err(CorrelateError::DimensionMismatch {
            what: "test shapes against the sensors",
            expected: layout.len(),
            got: test.shapes.nrows(),
        });
    }
    if !test.has_shapes() {
        let f_model = model.frequencies_hz();
        let mut pairing =
            crate::pairing::pair_by_frequency(&test.frequencies_hz, &f_model, options)?;
        pairing.warnings.insert(0, FREQUENCIES_ONLY.to_string());
        if options.damped {
            pairing.warnings.push(
                "the damped modes were asked for, but without test shapes there is no complex MAC to compare them with".into(),
            );
        }
        return Ok(CorrelationReport {
            f_test: test.frequencies_hz.clone(),
            f_model,
            mac: Vec::new(),
            pairing,
            msd: Vec::new(),
            comac: Vec::new(),
            damped: false,
        });
    }
    // a repeated eigenvalue's basis is the eigensolver's: turn it towards the test first
    let (phia, _) = align_repeated(
        &model.values,
        layout.measure_all(model.shapes.as_ref())?.as_ref(),
        test.shapes.as_ref(),
    )?;
    let mac = mac_matrix(test.shapes.as_ref(), phia.as_ref())?;
    let f_model = model.frequencies_hz();
    let mut pairing = pair_modes(mac.as_ref(), &test.frequencies_hz, &f_model, options)?;
    // MAC compares shapes at the sensors: with fewer readings than test modes the shapes cannot
    // all be told apart there (with one reading every MAC is 1), and a pair rests on the
    // frequencies alone
    if layout.len() < test.len() || layout.len() == 1 {
        pairing.warnings.insert(
            0,
            format!(
                "{} reading{} for {} test mode{}: MAC cannot tell {} shapes apart at the sensors{}, so the pairs rest on the frequencies (the nearest one wins among equal MACs); check them, or measure more DOFs",
                layout.len(),
                if layout.len() == 1 { "" } else { "s" },
                test.len(),
                if test.len() == 1 { "" } else { "s" },
                if layout.len() == 1 { "any" } else { "all the" },
                if layout.len() == 1 { " (every MAC is 1)" } else { "" }
            ),
        );
    }
    let col = |m: MatRef<'_, f64>, j: usize| -> Vec<f64> { m.col(j).iter().copied().collect() };
    let msd = pairing
        .pairs
        .iter()
        .map(|p| {
            msd(
                &col(test.shapes.as_ref(), p.test),
                &col(phia.as_ref(), p.model),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let zeros = vec![0.0; layout.len()];
    if options.damped {
        // the model's damped modes at the sensors, Phi_a q (the raw shapes: q is in their
        // coordinates), against the test's complex shapes (or real ones)
        let q = model.damped.as_ref().ok_or_else(|| CorrelateError::Invalid {
            what: "damped correlation",
            reason: "the model's modes carry no damped modes (a model of K, M and its structural damping is needed: another solver's modes have none)".into(),
        })?;
        let raw = layout.measure_all(model.shapes.as_ref())?;
        for p in &mut pairing.pairs {
            let (re, im): (Vec<f64>, Vec<f64>) = (0..layout.len())
                .map(|i| {
                    let mut v = faer::c64::new(0.0, 0.0);
                    for j in 0..raw.ncols() {
                        v += q[(j, p.model)] * raw[(i, j)];
                    }
                    (v.re, v.im)
                })
                .unzip();
            let test_im = test
                .imaginary
                .as_ref()
                .map_or_else(|| zeros.clone(), |im| col(im.as_ref(), p.test));
            p.complex_mac = Some(crate::correlation::complex_mac(
                &col(test.shapes.as_ref(), p.test),
                &test_im,
                &re,
                &im,
            )?);
        }
    } else if let Some(im) = &test.imaginary {
        for p in &mut pairing.pairs {
            p.complex_mac = Some(crate::correlation::complex_mac(
                &col(test.shapes.as_ref(), p.test),
                &col(im.as_ref(), p.test),
                &col(phia.as_ref(), p.model),
                &zeros,
            )?);
        }
    }
    let pairs = pairing.index_pairs();
    let comac = if pairs.is_empty() {
        Vec::new()
    } else {
        comac(test.shapes.as_ref(), phia.as_ref(), &pairs)?
    };
    Ok(CorrelationReport {
        f_test: test.frequencies_hz.clone(),
        f_model,
        mac: (0..mac.nrows())
            .map(|i| (0..mac.ncols()).map(|j| mac[(i, j)]).collect())
            .collect(),
        pairing,
        msd,
        comac,
        damped: options.damped,
    })
}

impl fmt::Display for CorrelationReport {
    /// The paired modes as a Markdown table (the paper's Table 1 with MAC and MSD).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // complex test modes: their complex MAC in a column of its own
        let complex = self.pairing.pairs.iter().any(|p| p.complex_mac.is_some());
        let (head, rule, blank) = if complex {
            (" complex MAC |", "---|", " - |")
        } else {
            ("", "", "")
        };
        writeln!(
            f,
            "| test | f test (Hz) | model | f model (Hz) | error (%) | gap (s^-2) | MAC | MSD |{head}"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|{rule}")?;
        for (k, p) in self.pairing.pairs.iter().enumerate() {
            let or_dash = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
            let extra = if complex {
                format!(" {} |", or_dash(p.complex_mac))
            } else {
                String::new()
            };
            writeln!(
                f,
                "| {} | {:.1} | {} | {:.1} | {:+.2} | {:.4e} | {} | {} |{extra}",
                p.test + 1,
                p.f_test,
                p.model + 1,
                p.f_model,
                100.0 * p.frequency_error,
                p.eigenvalue_gap,
                or_dash(p.mac),
                or_dash(self.msd.get(k).copied())
            )?;
        }
        for t in &self.pairing.unpaired_test {
            writeln!(
                f,
                "| {} | {:.1} | - | - | - | - | < {:.2} | - |{blank}",
                t + 1,
                self.f_test[*t],
                self.pairing.mac_threshold
            )?;
        }
        let window = self
            .pairing
            .max_frequency_error
            .map(|w| format!(" within {:.1} % frequency error", 100.0 * w))
            .unwrap_or_default();
        if self.mac.is_empty() && !self.f_test.is_empty() {
            writeln!(
                f,
                "\nerror = (f model - f test) / f test; gap = |lambda model - lambda test| with \
                 lambda = (2 pi f)^2; no MAC or MSD (the test has no shapes); pairs by optimal \
                 assignment on the frequencies (the smallest total relative error){window}."
            )?;
        } else {
            writeln!(
                f,
                "\nerror = (f model - f test) / f test; gap = |lambda model - lambda test| with \
                 lambda = (2 pi f)^2; MAC and MSD (mode shape difference after the modal scale factor) \
                 on the sensor readings; pairs by optimal assignment at MAC >= {}{window}.",
                self.pairing.mac_threshold,
            )?;
            if self.damped {
                writeln!(
                    f,
                    "complex MAC = |psi^H phi|^2 / ((psi^H psi)(phi^H phi)) against the model's \
                     damped modes phi = Phi q of its structural damping (both sides complex); MAC \
                     and MSD use the real shapes."
                )?;
            } else if complex {
                writeln!(
                    f,
                    "The test's modes are complex: MAC and MSD use each shape turned by the phase \
                     of its largest component, real part; complex MAC = |psi^H phi|^2 / \
                     ((psi^H psi)(phi^T phi)) uses the whole complex shape psi."
                )?;
            }
        }
        for w in &self.pairing.warnings {
            writeln!(f, "warning: {w}")?;
        }
        Ok(())
    }
}

/// The a priori assessment of one test mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Assessment {
    /// Test mode (0-based).
    pub test: usize,
    /// Residual norms (`rho_M`, `rho_2`, Rayleigh quotient).
    pub norms: ResidualNorms,
    /// `[f_lo, f_hi]` (Hz) that holds a model frequency (Theorem 2, rigorous form).
    pub frequency_interval_hz: (f64, f64),
    /// The paired model mode, if any.
    pub paired_model: Option<usize>,
    /// Every bound that could be formed.
    pub bounds: Vec<Bound>,
}

/// Residual norms and bounds for full-length test vectors `x` (columns; expanded or measured on
/// every DOF) with identified eigenvalues `lambdas`; `paired[i]` names the model mode paired with
/// test mode `i` (an index into `spectrum.values`, with its shape in `model` when given).
///
/// # Errors
/// As [`Estimator::residual_norms`] and [`assess`].
pub fn estimate(
    k: &SparseMatrix,
    m: &SparseMatrix,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
    spectrum: &ModelSpectrum,
    model: Option<&ModeSet>,
    paired: &[Option<usize>],
) -> Result<Vec<Assessment>, CorrelateError> {
    if paired.len() != lambdas.len() {
        return Err(CorrelateError::DimensionMismatch {
            what: "pairs against test modes",
            expected: lambdas.len(),
            got: paired.len(),
        });
    }
    let (norms, _) = Estimator::new(k, m)?.residual_norms(lambdas, x)?;
    norms
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let xi: Vec<f64> = x.col(i).iter().copied().collect();
            let shape: Option<Vec<f64>> = match (paired[i], model) {
                (Some(j), Some(ms)) if j < ms.len() => {
                    Some(ms.shapes.col(j).iter().copied().collect())
                }
                _ => None,
            };
            let bounds = assess(
                m,
                &xi,
                n,
                spectrum,
                paired[i].map(|j| PairedModel {
                    index: j,
                    shape: shape.as_deref(),
                }),
            )?;
            Ok(Assessment {
                test: i,
                norms: *n,
                frequency_interval_hz: n.frequency_interval_hz(),
                paired_model: paired[i],
                bounds,
            })
        })
        .collect()
}
