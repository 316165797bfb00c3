//! Parameter groups: `K(p) = K_0 + sum_g p_g K_g`, `M(q) = M_0 + sum_g q_g M_g` (docs/MATH.md,
//! "Updating").
//!
//! A group is a set of elements (an element set, or one element on its own); `K_g`, `M_g` are its
//! assembled element matrices. `p_g = -0.2` means 20 % less stiffness in group `g`. The element
//! matrices are computed once; `K(p)` is written into the values of the fixed pattern, and
//! `K_g x` is formed element by element (SB-EBE's sensitivity columns need nothing more).

use crate::FemError;
use crate::assembly::{Assembler, MassKind, SystemMatrices, element_matrices};
use crate::model::Model;
use femu_sparse::SparseMatrix;
use rayon::prelude::*;

/// How a group's parameter enters its elements' matrices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GroupLaw {
    /// `K(p) = K_0 + p K_g` and `M(q) = M_0 + q M_g`: a factor on the group's stiffness (a
    /// modulus, a spring's stiffness) and, separately, on its mass (a density).
    #[default]
    Scale,
    /// The relative change `p` of the thickness of a group of shells: `t -> t (1 + p)`, with
    /// the membrane, shear and drilling stiffness and the mass `rho t` scaled by `1 + p`, the
    /// bending stiffness and the rotary inertia by `(1 + p)^3`, the non-structural mass kept
    /// (docs/MATH.md, "Thickness parameters"). One parameter moves stiffness and mass; the group
    /// has no separate mass factor.
    Thickness,
    /// A factor `q` on a set of concentrated masses ([`crate::model::MassRef`]): `M(q) = M_0 +
    /// q M_g`, no stiffness (docs/MATH.md, "Mass parameters").
    Mass,
    /// A factor on one part of a set of beams' stiffness
    /// ([`crate::structural::SectionPart`]: `E A`, `G J`, or a bending plane's `E I` with its
    /// shear): `K(p) = K_0 + p K_part`, no mass (docs/MATH.md, "Beam section parameters").
    Section(crate::structural::SectionPart),
}

/// A named set of elements (internal indices) whose stiffness and mass are scaled together.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParameterGroup {
    /// Name: the element set's name, or `"E<id>"` for a single element; `"EI1:<set>"` (and
    /// `EA:`, `GJ:`, `EI2:`) for a part of its beams' stiffness; `"t:<set>"` for the
    /// thickness of a set's shells.
    pub name: String,
    /// Internal indices of solid elements.
    pub elements: Vec<usize>,
    /// Indices of structural elements (beams, rods, springs, bushings, shells;
    /// [`Model::structural`]): a spring's or bushing's stiffness, a beam's or shell's modulus.
    pub structural: Vec<usize>,
    /// Concentrated masses (a [`GroupLaw::Mass`] group's).
    pub masses: Vec<crate::model::MassRef>,
    /// How the group's parameter acts.
    pub law: GroupLaw,
}

impl ParameterGroup {
    /// A group of solid elements.
    pub fn solids(name: impl Into<String>, elements: Vec<usize>) -> Self {
        Self {
            name: name.into(),
            elements,
            structural: Vec::new(),
            masses: Vec::new(),
            law: GroupLaw::Scale,
        }
    }

    /// The thickness of the shells `structural` (indices in [`Model::structural`]), named
    /// `name`.
    pub fn thickness(name: impl Into<String>, structural: Vec<usize>) -> Self {
        Self {
            name: name.into(),
            elements: Vec::new(),
            structural,
            masses: Vec::new(),
            law: GroupLaw::Thickness,
        }
    }

    /// One section part of the two-node beams `structural` (indices in [`Model::structural`]),
    /// named `name` ([`GroupLaw::Section`]).
    pub fn section(
        name: impl Into<String>,
        part: crate::structural::SectionPart,
        structural: Vec<usize>,
    ) -> Self {
        Self {
            name: name.into(),
            elements: Vec::new(),
            structural,
            masses: Vec::new(),
            law: GroupLaw::Section(part),
        }
    }

    /// The concentrated masses `masses`, named `name` ([`GroupLaw::Mass`]).
    pub fn masses(name: impl Into<String>, masses: Vec<crate::model::MassRef>) -> Self {
        Self {
            name: name.into(),
            elements: Vec::new(),
            structural: Vec::new(),
            masses,
            law: GroupLaw::Mass,
        }
    }
}

/// The prefix of a thickness group's name: `"t:SKIN"` is the thickness of set `SKIN`'s shells.
pub const THICKNESS_PREFIX: &str = "t:";

/// A concentrated mass's points (the DOF map's) and its mass matrix, row-major; or a beam's
/// points and the stiffness of a section part.
type MassItem = (Vec<usize>, Vec<f64>);

/// A shell's matrices split by their order in the thickness
/// ([`crate::structural::StructuralElement::thickness_parts`]).
#[derive(Debug, Clone)]
struct ThicknessParts {
    k1: Vec<f64>,
    m1: Vec<f64>,
    k3: Vec<f64>,
    m3: Vec<f64>,
}

/// Parameter groups with their element matrices, on a model's pattern.
#[derive(Debug, Clone)]
pub struct ParameterGroups {
    groups: Vec<ParameterGroup>,
    mass_kind: MassKind,
    /// slot of each mesh element, `usize::MAX` if in no group
    slot: Vec<usize>,
    /// slot of each structural element, `usize::MAX` if in no group
    structural_slot: Vec<usize>,
    /// the DOF map's points of each slot (solid elements: their nodes)
    points: Vec<Vec<usize>>,
    slot_offset: Vec<usize>,
    ke: Vec<f64>,
    me: Vec<f64>,
    /// The thickness parts of each slot in a thickness group (`None` elsewhere).
    thickness: Vec<Option<Box<ThicknessParts>>>,
    /// Per group, the points and mass matrix of each of its concentrated masses (a
    /// [`GroupLaw::Mass`] group's; empty for the others).
    mass_items: Vec<Vec<MassItem>>,
    /// Per group, the points and section-part stiffness of each of its beams (a
    /// [`GroupLaw::Section`] group's; empty for the others).
    section_items: Vec<Vec<MassItem>>,
    /// Groups given as assembled matrices instead of elements ([`ParameterGroups::from_matrices`]).
    matrices: Option<MatrixGroups>,
}

/// Groups given as assembled `K_g`, `M_g` on the free DOFs (another solver's), with where each
/// entry lands in the nominal stiffness pattern.
#[derive(Debug, Clone)]
struct MatrixGroups {
    k: Vec<SparseMatrix>,
    m: Vec<SparseMatrix>,
    /// For each group, the index in the nominal `K`'s values of each entry of `K_g`, then of `M_g`.
    k_at: Vec<Vec<usize>>,
    m_at: Vec<Vec<usize>>,
    /// For a lumped nominal `M`: the index in its values of each (diagonal) entry of `M_g`.
    m_lumped_at: Vec<Vec<usize>>,
    /// The translational mass of each group, kg.
    mass: Vec<f64>,
    /// The free DOFs each group touches, sorted.
    dofs: Vec<Vec<usize>>,
}

/// The value index in `pattern` of each stored entry of `a`; `None` at the first entry `pattern`
/// lacks, with its row and column.
fn positions(pattern: &SparseMatrix, a: &SparseMatrix) -> Result<Vec<usize>, (usize, usize)> {
    let ptr = pattern.indptr();
    let ptr = ptr.raw_storage();
    let rows = pattern.indices();
    femu_sparse::csc::entries(a)
        .map(|(i, j, _)| {
            rows[ptr[j]..ptr[j + 1]]
                .binary_search(&i)
                .map(|k| ptr[j] + k)
                .map_err(|_| (i, j))
        })
        .collect()
}

/// `base`'s mass as values on its stiffness pattern (zeros where the mass has no entry).
fn mass_on_stiffness_pattern(base: &SystemMatrices) -> Result<Vec<f64>, FemError> {
    let mut m_on_k = vec![0.0; base.k.nnz()];
    femu_sparse::csc::for_entries_within(&base.k, &base.m, |pm, pk| {
        m_on_k[pk] = base.m.data()[pm];
    })
    .map_err(|_| FemError::LengthMismatch {
        what: "base mass pattern inside the stiffness pattern",
        expected: base.k.nnz(),
        got: base.m.nnz(),
    })?;
    Ok(m_on_k)
}

/// `t^T M t` for the unit translation `t` along x of every node (the free x DOFs): the mass that
/// moves with the structure along x, kg.
pub fn translational_mass(m: &SparseMatrix, dofs: &crate::dof::DofMap) -> f64 {
    let along_x: Vec<bool> = (0..dofs.free_count())
        .map(|f| {
            let (p, c) = dofs.free_dof(f);
            c == 0 && !dofs.point_node(p).1
        })
        .collect();
    femu_sparse::csc::entries(m)
        .filter(|(i, j, _)| along_x[*i] && along_x[*j])
        .map(|(_, _, v)| v)
        .sum()
}

/// The group a set name stands for: the set's elements scaled, or with [`THICKNESS_PREFIX`]
/// the thickness of its shells; a mass set's masses ([`Model::mass_set`]) scaled.
///
/// # Errors
/// [`FemError::UnknownElementSet`].
pub fn group_of_set(model: &Model, name: &str) -> Result<ParameterGroup, FemError> {
    for part in crate::structural::SectionPart::ALL {
        if let Some(set) = name.strip_prefix(part.prefix()) {
            let (elements, structural) = model.element_set_members(set)?;
            let mut g = ParameterGroup::section(name, part, structural);
            g.elements = elements;
            return Ok(g);
        }
    }
    if let Some(set) = name.strip_prefix(THICKNESS_PREFIX) {
        let (elements, structural) = model.element_set_members(set)?;
        let mut g = ParameterGroup::thickness(name, structural);
        g.elements = elements;
        return Ok(g);
    }
    if let Some(masses) = model.mass_set(name)
        && !model.element_set_names().iter().any(|s| s == name)
    {
        return Ok(ParameterGroup::masses(name, masses.to_vec()));
    }
    let (elements, structural) = model.element_set_members(name)?;
    Ok(ParameterGroup {
        name: name.into(),
        elements,
        structural,
        masses: Vec::new(),
        law: GroupLaw::Scale,
    })
}

impl ParameterGroups {
    /// Groups given as assembled matrices on `base`'s free DOFs (another solver's, read whole):
    /// `K_g` and `M_g` of each named group, whose entries must lie in `base`'s stiffness pattern
    /// (and, for a lumped `base` mass, `M_g` on its diagonal). No element is involved: the products
    /// and `K(p)` are formed from the matrices.
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`] for a size that is not `base`'s, an entry outside the pattern
    /// (its row and column), or a group without an entry.
    pub fn from_matrices(
        base: &SystemMatrices,
        groups: Vec<(String, SparseMatrix, SparseMatrix)>,
    ) -> Result<Self, FemError> {
        let n = base.k.rows();
        let mut mg = MatrixGroups {
            k: Vec::new(),
            m: Vec::new(),
            k_at: Vec::new(),
            m_at: Vec::new(),
            m_lumped_at: Vec::new(),
            mass: Vec::new(),
            dofs: Vec::new(),
        };
        let mut named = Vec::new();
        let lumped = base.mass_kind == MassKind::Lumped;
        for (name, k, m) in groups {
            let bad = |reason: String| FemError::InvalidGroup {
                name: name.clone(),
                reason,
            };
            for (what, a) in [("stiffness", &k), ("mass", &m)] {
                if a.rows() != n || a.cols() != n {
                    return Err(bad(format!(
                        "its {what} is {} x {}, the model's {n} x {n}",
                        a.rows(),
                        a.cols()
                    )));
                }
            }
            if k.nnz() == 0 && m.nnz() == 0 {
                return Err(bad(
                    "its stiffness and mass are zero: it changes nothing".into()
                ));
            }
            let outside = |what: &str, (i, j): (usize, usize)| {
                bad(format!(
                    "its {what} has an entry at row {} and column {} where the model's stiffness has none",
                    i + 1,
                    j + 1
                ))
            };
            mg.k_at
                .push(positions(&base.k, &k).map_err(|e| outside("stiffness", e))?);
            mg.m_at
                .push(positions(&base.k, &m).map_err(|e| outside("mass", e))?);
            mg.m_lumped_at.push(if lumped {
                positions(&base.m, &m).map_err(|(i, j)| {
                    bad(format!(
                        "its mass has an entry at row {} and column {} off the model's lumped (diagonal) mass",
                        i + 1,
                        j + 1
                    ))
                })?
            } else {
                Vec::new()
            });
            let mut dofs: Vec<usize> = femu_sparse::csc::entries(&k)
                .chain(femu_sparse::csc::entries(&m))
                .flat_map(|(i, j, _)| [i, j])
                .collect();
            dofs.sort_unstable();
            dofs.dedup();
            mg.dofs.push(dofs);
            mg.mass.push(translational_mass(&m, &base.dofs));
            mg.k.push(k);
            mg.m.push(m);
            named.push(ParameterGroup::solids(name, Vec::new()));
        }
        Ok(Self {
            groups: named,
            mass_kind: base.mass_kind,
            slot: Vec::new(),
            structural_slot: Vec::new(),
            points: Vec::new(),
            slot_offset: Vec::new(),
            ke: Vec::new(),
            me: Vec::new(),
            thickness: Vec::new(),
            mass_items: Vec::new(),
            section_items: Vec::new(),
            matrices: Some(mg),
        })
    }

    /// Whether the groups are assembled matrices ([`ParameterGroups::from_matrices`]) rather than
    /// element sets.
    pub fn from_assembled_matrices(&self) -> bool {
        self.matrices.is_some()
    }

    /// Groups given explicitly. Element matrices are computed in parallel for every element in
    /// some group; `mass_kind` must match the system mass they will be added to.
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`] for an empty group or an element index out of range, and the
    /// errors of element computation.
    pub fn new(
        model: &Model,
        groups: Vec<ParameterGroup>,
        mass_kind: MassKind,
    ) -> Result<Self, FemError> {
        let ne = model.mesh().element_count();
        let ns = model.structural().len();
        let mut slot = vec![usize::MAX; ne];
        let mut structural_slot = vec![usize::MAX; ns];
        let mut slot_element = Vec::new();
        let mut slot_structural = Vec::new();
        for g in &groups {
            if g.elements.is_empty() && g.structural.is_empty() && g.masses.is_empty() {
                return Err(FemError::InvalidGroup {
                    name: g.name.clone(),
                    reason: "no elements".into(),
                });
            }
            if (g.law == GroupLaw::Mass) != g.masses.is_empty() {
                // a mass group holds masses only; masses belong in a mass group
            } else {
                return Err(FemError::InvalidGroup {
                    name: g.name.clone(),
                    reason: if g.law == GroupLaw::Mass {
                        "a mass group has no masses".into()
                    } else {
                        "concentrated masses are updated in a mass group of their own".into()
                    },
                });
            }
            if g.law == GroupLaw::Mass && !(g.elements.is_empty() && g.structural.is_empty()) {
                return Err(FemError::InvalidGroup {
                    name: g.name.clone(),
                    reason: "a mass group holds masses, not elements".into(),
                });
            }
            if g.law == GroupLaw::Thickness {
                let bad = |reason: String| FemError::InvalidGroup {
                    name: g.name.clone(),
                    reason,
                };
                if let Some(&e) = g.elements.first() {
                    let which = if e < ne {
                        format!("solid element {}", model.mesh().element(e).id)
                    } else {
                        format!("solid element index {e} (out of range)")
                    };
                    return Err(bad(format!(
                        "a thickness applies to shells; {which} has none"
                    )));
                }
                for &e in &g.structural {
                    let el = model
                        .structural()
                        .get(e)
                        .ok_or_else(|| bad(format!("structural element index {e} out of range")))?;
                    if !matches!(el.kind, crate::structural::StructuralKind::Shell(_)) {
                        return Err(bad(format!(
                            "a thickness applies to shells; element {} is a {}",
                            el.id,
                            el.kind.name()
                        )));
                    }
                }
            }
            if let (GroupLaw::Section(_), Some(&e)) = (g.law, g.elements.first()) {
                return Err(FemError::InvalidGroup {
                    name: g.name.clone(),
                    reason: format!(
                        "a section parameter applies to beams; solid element {} has no section",
                        model.mesh().element(e.min(ne.saturating_sub(1))).id
                    ),
                });
            }
            for &e in &g.elements {
                if e >= ne {
                    return Err(FemError::InvalidGroup {
                        name: g.name.clone(),
                        reason: format!("element index {e} out of range"),
                    });
                }
                if slot[e] == usize::MAX {
                    slot[e] = slot_element.len();
                    slot_element.push(e);
                }
            }
            for &e in &g.structural {
                if e >= ns {
                    return Err(FemError::InvalidGroup {
                        name: g.name.clone(),
                        reason: format!("structural element index {e} out of range"),
                    });
                }
                if structural_slot[e] == usize::MAX {
                    structural_slot[e] = slot_element.len() + slot_structural.len();
                    slot_structural.push(e);
                }
            }
        }
        let mats: Vec<(Vec<f64>, Vec<f64>)> = slot_element
            .par_iter()
            .map(|e| element_matrices(model, *e, mass_kind))
            .collect::<Result<_, _>>()?;
        let mut points: Vec<Vec<usize>> = slot_element
            .iter()
            .map(|e| model.mesh().element(*e).nodes.to_vec())
            .collect();
        let mut slot_offset = Vec::with_capacity(mats.len() + slot_structural.len() + 1);
        slot_offset.push(0);
        let (mut ke, mut me) = (Vec::new(), Vec::new());
        for (k, m) in mats {
            ke.extend_from_slice(&k);
            me.extend_from_slice(&m);
            slot_offset.push(ke.len());
        }
        let mut thickness: Vec<Option<Box<ThicknessParts>>> = vec![None; slot_offset.len() - 1];
        if !slot_structural.is_empty() {
            let dofs = model.dof_map()?;
            let thick: std::collections::HashSet<usize> = groups
                .iter()
                .filter(|g| g.law == GroupLaw::Thickness)
                .flat_map(|g| g.structural.iter().copied())
                .collect();
            let coords = model.mesh().coords();
            for &e in &slot_structural {
                let el = &model.structural()[e];
                let sm = el.matrices(coords, mass_kind)?;
                points.push(crate::assembly::structural_points(&dofs, &sm.parts));
                ke.extend_from_slice(&sm.k);
                me.extend_from_slice(&sm.m);
                slot_offset.push(ke.len());
                thickness.push(if thick.contains(&e) {
                    el.thickness_parts(coords, mass_kind)?.map(|[l, c]| {
                        Box::new(ThicknessParts {
                            k1: l.k,
                            m1: l.m,
                            k3: c.k,
                            m3: c.m,
                        })
                    })
                } else {
                    None
                });
            }
        }
        let mass_items = mass_group_items(model, &groups)?;
        let section_items = section_group_items(model, &groups)?;
        Ok(Self {
            groups,
            mass_kind,
            slot,
            structural_slot,
            points,
            slot_offset,
            ke,
            me,
            thickness,
            mass_items,
            section_items,
            matrices: None,
        })
    }

    /// One group per element, named `"E<element id>"` (element-by-element updating).
    ///
    /// # Errors
    /// As [`ParameterGroups::new`].
    pub fn elementwise(model: &Model, mass_kind: MassKind) -> Result<Self, FemError> {
        let mut groups: Vec<ParameterGroup> = model
            .mesh()
            .elements()
            .map(|el| ParameterGroup::solids(format!("E{}", el.id), vec![el.index]))
            .collect();
        groups.extend(
            model
                .structural()
                .iter()
                .enumerate()
                .map(|(i, s)| ParameterGroup {
                    name: format!("E{}", s.id),
                    elements: Vec::new(),
                    structural: vec![i],
                    masses: Vec::new(),
                    law: GroupLaw::Scale,
                }),
        );
        Self::new(model, groups, mass_kind)
    }

    /// One group per named element set (its solid and its structural elements:
    /// [`Model::element_set_members`]); a name `"t:SET"` ([`THICKNESS_PREFIX`]) is the
    /// thickness of set `SET`'s shells ([`GroupLaw::Thickness`]), `"EA:SET"`, `"GJ:SET"`,
    /// `"EI1:SET"`, `"EI2:SET"` a part of its beams' stiffness ([`GroupLaw::Section`]).
    ///
    /// # Errors
    /// [`FemError::UnknownElementSet`], and as [`ParameterGroups::new`].
    pub fn from_element_sets(
        model: &Model,
        sets: &[&str],
        mass_kind: MassKind,
    ) -> Result<Self, FemError> {
        let groups = sets
            .iter()
            .map(|s| group_of_set(model, s))
            .collect::<Result<_, FemError>>()?;
        Self::new(model, groups, mass_kind)
    }

    /// Number of groups.
    pub fn len(&self) -> usize {
        self.groups.len()
    }

    /// Whether there are no groups.
    pub fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }

    /// The groups.
    pub fn groups(&self) -> &[ParameterGroup] {
        &self.groups
    }

    fn slot_slices(&self, s: usize) -> (&[usize], &[f64], &[f64]) {
        let r = self.slot_offset[s]..self.slot_offset[s + 1];
        (&self.points[s], &self.ke[r.clone()], &self.me[r])
    }

    /// The points, stiffness and mass of each element of a group, solid and structural.
    fn items<'a>(
        &'a self,
        group: &'a ParameterGroup,
    ) -> impl Iterator<Item = (&'a [usize], &'a [f64], &'a [f64])> + 'a {
        group
            .elements
            .iter()
            .map(|&e| self.slot[e])
            .chain(group.structural.iter().map(|&e| self.structural_slot[e]))
            .map(|s| self.slot_slices(s))
    }

    /// The points and thickness parts of each shell of a thickness group.
    fn thickness_items<'a>(
        &'a self,
        group: &'a ParameterGroup,
    ) -> impl Iterator<Item = (&'a [usize], &'a ThicknessParts)> + 'a {
        group.structural.iter().filter_map(|&e| {
            let s = self.structural_slot[e];
            self.thickness[s]
                .as_deref()
                .map(|t| (&self.points[s][..], t))
        })
    }

    fn check_group(&self, g: usize) -> Result<&ParameterGroup, FemError> {
        self.groups.get(g).ok_or_else(|| FemError::InvalidGroup {
            name: format!("#{g}"),
            reason: format!("only {} groups", self.len()),
        })
    }

    /// `y += dK/dp_g x` (stiffness) or `y += dM/dp_g x` (mass) at `p_g = at`, on free-DOF
    /// vectors: `K_g x` or `M_g x` for a [`GroupLaw::Scale`] group (whatever `at`), `(K_1 +
    /// 3 (1 + at)^2 K_3) x` or its mass's for a thickness group.
    #[allow(clippy::too_many_arguments)]
    fn product(
        &self,
        asm: &Assembler,
        g: usize,
        mass: bool,
        at: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        let n = match &self.matrices {
            Some(mg) => mg.k.first().map_or(0, |k| k.rows()),
            None => asm.dofs().free_count(),
        };
        for (what, len) in [("x in K_g x", x.len()), ("y in K_g x", y.len())] {
            if len != n {
                return Err(FemError::LengthMismatch {
                    what,
                    expected: n,
                    got: len,
                });
            }
        }
        let group = self.check_group(g)?;
        if let Some(mg) = &self.matrices {
            let a = if mass { &mg.m[g] } else { &mg.k[g] };
            for (i, j, v) in femu_sparse::csc::entries(a) {
                y[i] += v * x[j];
            }
            return Ok(());
        }
        let dm = asm.dofs();
        let mut xe = Vec::with_capacity(60);
        match group.law {
            GroupLaw::Scale => {
                for (nodes, ke, me) in self.items(group) {
                    let a = if mass { me } else { ke };
                    element_product(dm, nodes, a, 1.0, x, y, &mut xe);
                }
            }
            GroupLaw::Thickness => {
                let cubic = 3.0 * (1.0 + at) * (1.0 + at);
                for (nodes, t) in self.thickness_items(group) {
                    let (a1, a3) = if mass { (&t.m1, &t.m3) } else { (&t.k1, &t.k3) };
                    element_product(dm, nodes, a1, 1.0, x, y, &mut xe);
                    element_product(dm, nodes, a3, cubic, x, y, &mut xe);
                }
            }
            GroupLaw::Mass => {
                if mass {
                    for (points, a) in &self.mass_items[g] {
                        element_product(dm, points, a, 1.0, x, y, &mut xe);
                    }
                }
            }
            GroupLaw::Section(_) => {
                if !mass {
                    for (points, a) in &self.section_items[g] {
                        element_product(dm, points, a, 1.0, x, y, &mut xe);
                    }
                }
            }
        }
        Ok(())
    }

    /// `y += dK/dp_g x` at `p_g = at`: `K_g x` for a group that scales its elements' stiffness,
    /// `(K_1 + 3 (1 + at)^2 K_3) x` for a thickness group ([`GroupLaw::Thickness`]); the
    /// derivative of the residual `(K(p) - lambda M) x` that SB-EBE's Gauss-Newton steps use
    /// at the current parameters.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] or [`FemError::InvalidGroup`].
    pub fn stiffness_derivative_product(
        &self,
        asm: &Assembler,
        g: usize,
        at: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        self.product(asm, g, false, at, x, y)
    }

    /// `y += dM/dp_g x` at `p_g = at`: `M_g x` for a mass factor, `(M_1 + 3 (1 + at)^2 M_3) x`
    /// for a thickness group.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] or [`FemError::InvalidGroup`].
    pub fn mass_derivative_product(
        &self,
        asm: &Assembler,
        g: usize,
        at: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        self.product(asm, g, true, at, x, y)
    }

    /// `y += K_g(at) x`: group `g`'s own stiffness at `p_g = at`, `(1 + at) K_g x` for a group
    /// that scales its elements, `((1 + at) K_1 + (1 + at)^3 K_3) x` for a thickness group, nothing
    /// for a mass group (the stiffness a per-group loss factor damps, docs/MATH.md, "Updating from
    /// frequency responses").
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] or [`FemError::InvalidGroup`].
    pub fn stiffness_now_product(
        &self,
        asm: &Assembler,
        g: usize,
        at: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        match self.check_group(g)?.law {
            GroupLaw::Mass => Ok(()),
            GroupLaw::Scale | GroupLaw::Section(_) => {
                let mut z = vec![0.0; y.len()];
                self.product(asm, g, false, at, x, &mut z)?;
                for (a, b) in y.iter_mut().zip(&z) {
                    *a += (1.0 + at) * b;
                }
                Ok(())
            }
            GroupLaw::Thickness => {
                let (n, dm) = (asm.dofs().free_count(), asm.dofs());
                if x.len() != n || y.len() != n {
                    return Err(FemError::LengthMismatch {
                        what: "x and y in K_g x",
                        expected: n,
                        got: x.len().min(y.len()),
                    });
                }
                let (c1, c3) = (1.0 + at, (1.0 + at).powi(3));
                let mut xe = Vec::with_capacity(60);
                for (nodes, t) in self.thickness_items(&self.groups[g]) {
                    element_product(dm, nodes, &t.k1, c1, x, y, &mut xe);
                    element_product(dm, nodes, &t.k3, c3, x, y, &mut xe);
                }
                Ok(())
            }
        }
    }

    /// `values += c K_g(at)` on the stiffness pattern of `asm` (the values of `K` as the assembly
    /// stores them): group `g`'s own stiffness at `p_g = at`, as
    /// [`ParameterGroups::stiffness_now_product`] applies it.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] for `values` of another length than the pattern's,
    /// [`FemError::InvalidGroup`].
    pub fn add_stiffness_now(
        &self,
        asm: &Assembler,
        g: usize,
        at: f64,
        c: f64,
        values: &mut [f64],
    ) -> Result<(), FemError> {
        let group = self.check_group(g)?;
        if let Some(mg) = &self.matrices {
            if mg.k_at[g].iter().any(|&i| i >= values.len()) {
                return Err(FemError::LengthMismatch {
                    what: "stiffness values against the group's matrix",
                    expected: values.len(),
                    got: mg.k_at[g].iter().max().map_or(0, |m| m + 1),
                });
            }
            for (i, v) in mg.k_at[g].iter().zip(mg.k[g].data()) {
                values[*i] += c * (1.0 + at) * v;
            }
            return Ok(());
        }
        if values.len() != asm.nnz() {
            return Err(FemError::LengthMismatch {
                what: "stiffness values",
                expected: asm.nnz(),
                got: values.len(),
            });
        }
        match group.law {
            GroupLaw::Mass => {}
            GroupLaw::Scale => {
                for (nodes, ke, _) in self.items(group) {
                    asm.scatter(nodes, |i, l, w| values[i] += c * (1.0 + at) * w * ke[l]);
                }
            }
            GroupLaw::Section(_) => {
                for (nodes, ke) in &self.section_items[g] {
                    asm.scatter(nodes, |i, l, w| values[i] += c * (1.0 + at) * w * ke[l]);
                }
            }
            GroupLaw::Thickness => {
                let (c1, c3) = (c * (1.0 + at), c * (1.0 + at).powi(3));
                for (nodes, t) in self.thickness_items(group) {
                    asm.scatter(nodes, |i, l, w| {
                        values[i] += w * (c1 * t.k1[l] + c3 * t.k3[l])
                    });
                }
            }
        }
        Ok(())
    }

    /// The law of group `g`'s parameter.
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`].
    pub fn law(&self, g: usize) -> Result<GroupLaw, FemError> {
        Ok(self.check_group(g)?.law)
    }

    /// `y += K_g x` for group `g` (free-DOF vectors): the SB-EBE sensitivity column of docs/MATH.md
    /// (for a thickness group, the derivative at the nominal thickness).
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] or [`FemError::InvalidGroup`].
    pub fn stiffness_product(
        &self,
        model: &Model,
        asm: &Assembler,
        g: usize,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        let _ = model;
        self.product(asm, g, false, 0.0, x, y)
    }

    /// `y += M_g x` for group `g`.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] or [`FemError::InvalidGroup`].
    pub fn mass_product(
        &self,
        model: &Model,
        asm: &Assembler,
        g: usize,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<(), FemError> {
        let _ = model;
        self.product(asm, g, true, 0.0, x, y)
    }

    /// Writes `K(p) = K_0 + sum_g p_g K_g` and `M(q) = M_0 + sum_g q_g M_g` into `out`, whose
    /// `K` must have `base`'s pattern (a clone of `base` the first time, then reused: `K`, and a
    /// lumped `M`, are written in place). The consistent `M(q)` is formed on `K`'s pattern and
    /// stored anew without its exact zeros, as the assembly stores it.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`] for `p`, `q` or a pattern that is not the assembler's.
    pub fn write_parameterized(
        &self,
        _model: &Model,
        asm: &Assembler,
        base: &SystemMatrices,
        p: &[f64],
        q: &[f64],
        out: &mut SystemMatrices,
    ) -> Result<(), FemError> {
        for (what, len) in [
            ("stiffness parameters p", p.len()),
            ("mass parameters q", q.len()),
        ] {
            if len != self.len() {
                return Err(FemError::LengthMismatch {
                    what,
                    expected: self.len(),
                    got: len,
                });
            }
        }
        // the consistent M is made anew (below), without its zeros: its pattern may change
        let lumped = self.mass_kind == MassKind::Lumped;
        for (what, a, b, check) in [
            ("K pattern", &base.k, &out.k, true),
            ("M pattern", &base.m, &out.m, lumped),
        ] {
            if check && (a.nnz() != b.nnz() || a.indptr().raw_storage() != b.indptr().raw_storage())
            {
                return Err(FemError::LengthMismatch {
                    what,
                    expected: a.nnz(),
                    got: b.nnz(),
                });
            }
        }
        if let Some(mg) = &self.matrices {
            return self.write_matrix_groups(mg, base, p, q, out);
        }
        if base.k.nnz() != asm.nnz() || base.mass_kind != self.mass_kind {
            return Err(FemError::LengthMismatch {
                what: "base matrices against the assembler",
                expected: asm.nnz(),
                got: base.k.nnz(),
            });
        }
        out.k.data_mut().copy_from_slice(base.k.data());
        // the consistent mass on K's pattern while the groups are added, then without its zeros
        let mut m_on_k = Vec::new();
        if lumped {
            out.m.data_mut().copy_from_slice(base.m.data());
        } else {
            m_on_k = mass_on_stiffness_pattern(base)?;
        }
        for (g, group) in self.groups.iter().enumerate() {
            if group.law == GroupLaw::Mass {
                if p[g] != 0.0 {
                    return Err(FemError::InvalidGroup {
                        name: group.name.clone(),
                        reason: format!("a mass group has no stiffness factor (p = {})", p[g]),
                    });
                }
                if q[g] == 0.0 {
                    continue;
                }
                for (points, a) in &self.mass_items[g] {
                    let target = MassTarget::of(self.mass_kind, &mut m_on_k, &mut out.m);
                    add_scaled_mass(asm, target, points, a, q[g]);
                }
                continue;
            }
            if group.law == GroupLaw::Thickness {
                if q[g] != 0.0 {
                    return Err(FemError::InvalidGroup {
                        name: group.name.clone(),
                        reason: format!(
                            "a thickness group has no mass factor (q = {}): its thickness moves its mass",
                            q[g]
                        ),
                    });
                }
                if p[g] == 0.0 {
                    continue;
                }
                let (c1, c3) = (p[g], (1.0 + p[g]).powi(3) - 1.0);
                for (nodes, t) in self.thickness_items(group) {
                    let kd = out.k.data_mut();
                    asm.scatter(nodes, |i, l, w| kd[i] += w * (c1 * t.k1[l] + c3 * t.k3[l]));
                    for (part, c) in [(&t.m1, c1), (&t.m3, c3)] {
                        let target = MassTarget::of(self.mass_kind, &mut m_on_k, &mut out.m);
                        add_scaled_mass(asm, target, nodes, part, c);
                    }
                }
                continue;
            }
            if let GroupLaw::Section(_) = group.law {
                if q[g] != 0.0 {
                    return Err(FemError::InvalidGroup {
                        name: group.name.clone(),
                        reason: format!(
                            "a section parameter moves a stiffness alone (q = {})",
                            q[g]
                        ),
                    });
                }
                if p[g] != 0.0 {
                    for (nodes, ke) in &self.section_items[g] {
                        let kd = out.k.data_mut();
                        asm.scatter(nodes, |i, l, w| kd[i] += p[g] * w * ke[l]);
                    }
                }
                continue;
            }
            for (nodes, ke, me) in self.items(group) {
                if p[g] != 0.0 {
                    let kd = out.k.data_mut();
                    asm.scatter(nodes, |i, l, w| kd[i] += p[g] * w * ke[l]);
                }
                if q[g] != 0.0 {
                    let target = MassTarget::of(self.mass_kind, &mut m_on_k, &mut out.m);
                    add_scaled_mass(asm, target, nodes, me, q[g]);
                }
            }
        }
        if !lumped {
            out.m = asm.without_zeros(&m_on_k);
        }
        Ok(())
    }

    /// [`ParameterGroups::write_parameterized`] for groups given as matrices.
    fn write_matrix_groups(
        &self,
        mg: &MatrixGroups,
        base: &SystemMatrices,
        p: &[f64],
        q: &[f64],
        out: &mut SystemMatrices,
    ) -> Result<(), FemError> {
        if base.mass_kind != self.mass_kind || mg.k_at.iter().flatten().any(|&i| i >= base.k.nnz())
        {
            return Err(FemError::LengthMismatch {
                what: "base matrices against the groups' matrices",
                expected: base.k.nnz(),
                got: out.k.nnz(),
            });
        }
        out.k.data_mut().copy_from_slice(base.k.data());
        for (g, k) in mg.k.iter().enumerate() {
            if p[g] != 0.0 {
                let kd = out.k.data_mut();
                for (at, v) in mg.k_at[g].iter().zip(k.data()) {
                    kd[*at] += p[g] * v;
                }
            }
        }
        if self.mass_kind == MassKind::Lumped {
            out.m.data_mut().copy_from_slice(base.m.data());
            for (g, m) in mg.m.iter().enumerate() {
                if q[g] != 0.0 {
                    let md = out.m.data_mut();
                    for (at, v) in mg.m_lumped_at[g].iter().zip(m.data()) {
                        md[*at] += q[g] * v;
                    }
                }
            }
            return Ok(());
        }
        let mut m_on_k = mass_on_stiffness_pattern(base)?;
        for (g, m) in mg.m.iter().enumerate() {
            if q[g] != 0.0 {
                for (at, v) in mg.m_at[g].iter().zip(m.data()) {
                    m_on_k[*at] += q[g] * v;
                }
            }
        }
        out.m = femu_sparse::csc::without_zeros_of(
            (base.k.rows(), base.k.cols()),
            base.k.indptr().raw_storage(),
            base.k.indices(),
            &m_on_k,
        );
        Ok(())
    }

    /// `K(p)` and `M(q)` as new matrices on `base`'s pattern; see
    /// [`ParameterGroups::write_parameterized`] to reuse storage in a loop.
    ///
    /// # Errors
    /// As [`ParameterGroups::write_parameterized`].
    pub fn parameterized(
        &self,
        model: &Model,
        asm: &Assembler,
        base: &SystemMatrices,
        p: &[f64],
        q: &[f64],
    ) -> Result<SystemMatrices, FemError> {
        let mut out = base.clone();
        self.write_parameterized(model, asm, base, p, q, &mut out)?;
        Ok(out)
    }

    /// The mass of group `g` in kg (the sum of the translational x-x entries of its element masses,
    /// `rho V` for consistent and lumped mass alike): the weights of SB-EBE's total-mass guard.
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`].
    pub fn group_mass(&self, model: &Model, g: usize) -> Result<f64, FemError> {
        let group = self.check_group(g)?;
        if let Some(mg) = &self.matrices {
            return Ok(mg.mass[g]);
        }
        let mut total = 0.0;
        let nodes = model.mesh().node_count();
        // a thickness group's mass that moves with its parameter: rho t, not the NSM
        let items: Vec<(&[usize], &[f64])> = match group.law {
            GroupLaw::Scale => self.items(group).map(|(p, _, m)| (p, m)).collect(),
            GroupLaw::Mass => self.mass_items[g]
                .iter()
                .map(|(p, m)| (&p[..], &m[..]))
                .collect(),
            GroupLaw::Thickness => self
                .thickness_items(group)
                .map(|(p, t)| (p, &t.m1[..]))
                .collect(),
            // a section part moves no mass
            GroupLaw::Section(_) => Vec::new(),
        };
        for (points, me) in items {
            let nn = points.len();
            let nd = 3 * nn;
            // translations only: a structural element's rotation points hold rotary inertia
            let moving: Vec<usize> = (0..nn).filter(|a| points[*a] < nodes).collect();
            for &a in &moving {
                for &b in &moving {
                    total += me[3 * a * nd + 3 * b];
                }
            }
        }
        Ok(total)
    }

    /// The free DOFs touched by group `g`, sorted: where `K_g x` and `M_g x` can be non-zero.
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`].
    pub fn group_dofs(
        &self,
        _model: &Model,
        asm: &Assembler,
        g: usize,
    ) -> Result<Vec<usize>, FemError> {
        let group = self.check_group(g)?;
        if let Some(mg) = &self.matrices {
            return Ok(mg.dofs[g].clone());
        }
        let mut dofs: Vec<usize> = self
            .items(group)
            .flat_map(|(points, _, _)| points.iter())
            .chain(
                self.mass_items[g]
                    .iter()
                    .flat_map(|(points, _)| points.iter()),
            )
            .flat_map(|nd| (0..3).flat_map(move |c| asm.dofs().terms(*nd, c).iter().map(|t| t.0)))
            .collect();
        dofs.sort_unstable();
        dofs.dedup();
        Ok(dofs)
    }

    /// The mass kind the element matrices were computed for.
    pub fn mass_kind(&self) -> MassKind {
        self.mass_kind
    }

    /// The assembled `K_g` of one group alone, on the stiffness pattern (for inspection and tests;
    /// for a thickness group `dK/dp` at the nominal thickness, `K_1 + 3 K_3`).
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`].
    pub fn group_stiffness(
        &self,
        _model: &Model,
        asm: &Assembler,
        g: usize,
    ) -> Result<SparseMatrix, FemError> {
        let group = self.check_group(g)?;
        if let Some(mg) = &self.matrices {
            return Ok(mg.k[g].clone());
        }
        let mut v = vec![0.0; asm.nnz()];
        match group.law {
            GroupLaw::Scale => {
                for (points, ke, _) in self.items(group) {
                    asm.scatter(points, |i, l, w| v[i] += w * ke[l]);
                }
            }
            GroupLaw::Thickness => {
                for (points, t) in self.thickness_items(group) {
                    asm.scatter(points, |i, l, w| v[i] += w * (t.k1[l] + 3.0 * t.k3[l]));
                }
            }
            GroupLaw::Section(_) => {
                for (points, ke) in &self.section_items[g] {
                    asm.scatter(points, |i, l, w| v[i] += w * ke[l]);
                }
            }
            GroupLaw::Mass => {}
        }
        Ok(asm.pattern_matrix(v))
    }
}

/// `y += alpha T^T A T x` for one element's matrix `a` on `nodes` (the DOF map's points): gather
/// the element's DOFs through `T`, multiply, scatter back. `xe` is scratch.
fn element_product(
    dm: &crate::dof::DofMap,
    nodes: &[usize],
    a: &[f64],
    alpha: f64,
    x: &[f64],
    y: &mut [f64],
    xe: &mut Vec<f64>,
) {
    xe.clear();
    xe.extend(nodes.iter().flat_map(|nd| {
        (0..3).map(|c| dm.terms(*nd, c).iter().map(|(f, w)| w * x[*f]).sum::<f64>())
    }));
    let nd = xe.len();
    for (r, nd_r) in nodes
        .iter()
        .flat_map(|n| (0..3).map(move |c| (*n, c)))
        .enumerate()
    {
        let t = dm.terms(nd_r.0, nd_r.1);
        if t.is_empty() {
            continue;
        }
        let row = &a[r * nd..(r + 1) * nd];
        let s: f64 = row.iter().zip(xe.iter()).map(|(v, xv)| v * xv).sum();
        for (f, w) in t {
            y[*f] += alpha * w * s;
        }
    }
}

/// The points and mass matrices of each [`GroupLaw::Mass`] group's masses (empty lists for the
/// other groups): a point mass's 3 x 3 on its node, a rigid mass's 6 x 6 on its node and its
/// rotation point, as the assembly adds them (a coupled one keeps the lumped mass on the stiffness
/// pattern, [`Assembler::lumped_on_pattern`]).
fn mass_group_items(
    model: &Model,
    groups: &[ParameterGroup],
) -> Result<Vec<Vec<MassItem>>, FemError> {
    use crate::model::MassRef;
    if groups.iter().all(|g| g.law != GroupLaw::Mass) {
        return Ok(vec![Vec::new(); groups.len()]);
    }
    let dofs = model.dof_map()?;
    groups
        .iter()
        .map(|g| {
            if g.law != GroupLaw::Mass {
                return Ok(Vec::new());
            }
            let out_of_range = |kind: &str, i: usize| FemError::InvalidGroup {
                name: g.name.clone(),
                reason: format!("{kind} mass {i} out of range"),
            };
            let mut items = Vec::with_capacity(g.masses.len());
            for m in &g.masses {
                let (points, a): (Vec<usize>, Vec<f64>) = match *m {
                    MassRef::Point(i) => {
                        let p = model
                            .point_masses()
                            .get(i)
                            .ok_or_else(|| out_of_range("point", i))?;
                        (vec![p.node], p.mass.iter().flatten().copied().collect())
                    }
                    MassRef::Rigid(i) => {
                        let r = model
                            .rigid_masses()
                            .get(i)
                            .ok_or_else(|| out_of_range("rigid", i))?;
                        // the assembly skips a rigid mass whose node lost its rotations
                        let Some(rp) = dofs.rotation_point(r.node) else {
                            continue;
                        };
                        (
                            vec![r.node, rp],
                            r.matrix.iter().flatten().copied().collect(),
                        )
                    }
                };
                items.push((points, a));
            }
            Ok(items)
        })
        .collect()
}

/// The points and section-part stiffness of each beam of each [`GroupLaw::Section`] group (empty
/// lists for the other groups); a group element that is not a two-node beam, or one with end
/// releases, is refused with its id.
fn section_group_items(
    model: &Model,
    groups: &[ParameterGroup],
) -> Result<Vec<Vec<MassItem>>, FemError> {
    if groups
        .iter()
        .all(|g| !matches!(g.law, GroupLaw::Section(_)))
    {
        return Ok(vec![Vec::new(); groups.len()]);
    }
    let dofs = model.dof_map()?;
    let coords = model.mesh().coords();
    groups
        .iter()
        .map(|g| {
            let GroupLaw::Section(part) = g.law else {
                return Ok(Vec::new());
            };
            let bad = |reason: String| FemError::InvalidGroup {
                name: g.name.clone(),
                reason,
            };
            g.structural
                .iter()
                .map(|&e| {
                    let el = model
                        .structural()
                        .get(e)
                        .ok_or_else(|| bad(format!("structural element index {e} out of range")))?;
                    let k = el
                        .section_part(coords, part)
                        .map_err(|err| bad(err.to_string()))?
                        .ok_or_else(|| {
                            bad(format!(
                                "a section parameter applies to two-node beams; element {} is a {}",
                                el.id,
                                el.kind.name()
                            ))
                        })?;
                    let points = crate::assembly::structural_points(&dofs, &el.parts());
                    Ok((points, k))
                })
                .collect()
        })
        .collect()
}

/// Where a scaled mass goes: the consistent mass's values on the stiffness pattern, or the lumped
/// (diagonal) mass's values.
enum MassTarget<'a> {
    Consistent(&'a mut [f64]),
    Lumped(&'a mut [f64]),
}

impl<'a> MassTarget<'a> {
    fn of(kind: MassKind, on_k: &'a mut [f64], lumped: &'a mut SparseMatrix) -> Self {
        match kind {
            MassKind::Consistent => MassTarget::Consistent(on_k),
            MassKind::Lumped => MassTarget::Lumped(lumped.data_mut()),
        }
    }
}

/// Adds `factor` times one item's mass matrix `a` (on the DOF map's `points`) to `target`: the
/// whole matrix on the stiffness pattern, or its diagonal into a lumped mass.
fn add_scaled_mass(
    asm: &Assembler,
    target: MassTarget<'_>,
    points: &[usize],
    a: &[f64],
    factor: f64,
) {
    match target {
        MassTarget::Consistent(m) => asm.scatter(points, |i, l, w| m[i] += factor * w * a[l]),
        // a lumped mass on the stiffness pattern keeps coupled masses whole (a diagonal one is
        // the same either way)
        MassTarget::Lumped(md) if asm.lumped_on_pattern() => {
            asm.scatter(points, |i, l, w| md[i] += factor * w * a[l]);
        }
        MassTarget::Lumped(md) => {
            let nd = 3 * points.len();
            asm.scatter_lumped(
                points,
                |b, i| a[(3 * b + i) * nd + 3 * b + i],
                |f, v| md[f] += factor * v,
            );
        }
    }
}
