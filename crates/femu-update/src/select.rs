//! Which parameters the data support: forward selection on the weighted least-squares objective
//! of inverse eigensensitivity, with an F-test (`docs/MATH.md`, "Selecting the parameters").
//!
//! The paper's residual ranking ([`crate::localise`](mod@crate::localise)) reads the error's location from expanded
//! shapes; with noise at the sensors the expansion spreads it over the model, and the ranking
//! follows the noise. The selection here asks the statistical question directly, as Friswell and
//! Mottershead's subset selection does: on the residual `r` (frequencies and sensor readings, each
//! in units of the test's uncertainty) and its Jacobian `J` with respect to every candidate's
//! stiffness factor,
//! - each step adds the candidate that lowers `chi^2 = min ||r + J_S d||^2` most;
//! - it is kept when its decrease is significant against the scatter left,
//!   `F = (chi^2_old - chi^2_new) / max(chi^2_new / (n - |S|), 1)`, under `F(1, n - |S|)` at the level
//!   `alpha / m` (Bonferroni over the `m` candidates still competing: the best of many is tested);
//! - the first candidate that fails stops the selection.
//!
//! The residual left (`chi^2_new`) contains the test's noise and whatever the model cannot
//! represent (discretisation, model form), so the test does not need the uncertainty to be right:
//! a scatter larger than assumed raises the bar for every candidate alike. A scatter smaller than
//! the uncertainty explains (a noise-free test, a fit at round-off) does not lower it: the floor
//! of one per residual makes the test a chi-square test against the stated uncertainty there.
//!
//! The selection is linear at the parameters it is given (the nominal model, or the last fit
//! when [`forward`] starts from a selected set): the updating workflow refits and asks again.
//! Its stability is measured by resampling: every sensor left out in turn, and noise drawn at the
//! scatter of the fit added to the residual ([`Stability`]). Candidates whose sensitivities are
//! parallel (a region and its mirror image, seen by frequencies alone) cannot be told apart: a
//! resample that picks the other one counts for the choice, and the pair is reported
//! ([`ParameterSelection::equivalents`]).

use crate::UpdateError;
use crate::problem::UpdateModel;
use crate::sensitivity::{SensitivityOptions, evaluate, jacobian};
use faer::Mat;
use femu_correlate::{SensorLayout, TestModes};
use serde::{Deserialize, Serialize};

/// Two candidates whose Jacobian columns have at least this cosine are indistinguishable by the
/// data (a region and its mirror image, seen by frequencies alone).
pub const EQUIVALENT_COSINE: f64 = 0.999;

/// Settings of the selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SelectionOptions {
    /// The significance level of each step's F-test before the Bonferroni correction (default 0.05).
    pub significance: f64,
    /// At most this many parameters (default: no limit beyond the residuals' count).
    pub max_parameters: Option<usize>,
    /// Noise resamples for the stability report (default 40; 0: none).
    pub resamples: usize,
    /// Seed of the resampling noise (the report is reproducible).
    pub seed: u64,
    /// A significant candidate is kept when at least this fraction of the resamples select it
    /// too (default 0.8; stability selection): a candidate that only this realisation of the
    /// noise, or one sensor, supports is not kept.
    pub stability: f64,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        Self {
            significance: 0.05,
            max_parameters: None,
            resamples: 40,
            seed: 1,
            stability: 0.8,
        }
    }
}

/// One step of the forward selection: the best candidate at that step and its test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SelectionStep {
    /// The candidate parameter (`k:r3`).
    pub parameter: String,
    /// Its index among the model's parameters.
    pub index: usize,
    /// The objective before adding it.
    pub chi_square_before: f64,
    /// The objective with it (linearised).
    pub chi_square: f64,
    /// `F = (chi^2_before - chi^2) / max(chi^2 / nu, 1)`.
    pub f_statistic: f64,
    /// Degrees of freedom left, `nu = n - |S|`.
    pub dof: usize,
    /// `P(F(1, nu) > F)`.
    pub p_value: f64,
    /// The level it is tested at: `alpha / m` for `m` candidates competing.
    pub level: f64,
    /// Whether the F-test found it significant (`p < level`).
    pub significant: bool,
    /// The fraction of the resamples that select it too (`None`: not resampled).
    pub stability: Option<f64>,
    /// Whether it was kept: significant, and stable under resampling.
    pub kept: bool,
}

/// How often each candidate is selected when the data are resampled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stability {
    /// The parameter.
    pub parameter: String,
    /// Fraction of the resamples that selected it.
    pub selected: f64,
    /// Fraction of the resamples that selected it first.
    pub first: f64,
}

/// The parameters the data support.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterSelection {
    /// Indices of the kept parameters (into the model's), in the order they were added.
    pub selected: Vec<usize>,
    /// Every step, the last one the first candidate the F-test rejected (when one was tested).
    pub steps: Vec<SelectionStep>,
    /// The objective at the parameters the selection was linearised at.
    pub chi_square: f64,
    /// The number of residuals.
    pub residuals: usize,
    /// Per candidate, over the resamples (empty when none).
    pub stability: Vec<Stability>,
    /// The resamples: `sensors` left out one at a time, then `noise` draws.
    pub resamples: (usize, usize),
    /// The criterion, in words.
    pub criterion: String,
    /// Each significant parameter with the candidates the data cannot tell it from (their
    /// Jacobian columns parallel to within [`EQUIVALENT_COSINE`]): the data say "one of these".
    pub equivalents: Vec<(String, Vec<String>)>,
}

impl ParameterSelection {
    /// The names of the selected parameters.
    pub fn names(&self) -> Vec<&str> {
        self.steps
            .iter()
            .filter(|s| s.kept)
            .map(|s| s.parameter.as_str())
            .collect()
    }

    /// The stability of a parameter, when resampled.
    pub fn stability_of(&self, parameter: &str) -> Option<&Stability> {
        self.stability.iter().find(|s| s.parameter == parameter)
    }
}

impl std::fmt::Display for ParameterSelection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "Selection ({}), chi-square {:.4e} over {} residuals:",
            self.criterion, self.chi_square, self.residuals
        )?;
        writeln!(
            f,
            "| step | parameter | chi-square after | F | p | level | significant | selected in resamples | kept |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|")?;
        let yes = |b: bool| if b { "yes" } else { "no" };
        for (k, s) in self.steps.iter().enumerate() {
            writeln!(
                f,
                "| {} | {} | {:.4e} | {:.3e} | {:.2e} | {:.2e} | {} | {} | {} |",
                k + 1,
                s.parameter,
                s.chi_square,
                s.f_statistic,
                s.p_value,
                s.level,
                yes(s.significant),
                s.stability
                    .map_or("-".to_string(), |t| format!("{:.0} %", 100.0 * t)),
                yes(s.kept)
            )?;
        }
        for (p, same) in &self.equivalents {
            writeln!(
                f,
                "\n{p} cannot be told from {} by these data (parallel sensitivities): the error is in one of them, the data do not say which.",
                same.join(", ")
            )?;
        }
        if self.resamples.0 + self.resamples.1 > 0 {
            writeln!(
                f,
                "\nResamples: {} with one reading left out in turn, {} with noise at the fit's scatter added.",
                self.resamples.0, self.resamples.1
            )?;
        }
        Ok(())
    }
}

/// Forward selection on a linear least-squares problem `min ||r + J_S d||^2`, starting from the
/// columns `start` (already in the model: their fit is assumed done, `r` its residual or the
/// residual before it). Returns the steps, the last one the first rejected candidate.
///
/// `names` names `J`'s columns; `options.max_parameters` caps the selected set.
pub fn forward(
    jac: &Mat<f64>,
    r: &[f64],
    names: &[String],
    start: &[usize],
    options: &SelectionOptions,
) -> Vec<SelectionStep> {
    let (n, p) = (jac.nrows(), jac.ncols());
    let cap = options.max_parameters.unwrap_or(p).min(p);
    // orthonormal basis of the selected columns (modified Gram-Schmidt, twice)
    let mut q: Vec<Vec<f64>> = Vec::new();
    let project_out = |q: &[Vec<f64>], v: &mut [f64]| {
        for _ in 0..2 {
            for b in q {
                let c: f64 = b.iter().zip(v.iter()).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(y, x)| *y -= c * x);
            }
        }
    };
    let column = |k: usize| -> Vec<f64> { (0..n).map(|i| jac[(i, k)]).collect() };
    let mut chosen: Vec<usize> = Vec::new();
    for &k in start {
        let mut v = column(k);
        let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        project_out(&q, &mut v);
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 1e-10 * norm0 && norm > 0.0 {
            q.push(v.iter().map(|x| x / norm).collect());
        }
        chosen.push(k);
    }
    let mut res = r.to_vec();
    project_out(&q, &mut res);
    let mut chi: f64 = res.iter().map(|x| x * x).sum();
    let mut steps = Vec::new();
    while chosen.len() < cap {
        let dof = n.saturating_sub(chosen.len() + 1);
        if dof == 0 {
            break;
        }
        let mut best: Option<(usize, f64, Vec<f64>)> = None;
        let mut competing = 0;
        for k in (0..p).filter(|k| !chosen.contains(k)) {
            let mut v = column(k);
            let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            project_out(&q, &mut v);
            let vv: f64 = v.iter().map(|x| x * x).sum();
            if !(vv.sqrt() > 1e-10 * norm0) {
                // nothing new: the data cannot tell it from the selected ones
                continue;
            }
            competing += 1;
            let c: f64 = v.iter().zip(&res).map(|(x, y)| x * y).sum();
            let drop = c * c / vv;
            if best.as_ref().is_none_or(|b| drop > b.1) {
                best = Some((k, drop, v.iter().map(|x| x / vv.sqrt()).collect()));
            }
        }
        let Some((k, drop, u)) = best else { break };
        let after = (chi - drop).max(0.0);
        // the scatter left, never below what the test's uncertainty explains (1 per residual):
        // a fit closer than the noise does not make round-off significant
        let f = drop / (after / dof as f64).max(1.0);
        let p_value = f_survival(f, dof as f64);
        let level = options.significance / competing.max(1) as f64;
        let significant = p_value < level;
        steps.push(SelectionStep {
            parameter: names[k].clone(),
            index: k,
            chi_square_before: chi,
            chi_square: after,
            f_statistic: f,
            dof,
            p_value,
            level,
            significant,
            stability: None,
            kept: significant,
        });
        if !significant {
            break;
        }
        let c: f64 = u.iter().zip(&res).map(|(x, y)| x * y).sum();
        res.iter_mut().zip(&u).for_each(|(y, x)| *y -= c * x);
        q.push(u);
        chosen.push(k);
        chi = after;
    }
    steps
}

/// Selects, among `up`'s parameters, those the tuned test modes support, linearised at `up`'s
/// current parameters: residuals and Jacobian of inverse eigensensitivity (`options`: shapes,
/// uncertainty, pairing), forward selection with the F-test ([`forward`]), kept where stable
/// over the resamples ([`select_linear`]).
///
/// # Errors
/// Those of inverse eigensensitivity's evaluation (a lost pair, eigensolver errors), bad options.
pub fn select_parameters(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    selection: &SelectionOptions,
) -> Result<ParameterSelection, UpdateError> {
    forward_at(up, layout, test, options, &[], selection)
}

/// The selection from the parameters `start`, linearised at `up`'s current parameters (a fit of
/// `start`): whether another candidate still lowers the objective significantly, and stably,
/// once the selected ones have taken their fitted values. `start = []` at the nominal model is
/// [`select_parameters`].
///
/// # Errors
/// As [`select_parameters`].
pub fn forward_at(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    start: &[usize],
    selection: &SelectionOptions,
) -> Result<ParameterSelection, UpdateError> {
    check(selection)?;
    options.uncertainty.check()?;
    let eval = evaluate(up, layout, test, options, 0)?;
    let jac = jacobian(up, layout, test, options, &eval)?;
    let names: Vec<String> = up.parameters().iter().map(|p| p.name.clone()).collect();
    Ok(select_linear(
        &jac,
        &eval.residual,
        &names,
        start,
        if options.shapes { layout.len() } else { 0 },
        test.len(),
        selection,
    ))
}

fn check(selection: &SelectionOptions) -> Result<(), UpdateError> {
    if !(selection.significance > 0.0 && selection.significance < 1.0) {
        return Err(UpdateError::Invalid {
            what: "selection significance",
            reason: format!("{} must lie in (0, 1)", selection.significance),
        });
    }
    if !(0.0..=1.0).contains(&selection.stability) {
        return Err(UpdateError::Invalid {
            what: "selection stability",
            reason: format!("{} must lie in [0, 1]", selection.stability),
        });
    }
    Ok(())
}

/// The selection on a linear problem from the columns `start`, with its resampling: the rows
/// are `modes` frequency residuals, then `sensors` readings per mode (0: frequencies only).
/// A significant step is kept when at least `options.stability` of the resamples (each reading
/// left out in turn, then noise at the fit's scatter) find it significant too.
pub fn select_linear(
    jac: &Mat<f64>,
    r: &[f64],
    names: &[String],
    start: &[usize],
    sensors: usize,
    modes: usize,
    options: &SelectionOptions,
) -> ParameterSelection {
    let mut steps = forward(jac, r, names, start, options);
    let chi: f64 = r.iter().map(|x| x * x).sum();
    // the scatter the fit leaves, per residual (at least the assumed uncertainty's)
    let significant = steps.iter().filter(|s| s.significant).count();
    let left = steps
        .iter()
        .rfind(|s| s.significant)
        .map_or(chi, |s| s.chi_square);
    let nu = r.len().saturating_sub(start.len() + significant).max(1);
    let scatter = (left / nu as f64).max(1.0).sqrt();
    let p = jac.ncols();
    let (mut chosen, mut first) = (vec![0usize; p], vec![0usize; p]);
    let mut tally = |steps: &[SelectionStep]| {
        for (k, s) in steps.iter().filter(|s| s.significant).enumerate() {
            chosen[s.index] += 1;
            if k == 0 {
                first[s.index] += 1;
            }
        }
    };
    // every reading left out in turn (in every mode)
    let mut jackknife = 0;
    if sensors > 1 {
        for s in 0..sensors {
            let rows: Vec<usize> = (0..r.len())
                .filter(|&i| i < modes || (i - modes) % sensors != s)
                .collect();
            let j = Mat::from_fn(rows.len(), p, |a, b| jac[(rows[a], b)]);
            let rr: Vec<f64> = rows.iter().map(|&i| r[i]).collect();
            tally(&forward(&j, &rr, names, start, options));
            jackknife += 1;
        }
    }
    // noise at the fit's scatter added to the residual
    let mut rng = SplitMix(options.seed);
    for _ in 0..options.resamples {
        let rr: Vec<f64> = r.iter().map(|x| x + scatter * rng.normal()).collect();
        tally(&forward(jac, &rr, names, start, options));
    }
    let total = jackknife + options.resamples;
    let stability: Vec<Stability> = if total == 0 {
        Vec::new()
    } else {
        (0..p)
            .filter(|k| !start.contains(k))
            .map(|k| Stability {
                parameter: names[k].clone(),
                selected: chosen[k] as f64 / total as f64,
                first: first[k] as f64 / total as f64,
            })
            .collect()
    };
    // candidates the data cannot tell apart: parallel columns (mirror regions seen by
    // frequencies alone); a resample that chose an equivalent of a step's parameter counts for it
    let norms: Vec<f64> = (0..p)
        .map(|k| {
            (0..jac.nrows())
                .map(|i| jac[(i, k)].powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let parallel = |a: usize, b: usize| -> bool {
        let d: f64 = (0..jac.nrows()).map(|i| jac[(i, a)] * jac[(i, b)]).sum();
        norms[a] > 0.0 && norms[b] > 0.0 && d.abs() >= EQUIVALENT_COSINE * norms[a] * norms[b]
    };
    let mut equivalents = Vec::new();
    for s in &mut steps {
        let same: Vec<usize> = (0..p)
            .filter(|c| *c != s.index && !start.contains(c) && parallel(s.index, *c))
            .collect();
        if total > 0 {
            let count = chosen[s.index] + same.iter().map(|c| chosen[*c]).sum::<usize>();
            let f = (count as f64 / total as f64).min(1.0);
            s.stability = Some(f);
            s.kept = s.significant && f >= options.stability;
        }
        if s.significant && !same.is_empty() {
            equivalents.push((
                s.parameter.clone(),
                same.iter().map(|c| names[*c].clone()).collect(),
            ));
        }
    }
    ParameterSelection {
        selected: steps.iter().filter(|s| s.kept).map(|s| s.index).collect(),
        steps,
        equivalents,
        chi_square: chi,
        residuals: r.len(),
        stability,
        resamples: (jackknife, options.resamples),
        criterion: format!(
            "forward selection, F-test at {} with Bonferroni over the candidates, kept where at least {:.0} % of the resamples agree",
            options.significance,
            100.0 * options.stability
        ),
    }
}

/// SplitMix64 with Box-Muller: reproducible standard normal draws for the resampling.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// `P(F(1, nu) > f)`: the regularised incomplete beta `I_{nu / (nu + f)}(nu / 2, 1 / 2)`.
pub fn f_survival(f: f64, nu: f64) -> f64 {
    if f.is_nan() {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 1.0;
    }
    if f.is_infinite() {
        return 0.0;
    }
    incomplete_beta(nu / (nu + f), nu / 2.0, 0.5)
}

/// `ln Gamma(x)`, x > 0 (Lanczos, g = 7, nine terms: about 1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // reflection
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised incomplete beta function `I_x(a, b)` (continued fraction, modified Lentz).
fn incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    // the continued fraction converges fast for x < (a + 1) / (a + b + 2)
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_fraction(x, a, b) / a
    } else {
        1.0 - front * beta_fraction(1.0 - x, b, a) / b
    }
}

fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let guard = |v: f64| if v.abs() < tiny { tiny } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / guard(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..400 {
        let m = m as f64;
        let m2 = 2.0 * m;
        // the even and the odd step of the continued fraction (modified Lentz)
        let mut del = 1.0;
        for aa in [
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ] {
            d = 1.0 / guard(1.0 + aa * d);
            c = guard(1.0 + aa / c);
            del = d * c;
            h *= del;
        }
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against closed forms and published table values: `F(1, 1)` is the square of a Cauchy
    /// variable, `P(F > f) = 1 - (2 / pi) atan(sqrt f)`; for `F(1, 2)`,
    /// `I_x(1, 1/2) = 1 - sqrt(1 - x)` gives `P(F > f) = 1 - sqrt(f / (2 + f))`; Student's t
    /// quantiles (Abramowitz and Stegun, table 26.10; `F(1, nu) = t(nu)^2`):
    /// `t_0.975(10) = 2.228139`, `t_0.995(5) = 4.032143`, `t_0.975(30) = 2.042272`.
    #[test]
    fn f_distribution_against_closed_forms_and_tables() {
        for f in [0.01, 0.3, 1.0, 4.0, 50.0, 1e4] {
            let cauchy = 1.0 - 2.0 / std::f64::consts::PI * f64::atan(f64::sqrt(f));
            assert!((f_survival(f, 1.0) - cauchy).abs() < 1e-13, "{f}");
            let two = 1.0 - (f / (2.0 + f)).sqrt();
            assert!((f_survival(f, 2.0) - two).abs() < 1e-13, "{f}");
        }
        for (t, nu, p) in [
            (2.228_139, 10.0, 0.05),
            (4.032_143, 5.0, 0.01),
            (2.042_272, 30.0, 0.05),
        ] {
            let got = f_survival(t * t, nu);
            assert!(
                (got - p).abs() < 2e-7 * p.max(1.0) + 1e-7,
                "{t} {nu}: {got}"
            );
        }
        assert_eq!(f_survival(0.0, 3.0), 1.0);
        assert_eq!(f_survival(f64::INFINITY, 3.0), 0.0);
    }

    /// A hand-made linear problem: column 1 explains the residual (plus small noise), columns 0
    /// and 2 do not: the selection keeps 1 and stops at the next.
    #[test]
    fn forward_keeps_the_column_that_explains_and_stops() {
        let n = 40;
        let mut rng = SplitMix(3);
        let jac = Mat::from_fn(n, 3, |i, k| match k {
            0 => (i as f64 * 0.37).sin(),
            1 => (i as f64 * 0.11).cos() + 0.2,
            _ => ((i * i) as f64 * 0.05).sin(),
        });
        let r: Vec<f64> = (0..n)
            .map(|i| -0.3 * 25.0 * jac[(i, 1)] + rng.normal())
            .collect();
        let names: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let s = select_linear(&jac, &r, &names, &[], 0, n, &SelectionOptions::default());
        assert_eq!(s.selected, vec![1], "{s}");
        assert_eq!(s.steps.len(), 2);
        assert!(!s.steps[1].significant && !s.steps[1].kept);
        // the decrease of the first step is the projection of r on column 1, by hand
        let jj: f64 = (0..n).map(|i| jac[(i, 1)] * jac[(i, 1)]).sum();
        let jr: f64 = (0..n).map(|i| jac[(i, 1)] * r[i]).sum();
        let chi: f64 = r.iter().map(|x| x * x).sum();
        assert!((s.steps[0].chi_square - (chi - jr * jr / jj)).abs() < 1e-9 * chi);
        let b = s.stability_of("b").unwrap();
        assert!(b.selected > 0.9 && b.first > 0.9, "{b:?}");
    }
}
