//! Mode pairing by optimal assignment (docs/MATH.md, "Pairing").
//!
//! Each test mode is paired with at most one model mode and each model mode with at most one test
//! mode, maximising the total MAC over admissible pairs (MAC at or above the threshold): the
//! Hungarian algorithm, not a greedy choice, so two modes whose order swapped between model and
//! test are both paired correctly. A test mode with no admissible partner is reported unpaired,
//! never forced onto a poor match. An optional frequency window makes pairs with a larger
//! relative frequency error inadmissible; without one, pairs beyond 10 % are accepted on MAC alone
//! and named in [`Pairing::warnings`].

use crate::CorrelateError;
use crate::correlation::{eigenvalue_gap_hz, frequency_error};
use faer::MatRef;
use serde::{Deserialize, Serialize};

/// Pairing settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PairingOptions {
    /// Smallest MAC accepted for a pair (default 0.8, the paper's "80 %, typically").
    pub mac_threshold: f64,
    /// Largest relative frequency error `|f_model - f_test| / f_test` of an admissible pair
    /// (`None`: MAC alone decides, with a warning for each pair beyond
    /// [`LARGE_FREQUENCY_ERROR`]).
    #[serde(default)]
    pub max_frequency_error: Option<f64>,
    /// Compare each pair's complex shapes with the model's damped modes ([`ModeSet::damped`],
    /// which must then be there) instead of its real ones: the complex MAC with both sides
    /// complex.
    ///
    /// [`ModeSet::damped`]: crate::ModeSet::damped
    #[serde(default)]
    pub damped: bool,
}

impl PairingOptions {
    /// The frequency window, checked.
    ///
    /// # Errors
    /// A window that is not a positive, finite relative error.
    pub fn window(&self) -> Result<Option<f64>, CorrelateError> {
        match self.max_frequency_error {
            Some(w) if !(w.is_finite() && w > 0.0) => Err(CorrelateError::Invalid {
                what: "frequency window",
                reason: format!("{w} is not a positive relative error"),
            }),
            w => Ok(w),
        }
    }
}

impl Default for PairingOptions {
    fn default() -> Self {
        Self {
            mac_threshold: 0.8,
            max_frequency_error: None,
            damped: false,
        }
    }
}

/// A pair whose frequency error exceeds this (10 %) was most likely made on MAC alone by a
/// sparse sensor set that cannot tell two shapes apart: the pairing warns.
pub const LARGE_FREQUENCY_ERROR: f64 = 0.10;

/// A test mode paired with a model mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pair {
    /// Test mode (0-based column).
    pub test: usize,
    /// Model mode (0-based column).
    pub model: usize,
    /// The MAC that paired them (`None`: paired by frequency, the test has no shapes).
    pub mac: Option<f64>,
    /// Test frequency, Hz.
    pub f_test: f64,
    /// Model frequency, Hz.
    pub f_model: f64,
    /// `(f_model - f_test) / f_test` (Table 1).
    pub frequency_error: f64,
    /// `|lambda_id - lambda_j|`, s^-2 (Table 2).
    pub eigenvalue_gap: f64,
    /// For a complex test mode, the complex MAC of its complex shape with the model's
    /// ([`crate::correlation::complex_mac`]); `None` for real test data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub complex_mac: Option<f64>,
}

impl Pair {
    /// Test mode `test` (frequency `f_test`) with model mode `model` (`f_model`).
    fn new(test: usize, model: usize, mac: Option<f64>, f_test: f64, f_model: f64) -> Self {
        Self {
            test,
            model,
            mac,
            f_test,
            f_model,
            frequency_error: frequency_error(f_test, f_model),
            eigenvalue_gap: eigenvalue_gap_hz(f_test, f_model),
            complex_mac: None,
        }
    }
}

/// The result of pairing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pairing {
    /// Pairs, in test mode order.
    pub pairs: Vec<Pair>,
    /// Test modes with no model mode at or above the threshold.
    pub unpaired_test: Vec<usize>,
    /// The threshold used.
    pub mac_threshold: f64,
    /// The frequency window used (relative), if any.
    #[serde(default)]
    pub max_frequency_error: Option<f64>,
    /// Pairs the reader should check: a frequency error above [`LARGE_FREQUENCY_ERROR`] accepted
    /// on MAC alone, or a test mode left unpaired by the frequency window only.
    #[serde(default)]
    pub warnings: Vec<String>,
}

impl Pairing {
    /// The pair of a test mode, if it was paired.
    pub fn of_test(&self, test: usize) -> Option<&Pair> {
        self.pairs.iter().find(|p| p.test == test)
    }

    /// `(test, model)` index pairs.
    pub fn index_pairs(&self) -> Vec<(usize, usize)> {
        self.pairs.iter().map(|p| (p.test, p.model)).collect()
    }
}

/// Pairs test modes (rows of `mac`) with model modes (columns).
///
/// `docs/MATH.md`, "Pairing" (MAC (16)).
///
/// # Errors
/// Sizes that do not match the frequency lists, a MAC outside `[0, 1]` (beyond round-off) or
/// not finite, a threshold outside `(0, 1]`.
pub fn pair_modes(
    mac: MatRef<'_, f64>,
    f_test: &[f64],
    f_model: &[f64],
    options: &PairingOptions,
) -> Result<Pairing, CorrelateError> {
    let (t, m) = (mac.nrows(), mac.ncols());
    if f_test.len() != t || f_model.len() != m {
        return Err(CorrelateError::DimensionMismatch {
            what: "MAC matrix against the frequency lists (test rows, model columns)",
            expected: t * m,
            got: f_test.len() * f_model.len(),
        });
    }
    let thr = options.mac_threshold;
    if !(thr > 0.0 && thr <= 1.0) {
        return Err(CorrelateError::Invalid {
            what: "MAC threshold",
            reason: format!("{thr} is not in (0, 1]"),
        });
    }
    for i in 0..t {
        for j in 0..m {
            let v = mac[(i, j)];
            if !(v.is_finite() && (-1e-12..=1.0 + 1e-12).contains(&v)) {
                return Err(CorrelateError::Invalid {
                    what: "MAC value",
                    reason: format!("MAC({i}, {j}) = {v} is not in [0, 1]"),
                });
            }
        }
    }
    let window = options.window()?;
    let in_window = |i: usize, j: usize| {
        window.is_none_or(|w| frequency_error(f_test[i], f_model[j]).abs() <= w)
    };
    // MAC, less 1e-9 times the relative frequency error (at most 1): among MACs equal to within
    // round-off (few sensors that cannot tell two modes apart) the nearer frequency wins, not
    // whichever round-off favours
    let weight = |i: usize, j: usize| -> f64 {
        let v = mac[(i, j)];
        if v >= thr && in_window(i, j) {
            v - 1e-9 * frequency_error(f_test[i], f_model[j]).abs().min(1.0)
        } else {
            0.0
        }
    };
    let assignment = assign(t, m, weight);
    let mut pairs = Vec::new();
    let mut unpaired_test = Vec::new();
    let mut warnings = Vec::new();
    for (i, a) in assignment.iter().enumerate() {
        match a {
            Some(j) if weight(i, *j) > 0.0 => {
                pairs.push(Pair::new(i, *j, Some(mac[(i, *j)]), f_test[i], f_model[*j]))
            }
            _ => {
                if window.is_some() && (0..m).any(|j| mac[(i, j)] >= thr) {
                    warnings.push(format!(
                        "test mode {} is unpaired: a model mode reaches MAC {thr} with it, but only outside the frequency window of {:.1} %",
                        i + 1,
                        100.0 * window.unwrap_or(0.0)
                    ));
                }
                unpaired_test.push(i);
            }
        }
    }
    for p in &pairs {
        if window.is_none() && p.frequency_error.abs() > LARGE_FREQUENCY_ERROR {
            warnings.push(format!(
                "test mode {} is paired with model mode {} on MAC {:.3} alone at {:+.1} % frequency error: check the pair, or set a frequency window",
                p.test + 1,
                p.model + 1,
                p.mac.unwrap_or(f64::NAN),
                100.0 * p.frequency_error
            ));
        }
    }
    Ok(Pairing {
        pairs,
        unpaired_test,
        mac_threshold: thr,
        max_frequency_error: window,
        warnings,
    })
}

/// Pairs test modes with model modes by frequency alone, for a test without shapes: the optimal
/// assignment that minimises the total relative frequency error `sum |f_model - f_test| / f_test`
/// (so modes keep their order unless the frequencies say otherwise), within the frequency window
/// when one is given. Every pair is named in the warnings when two model modes lie within 5 % of
/// each other near a test mode (frequencies alone cannot tell which one it is).
///
/// `docs/MATH.md`, "Pairing".
///
/// # Errors
/// A bad frequency window.
pub fn pair_by_frequency(
    f_test: &[f64],
    f_model: &[f64],
    options: &PairingOptions,
) -> Result<Pairing, CorrelateError> {
    let window = options.window()?;
    let (t, m) = (f_test.len(), f_model.len());
    // rigid-body modes (zero frequency) are never paired with a test mode
    let elastic = |j: usize| f_model[j] > 1e-6 * f_model.last().copied().unwrap_or(1.0).abs();
    let weight = |i: usize, j: usize| -> f64 {
        let e = frequency_error(f_test[i], f_model[j]).abs();
        if elastic(j) && window.is_none_or(|w| e <= w) {
            // positive, larger for nearer frequencies
            2.0 - e.min(1.0)
        } else {
            0.0
        }
    };
    let assignment = assign(t, m, weight);
    let (mut pairs, mut unpaired_test, mut warnings) = (Vec::new(), Vec::new(), Vec::new());
    for (i, a) in assignment.iter().enumerate() {
        match a {
            Some(j) if weight(i, *j) > 0.0 => {
                let close: Vec<usize> = (0..m)
                    .filter(|k| *k != *j && elastic(*k))
                    .filter(|k| (f_model[*k] - f_model[*j]).abs() <= 0.05 * f_model[*j])
                    .collect();
                if !close.is_empty() {
                    warnings.push(format!(
                        "test mode {} is paired by frequency with model mode {} ({:.1} Hz), but model mode{} {} lie{} within 5 %: without shapes the pair is a guess",
                        i + 1,
                        j + 1,
                        f_model[*j],
                        if close.len() == 1 { "" } else { "s" },
                        close.iter().map(|k| (k + 1).to_string()).collect::<Vec<_>>().join(", "),
                        if close.len() == 1 { "s" } else { "" }
                    ));
                }
                pairs.push(Pair::new(i, *j, None, f_test[i], f_model[*j]))
            }
            _ => unpaired_test.push(i),
        }
    }
    for p in &pairs {
        if window.is_none() && p.frequency_error.abs() > LARGE_FREQUENCY_ERROR {
            warnings.push(format!(
                "test mode {} is paired by frequency with model mode {} at {:+.1} % frequency error: check the pair, or set a frequency window",
                p.test + 1,
                p.model + 1,
                100.0 * p.frequency_error
            ));
        }
    }
    Ok(Pairing {
        pairs,
        unpaired_test,
        mac_threshold: options.mac_threshold,
        max_frequency_error: window,
        warnings,
    })
}

/// The maximum-weight assignment of `t` rows to `m` columns, either way round (the Hungarian
/// algorithm needs rows <= columns: transposed otherwise). Returns the column of each row.
fn assign(t: usize, m: usize, weight: impl Fn(usize, usize) -> f64) -> Vec<Option<usize>> {
    if t <= m {
        return hungarian_max(t, m, weight);
    }
    let cols = hungarian_max(m, t, |j, i| weight(i, j));
    let mut rows = vec![None; t];
    for (j, i) in cols.iter().enumerate() {
        if let Some(i) = i {
            rows[*i] = Some(j);
        }
    }
    rows
}

/// Maximum-weight assignment of `n` rows to `m >= n` columns (Kuhn-Munkres with potentials,
/// O(n^2 m)). Returns the column of each row.
fn hungarian_max(n: usize, m: usize, weight: impl Fn(usize, usize) -> f64) -> Vec<Option<usize>> {
    if n == 0 {
        return Vec::new();
    }
    // Minimise cost = -weight. 1-based arrays with a virtual column 0, as in the classic form.
    let cost = |i: usize, j: usize| -weight(i - 1, j - 1);
    let inf = f64::INFINITY;
    let (mut u, mut v) = (vec![0.0; n + 1], vec![0.0; m + 1]);
    let (mut p, mut way) = (vec![0usize; m + 1], vec![0usize; m + 1]);
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0;
        let mut minv = vec![inf; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = inf;
            let mut j1 = 0;
            for j in 1..=m {
                if !used[j] {
                    let cur = cost(i0, j) - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=m {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    let mut rows = vec![None; n];
    for j in 1..=m {
        if p[j] != 0 {
            rows[p[j] - 1] = Some(j - 1);
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: rigid-body modes (0 Hz) are never paired; 100, 210 and 290 Hz take 105, 200 and
    /// 300 Hz (the smallest total relative error: 5 % + 4.8 % + 3.4 %); the 305 Hz mode within
    /// 5 % of 300 Hz is named; a 4 % window leaves 210 Hz (-4.8 %) unpaired.
    #[test]
    fn frequency_pairing_by_hand() {
        let f_model = [0.0, 0.0, 105.0, 200.0, 300.0, 305.0];
        let p = pair_by_frequency(&[100.0, 210.0, 290.0], &f_model, &PairingOptions::default())
            .unwrap();
        assert_eq!(p.index_pairs(), vec![(0, 2), (1, 3), (2, 4)]);
        assert!(p.pairs.iter().all(|q| q.mac.is_none()));
        assert!((p.pairs[1].frequency_error - (200.0 / 210.0 - 1.0)).abs() < 1e-15);
        assert!(
            p.warnings.iter().any(|w| w.contains("test mode 3")
                && w.contains("model mode 5")
                && w.contains("6 lies within 5 %")),
            "{:?}",
            p.warnings
        );
        let windowed = PairingOptions {
            max_frequency_error: Some(0.04),
            ..Default::default()
        };
        let p = pair_by_frequency(&[100.0, 210.0, 290.0], &f_model, &windowed).unwrap();
        assert_eq!(p.unpaired_test, vec![0, 1]);
        assert_eq!(p.index_pairs(), vec![(2, 4)]);
        // swapped order in the test: the nearest frequency, not the order, decides
        let p = pair_by_frequency(&[300.0, 104.0], &f_model, &PairingOptions::default()).unwrap();
        assert_eq!(p.index_pairs(), vec![(0, 4), (1, 2)]);
    }

    /// Exhaustive search over all injective maps rows -> columns (small sizes only).
    fn brute(n: usize, m: usize, w: &dyn Fn(usize, usize) -> f64) -> f64 {
        fn go(
            i: usize,
            n: usize,
            m: usize,
            used: &mut Vec<bool>,
            w: &dyn Fn(usize, usize) -> f64,
        ) -> f64 {
            if i == n {
                return 0.0;
            }
            let mut best = f64::NEG_INFINITY;
            for j in 0..m {
                if !used[j] {
                    used[j] = true;
                    best = best.max(w(i, j) + go(i + 1, n, m, used, w));
                    used[j] = false;
                }
            }
            best
        }
        go(0, n, m, &mut vec![false; m], w)
    }

    #[test]
    fn hungarian_equals_exhaustive_search() {
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (n, m) in [(1, 1), (2, 3), (3, 3), (4, 6), (5, 5), (3, 7)] {
            for _ in 0..20 {
                let w: Vec<f64> = (0..n * m).map(|_| rnd()).collect();
                let f = |i: usize, j: usize| w[i * m + j];
                let a = hungarian_max(n, m, f);
                let total: f64 = a.iter().enumerate().map(|(i, j)| f(i, j.unwrap())).sum();
                let mut cols: Vec<usize> = a.iter().map(|j| j.unwrap()).collect();
                cols.sort();
                cols.dedup();
                assert_eq!(cols.len(), n, "each column used once");
                assert!((total - brute(n, m, &f)).abs() < 1e-12);
            }
        }
    }
}
