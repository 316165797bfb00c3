//! `femu info FILE`: what a file femu reads contains, and what femu would do with it.

use crate::StudyError;

/// What femu does with a test of frequencies alone.
const FREQUENCIES_ALONE: &str = "a test of frequencies alone, without shapes (femu correlate pairs by frequency, femu update fits the frequencies; estimate and expand need shapes)";
use femu_fem::mesh::Mesh;
use femu_io::Format;
use std::fmt::Write as _;
use std::path::Path;

fn mesh_lines(s: &mut String, mesh: &Mesh) {
    let _ = writeln!(s, "nodes: {}", mesh.node_count());
    let kinds: Vec<String> = mesh
        .kind_counts()
        .iter()
        .map(|(k, n)| format!("{n} {}", k.abaqus_name()))
        .collect();
    let _ = writeln!(
        s,
        "solid elements: {} ({})",
        mesh.element_count(),
        if kinds.is_empty() {
            "none".into()
        } else {
            kinds.join(", ")
        }
    );
    for (name, set) in mesh.node_sets() {
        let _ = writeln!(s, "node set {name}: {} nodes", set.len());
    }
    for (name, set) in mesh.element_sets() {
        let _ = writeln!(s, "element set {name}: {} elements", set.len());
    }
}

/// The beams, rods, springs and bushings, when there are any, and their sets.
fn structural_lines(s: &mut String, model: &femu_fem::model::Model) {
    use femu_fem::structural::StructuralKind;
    let all = model.structural();
    if all.is_empty() {
        return;
    }
    let count = |f: fn(&StructuralKind) -> bool| all.iter().filter(|e| f(&e.kind)).count();
    let _ = writeln!(
        s,
        "structural elements: {} ({} shells, {} beams, {} rods, {} springs, {} dampers, {} scalar masses, {} bushings; nodes with rotations: {})",
        all.len(),
        count(|k| matches!(k, StructuralKind::Shell(_))),
        count(|k| matches!(k, StructuralKind::Beam(_))),
        count(|k| matches!(k, StructuralKind::Rod(_))),
        count(|k| matches!(k, StructuralKind::Spring(s) if s.k != 0.0)),
        count(|k| matches!(k, StructuralKind::Spring(s) if s.k == 0.0 && s.viscous != 0.0)),
        count(|k| matches!(k, StructuralKind::Spring(s) if s.k == 0.0 && s.viscous == 0.0)),
        count(|k| matches!(k, StructuralKind::Bushing(_))),
        model.rotation_nodes().len()
    );
    // the shells by kind, when there are any
    let mut kinds: std::collections::BTreeMap<&str, usize> = Default::default();
    for e in all {
        if let StructuralKind::Shell(sh) = &e.kind {
            let kind = match (e.nodes.len(), sh.bending == 0.0) {
                (3, false) => "of 3 nodes",
                (4, false) => "of 4 nodes",
                (_, false) => "of 8 nodes",
                (3, true) => "membranes of 3 nodes",
                (4, true) => "membranes of 4 nodes",
                (_, true) => "membranes of 8 nodes",
            };
            *kinds.entry(kind).or_default() += 1;
        }
    }
    if !kinds.is_empty() {
        let list: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
        let _ = writeln!(s, "shells: {}", list.join(", "));
    }
    for (name, set) in model.structural_sets() {
        let _ = writeln!(s, "element set {name}: {} structural elements", set.len());
    }
}

/// The elements with a structural damping coefficient of their material (Nastran's `GE`, Abaqus'
/// `*DAMPING, STRUCTURAL`), when there are any: what a direct frequency response adds as
/// `i sum_e GE_e K_e`.
/// The direct input matrices' entries (Nastran's `K2GG`, `M2GG`), when there are any.
fn direct_line(s: &mut String, model: &femu_fem::model::Model) {
    use femu_fem::model::DirectMatrix;
    let [k, m, d] = DirectMatrix::ALL.map(|w| model.direct_entries(w).len());
    if k + m + d > 0 {
        let _ = writeln!(
            s,
            "direct input matrices (K2GG, M2GG, K42GG): {k} stiffness and {m} mass entries added to the assembled K and M, {d} structural damping entries to femu frf's K4"
        );
    }
}

fn damping_line(s: &mut String, model: &femu_fem::model::Model) {
    if let Some(u) = model.uniform_damping() {
        let _ = writeln!(
            s,
            "damping of the whole model: {} (femu frf uses it when given no damping)",
            match u {
                femu_fem::model::UniformDamping::LossFactor(g) =>
                    format!("a loss factor of {g} (PARAM,G)"),
                femu_fem::model::UniformDamping::Rayleigh { alpha, beta } =>
                    format!("Rayleigh alpha {alpha:e} s^-1, beta {beta:e} s"),
            }
        );
    }
    if let Some(t) = model.modal_damping() {
        let _ = writeln!(
            s,
            "modal damping table ({}): {} points, {:?} from {} to {} Hz{} (femu frf's modal superposition uses it when given no damping)",
            if t.hold_ends {
                "*MODAL DAMPING, DEFINITION=FREQUENCY RANGE"
            } else {
                "SDAMPING"
            },
            t.points.len(),
            t.units,
            t.points.first().map_or(0.0, |p| p.0),
            t.points.last().map_or(0.0, |p| p.0),
            if model.modal_damping_structural() {
                if t.hold_ends {
                    ", as each mode's complex stiffness (STRUCTURAL)"
                } else {
                    ", as each mode's complex stiffness (KDAMP = -1)"
                }
            } else {
                ""
            }
        );
    }
    let ranges = model.mode_ratio_ranges();
    if !ranges.is_empty() {
        let structural = model.modal_damping_structural();
        let _ = writeln!(
            s,
            "modal damping by mode number (*MODAL DAMPING): {}{} (femu frf's modal superposition uses it when given no damping)",
            ranges
                .iter()
                .map(|(a, b, z)| {
                    let value = if structural { 2.0 * z } else { *z };
                    if a == b {
                        format!("mode {a} {value}")
                    } else {
                        format!("modes {a}-{b} {value}")
                    }
                })
                .collect::<Vec<_>>()
                .join(", "),
            if structural {
                ", structural damping factors: each mode's complex stiffness"
            } else {
                ", viscous ratios"
            }
        );
    }
    let d = model.element_damping();
    if d.is_empty() {
        return;
    }
    let (lo, hi) = d
        .values()
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
    let _ = writeln!(
        s,
        "structural damping of the materials: {} elements, GE {}{} (femu frf --direct adds it)",
        d.len(),
        lo,
        if hi > lo {
            format!(" to {hi}")
        } else {
            String::new()
        }
    );
}

/// The mass sets (a Nastran CONM2 each, an Abaqus `*MASS` element set), when there are any: the
/// names that update concentrated masses.
fn mass_set_lines(s: &mut String, model: &femu_fem::model::Model) {
    let names = model.mass_set_names();
    if names.is_empty() {
        return;
    }
    let shown: Vec<&str> = names.iter().take(8).map(String::as_str).collect();
    let _ = writeln!(
        s,
        "mass sets (updating candidates for their masses): {}{}",
        shown.join(", "),
        if names.len() > shown.len() {
            format!(" and {} more", names.len() - shown.len())
        } else {
            String::new()
        }
    );
}

/// The 8-node bricks built with incompatible modes, when there are any.
fn formulation_line(s: &mut String, model: &femu_fem::model::Model) {
    let n = (0..model.mesh().element_count())
        .filter(|e| model.formulation(*e) == femu_fem::element::Formulation::IncompatibleModes)
        .count();
    if n > 0 {
        let _ = writeln!(
            s,
            "8-node bricks with incompatible modes (C3D8I): {n} of {}",
            model.mesh().element_count()
        );
    }
}

fn frequencies(f: &[f64]) -> String {
    let shown: Vec<String> = f.iter().take(12).map(|v| format!("{v:.4}")).collect();
    format!(
        "{}{}",
        shown.join(", "),
        if f.len() > 12 { ", ..." } else { "" }
    )
}

/// A description of `path`: its content by the reader femu would use, its warnings, and what
/// femu would do with it (a model, a test, both, or neither).
///
/// # Errors
/// The readers' errors (the file is not valid), and an extension femu does not read.
pub fn describe(path: &Path) -> Result<String, StudyError> {
    let mut s = format!("{}\n", path.display());
    let mut warnings: Vec<String> = Vec::new();
    let (s_, w) = (&mut s, &mut warnings);
    let format = Format::from_path(path);
    if let Some(f) = format {
        w.extend(crate::load::read_by_content(path, f));
    }
    match format {
        Some(Format::Inp) => describe_inp(path, s_, w)?,
        Some(Format::Nastran) => describe_nastran(path, s_, w)?,
        Some(Format::Gmsh) => describe_gmsh(path, s_, w)?,
        Some(Format::Universal) => describe_universal(path, s_, w)?,
        Some(f @ (Format::Json | Format::Csv)) => describe_test_table(path, f == Format::Json, s_)?,
        Some(Format::Matrices) => describe_matrices(path, s_, w)?,
        Some(Format::Results) => describe_results(path, s_, w)?,
        None => {
            let all = femu_io::format::all_extensions();
            return Err(StudyError::in_file(
                path,
                "format",
                format!(
                    "femu reads {}; the file's extension is none of them",
                    all.iter()
                        .map(|e| format!(".{e}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    for w in &warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    Ok(s)
}

/// What [`describe`] says of an Abaqus/CalculiX deck.
fn describe_inp(path: &Path, s: &mut String, warnings: &mut Vec<String>) -> Result<(), StudyError> {
    let deck = femu_io::inp::read_inp(path)?;
    let _ = writeln!(s, "format: Abaqus/CalculiX input deck");
    mesh_lines(s, &deck.mesh);
    for (name, m) in &deck.materials {
        let elastic = match &m.elasticity {
            femu_fem::material::Elasticity::Isotropic { e, nu } => {
                format!("E = {e:e} Pa, nu = {nu}")
            }
            _ => "anisotropic".to_string(),
        };
        let damping = match deck.material_damping.get(name) {
            Some(d) => {
                let mut parts = Vec::new();
                if d.structural != 0.0 {
                    parts.push(format!(", structural damping {}", d.structural));
                }
                if d.alpha != 0.0 || d.beta != 0.0 {
                    parts.push(format!(
                        ", Rayleigh damping alpha {:e} s^-1, beta {:e} s",
                        d.alpha, d.beta
                    ));
                }
                parts.concat()
            }
            None => String::new(),
        };
        let _ = writeln!(
            s,
            "material {name}: {elastic}, density {} kg/m^3{damping}",
            m.density
        );
    }
    let mut mass_sets = deck.point_mass_sets.clone();
    mass_sets.sort();
    mass_sets.dedup();
    if !mass_sets.is_empty() {
        let _ = writeln!(
            s,
            "mass sets (updating candidates for their masses): {}",
            mass_sets.join(", ")
        );
    }
    let _ = writeln!(s, "solid sections: {}", deck.sections.len());
    let _ = writeln!(s, "boundary conditions: {}", deck.boundaries.len());
    if let Some(f) = deck.frequency {
        let _ = writeln!(s, "frequency step: {} modes", f.count);
    }
    warnings.extend(deck.warnings.iter().map(ToString::to_string));
    let (model, built) = deck.to_model_with_warnings()?;
    warnings.extend(built.iter().map(ToString::to_string));
    damping_line(s, &model);
    formulation_line(s, &model);
    warnings.extend(crate::load::units_hint(&model, path));
    let _ = writeln!(
        s,
        "femu would: use it as a model with {} free DOFs (femu modes, correlate, estimate, update)",
        model.dof_map()?.free_count()
    );
    Ok(())
}

/// What [`describe`] says of another solver's matrices: their files, size and DOFs, and where
/// the nodes' coordinates would come from.
fn describe_matrices(
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("op4"))
    {
        // an OUTPUT4 file may hold any matrices: each, then what femu would make of them (a
        // file of other matrices is a valid file femu has no model in)
        let _ = writeln!(
            s,
            "format: {}",
            femu_io::matrices::MatrixSource::NastranOp4.name()
        );
        for m in femu_io::op4::read_op4(path)? {
            let _ = writeln!(
                s,
                "matrix {}: {} x {}, {}, {}, {} stored values ({})",
                m.name,
                m.rows,
                m.cols,
                m.form_name(),
                m.kind_name(),
                m.re.len(),
                m.at
            );
        }
        match femu_io::matrices::read_matrices(path) {
            Ok(ext) => return describe_matrix_set(ext, path, s, warnings),
            Err(e) => {
                let _ = writeln!(s, "femu would: not use it as a model ({e})");
                return Ok(());
            }
        }
    }
    let ext = femu_io::matrices::read_matrices(path)?;
    let _ = writeln!(s, "format: {}", ext.source.name());
    describe_matrix_set(ext, path, s, warnings)
}

/// What [`describe`] says of a matrix set read: its rows and what femu would do with it.
fn describe_matrix_set(
    ext: femu_io::matrices::ExternalMatrices,
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let (k_nnz, m_nnz) = (ext.k.nnz(), ext.m.nnz());
    let names: Vec<String> = ext.files.iter().map(|f| f.display().to_string()).collect();
    let _ = writeln!(s, "files: {}", names.join(", "));
    let nodes: std::collections::BTreeSet<u64> = ext.dofs.iter().map(|d| d.node).collect();
    let rotations = ext.dofs.iter().filter(|d| d.component >= 3).count();
    let _ = writeln!(
        s,
        "rows: {} DOFs on {} nodes ({rotations} of them rotations); nnz(K) = {}, nnz(M) = {}",
        ext.dofs.len(),
        nodes.len(),
        k_nnz,
        m_nnz
    );
    match femu_io::matrices::default_node_table(path).filter(|p| p.exists()) {
        Some(table) => {
            let (model, sys, _, w) =
                crate::external::model_of_matrices(ext, path, Some(&table), false)?;
            warnings.extend(w);
            let _ = writeln!(
                s,
                "node coordinates: {} ({} nodes)",
                table.display(),
                model.mesh().node_count()
            );
            let _ = writeln!(
                s,
                "femu would: use it as a model with {} free DOFs (femu modes, correlate, estimate, expand, frf; update over groups given as NAME=FILE, the same model's matrices with the group's modulus and density doubled)",
                sys.dofs.free_count()
            );
        }
        None => {
            let _ = writeln!(
                s,
                "node coordinates: none beside the matrices ({}); femu would use it as a model given --nodes FILE",
                femu_io::matrices::default_node_table(path)
                    .map_or_else(|| "-".into(), |p| p.display().to_string())
            );
        }
    }
    Ok(())
}

/// What [`describe`] says of another solver's results: its nodes and modes.
fn describe_results(
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if crate::external::nastran_results(path)
        && crate::external::nastran_deck_beside(path).is_none()
    {
        // the modes alone: their grids' positions are in the run's deck
        let modes = crate::external::read_nastran_modes(path)?;
        let hz: Vec<f64> = modes
            .modes
            .iter()
            .map(|m| m.eigenvalue.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect();
        let _ = writeln!(
            s,
            "format: Nastran results (.{}): real eigenvectors",
            ext.as_deref().unwrap_or("")
        );
        let _ = writeln!(
            s,
            "modes: {} at {} grids; Hz: {}",
            modes.modes.len(),
            modes.modes[0].points.len(),
            frequencies(&hz)
        );
        let _ = writeln!(
            s,
            "femu would: use them as the model's modes in femu correlate given the run's deck for the grids' positions (none of the same name beside it: --nodes DECK)"
        );
        return Ok(());
    }
    let r = crate::external::load_result_modes(path, None)?;
    let _ = writeln!(
        s,
        "format: {}",
        match ext.as_deref() {
            Some("f06") => {
                "Nastran printed output (.f06): real eigenvectors, the grids from the run's deck"
            }
            Some("op2") => "Nastran OP2: real eigenvectors (OUGV1), the grids from the run's deck",
            Some("dat") => {
                "CalculiX printed output (.dat): the displacements *NODE PRINT gives each mode, the nodes from the run's deck"
            }
            _ => "CalculiX results (.frd)",
        }
    );
    let _ = writeln!(s, "nodes: {}", r.model.mesh().node_count());
    let _ = writeln!(
        s,
        "modes: {}; Hz: {}",
        r.modes.len(),
        frequencies(&r.modes.frequencies_hz())
    );
    warnings.extend(r.warnings);
    let _ = writeln!(
        s,
        "femu would: use them as the model's modes in femu correlate (no Sturm proof that none was skipped; estimate, expand, frf and update need K and M)"
    );
    Ok(())
}

/// What [`describe`] says of Nastran bulk data.
fn describe_nastran(
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let deck = femu_io::nastran::read_bdf(path, &femu_io::nastran::BdfOptions::default())?;
    let _ = writeln!(s, "format: Nastran bulk data");
    let model = &deck.model;
    mesh_lines(s, model.mesh());
    structural_lines(s, model);
    direct_line(s, model);
    damping_line(s, model);
    mass_set_lines(s, model);
    formulation_line(s, model);
    let _ = writeln!(
        s,
        "point masses (CONM2): {}; constrained DOFs: {} (SPC set {}, permanent constraints of {} grids); dependent DOFs (RBE2, RBAR, RBE3, blank mid-side grids): {}",
        model.point_masses().len() + model.rigid_masses().len(),
        model.fixed_dofs().count(),
        deck.spc_set
            .map_or("none selected".to_string(), |s| s.to_string()),
        deck.permanent_constraints,
        model.constraints().len()
    );
    let _ = writeln!(
        s,
        "mass: {} ({})",
        match deck.mass {
            femu_fem::assembly::MassKind::Lumped => "lumped",
            _ => "coupled (consistent)",
        },
        match deck.coupmass {
            Some(v) => format!("PARAM,COUPMASS,{v}"),
            None => "no PARAM,COUPMASS: MSC Nastran's default".to_string(),
        }
    );
    if let Some((v1, v2, nd)) = deck.eigrl {
        let _ = writeln!(
            s,
            "EIGRL (femu modes solves it unless given --count, --shift or --band): {} modes{}",
            nd.map_or("all".to_string(), |n| n.to_string()),
            match (v1, v2) {
                (Some(a), Some(b)) => format!(" in [{a}, {b}] Hz"),
                (Some(a), None) => format!(" above {a} Hz"),
                (None, Some(b)) => format!(" below {b} Hz"),
                _ => String::new(),
            }
        );
    }
    warnings.extend(deck.warnings.iter().map(ToString::to_string));
    warnings.extend(crate::load::units_hint(model, path));
    let _ = writeln!(
        s,
        "femu would: use it as a model with {} free DOFs (femu modes, correlate, estimate, update)",
        model.dof_map()?.free_count()
    );
    Ok(())
}

/// What [`describe`] says of a Gmsh mesh.
fn describe_gmsh(
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let g = femu_io::gmsh::read_msh(path)?;
    let _ = writeln!(s, "format: Gmsh mesh");
    mesh_lines(s, &g.mesh);
    // the groups a section makes shells or beams of, with their element types
    let kinds = |elements: &[femu_io::gmsh::GroupElement]| {
        let mut count: std::collections::BTreeMap<i64, usize> = Default::default();
        for e in elements {
            *count.entry(e.gmsh_type).or_default() += 1;
        }
        count
            .iter()
            .map(|(t, n)| {
                let name = match t {
                    1 => "2-node line",
                    8 => "3-node line",
                    2 => "3-node triangle",
                    3 => "4-node quadrangle",
                    16 => "8-node quadrangle",
                    _ => "quadratic element femu does not build",
                };
                format!("{n} {name}{} (type {t})", if *n == 1 { "" } else { "s" })
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    // on a mesh of volumes these groups are usually faces and edges to clamp or load: the hint
    // at sections is for a mesh without volumes
    let volumes = g.mesh.element_count() > 0;
    for (name, elements) in &g.surfaces {
        let _ = writeln!(
            s,
            "surface group {name}: {} (its nodes a set{})",
            kinds(elements),
            if volumes {
                String::new()
            } else {
                format!("; shells with --shell {name}=THICKNESS")
            }
        );
    }
    for (name, elements) in &g.curves {
        let _ = writeln!(
            s,
            "line group {name}: {} (its nodes a set{})",
            kinds(elements),
            if volumes {
                String::new()
            } else {
                format!("; beams with --beam {name}=rect:A,B")
            }
        );
    }
    warnings.extend(g.warnings.iter().map(ToString::to_string));
    let _ = writeln!(
        s,
        "femu would: use it as a model once given a material (--young, --poisson, --density){} and, if clamped, the sets to fix (--fix)",
        if volumes {
            ""
        } else {
            ", its surface and line groups' sections (it has no volume elements)"
        }
    );
    Ok(())
}

/// What [`describe`] says of a universal file.
fn describe_universal(
    path: &Path,
    s: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let u = femu_io::uff::read_uff(path)?;
    let _ = writeln!(s, "format: universal file");
    if let Some(units) = &u.units {
        let _ = writeln!(
            s,
            "units (164): {} (code {}), length factor {}",
            units.description, units.code, units.factors[0]
        );
    }
    if let Some(h) = &u.header {
        let _ = writeln!(
            s,
            "header (151): model {:?}, description {:?}, written by {:?}",
            h.model, h.description, h.program
        );
    }
    let _ = writeln!(
        s,
        "nodes ({}): {}",
        if u.nodes_2411 { "2411" } else { "15" },
        u.nodes.len()
    );
    if !u.coordinate_systems.is_empty() {
        let turned = u
            .coordinate_systems
            .values()
            .filter(|c| !c.is_global_orientation())
            .count();
        let curvilinear = u
            .coordinate_systems
            .values()
            .filter(|c| c.kind != 0)
            .count();
        let _ = writeln!(
            s,
            "coordinate systems (18/2420): {} ({} turned from the global axes, {} cylindrical or spherical); {} nodes measure in one of them (read in global directions)",
            u.coordinate_systems.len(),
            turned,
            curvilinear,
            u.displacement_systems.len()
        );
    }
    let solids = u
        .elements
        .iter()
        .filter(|e| (111..=118).contains(&e.descriptor))
        .count();
    let _ = writeln!(
        s,
        "elements (2412): {} ({} solids, {} beams, shells and others)",
        u.elements.len(),
        solids,
        u.elements.len() - solids
    );
    for g in &u.groups {
        let _ = writeln!(
            s,
            "group {}: {} nodes, {} elements",
            g.name,
            g.nodes.len(),
            g.elements.len()
        );
    }
    for t in &u.trace_lines {
        let _ = writeln!(
            s,
            "trace line {} ({}): {} labels",
            t.number,
            t.id,
            t.nodes.len()
        );
    }
    if !u.modes.is_empty() {
        let f: Vec<f64> = u.modes.iter().map(|m| m.frequency_hz).collect();
        let _ = writeln!(
            s,
            "modes ({}): {} at {} nodes{}; Hz: {}",
            match (u.modes_from_2414, u.modes.len() - u.modes_from_2414) {
                (0, _) => "55: test modes".to_string(),
                (_, 0) => "2414: analysis results of an FE code".to_string(),
                (r, t) => format!("{t} of dataset 55, {r} of dataset 2414"),
            },
            u.modes.len(),
            u.modes[0].values.len(),
            if u.modes.iter().any(|m| m.complex) {
                ", complex (read as real shapes)"
            } else {
                ""
            },
            frequencies(&f)
        );
        for m in u.modes.iter().filter(|m| m.complex) {
            let _ = writeln!(
                s,
                "mode {} ({:.2} Hz): damping {:.3} %{}",
                m.number,
                m.frequency_hz,
                100.0 * m.damping,
                m.complexity.map_or(String::new(), |c| format!(
                    ", MPC {:.3}, MPD {:.1} degrees{}",
                    c.mpc,
                    c.mpd_degrees,
                    if c.mpc < femu_correlate::complexity::MPC_WARNING {
                        " (far from real)"
                    } else {
                        ""
                    }
                ))
            );
        }
        if u.modes.iter().any(|m| m.complex) {
            let _ = writeln!(
                s,
                "complex modes are made real: each turned by the phase of its largest component, its real part kept (MPC 1: nothing lost)"
            );
        }
    }
    if !u.functions.is_empty() {
        let _ = writeln!(s, "functions (58/58b): {}", u.functions.len());
    }
    warnings.extend(u.warnings.iter().map(ToString::to_string));
    let mut does = Vec::new();
    if solids > 0 {
        does.push("a model (with a material given on the command line)");
    }
    if !u.modes.is_empty() && u.modes.iter().all(|m| m.values.is_empty()) {
        does.push(FREQUENCIES_ALONE);
    } else if !u.modes.is_empty() {
        does.push("test modes (femu correlate, estimate, expand, update)");
    } else if !u.nodes.is_empty() && solids == 0 {
        does.push("a test wireframe (its nodes' coordinates, for --map), without modes");
    }
    let _ = writeln!(
        s,
        "femu would: {}",
        if does.is_empty() {
            "nothing: no solid mesh and no modes (its functions and geometry are read by femu_io::uff)".to_string()
        } else {
            format!("use it as {}", does.join(" and as "))
        }
    );
    Ok(())
}

/// What [`describe`] says of test modes in JSON or CSV.
fn describe_test_table(path: &Path, json: bool, s: &mut String) -> Result<(), StudyError> {
    let data = if json {
        femu_io::json::read_test_json(path)?
    } else {
        femu_io::csv::read_test_csv(path)?
    };
    let mut nodes: Vec<u64> = data.sensors.iter().map(|s| s.node).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let _ = writeln!(
        s,
        "format: test modes ({})",
        if json { "JSON" } else { "CSV" }
    );
    let _ = writeln!(
        s,
        "modes: {}; Hz: {}",
        data.modes.len(),
        frequencies(&data.modes.frequencies_hz)
    );
    let _ = writeln!(
        s,
        "sensors: {} readings at {} nodes",
        data.sensors.len(),
        nodes.len()
    );
    if data.modes.has_shapes() {
        let _ = writeln!(
            s,
            "femu would: use it as test modes, its node ids being the model's (femu correlate, estimate, expand, update)"
        );
    } else {
        let _ = writeln!(s, "femu would: use it as {FREQUENCIES_ALONE}");
    }
    Ok(())
}
