//! The modes workflow: the lowest modes of a model, those nearest a frequency, or every mode in a
//! band, each result with its evidence (residuals and the Sturm count that proves no mode in the
//! interval was skipped).

use crate::StudyError;
use crate::load::LoadedModel;
use femu_correlate::modes::eigenvalue_of_hz;
use femu_fem::assembly::MassKind;
use femu_sparse::eigen::{EigenOptions, EigenStats, Modes, ResidualKind, Which};
use femu_sparse::slepc::Engine;
use serde::Serialize;

/// Which modes [`solve_modes`] computes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModesOptions {
    /// How many (lowest, or nearest the shift). Default: the deck's `*FREQUENCY` count, or 10.
    pub count: Option<usize>,
    /// Modes nearest this frequency, Hz.
    pub shift_hz: Option<f64>,
    /// Every mode between two frequencies, Hz.
    pub band_hz: Option<(f64, f64)>,
    /// The eigensolver's settings: its engine, and the right-hand sides it solves together
    /// ([`EigenOptions::block_size`], default 4). Wider blocks read the factor fewer times per
    /// vector and need more vectors: on this project's 50k-DOF benchmarks blocks of 4 solved 74
    /// and 131 vectors where blocks of 2 solved 53 and 99 (ARPACK: 53 and 100) and took 6-21 %
    /// longer (docs/SCALING.md, "Block size and the count of solved vectors").
    pub eigen: EigenOptions,
    /// Also the complex modes of the model's damping (structural: each material's `GE`, a
    /// model-wide loss factor; viscous: dampers, Rayleigh, modal ratios), in the space of the real
    /// modes solved ([`damped_modes`]; docs/MATH.md, "Damped modes").
    pub damped: bool,
}

/// Where an eigensolve's time went and how much work it did: [`EigenStats`] with the block size
/// and the time outside the phases (what `femu modes --json` writes under `eigensolver`, the
/// statistics' fields beside `block_size` and `other_seconds`). The phases' seconds and
/// `other_seconds` add up to `total_seconds` (docs/SCALING.md, "The block within itself, the Ritz
/// vectors' products and the input checks").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EigenReport {
    /// Right-hand sides solved together (`None`: SLEPc's iteration, [`Engine::Slepc`], whose
    /// solves femu does not count).
    pub block_size: Option<usize>,
    /// The solve's statistics.
    #[serde(flatten)]
    pub stats: EigenStats,
    /// What the phases leave out ([`EigenStats::other_seconds`]), s.
    pub other_seconds: f64,
}

impl EigenReport {
    /// The report of a solve's statistics `s`, whose blocks were `block_size` wide (`None`:
    /// SLEPc's solve).
    pub fn new(s: &EigenStats, block_size: Option<usize>) -> Self {
        Self {
            block_size,
            stats: s.clone(),
            other_seconds: s.other_seconds(),
        }
    }

    /// One line for a terminal: `2 factorizations 0.39 s, 74 vectors solved in blocks of 4
    /// 0.50 s, ...`.
    pub fn summary(&self) -> String {
        let s = &self.stats;
        let plural = if s.factorizations == 1 { "" } else { "s" };
        match self.block_size {
            Some(block) => format!(
                "{} factorization{plural} {:.2} s ({:.1} million entries, {:.1} GFLOP each), {} \
                 vectors solved in blocks of {block} {:.2} s, orthogonalisation {:.2} s, \
                 Rayleigh-Ritz {:.2} s, checks and analysis {:.2} s, other {:.2} s; {:.2} s in all",
                s.factorizations,
                s.factor_seconds,
                s.factor_len as f64 * 1e-6,
                s.factor_flops * 1e-9,
                s.solved_vectors,
                s.solve_seconds,
                s.orthogonalization_seconds,
                s.ritz_seconds,
                s.check_seconds + s.symbolic_seconds,
                self.other_seconds,
                s.total_seconds
            ),
            None => format!(
                "SLEPc's iteration {:.2} s ({} vectors solved{}), {} Sturm factorization{plural} \
                 {:.2} s, analysis {:.2} s; {:.2} s in all",
                s.solve_seconds,
                s.solved_vectors,
                if s.factor_len > 0 {
                    format!(
                        ", {:.1} million entries in MUMPS's factor",
                        s.factor_len as f64 * 1e-6
                    )
                } else {
                    String::new()
                },
                s.factorizations,
                s.factor_seconds,
                s.symbolic_seconds,
                s.total_seconds
            ),
        }
    }
}

/// The summary of a modes run (what `femu modes --json` writes).
#[derive(Debug, Clone, Serialize)]
pub struct ModesReport {
    /// The model file.
    pub model: String,
    /// Free DOFs.
    pub dofs: usize,
    /// `consistent` or `lumped`.
    pub mass: &'static str,
    /// For a model read as another solver's matrices: which (`CalculiX's stored matrices`, ...)
    /// and the files of its stiffness, mass, DOF table and node coordinates.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub matrices: Option<MatricesReport>,
    /// Frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Eigenvalues `omega^2`, s^-2.
    pub eigenvalues: Vec<f64>,
    /// Residual of each mode, of the kind in `residual_kinds`.
    pub residuals: Vec<f64>,
    /// `relative` (`||K x - lambda M x|| / ||K x||`) or, for a zero-energy (rigid-body) mode,
    /// `backward` (`||K x - lambda M x|| / ((||K||_1 + |lambda| ||M||_1) ||x||)`).
    pub residual_kinds: Vec<&'static str>,
    /// How many modes were asked for (fewer than returned when the request ended inside a
    /// repeated eigenvalue, which is returned whole).
    pub requested: usize,
    /// Whether the Sturm count matches the modes returned.
    pub sturm_verified: bool,
    /// Eigenvalues in the counted interval by inertia.
    pub sturm_count: usize,
    /// Lower end of the counted interval, s^-2 (absent: from minus infinity).
    pub sturm_lower: Option<f64>,
    /// Upper end of the counted interval, s^-2.
    pub sturm_upper: f64,
    /// What the user should know about the result (a completed cluster, rigid-body residuals).
    pub notes: Vec<String>,
    /// Wall time of the solve, s.
    pub seconds: f64,
    /// Where loading the model spent its time.
    pub load: crate::load::LoadTimings,
    /// Where the eigensolve's time went.
    pub eigensolver: EigenReport,
    /// The damped (complex) modes, when asked for ([`ModesOptions::damped`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub damped: Vec<DampedMode>,
}

/// One complex mode of the damped model, as `femu modes --damped` reports it (Nastran's complex
/// eigenvalue conventions).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DampedMode {
    /// `Im p / (2 pi)`, Hz (0 for a mode that does not oscillate).
    pub frequency_hz: f64,
    /// Nastran's damping coefficient `g = -2 Re p / Im p` (a structural loss factor, twice a
    /// light viscous ratio).
    pub damping: f64,
    /// The ratio to critical damping `-Re p / |p|`.
    pub damping_ratio: f64,
    /// The root `p` (`u = phi e^(p t)`), `[re, im]`, s^-1.
    pub eigenvalue: [f64; 2],
    /// The shape's modal phase collinearity over the free DOFs (1: real up to one phase).
    pub mpc: f64,
    /// Its mean phase deviation, degrees.
    pub mpd_degrees: f64,
}

/// The complex modes of `loaded`'s damping in the space of its real `modes` (docs/MATH.md,
/// "Damped modes"): the structural damping `K_4` of the elements' and springs' `GE` projected on
/// them plus a model-wide loss factor `g` as `g Lambda`, and the viscous damping of its dampers
/// (bushings' `B`) projected, plus Rayleigh's `alpha I + beta Lambda` and the deck's modal ratios
/// (`SDAMPING`'s table, `*MODAL DAMPING`) as `2 zeta_r omega_r`. As many modes as real ones, the
/// lowest of them the accurate ones (a Rayleigh-Ritz approximation in the real modes).
///
/// The deck's modal ratios are stated in `notes`.
///
/// # Errors
/// A model without damping, and the projection's errors.
pub fn damped_modes(
    loaded: &LoadedModel,
    modes: &Modes,
    notes: &mut Vec<String>,
) -> Result<Vec<DampedMode>, StudyError> {
    let d = damped_in(loaded, modes, notes)?;
    let n = modes.values.len();
    let dofs = modes.vectors.nrows();
    Ok((0..n)
        .map(|r| {
            // the shape Phi q over the free DOFs
            let shape: Vec<(f64, f64)> = (0..dofs)
                .map(|i| {
                    let mut v = faer::c64::new(0.0, 0.0);
                    for j in 0..n {
                        v += d.coordinates[(j, r)] * modes.vectors[(i, j)];
                    }
                    (v.re, v.im)
                })
                .collect();
            let c = femu_correlate::complexity::Complexity::of(&shape);
            DampedMode {
                frequency_hz: d.frequency_hz(r),
                damping: d.damping(r),
                damping_ratio: d.ratio(r),
                eigenvalue: [d.roots[r].re, d.roots[r].im],
                mpc: c.map_or(1.0, |c| c.mpc),
                mpd_degrees: c.map_or(0.0, |c| c.mpd_degrees),
            }
        })
        .collect())
}

/// The model's `modes` as a universal file (docs/MATH.md, "Damped modes"): units (SI), every mesh
/// node (dataset 2411) and each mode as dataset 55 on the nodes' translations (`u = T z`: zeros at
/// held DOFs); with `damped`, the damped modes instead, as complex data whose eigenvalue is the
/// root `p` (frequency `|p| / 2 pi` and ratio `-Re p / |p|` in the file's terms), which test
/// software imports for pre-test analysis and which `femu correlate` reads back as a test.
///
/// # Errors
/// As [`damped_modes`] when `damped`; a vector of another length than the free DOFs.
pub fn modes_universal(
    loaded: &LoadedModel,
    modes: &Modes,
    damped: bool,
) -> Result<femu_io::uff::Universal, StudyError> {
    use femu_io::uff::{UffMode, UffNode, UffUnits, Universal};
    let mesh = loaded.model.mesh();
    let dofs = &loaded.sys.dofs;
    let n = modes.values.len();
    let expand = |j: usize| -> Result<Vec<f64>, StudyError> {
        Ok(dofs.expand(&modes.vectors.col(j).iter().copied().collect::<Vec<f64>>())?)
    };
    let real: Vec<Vec<f64>> = (0..n).map(expand).collect::<Result<_, _>>()?;
    let at = |u: &[f64], i: usize| [u[3 * i], u[3 * i + 1], u[3 * i + 2]];
    let mut uff = Universal {
        units: Some(UffUnits {
            code: 1,
            description: "SI".into(),
            factors: [1.0, 1.0, 1.0],
        }),
        nodes: (0..mesh.node_count())
            .map(|i| UffNode {
                id: mesh.node_id(i),
                x: mesh.coords()[i],
            })
            .collect(),
        nodes_2411: true,
        ..Default::default()
    };
    let ids: Vec<u64> = (0..mesh.node_count()).map(|i| mesh.node_id(i)).collect();
    if !damped {
        for (j, u) in real.iter().enumerate() {
            uff.modes.push(UffMode {
                number: j as i64 + 1,
                frequency_hz: modes.values[j].max(0.0).sqrt() / (2.0 * std::f64::consts::PI),
                damping: 0.0,
                modal_mass: 1.0,
                values: ids
                    .iter()
                    .enumerate()
                    .map(|(i, id)| (*id, at(u, i)))
                    .collect(),
                complex: false,
                complexity: None,
                imaginary: None,
            });
        }
        return Ok(uff);
    }
    let d = damped_in(loaded, modes, &mut Vec::new())?;
    for r in 0..n {
        // Phi q over the nodes' translations
        let (mut re, mut im) = (vec![0.0; real[0].len()], vec![0.0; real[0].len()]);
        for (j, u) in real.iter().enumerate() {
            let q = d.coordinates[(j, r)];
            for (k, v) in u.iter().enumerate() {
                re[k] += q.re * v;
                im[k] += q.im * v;
            }
        }
        let p = d.roots[r];
        uff.modes.push(UffMode {
            number: r as i64 + 1,
            frequency_hz: p.norm() / (2.0 * std::f64::consts::PI),
            damping: d.ratio(r),
            modal_mass: 0.0,
            values: ids
                .iter()
                .enumerate()
                .map(|(i, id)| (*id, at(&re, i)))
                .collect(),
            complex: true,
            complexity: None,
            imaginary: Some((0..ids.len()).map(|i| at(&im, i)).collect()),
        });
    }
    Ok(uff)
}

/// `modes` as the correlation's mode set, with the coordinates of the model's damped modes in
/// them when `damped` (the complex MAC then compares with those: [`PairingOptions::damped`]).
///
/// # Errors
/// As [`damped_modes`] when `damped`.
///
/// [`PairingOptions::damped`]: femu_correlate::PairingOptions::damped
pub fn mode_set(
    loaded: &LoadedModel,
    modes: &Modes,
    damped: bool,
) -> Result<femu_correlate::ModeSet, StudyError> {
    let set = femu_correlate::ModeSet::from_modes(modes);
    if !damped {
        return Ok(set);
    }
    let d = damped_in(loaded, modes, &mut Vec::new())?;
    Ok(set.with_damped(d.coordinates)?)
}

/// The damped modes of `loaded` in the space of `modes` ([`damped_modes`]), with a note in
/// `notes` for the deck's modal ratios.
fn damped_in(
    loaded: &LoadedModel,
    modes: &Modes,
    notes: &mut Vec<String>,
) -> Result<femu_correlate::damped::DampedModes, StudyError> {
    use femu_fem::model::UniformDamping;
    let dampers = loaded.asm.dampers(&loaded.model, loaded.sys.mass_kind)?;
    let mut projected = femu_correlate::frf::ModalDampers::project(
        dampers.structural.as_ref(),
        dampers.viscous.as_ref(),
        modes.vectors.as_ref(),
    )?;
    let n = modes.values.len();
    let values = &modes.values;
    let diagonal = |m: &mut Option<faer::Mat<f64>>, of: &dyn Fn(usize) -> f64| {
        let m = m.get_or_insert_with(|| faer::Mat::zeros(n, n));
        for r in 0..n {
            m[(r, r)] += of(r);
        }
    };
    match loaded.model.uniform_damping() {
        None => {}
        Some(UniformDamping::LossFactor(g)) => {
            diagonal(&mut projected.structural, &|r| g * values[r]);
        }
        Some(UniformDamping::Rayleigh { alpha, beta }) => {
            diagonal(&mut projected.viscous, &|r| alpha + beta * values[r]);
        }
    }
    match crate::frf::deck_modal_damping(&loaded.model, &modes.frequencies_hz(), notes) {
        Some(femu_correlate::frf::Damping::Ratios(ratios)) => {
            diagonal(&mut projected.viscous, &|r| {
                2.0 * ratios[r] * values[r].max(0.0).sqrt()
            });
        }
        Some(femu_correlate::frf::Damping::LossFactors(g)) => {
            diagonal(&mut projected.structural, &|r| g[r] * values[r]);
        }
        _ => {}
    }
    if projected.structural.is_none() && projected.viscous.is_none() {
        return Err(StudyError::invalid(
            "damped modes",
            "the model has no damping (no material, spring or bushing GE or B, no PARAM,G, Rayleigh or modal damping)",
        ));
    }
    Ok(femu_correlate::damped::damped_modes(values, &projected)?)
}

/// Where a model read as matrices came from, as [`ModesReport`] states it.
#[derive(Debug, Clone, Serialize)]
pub struct MatricesReport {
    /// The solver's format.
    pub format: &'static str,
    /// Stiffness, mass and DOF table.
    pub files: Vec<String>,
    /// The node coordinates.
    pub nodes: String,
}

impl MatricesReport {
    /// The report of `origin`.
    pub fn of(origin: &crate::external::MatrixOrigin) -> Self {
        Self {
            format: origin.source.name(),
            files: origin
                .files
                .iter()
                .map(|f| f.display().to_string())
                .collect(),
            nodes: origin.nodes.display().to_string(),
        }
    }
}

/// Solves for the modes `options` asks for; where it asks for none (no count, shift or band), those
/// of the deck: an Abaqus `*FREQUENCY` step's count, or a Nastran `EIGRL`'s `ND` (the lowest `ND`)
/// or `V1`-`V2` range (every mode in it), as Nastran would compute them; else the lowest 10.
///
/// # Errors
/// A count of 0, a negative or non-finite frequency, a band with `LO >= HI`, and the
/// eigensolver's errors.
pub fn solve_modes(
    loaded: &LoadedModel,
    options: &ModesOptions,
) -> Result<(Modes, ModesReport), StudyError> {
    let start = std::time::Instant::now();
    let sys = &loaded.sys;
    let asked = options.count.is_some() || options.shift_hz.is_some() || options.band_hz.is_some();
    let mut deck_notes = Vec::new();
    let mut band_hz = options.band_hz;
    let mut deck_count = loaded.frequency.map(|f| f.count);
    if let (false, Some((v1, v2, nd))) = (asked, loaded.eigrl) {
        match (v1, v2, nd) {
            (lo, Some(hi), nd) => {
                band_hz = Some((lo.unwrap_or(0.0).max(0.0), hi));
                deck_notes.push(format!(
                    "the deck's EIGRL: every mode from {} to {hi} Hz{}",
                    lo.unwrap_or(0.0).max(0.0),
                    nd.map_or(String::new(), |n| format!(
                        " (its ND = {n} is not a cap here: femu returns the whole range, Sturm-verified)"
                    ))
                ));
            }
            (None | Some(0.0), None, Some(nd)) => {
                deck_count = Some(nd);
                deck_notes.push(format!("the deck's EIGRL: the lowest {nd} modes"));
            }
            (Some(lo), None, nd) => {
                return Err(StudyError::invalid(
                    "EIGRL",
                    format!(
                        "V1 = {lo} Hz without V2{}: the modes above a frequency are not a request femu solves; give --count, --shift or --band",
                        nd.map_or(String::new(), |n| format!(" (ND = {n})"))
                    ),
                ));
            }
            (_, None, None) => {}
        }
    }
    let mut count = options.count.or(deck_count).unwrap_or(10);
    if count == 0 {
        return Err(StudyError::invalid("count", "must be at least 1"));
    }
    // a deck's count is what its solver would look for: it returns the modes that exist
    let dim = sys.k.rows();
    if options.count.is_none() && count > dim && dim > 0 {
        deck_notes.push(format!(
            "the deck asks for {count} modes and the model has {dim} free degrees of freedom: all {dim}, as its solver returns the modes that exist"
        ));
        count = dim;
    }
    let which = match (options.shift_hz, band_hz) {
        (Some(hz), _) => {
            if !(hz.is_finite() && hz >= 0.0) {
                return Err(StudyError::invalid(
                    "shift",
                    format!("{hz} Hz must be a non-negative frequency"),
                ));
            }
            Which::Nearest {
                shift: eigenvalue_of_hz(hz),
                count,
            }
        }
        (None, Some((lo, hi))) => {
            if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
                return Err(StudyError::invalid(
                    "band",
                    format!("{lo} {hi}: need 0 <= LO < HI (Hz)"),
                ));
            }
            Which::Band {
                lo: eigenvalue_of_hz(lo),
                hi: eigenvalue_of_hz(hi),
            }
        }
        (None, None) => Which::Lowest(count),
    };
    // the block size is checked by the eigensolver (1 to `MAX_BLOCK`)
    let eigen = &options.eigen;
    let modes = sys.modes(which, eigen)?;
    let report = ModesReport {
        model: loaded.path.display().to_string(),
        load: loaded.timings,
        dofs: sys.k.rows(),
        matrices: loaded.matrices.as_ref().map(MatricesReport::of),
        mass: match loaded.sys.mass_kind {
            MassKind::Lumped => "lumped",
            _ => "consistent",
        },
        frequencies_hz: modes.frequencies_hz(),
        eigenvalues: modes.values.clone(),
        residuals: modes.residuals.clone(),
        residual_kinds: modes.residual_kinds.iter().map(|k| k.name()).collect(),
        requested: modes.requested,
        sturm_verified: modes.sturm.verified(),
        sturm_count: modes.sturm.count,
        sturm_lower: modes.sturm.lower,
        sturm_upper: modes.sturm.upper,
        notes: deck_notes
            .into_iter()
            .chain(notes(&modes, matches!(which, Which::Band { .. })))
            .collect(),
        seconds: start.elapsed().as_secs_f64(),
        eigensolver: EigenReport::new(
            &modes.stats,
            matches!(eigen.engine, Engine::Femu).then_some(eigen.block_size),
        ),
        damped: Vec::new(),
    };
    let mut report = report;
    if options.damped {
        report.damped = damped_modes(loaded, &modes, &mut report.notes)?;
    }
    Ok((modes, report))
}

/// What a reader of a modes table should be told: a request completed to a whole cluster, and
/// which modes report the backward error rather than the relative residual.
pub fn notes(modes: &Modes, band: bool) -> Vec<String> {
    let mut notes = Vec::new();
    if !band && modes.values.len() > modes.requested {
        notes.push(format!(
            "{} modes requested, {} returned: the request ended inside a repeated eigenvalue \
             (eigenvalues equal within the solver's tie tolerance), which is returned whole",
            modes.requested,
            modes.values.len(),
        ));
    }
    let zero: Vec<String> = modes
        .residual_kinds
        .iter()
        .enumerate()
        .filter(|(_, k)| **k == ResidualKind::Backward)
        .map(|(j, _)| (j + 1).to_string())
        .collect();
    if !zero.is_empty() {
        notes.push(format!(
            "mode(s) {} have no strain energy (rigid-body): their residual is the backward error \
             ||K x - lambda M x|| / ((||K|| + |lambda| ||M||) ||x||), since K x is round-off",
            zero.join(", ")
        ));
    }
    notes
}

/// The lowest `count` modes (default: twice the test modes plus 4, at most the DOFs), as the
/// correlation and estimate workflows need them, solved with `eigen`.
///
/// # Errors
/// The eigensolver's errors.
pub fn lowest_for_test(
    loaded: &LoadedModel,
    count: Option<usize>,
    test_modes: usize,
    eigen: &EigenOptions,
) -> Result<Modes, StudyError> {
    let sys = &loaded.sys;
    let count = count.unwrap_or(2 * test_modes + 4).min(sys.k.rows());
    Ok(sys.modes(Which::Lowest(count), eigen)?)
}
