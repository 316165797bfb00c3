//! The model's own error: how far its mesh is from converged, estimated by solving the same mesh
//! with quadratic elements (every linear element gets straight mid-edge nodes; same materials,
//! same constraints), or for a quadratic mesh the same mesh split once, and pairing the modes by
//! MAC at the original nodes. For a linear mesh that
//! locks in bending (one or two hex8 through a plate's thickness) the difference is the error that
//! updating would otherwise absorb into its parameters; `docs/MATH.md`, "The truth check".

use crate::UpdateError;
use femu_correlate::correlation::mac_matrix;
use femu_correlate::{ModeSet, PairingOptions, Sensor, SensorLayout, pair_modes};
use femu_fem::assembly::{Assembler, MassKind};
use femu_fem::generate::{quadratic_refinement, refine};
use femu_fem::model::Model;
use femu_sparse::eigen::{EigenOptions, Which};
use serde::Serialize;

/// The discretisation error of a model's modes.
#[derive(Debug, Clone, Serialize)]
pub struct DiscretisationEstimate {
    /// What the modes were compared with.
    pub reference: String,
    /// DOFs of the reference.
    pub reference_dofs: usize,
    /// Per model mode (in the order of the modes given): `(f_model - f_reference) / f_reference`,
    /// `None` when no reference mode pairs with it (MAC below 0.8).
    pub relative: Vec<Option<f64>>,
    /// The model modes' frequencies, Hz (the same order).
    pub frequencies_hz: Vec<f64>,
}

/// The largest reference femu builds for the estimate, in DOFs: beyond it the estimate is skipped
/// and said (a quadratic mesh split once has about eight times its nodes).
pub const REFERENCE_DOF_LIMIT: usize = 3_000_000;

/// Why [`estimate`] will not estimate `model`'s discretisation error, when it will not: a
/// quadratic mesh with pyramids (not split), or a reference above [`REFERENCE_DOF_LIMIT`]
/// (its size estimated from the node count).
pub fn not_estimated(model: &Model) -> Option<String> {
    if !model.structural().is_empty() {
        return Some(format!(
            "the model has {} beams, rods, springs or bushings, which femu's refinement does not carry (their own discretisation error: compare with a mesh of more beam elements)",
            model.structural().len()
        ));
    }
    let mesh = model.mesh();
    let quadratic = mesh.elements().all(|e| e.kind.is_quadratic());
    if quadratic
        && mesh
            .elements()
            .any(|e| e.kind == femu_fem::element::ElementKind::Pyramid13)
    {
        return Some("its quadratic mesh has pyramids, which femu does not split (refine it once and compare to know it)".into());
    }
    // nodes of the reference: a split quadratic mesh about 8 times, a linear one with its
    // mid-edge nodes at most 7 times (tetrahedra; about 4 for bricks)
    let factor = if quadratic { 8 } else { 7 };
    let dofs = 3 * factor * mesh.node_count();
    (dofs > REFERENCE_DOF_LIMIT).then(|| {
        format!(
            "its reference ({}) would have about {dofs} DOFs, above femu's limit of {REFERENCE_DOF_LIMIT} for it (refine the model once and compare to know it, or --no-discretisation)",
            if quadratic {
                "the mesh split once"
            } else {
                "the mesh with quadratic elements"
            }
        )
    })
}

/// Estimates the discretisation error of the first modes of `model` (`modes`, the model's own
/// modes, consistent mass) against a finer model of the same structure: a linear (or mixed) mesh
/// with quadratic elements, a quadratic mesh split once (every element in eight, placed by its
/// parent's shape functions: the reference contains the model, so its eigenvalues are lower).
/// `None` where [`not_estimated`] says why. The reference is solved with `eigen`.
///
/// # Errors
/// Building or solving the quadratic model.
pub fn estimate(
    model: &Model,
    modes: &ModeSet,
    eigen: &EigenOptions,
) -> Result<Option<DiscretisationEstimate>, UpdateError> {
    if !model.structural().is_empty() {
        return Ok(None);
    }
    let mesh = model.mesh();
    // a linear (or mixed) mesh against itself with quadratic elements; a quadratic one against
    // itself split once, each child placed by its parent's shape functions
    let quadratic = mesh.elements().all(|e| e.kind.is_quadratic());
    let (refinement, reference_name) = if quadratic {
        if mesh
            .elements()
            .any(|e| e.kind == femu_fem::element::ElementKind::Pyramid13)
        {
            return Ok(None);
        }
        (
            refine(mesh)?,
            "the same mesh split once (each element in eight)",
        )
    } else {
        (
            quadratic_refinement(mesh),
            "the same mesh with quadratic elements",
        )
    };
    let qmesh = refinement.mesh;
    // materials element by element (a child takes its parent's), grouped by material
    let mut by_material: Vec<(femu_fem::material::Material, Vec<u64>)> = Vec::new();
    for (e, p) in refinement.parent.iter().enumerate() {
        let m = model.material_of(*p)?;
        let id = qmesh.element(e).id;
        match by_material.iter_mut().find(|(d, _)| d == m) {
            Some(d) => d.1.push(id),
            None => by_material.push((m.clone(), vec![id])),
        }
    }
    let mut qm = qmesh;
    for (i, (_, ids)) in by_material.iter().enumerate() {
        qm.add_element_set(format!("__femu_discretisation_{i}"), ids)?;
    }
    let mut q = Model::new(qm)?;
    for (i, (m, _)) in by_material.iter().enumerate() {
        q.set_material(Some(&format!("__femu_discretisation_{i}")), m.clone())?;
    }
    // the same point masses, rotations and multipoint constraints (node ids are kept)
    for p in model.point_masses() {
        q.add_point_mass_matrix(mesh.node_id(p.node), p.mass)?;
    }
    for n in model.rotation_nodes() {
        q.add_rotations(mesh.node_id(*n))?;
    }
    for r in model.rigid_masses() {
        q.add_rigid_mass_copy(mesh.node_id(r.node), r)?;
    }
    for which in femu_fem::model::DirectMatrix::ALL {
        let entries: Vec<_> = model
            .direct_entries(which)
            .iter()
            .map(|e| {
                (
                    (mesh.node_id(e.a.0), e.a.1),
                    (mesh.node_id(e.b.0), e.b.1),
                    e.value,
                )
            })
            .collect();
        q.add_direct_entries(which, &entries, "direct input matrix")?;
    }
    let mut dependent: std::collections::HashSet<(u64, usize)> = Default::default();
    for con in model.constraints() {
        let (n, c) = con.dependent;
        let terms: Vec<((u64, usize), f64)> = con
            .terms
            .iter()
            .map(|((m, k), w)| ((mesh.node_id(*m), *k), *w))
            .collect();
        q.add_constraint((mesh.node_id(n), c), &terms, &con.label)?;
        dependent.insert((mesh.node_id(n), c));
    }
    // boundary conditions: the same nodes, and a new node where every original node of its face,
    // edge or cell is fixed; a new node whose original nodes are all dependent follows their
    // interpolation (exact for a rigid link, whose motion is affine)
    let fixed: std::collections::HashSet<(u64, usize)> = model
        .fixed_dofs()
        .map(|(n, c)| (mesh.node_id(n), c))
        .collect();
    let mut extra: Vec<(u64, usize)> = Vec::new();
    // (node, component, the interpolation it follows)
    type Tie = (u64, usize, Vec<((u64, usize), f64)>);
    let mut ties: Vec<Tie> = Vec::new();
    for (i, weights) in &refinement.new_nodes {
        let id = q.mesh().node_id(*i);
        let on: Vec<(u64, f64)> = weights
            .iter()
            .filter(|(_, w)| w.abs() > 1e-12)
            .map(|(n, w)| (mesh.node_id(*n), *w))
            .collect();
        for c in 0..3 {
            if on.iter().all(|(n, _)| fixed.contains(&(*n, c))) {
                extra.push((id, c));
            } else if on.iter().all(|(n, _)| dependent.contains(&(*n, c))) {
                ties.push((id, c, on.iter().map(|(n, w)| ((*n, c), *w)).collect()));
            }
        }
    }
    for (id, c) in fixed.iter().chain(&extra) {
        q.fix_node_dofs(*id, &[*c])?;
    }
    for (id, c, terms) in ties {
        q.add_constraint(
            (id, c),
            &terms,
            &format!("(node {id} of the discretisation reference, interpolated on its parent)"),
        )?;
    }
    let asm = Assembler::new(&q)?;
    let sys = asm.assemble_analysed(&q, MassKind::Consistent)?;
    let count = (modes.len() + 4).min(sys.k.rows());
    let reference = sys.modes(Which::Lowest(count), eigen)?;
    let reference = ModeSet::from_modes(&reference);
    // pair on the original nodes (the model's DOFs and the reference's, same ids), triaxial
    let nodes: Vec<u64> = (0..mesh.node_count()).map(|i| mesh.node_id(i)).collect();
    let model_dofs = model.dof_map()?;
    let sensors: Vec<Sensor> = nodes
        .iter()
        .flat_map(|id| (0..3).map(move |c| Sensor::axis(*id, c)))
        .filter(|s| {
            let c = (0..3).find(|c| s.direction[*c] != 0.0).unwrap_or(0);
            !fixed.contains(&(s.node, c))
        })
        .collect();
    let on_model = SensorLayout::new(mesh, &model_dofs, sensors.clone())?;
    let on_reference = SensorLayout::new(q.mesh(), &sys.dofs, sensors)?;
    let a = on_model.measure_all(modes.shapes.as_ref())?;
    let b = on_reference.measure_all(reference.shapes.as_ref())?;
    let mac = mac_matrix(a.as_ref(), b.as_ref())?;
    let f_model = modes.frequencies_hz();
    let f_ref = reference.frequencies_hz();
    let pairing = pair_modes(mac.as_ref(), &f_model, &f_ref, &PairingOptions::default())?;
    // rigid-body modes (zero frequency) have no relative error
    let relative = (0..modes.len())
        .map(|j| {
            pairing
                .of_test(j)
                .filter(|p| p.f_test > 1e-6 * f_ref.last().copied().unwrap_or(1.0))
                .map(|p| (p.f_test - p.f_model) / p.f_model)
        })
        .collect();
    let f_model = modes.frequencies_hz();
    Ok(Some(DiscretisationEstimate {
        reference: reference_name.into(),
        reference_dofs: sys.k.rows(),
        relative,
        frequencies_hz: f_model,
    }))
}

/// The discretisation error beside the test-analysis difference, per test mode, as a Markdown
/// table with its definitions (the modes paired before updating, as in `check`).
pub fn table(d: &DiscretisationEstimate, check: &crate::TruthCheck) -> String {
    use std::fmt::Write as _;
    let mut s = format!(
        "The model's modes against {} ({} DOF), mode by mode: what the mesh alone gets wrong.\n\n| test | f test (Hz) | f model (Hz) | discretisation (%) |\n|---|---|---|---|\n",
        d.reference, d.reference_dofs
    );
    for m in &check.modes {
        let _ = writeln!(
            s,
            "| {} | {:.1} | {} | {} |",
            m.test,
            m.f_test,
            m.f_before.map_or("unpaired".into(), |f| format!("{f:.1}")),
            m.f_before
                .and_then(|f| d.at_frequency(f))
                .map_or("-".into(), |e| format!("{:+.2}", 100.0 * e))
        );
    }
    s.push_str("\ndiscretisation = (f model - f reference) / f reference for the model mode paired with the test mode.\n");
    s
}

impl DiscretisationEstimate {
    /// The relative error of the model mode at frequency `f_hz` (the one a test mode paired with).
    pub fn at_frequency(&self, f_hz: f64) -> Option<f64> {
        self.frequencies_hz
            .iter()
            .position(|f| (f - f_hz).abs() <= 1e-9 * f_hz.abs().max(1.0))
            .and_then(|j| self.relative.get(j).copied().flatten())
    }
}
