//! A model: a mesh, materials assigned to element sets, fixed DOFs, point masses and multipoint
//! constraints (rigid links, weighted averages, linear equations; docs/MATH.md, "Multipoint
//! constraints").

use crate::FemError;
use crate::dof::{DofMap, LinearConstraint};
use crate::element::{ElementKind, Formulation};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::structural::{Part, StructuralElement};
use std::collections::{BTreeMap, BTreeSet};

/// A finite element model ready to assemble.
#[derive(Debug, Clone)]
pub struct Model {
    mesh: Mesh,
    materials: Vec<Material>,
    element_material: Vec<Option<usize>>,
    fixed: BTreeSet<(usize, usize)>,
    point_masses: Vec<PointMass>,
    rotation_nodes: Vec<usize>,
    /// Whether each node (internal index) is in `rotation_nodes`.
    has_rotation: Vec<bool>,
    constraints: Vec<LinearConstraint>,
    rigid_masses: Vec<RigidMass>,
    /// Direct input matrices added to the assembled stiffness and mass (Nastran's `K2GG`,
    /// `M2GG`).
    direct_stiffness: Vec<DirectEntry>,
    direct_mass: Vec<DirectEntry>,
    direct_damping: Vec<DirectEntry>,
    /// per element, when any is not [`Formulation::Full`] (empty: all full)
    formulations: Vec<Formulation>,
    /// Beams, rods, springs and bushings ([`crate::structural`]).
    structural: Vec<StructuralElement>,
    /// Named sets of structural elements (indices into `structural`).
    structural_sets: BTreeMap<String, Vec<usize>>,
    /// The index in `structural` of each structural element id.
    structural_lookup: std::collections::HashMap<u64, usize>,
    /// Named sets of point and rigid masses (a Nastran CONM2, an Abaqus `*MASS` element set).
    mass_sets: BTreeMap<String, Vec<MassRef>>,
    /// The structural damping coefficient `GE` of solids, beams, rods and shells by element id
    /// (from their material); absent: none.
    element_damping: BTreeMap<u64, f64>,
    /// The Rayleigh damping `(alpha, beta)` of solids, beams, rods and shells by element id (from
    /// their material: Abaqus' `*DAMPING, ALPHA=, BETA=`); absent: none.
    element_rayleigh: BTreeMap<u64, (f64, f64)>,
    /// The damping the deck gives the whole model (Nastran's `PARAM,G`, CalculiX's `*DAMPING,
    /// ALPHA=, BETA=`).
    uniform_damping: Option<UniformDamping>,
    /// The modes' damping as a function of their frequency (Nastran's `TABDMP1`).
    modal_damping: Option<ModalDampingTable>,
    /// The modes' damping ratios by mode number (Abaqus' and CalculiX's `*MODAL DAMPING`).
    mode_ratios: Vec<(usize, usize, f64)>,
    /// The modes' Rayleigh damping by mode number (Abaqus' `*MODAL DAMPING, RAYLEIGH` with
    /// ranges): `(first, last, alpha, beta)`.
    mode_rayleigh: Vec<(usize, usize, f64, f64)>,
    /// How the modal damping acts: viscous (`false`), or as each mode's complex stiffness
    /// (`true`: Nastran's `PARAM,KDAMP,-1`, Abaqus' `*MODAL DAMPING, STRUCTURAL`).
    modal_damping_structural: bool,
}

/// How a modal damping table states each mode's damping (Nastran `TABDMP1`'s `TYPE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModalDampingUnits {
    /// The structural damping coefficient `g`: Nastran's default (`KDAMP = 1`) applies it as
    /// viscous damping of ratio `g / 2` at the mode's frequency.
    G,
    /// The ratio to critical damping `zeta`.
    Crit,
    /// The amplification factor `Q = 1 / (2 zeta)`.
    Q,
}

/// The modes' damping as a tabular function of their natural frequency (Nastran `TABDMP1`
/// selected by the case control's `SDAMPING`, Abaqus' `*MODAL DAMPING, DEFINITION=FREQUENCY
/// RANGE`): linear between the points; outside them linearly extrapolated from the two end points
/// (QRG TABDMP1, remarks) or held at the nearest end's value (Abaqus), as `hold_ends` says; at a
/// discontinuity (two points at one frequency) the mean of its two values.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalDampingTable {
    /// The units of the values.
    pub units: ModalDampingUnits,
    /// `(frequency in Hz, value)`, frequencies ascending.
    pub points: Vec<(f64, f64)>,
    /// Outside the points: the nearest end's value (`true`, Abaqus) or the end segments
    /// extended (`false`, Nastran).
    pub hold_ends: bool,
}

impl ModalDampingTable {
    /// The viscous damping ratio of a mode of `hz`: the table's value there, as a ratio (`g / 2`,
    /// `zeta`, or `1 / (2 Q)`).
    pub fn ratio_at(&self, hz: f64) -> f64 {
        let p = &self.points;
        let value = match p.len() {
            0 => 0.0,
            1 => p[0].1,
            _ if self.hold_ends && hz <= p[0].0 => p[0].1,
            n if self.hold_ends && hz >= p[n - 1].0 => p[n - 1].1,
            n => {
                // the segment that holds hz (the end segments extrapolate)
                let i = p[..n - 1]
                    .iter()
                    .rposition(|(f, _)| *f <= hz)
                    .unwrap_or(0)
                    .min(n - 2);
                let exact: Vec<f64> = p.iter().filter(|(f, _)| *f == hz).map(|v| v.1).collect();
                if exact.len() > 1 {
                    exact.iter().sum::<f64>() / exact.len() as f64
                } else {
                    let ((f0, g0), (f1, g1)) = (p[i], p[i + 1]);
                    if f1 == f0 {
                        (g0 + g1) / 2.0
                    } else {
                        g0 + (g1 - g0) * (hz - f0) / (f1 - f0)
                    }
                }
            }
        };
        match self.units {
            ModalDampingUnits::G => value / 2.0,
            ModalDampingUnits::Crit => value,
            ModalDampingUnits::Q => {
                if value > 0.0 {
                    1.0 / (2.0 * value)
                } else {
                    f64::INFINITY
                }
            }
        }
    }
}

/// The damping a deck gives the whole model, which a frequency response uses when its request
/// names none: Nastran's `PARAM,G` (a structural loss factor, `K (1 + i G)`), CalculiX's
/// `*DAMPING, ALPHA=, BETA=` (Rayleigh damping `C = alpha M + beta K`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum UniformDamping {
    /// A structural loss factor `eta`: `K (1 + i eta)`.
    LossFactor(f64),
    /// Rayleigh damping `C = alpha M + beta K` (s^-1 and s).
    Rayleigh {
        /// The mass coefficient, s^-1.
        alpha: f64,
        /// The stiffness coefficient, s.
        beta: f64,
    },
}

/// A concentrated mass of a model: [`Model::point_masses`] or [`Model::rigid_masses`] by index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MassRef {
    /// A point mass (translations only).
    Point(usize),
    /// A rigid mass (translations and rotations).
    Rigid(usize),
}

/// A rigid body's mass on a node that carries rotations (a rigid link's reference, where Nastran
/// puts a CONM2 with an offset and rotational inertia): its 6x6 mass matrix on the node's
/// translations and rotations, `[[m I, -m S(d)], [m S(d), -m S(d)^2 + J]]` for mass `m` at offset
/// `d` with inertia `J` about its centre of gravity (`S(d)` the cross-product matrix; docs/MATH.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidMass {
    /// Internal node index (a node with rotations).
    pub node: usize,
    /// The mass matrix on `(u_x, u_y, u_z, theta_x, theta_y, theta_z)`.
    pub matrix: [[f64; 6]; 6],
    /// The mass (kg).
    pub mass: f64,
    /// The centre of gravity's offset from the node (m, basic frame).
    pub offset: [f64; 3],
    /// The inertia about the centre of gravity (kg m^2, basic axes).
    pub inertia: [[f64; 3]; 3],
}

/// Which assembled matrix a direct input matrix adds to ([`Model::add_direct_entries`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DirectMatrix {
    /// The stiffness (Nastran's `K2GG`).
    Stiffness,
    /// The mass (Nastran's `M2GG`).
    Mass,
    /// The structural damping `K_4` of frequency responses and damped modes (Nastran's `K42GG`,
    /// entering as `i K_4`).
    StructuralDamping,
}

impl DirectMatrix {
    /// The three, in the order the assembly visits them.
    pub const ALL: [DirectMatrix; 3] = [
        DirectMatrix::Stiffness,
        DirectMatrix::Mass,
        DirectMatrix::StructuralDamping,
    ];
}

/// One entry of a direct input matrix as given: `((node id, component), (node id, component),
/// value)`, components 0-5 ([`Model::add_direct_entries`]).
pub type DirectTerm = ((u64, usize), (u64, usize), f64);

/// One entry of a direct input matrix: two DOFs `(node index, component 0-5)` and the value,
/// added to the assembled matrix at `(a, b)` and, off its diagonal, at `(b, a)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectEntry {
    /// The first DOF: internal node index, component (0-2 translations, 3-5 rotations).
    pub a: (usize, usize),
    /// The second DOF.
    pub b: (usize, usize),
    /// The value (N/m, N/rad, N m/rad; kg, kg m, kg m^2).
    pub value: f64,
}

/// A concentrated mass on a node: sensors, shakers, attached equipment.
///
/// femu's nodes carry translations only, so a point mass is its 3x3 translational mass matrix
/// (`m I` for a plain mass). A mass offset from its node moves rigidly with it: with rotations
/// the offset would couple them to the translations, but without rotational DOFs its
/// translational mass is unchanged by the offset, and rotational inertia has no DOF to act on
/// (readers warn when they drop it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Internal node index.
    pub node: usize,
    /// The translational mass matrix (kg), symmetric positive semi-definite.
    pub mass: [[f64; 3]; 3],
}

impl Model {
    /// A model on a mesh, after [`Mesh::validate`] (every element must have a positive Jacobian).
    ///
    /// # Errors
    /// The first geometry error of [`Mesh::validate`].
    pub fn new(mesh: Mesh) -> Result<Self, FemError> {
        mesh.validate()?;
        let n = mesh.element_count();
        let nodes = mesh.node_count();
        Ok(Self {
            mesh,
            materials: Vec::new(),
            element_material: vec![None; n],
            fixed: BTreeSet::new(),
            point_masses: Vec::new(),
            rotation_nodes: Vec::new(),
            has_rotation: vec![false; nodes],
            constraints: Vec::new(),
            rigid_masses: Vec::new(),
            direct_stiffness: Vec::new(),
            direct_mass: Vec::new(),
            direct_damping: Vec::new(),
            formulations: Vec::new(),
            structural: Vec::new(),
            structural_sets: BTreeMap::new(),
            structural_lookup: std::collections::HashMap::new(),
            mass_sets: BTreeMap::new(),
            element_damping: BTreeMap::new(),
            element_rayleigh: BTreeMap::new(),
            uniform_damping: None,
            modal_damping: None,
            mode_ratios: Vec::new(),
            mode_rayleigh: Vec::new(),
            modal_damping_structural: false,
        })
    }

    /// Gives modes `first..=last` (numbered from 1, lowest first) the viscous damping ratio
    /// `ratio` (Abaqus' and CalculiX's `*MODAL DAMPING`: a mode in no range is undamped); an
    /// empty list removes them.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] (named `modal damping`) for a range that starts at 0 or ends
    /// before it starts, or a ratio that is negative or not finite.
    pub fn set_mode_ratios(&mut self, ranges: Vec<(usize, usize, f64)>) -> Result<(), FemError> {
        if let Some((a, b, z)) = ranges
            .iter()
            .find(|(a, b, z)| *a == 0 || b < a || !(z.is_finite() && *z >= 0.0))
        {
            return Err(FemError::InvalidMaterial {
                name: "modal damping".into(),
                reason: format!(
                    "modes {a} to {b} with ratio {z}: modes are numbered from 1, the last not before the first, the ratio finite and at least 0"
                ),
            });
        }
        self.mode_ratios = ranges;
        Ok(())
    }

    /// Gives modes `first..=last` (from 1) Rayleigh damping `alpha M + beta K` (Abaqus'
    /// `*MODAL DAMPING, RAYLEIGH` by mode numbers): mode `r` of circular frequency `omega_r` the
    /// viscous ratio `alpha / (2 omega_r) + beta omega_r / 2`, a mode in no range undamped; an empty
    /// list removes them.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] (named `modal damping`) for a range that starts at 0 or ends
    /// before it starts, or a coefficient that is negative or not finite.
    pub fn set_mode_rayleigh(
        &mut self,
        ranges: Vec<(usize, usize, f64, f64)>,
    ) -> Result<(), FemError> {
        if let Some((a, b, al, be)) = ranges.iter().find(|(a, b, al, be)| {
            *a == 0 || b < a || !(al.is_finite() && *al >= 0.0 && be.is_finite() && *be >= 0.0)
        }) {
            return Err(FemError::InvalidMaterial {
                name: "modal damping".into(),
                reason: format!(
                    "modes {a} to {b} with Rayleigh alpha {al}, beta {be}: modes are numbered from 1, the last not before the first, the coefficients finite and at least 0"
                ),
            });
        }
        self.mode_rayleigh = ranges;
        Ok(())
    }

    /// The viscous ratio of mode `mode` (from 1) of circular frequency `omega` by
    /// [`Model::set_mode_rayleigh`]'s ranges (the last range that holds it; 0 in none), `None`
    /// without ranges.
    pub fn mode_rayleigh_ratio(&self, mode: usize, omega: f64) -> Option<f64> {
        if self.mode_rayleigh.is_empty() {
            return None;
        }
        Some(
            self.mode_rayleigh
                .iter()
                .rev()
                .find(|(a, b, _, _)| (*a..=*b).contains(&mode))
                .map_or(0.0, |&(_, _, alpha, beta)| {
                    if omega > 0.0 {
                        alpha / (2.0 * omega) + beta * omega / 2.0
                    } else {
                        0.0
                    }
                }),
        )
    }

    /// The ranges of [`Model::set_mode_ratios`]: modes `first..=last` and their ratio.
    pub fn mode_ratio_ranges(&self) -> &[(usize, usize, f64)] {
        &self.mode_ratios
    }

    /// The damping ratio of mode `mode` (from 1) by [`Model::set_mode_ratios`]'s ranges (the last
    /// range that holds it), `None` without ranges.
    pub fn mode_ratio(&self, mode: usize) -> Option<f64> {
        if self.mode_ratios.is_empty() {
            return None;
        }
        Some(
            self.mode_ratios
                .iter()
                .rev()
                .find(|(a, b, _)| (*a..=*b).contains(&mode))
                .map_or(0.0, |r| r.2),
        )
    }

    /// Gives the model's modes a damping table ([`ModalDampingTable`]); `None` removes it.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] (named `modal damping`) for no point, a frequency that is
    /// negative or not finite, frequencies out of order, a value that is not finite or that gives
    /// a negative ratio.
    pub fn set_modal_damping(&mut self, table: Option<ModalDampingTable>) -> Result<(), FemError> {
        if let Some(t) = &table {
            let bad = |reason: String| FemError::InvalidMaterial {
                name: "modal damping".into(),
                reason,
            };
            if t.points.is_empty() {
                return Err(bad("a table needs at least one point".into()));
            }
            if let Some((f, g)) = t
                .points
                .iter()
                .find(|(f, g)| !(f.is_finite() && *f >= 0.0 && g.is_finite()))
            {
                return Err(bad(format!(
                    "the point ({f}, {g}): frequencies are finite and at least 0, values finite"
                )));
            }
            if t.points.windows(2).any(|w| w[1].0 < w[0].0) {
                return Err(bad("the frequencies must ascend".into()));
            }
            if let Some((f, g)) = t.points.iter().find(|(_, g)| *g < 0.0) {
                return Err(bad(format!("the value {g} at {f} Hz is negative")));
            }
        }
        self.modal_damping = table;
        Ok(())
    }

    /// The modes' damping table, if any ([`Model::set_modal_damping`]).
    pub fn modal_damping(&self) -> Option<&ModalDampingTable> {
        self.modal_damping.as_ref()
    }

    /// Says how the modal damping (the table of [`Model::set_modal_damping`] or the ratios of
    /// [`Model::set_mode_ratios`]) acts: `false` (the default) as viscous damping, `2 zeta_r
    /// omega_r` in mode `r`'s equation; `true` as its complex stiffness, `lambda_r (1 + i g_r)`
    /// with the loss factor `g_r = 2 zeta_r` (Nastran's `PARAM,KDAMP,-1`, Abaqus'
    /// `*MODAL DAMPING, STRUCTURAL`; docs/MATH.md, "Frequency
    /// responses"). The two agree at each mode's resonance and differ away from it.
    pub fn set_modal_damping_structural(&mut self, structural: bool) {
        self.modal_damping_structural = structural;
    }

    /// Whether the modal damping acts as each mode's complex stiffness
    /// ([`Model::set_modal_damping_structural`]).
    pub fn modal_damping_structural(&self) -> bool {
        self.modal_damping_structural
    }

    /// Gives the whole model the damping its deck states ([`UniformDamping`]); `None` removes it.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] (named `damping`) for a value that is negative or not finite.
    pub fn set_uniform_damping(&mut self, d: Option<UniformDamping>) -> Result<(), FemError> {
        let values = match d {
            Some(UniformDamping::LossFactor(g)) => vec![g],
            Some(UniformDamping::Rayleigh { alpha, beta }) => vec![alpha, beta],
            None => Vec::new(),
        };
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(FemError::InvalidMaterial {
                name: "damping".into(),
                reason: format!("{v}: a damping coefficient is finite and at least 0"),
            });
        }
        self.uniform_damping = d;
        Ok(())
    }

    /// The damping the deck gives the whole model, if any ([`Model::set_uniform_damping`]).
    pub fn uniform_damping(&self) -> Option<UniformDamping> {
        self.uniform_damping
    }

    /// Gives the solid, beam, rod or shell `id` the structural damping coefficient `ge`: it adds
    /// `i ge K_e` to the dynamic stiffness of a direct frequency response (`K_4 = sum_e GE_e K_e`,
    /// Nastran's `GE` of the element's material, Abaqus' `*DAMPING, STRUCTURAL` of it; docs/MATH.md,
    /// "Frequency responses, directly"). It changes neither `K` nor `M`. A spring or a bushing
    /// carries its own `GE` ([`crate::structural::Spring::ge`]); `ge = 0` removes the element's.
    ///
    /// # Errors
    /// [`FemError::UnknownElement`] for an id of no element; [`FemError::InvalidStructural`] for
    /// a spring or a bushing, or a `ge` that is negative or not finite.
    pub fn set_element_damping(&mut self, id: u64, ge: f64) -> Result<(), FemError> {
        self.check_damped_element(id)?;
        if !(ge.is_finite() && ge >= 0.0) {
            return Err(FemError::InvalidStructural {
                element: id,
                reason: format!(
                    "a structural damping coefficient GE of {ge}: it must be finite and at least 0"
                ),
            });
        }
        if ge == 0.0 {
            self.element_damping.remove(&id);
        } else {
            self.element_damping.insert(id, ge);
        }
        Ok(())
    }

    /// That `id` is a solid, beam, rod or shell, which a material damps (a spring or a bushing has
    /// its own damping).
    fn check_damped_element(&self, id: u64) -> Result<(), FemError> {
        if let Some(s) = self.structural_index(id) {
            use crate::structural::StructuralKind;
            if matches!(
                self.structural[s].kind,
                StructuralKind::Spring(_) | StructuralKind::Bushing(_)
            ) {
                return Err(FemError::InvalidStructural {
                    element: id,
                    reason: "a spring or a bushing has its own damping (GE, B)".into(),
                });
            }
        } else if self.mesh.element_index(id).is_none() {
            return Err(FemError::UnknownElement { element: id });
        }
        Ok(())
    }

    /// The structural damping coefficients `GE` of solids, beams, rods and shells, by element id
    /// ([`Model::set_element_damping`]); elements without one are absent.
    pub fn element_damping(&self) -> &BTreeMap<u64, f64> {
        &self.element_damping
    }

    /// Gives the solid, beam, rod or shell `id` Rayleigh damping `C_e = alpha M_e + beta K_e` (its
    /// material's: Abaqus' `*DAMPING, ALPHA=, BETA=`; docs/MATH.md, "Frequency responses,
    /// directly"), viscous damping that adds `i w C_e` to the dynamic stiffness and enters the
    /// damped modes. It changes neither `K` nor `M`; `(0, 0)` removes the element's.
    ///
    /// # Errors
    /// As [`Model::set_element_damping`], for a coefficient that is negative or not finite.
    pub fn set_element_rayleigh(&mut self, id: u64, alpha: f64, beta: f64) -> Result<(), FemError> {
        self.check_damped_element(id)?;
        if !(alpha.is_finite() && alpha >= 0.0 && beta.is_finite() && beta >= 0.0) {
            return Err(FemError::InvalidStructural {
                element: id,
                reason: format!(
                    "Rayleigh damping alpha {alpha}, beta {beta}: each must be finite and at least 0"
                ),
            });
        }
        if alpha == 0.0 && beta == 0.0 {
            self.element_rayleigh.remove(&id);
        } else {
            self.element_rayleigh.insert(id, (alpha, beta));
        }
        Ok(())
    }

    /// The Rayleigh damping `(alpha, beta)` of solids, beams, rods and shells, by element id
    /// ([`Model::set_element_rayleigh`]); elements without one are absent.
    pub fn element_rayleigh(&self) -> &BTreeMap<u64, (f64, f64)> {
        &self.element_rayleigh
    }

    /// Adds a beam, rod, spring, bushing or shell; its nodes get rotations where it acts on them
    /// ([`Model::add_rotations`]). Its values and geometry are checked here
    /// ([`StructuralElement::check_geometry`]), so that a bad one (coincident ends, an orientation
    /// vector along the axis, a warped shell) is refused now, with its id.
    ///
    /// # Errors
    /// [`FemError::DuplicateElementId`] for an id a solid or structural element has;
    /// [`FemError::InvalidStructural`] for invalid values or geometry, or a node index out of
    /// range.
    pub fn add_structural(&mut self, element: StructuralElement) -> Result<usize, FemError> {
        let id = element.id;
        if self.mesh.element_index(id).is_some() || self.structural_index(id).is_some() {
            return Err(FemError::DuplicateElementId { id });
        }
        let nn = self.mesh.node_count();
        let parts = element.parts();
        if element.nodes.is_empty()
            || element
                .nodes
                .iter()
                .chain(parts.iter().map(|p| &p.0))
                .any(|n| *n >= nn)
        {
            return Err(FemError::InvalidStructural {
                element: id,
                reason: format!("its nodes {:?} are not nodes of the mesh", element.nodes),
            });
        }
        element.check_geometry(self.mesh.coords())?;
        for (n, part) in parts {
            if part == Part::Rotations {
                self.give_rotations(n);
            }
        }
        self.structural_lookup.insert(id, self.structural.len());
        self.structural.push(element);
        Ok(self.structural.len() - 1)
    }

    /// The beams, rods, springs and bushings.
    pub fn structural(&self) -> &[StructuralElement] {
        &self.structural
    }

    /// The index of the structural element with user id `id`.
    pub fn structural_index(&self, id: u64) -> Option<usize> {
        self.structural_lookup.get(&id).copied()
    }

    /// Replaces structural element `index` by `element` (new values, same nodes and parts: a
    /// parameter study or a test).
    ///
    /// # Errors
    /// [`FemError::InvalidStructural`] for an index out of range, different nodes or parts, or
    /// invalid values.
    pub fn set_structural(
        &mut self,
        index: usize,
        element: StructuralElement,
    ) -> Result<(), FemError> {
        let bad = |reason: String| FemError::InvalidStructural {
            element: element.id,
            reason,
        };
        let old = self
            .structural
            .get(index)
            .ok_or_else(|| bad(format!("no structural element at index {index}")))?;
        if old.nodes != element.nodes || old.parts() != element.parts() || old.id != element.id {
            return Err(bad(
                "a replacement must keep the element's id, nodes and the DOFs it acts on".into(),
            ));
        }
        element.check_geometry(self.mesh.coords())?;
        self.structural[index] = element;
        Ok(())
    }

    /// Names a set of structural elements by their ids (a property's elements); a set of the same
    /// name adds to it.
    ///
    /// # Errors
    /// [`FemError::UnknownElement`] for an id that is not a structural element.
    pub fn add_structural_set(
        &mut self,
        name: impl Into<String>,
        ids: &[u64],
    ) -> Result<(), FemError> {
        let idx = ids
            .iter()
            .map(|id| {
                self.structural_index(*id)
                    .ok_or(FemError::UnknownElement { element: *id })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let set = self.structural_sets.entry(name.into()).or_default();
        set.extend(idx);
        set.sort_unstable();
        set.dedup();
        Ok(())
    }

    /// The named sets of structural elements.
    pub fn structural_sets(&self) -> &BTreeMap<String, Vec<usize>> {
        &self.structural_sets
    }

    /// The names of every element set: the mesh's and the structural elements', sorted, once.
    pub fn element_set_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .mesh
            .element_sets()
            .keys()
            .chain(self.structural_sets.keys())
            .cloned()
            .collect();
        v.sort();
        v.dedup();
        v
    }

    /// The solid elements and the structural elements of set `name` (internal indices).
    ///
    /// # Errors
    /// [`FemError::UnknownElementSet`] when neither the mesh nor the structural elements have it.
    pub fn element_set_members(&self, name: &str) -> Result<(Vec<usize>, Vec<usize>), FemError> {
        let solids = self.mesh.element_sets().get(name).cloned();
        let structural = self.structural_sets.get(name).cloned();
        if solids.is_none() && structural.is_none() {
            return Err(FemError::UnknownElementSet { name: name.into() });
        }
        Ok((solids.unwrap_or_default(), structural.unwrap_or_default()))
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Assigns `material` to the elements of the named set, or to every element when `set` is
    /// `None`. Later assignments override earlier ones element by element.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] or [`FemError::UnknownElementSet`].
    pub fn set_material(&mut self, set: Option<&str>, material: Material) -> Result<(), FemError> {
        material.validate()?;
        let elements: Vec<usize> = match set {
            Some(name) => self.mesh.element_set(name)?.to_vec(),
            None => (0..self.mesh.element_count()).collect(),
        };
        self.materials.push(material);
        let m = self.materials.len() - 1;
        for e in elements {
            self.element_material[e] = Some(m);
        }
        Ok(())
    }

    /// The material of element `e` (internal index).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] naming the element id.
    pub fn material_of(&self, e: usize) -> Result<&Material, FemError> {
        self.element_material[e]
            .map(|m| &self.materials[m])
            .ok_or(FemError::NoMaterial {
                element: self.mesh.element(e).id,
            })
    }

    /// Sets how element `e` (internal index) forms its stiffness.
    ///
    /// # Errors
    /// [`FemError::InvalidFormulation`] for incompatible modes on an element that is not an
    /// 8-node brick.
    pub fn set_formulation(&mut self, e: usize, formulation: Formulation) -> Result<(), FemError> {
        let el = self.mesh.element(e);
        if formulation == Formulation::IncompatibleModes && el.kind != ElementKind::Hex8 {
            return Err(FemError::InvalidFormulation {
                element: el.id,
                kind: el.kind.abaqus_name(),
                reason: "incompatible modes are built for 8-node bricks only".into(),
            });
        }
        if self.formulations.is_empty() {
            if formulation == Formulation::Full {
                return Ok(());
            }
            self.formulations = vec![Formulation::Full; self.mesh.element_count()];
        }
        self.formulations[e] = formulation;
        Ok(())
    }

    /// How element `e` (internal index) forms its stiffness.
    pub fn formulation(&self, e: usize) -> Formulation {
        self.formulations.get(e).copied().unwrap_or_default()
    }

    /// Fixes components (0 = x, 1 = y, 2 = z) of every node of a named node set.
    ///
    /// # Errors
    /// [`FemError::UnknownNodeSet`] or [`FemError::InvalidComponent`].
    pub fn fix_set(&mut self, set: &str, components: &[usize]) -> Result<(), FemError> {
        let nodes = self.mesh.node_set(set)?.to_vec();
        self.fix_indices(&nodes, components)
    }

    /// Fixes components of nodes given by user id.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`] or [`FemError::InvalidComponent`].
    pub fn fix_nodes(&mut self, node_ids: &[u64], components: &[usize]) -> Result<(), FemError> {
        let nodes = node_ids
            .iter()
            .map(|n| {
                self.mesh
                    .node_index(*n)
                    .ok_or(FemError::UnknownNode { node: *n })
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.fix_indices(&nodes, components)
    }

    /// Fixes rotations (components 3, 4, 5 about x, y, z) of a node that carries them (a rigid
    /// link's reference node), as well as translations (0, 1, 2).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidComponent`] for a rotation of a node without
    /// rotations.
    pub fn fix_node_dofs(&mut self, node_id: u64, components: &[usize]) -> Result<(), FemError> {
        let n = self.node(node_id)?;
        for &c in components {
            if c > 5 || (c > 2 && !self.has_rotation[n]) {
                return Err(FemError::InvalidComponent {
                    node: node_id,
                    component: c,
                });
            }
            self.fixed.insert((n, c));
        }
        Ok(())
    }

    fn node(&self, id: u64) -> Result<usize, FemError> {
        self.mesh
            .node_index(id)
            .ok_or(FemError::UnknownNode { node: id })
    }

    fn fix_indices(&mut self, nodes: &[usize], components: &[usize]) -> Result<(), FemError> {
        if let Some(c) = components.iter().find(|c| **c > 2) {
            let node = nodes.first().map(|n| self.mesh.node_id(*n)).unwrap_or(0);
            return Err(FemError::InvalidComponent {
                node,
                component: *c,
            });
        }
        for n in nodes {
            for c in components {
                self.fixed.insert((*n, *c));
            }
        }
        Ok(())
    }

    /// Removes every constraint (a free-free model).
    pub fn clear_constraints(&mut self) {
        self.fixed.clear();
    }

    /// The fixed `(internal node, component)` pairs.
    pub fn fixed_dofs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.fixed.iter().copied()
    }

    /// Adds a point mass `m` (kg) on node `node_id` (`m I`, the same in every direction).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a mass that is not positive
    /// and finite.
    pub fn add_point_mass(&mut self, node_id: u64, m: f64) -> Result<(), FemError> {
        self.add_point_mass_matrix(node_id, [[m, 0.0, 0.0], [0.0, m, 0.0], [0.0, 0.0, m]])
    }

    /// Adds a point mass with a general symmetric translational mass matrix (kg).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a matrix that is not finite,
    /// symmetric and positive semi-definite with a positive trace.
    pub fn add_point_mass_matrix(
        &mut self,
        node_id: u64,
        mass: [[f64; 3]; 3],
    ) -> Result<(), FemError> {
        let node = self
            .mesh
            .node_index(node_id)
            .ok_or(FemError::UnknownNode { node: node_id })?;
        let bad = |reason: String| FemError::InvalidMaterial {
            name: format!("point mass on node {node_id}"),
            reason,
        };
        if mass.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad(format!("{mass:?} is not finite")));
        }
        let trace = mass[0][0] + mass[1][1] + mass[2][2];
        let scale = mass.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            for j in 0..3 {
                if (mass[i][j] - mass[j][i]).abs() > 1e-12 * scale {
                    return Err(bad(format!("{mass:?} is not symmetric")));
                }
            }
        }
        // positive semi-definite: the leading minors of the symmetric 3x3 (with a tolerance)
        let m = nalgebra::Matrix3::from_fn(|i, j| mass[i][j]);
        let low = m.symmetric_eigenvalues().min();
        if !(trace > 0.0) || low < -1e-12 * scale {
            return Err(bad(format!(
                "the mass must be positive (the matrix {mass:?} has eigenvalue {low:e})"
            )));
        }
        self.point_masses.push(PointMass { node, mass });
        Ok(())
    }

    /// The point masses.
    pub fn point_masses(&self) -> &[PointMass] {
        &self.point_masses
    }

    /// The last mass added ([`Model::add_point_mass`], [`Model::add_rigid_mass`]), to name it in
    /// a mass set.
    pub fn last_mass(&self, rigid: bool) -> Option<MassRef> {
        if rigid {
            self.rigid_masses.len().checked_sub(1).map(MassRef::Rigid)
        } else {
            self.point_masses.len().checked_sub(1).map(MassRef::Point)
        }
    }

    /// Adds masses to the mass set `name` (created if new): a group of concentrated masses whose
    /// value can be updated (docs/MATH.md, "Mass parameters").
    ///
    /// # Errors
    /// [`FemError::InvalidGroup`] for a mass that does not exist.
    pub fn add_mass_set(
        &mut self,
        name: impl Into<String>,
        masses: &[MassRef],
    ) -> Result<(), FemError> {
        let name = name.into();
        for m in masses {
            let ok = match m {
                MassRef::Point(i) => *i < self.point_masses.len(),
                MassRef::Rigid(i) => *i < self.rigid_masses.len(),
            };
            if !ok {
                return Err(FemError::InvalidGroup {
                    name,
                    reason: format!("{m:?} is not a mass of the model"),
                });
            }
        }
        self.mass_sets.entry(name).or_default().extend(masses);
        Ok(())
    }

    /// The masses of mass set `name`, if it exists.
    pub fn mass_set(&self, name: &str) -> Option<&[MassRef]> {
        self.mass_sets.get(name).map(Vec::as_slice)
    }

    /// The names of the mass sets, sorted.
    pub fn mass_set_names(&self) -> Vec<String> {
        self.mass_sets.keys().cloned().collect()
    }

    /// Adds a rigid body of mass `m` (kg) whose centre of gravity is at `offset` (m, basic frame)
    /// from node `node_id`, with inertia `inertia` (kg m^2, symmetric, about the centre of
    /// gravity, basic axes), on a node that carries rotations ([`Model::add_rotations`]): its
    /// translations and rotations both see it (see [`RigidMass`]).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a mass that is not positive
    /// and finite, an inertia that is not symmetric positive semi-definite, or a node without
    /// rotations.
    pub fn add_rigid_mass(
        &mut self,
        node_id: u64,
        m: f64,
        offset: [f64; 3],
        inertia: [[f64; 3]; 3],
    ) -> Result<(), FemError> {
        let node = self.node(node_id)?;
        let bad = |reason: String| FemError::InvalidMaterial {
            name: format!("rigid mass on node {node_id}"),
            reason,
        };
        if !self.has_rotation[node] {
            return Err(bad(
                "the node has no rotations (only a rigid link's reference node has them)".into(),
            ));
        }
        if !(m.is_finite() && m > 0.0)
            || offset
                .iter()
                .chain(inertia.iter().flatten())
                .any(|v| !v.is_finite())
        {
            return Err(bad(format!(
                "mass {m}, offset {offset:?} and inertia {inertia:?} must be finite, the mass positive"
            )));
        }
        let j = nalgebra::Matrix3::from_fn(|i, k| inertia[i][k]);
        let scale = j.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if (j - j.transpose()).iter().any(|v| v.abs() > 1e-12 * scale)
            || j.symmetric_eigenvalues().min() < -1e-12 * scale
        {
            return Err(bad(format!(
                "the inertia {inertia:?} must be symmetric positive semi-definite"
            )));
        }
        let d = offset;
        let sd = nalgebra::Matrix3::new(0.0, -d[2], d[1], d[2], 0.0, -d[0], -d[1], d[0], 0.0);
        let tr = -m * sd;
        let rr = -m * sd * sd + j;
        let mut matrix = [[0.0; 6]; 6];
        for i in 0..3 {
            matrix[i][i] = m;
            for k in 0..3 {
                matrix[i][3 + k] = tr[(i, k)];
                matrix[3 + k][i] = tr[(i, k)];
                matrix[3 + i][3 + k] = rr[(i, k)];
            }
        }
        self.rigid_masses.push(RigidMass {
            node,
            matrix,
            mass: m,
            offset,
            inertia,
        });
        Ok(())
    }

    /// Adds a rotary inertia `inertia` (kg m^2, symmetric positive semi-definite, basic axes) on
    /// the rotations of node `node_id`, which must carry them (Abaqus's ROTARYI element): a
    /// [`RigidMass`] of no mass and no offset.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a node without rotations or an
    /// inertia that is not finite, symmetric and positive semi-definite with a positive trace.
    pub fn add_rotary_inertia(
        &mut self,
        node_id: u64,
        inertia: [[f64; 3]; 3],
    ) -> Result<(), FemError> {
        let mut matrix = [[0.0; 6]; 6];
        for i in 0..3 {
            for k in 0..3 {
                matrix[3 + i][3 + k] = inertia[i][k];
            }
        }
        self.push_mass_matrix(node_id, matrix, "rotary inertia")
    }

    /// Adds a general symmetric 6x6 mass matrix on the translations and rotations of node
    /// `node_id` (basic axes, `(u_x, u_y, u_z, theta_x, theta_y, theta_z)`; Nastran's `CONM1`),
    /// held as a rigid mass whose `mass` is the mean of the translational diagonal, `inertia` the
    /// rotational block and `offset` zero (the matrix itself is what the assembly adds).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a node without rotations, a
    /// matrix that is not finite, symmetric and positive semi-definite, or has no mass.
    pub fn add_mass_matrix(&mut self, node_id: u64, matrix: [[f64; 6]; 6]) -> Result<(), FemError> {
        self.push_mass_matrix(node_id, matrix, "mass matrix")
    }

    /// [`Model::add_mass_matrix`], its errors naming `what` on the node.
    fn push_mass_matrix(
        &mut self,
        node_id: u64,
        matrix: [[f64; 6]; 6],
        what: &str,
    ) -> Result<(), FemError> {
        let node = self.node(node_id)?;
        let bad = |reason: String| FemError::InvalidMaterial {
            name: format!("{what} on node {node_id}"),
            reason,
        };
        if !self.has_rotation[node] {
            return Err(bad(
                "the node has no rotations (a beam's, a shell's or a rigid link's reference node has them)".into(),
            ));
        }
        let m = nalgebra::Matrix6::from_fn(|i, k| matrix[i][k]);
        let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if m.iter().any(|v| !v.is_finite())
            || !(m.trace() > 0.0)
            || (m - m.transpose()).iter().any(|v| v.abs() > 1e-12 * scale)
            || m.symmetric_eigenvalues().min() < -1e-12 * scale
        {
            return Err(bad(format!(
                "{matrix:?} must be finite, symmetric and positive semi-definite, with a positive trace"
            )));
        }
        self.rigid_masses.push(RigidMass {
            node,
            matrix,
            mass: (matrix[0][0] + matrix[1][1] + matrix[2][2]) / 3.0,
            offset: [0.0; 3],
            inertia: std::array::from_fn(|i| std::array::from_fn(|k| matrix[3 + i][3 + k])),
        });
        Ok(())
    }

    /// Adds a copy of rigid mass `r` (of this model or another) on node `node_id`, its matrix
    /// and description unchanged.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a node without rotations.
    pub fn add_rigid_mass_copy(&mut self, node_id: u64, r: &RigidMass) -> Result<(), FemError> {
        let node = self.node(node_id)?;
        if !self.has_rotation[node] {
            return Err(FemError::InvalidMaterial {
                name: format!("rigid mass on node {node_id}"),
                reason: "the node has no rotations".into(),
            });
        }
        self.rigid_masses.push(RigidMass { node, ..*r });
        Ok(())
    }

    /// Adds a direct input matrix to the assembled stiffness, mass or structural damping
    /// (Nastran's `K2GG`, `M2GG` and `K42GG`,
    /// added before constraints as there): symmetric, each unordered pair of DOFs `((node id,
    /// component), (node id, component), value)` given once, components 0-2 translations and 3-5
    /// rotations of nodes that have them. `label` names the matrix for messages. The assembly
    /// puts each entry on the pattern (a coupling no element makes widens it) and through the
    /// constraints like any element's.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::Constraint`] (with `label`) for a component beyond
    /// 5, a rotation of a node without rotations, a value that is not finite.
    pub fn add_direct_entries(
        &mut self,
        which: DirectMatrix,
        entries: &[DirectTerm],
        label: &str,
    ) -> Result<(), FemError> {
        let mut added = Vec::with_capacity(entries.len());
        for &((ga, ca), (gb, cb), value) in entries {
            let (a, b) = (self.dof_of((ga, ca), label)?, self.dof_of((gb, cb), label)?);
            if !value.is_finite() {
                return Err(FemError::Constraint {
                    label: label.into(),
                    reason: format!(
                        "the entry of node {ga} DOF {} and node {gb} DOF {} is {value}",
                        ca + 1,
                        cb + 1
                    ),
                });
            }
            added.push(DirectEntry { a, b, value });
        }
        match which {
            DirectMatrix::Stiffness => self.direct_stiffness.extend(added),
            DirectMatrix::Mass => self.direct_mass.extend(added),
            DirectMatrix::StructuralDamping => self.direct_damping.extend(added),
        }
        Ok(())
    }

    /// The direct input matrix entries of `which` ([`Model::add_direct_entries`]).
    pub fn direct_entries(&self, which: DirectMatrix) -> &[DirectEntry] {
        match which {
            DirectMatrix::Stiffness => &self.direct_stiffness,
            DirectMatrix::Mass => &self.direct_mass,
            DirectMatrix::StructuralDamping => &self.direct_damping,
        }
    }

    /// The rigid masses.
    pub fn rigid_masses(&self) -> &[RigidMass] {
        &self.rigid_masses
    }

    /// Gives node `node_id` three rotational DOFs (about x, y, z, radians; components 3, 4, 5),
    /// which only multipoint constraints connect (solid elements have none): a rigid link's
    /// reference node. Idempotent.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`].
    pub fn add_rotations(&mut self, node_id: u64) -> Result<(), FemError> {
        let n = self.node(node_id)?;
        self.give_rotations(n);
        Ok(())
    }

    /// Node `n` (internal index) gets rotations, once.
    fn give_rotations(&mut self, n: usize) {
        if !self.has_rotation[n] {
            self.has_rotation[n] = true;
            self.rotation_nodes.push(n);
        }
    }

    /// Whether node `n` (internal index) carries rotations.
    pub fn has_rotations(&self, n: usize) -> bool {
        self.has_rotation.get(n).copied().unwrap_or(false)
    }

    /// The nodes with rotational DOFs (internal indices).
    pub fn rotation_nodes(&self) -> &[usize] {
        &self.rotation_nodes
    }

    /// The DOF `(node id, component)` as `(internal index, component)`, for a constraint or a
    /// direct matrix named `label`.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::Constraint`] for a component beyond 5 or a rotation
    /// of a node without rotations.
    fn dof_of(&self, (id, c): (u64, usize), label: &str) -> Result<(usize, usize), FemError> {
        let n = self.node(id)?;
        if c > 5 || (c > 2 && !self.has_rotation[n]) {
            return Err(FemError::Constraint {
                label: label.into(),
                reason: format!(
                    "node {id} has no DOF {} (solid nodes have translations 1-3 only; rotations belong to beams, shells and rigid links' references)",
                    c + 1
                ),
            });
        }
        Ok((n, c))
    }

    /// Adds a linear multipoint constraint `u_dependent = sum_i w_i u_i` between DOFs given as
    /// `(node id, component)`, components 0-2 translations, 3-5 rotations of nodes with
    /// rotations. `label` says where it comes from (card, id, file and line) for error messages.
    /// Conflicts (a DOF dependent twice or also fixed, cycles) are found by [`Model::dof_map`].
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::Constraint`] for a component out of range, a
    /// rotation of a node without rotations or a weight that is not finite.
    pub fn add_constraint(
        &mut self,
        dependent: (u64, usize),
        terms: &[((u64, usize), f64)],
        label: &str,
    ) -> Result<(), FemError> {
        let dof = |d: (u64, usize)| self.dof_of(d, label);
        let dependent = dof(dependent)?;
        let mut t = Vec::with_capacity(terms.len());
        for &(d, w) in terms {
            if !w.is_finite() {
                return Err(FemError::Constraint {
                    label: label.into(),
                    reason: format!("the weight of node {} DOF {} is {w}", d.0, d.1 + 1),
                });
            }
            t.push((dof(d)?, w));
        }
        self.constraints.push(LinearConstraint {
            dependent,
            terms: t,
            label: label.into(),
        });
        Ok(())
    }

    /// A rigid link (Nastran RBE2, Abaqus/CalculiX kinematic coupling): the listed translation
    /// `components` (0, 1, 2) of every node in `nodes` follow the rigid motion of `reference`,
    /// `u_m = u_r + theta_r x (x_m - x_r)`. The reference gets rotations ([`Model::add_rotations`]);
    /// rotation directions that no linked node feels (all nodes on one line through the reference,
    /// or on the reference itself) are fixed by [`Model::dof_map`], having neither stiffness nor
    /// mass. A node listed twice, or the reference among the nodes, is skipped.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::Constraint`] for a component outside 0..3.
    pub fn add_rigid_link(
        &mut self,
        reference: u64,
        nodes: &[u64],
        components: &[usize],
        label: &str,
    ) -> Result<(), FemError> {
        if let Some(c) = components.iter().find(|c| **c > 2) {
            return Err(FemError::Constraint {
                label: label.into(),
                reason: format!(
                    "component {} of the linked nodes: solid nodes have translations 1-3 only",
                    c + 1
                ),
            });
        }
        let r = self.node(reference)?;
        self.add_rotations(reference)?;
        let xr = self.mesh.coords()[r];
        let mut seen = BTreeSet::new();
        for &id in nodes {
            let m = self.node(id)?;
            if m == r || !seen.insert(m) {
                continue;
            }
            let x = self.mesh.coords()[m];
            let d = [x[0] - xr[0], x[1] - xr[1], x[2] - xr[2]];
            // (theta x d)_c as coefficients of theta_x, theta_y, theta_z
            let rot = [[0.0, d[2], -d[1]], [-d[2], 0.0, d[0]], [d[1], -d[0], 0.0]];
            for &c in components {
                let mut terms = vec![((reference, c), 1.0)];
                for (j, w) in rot[c].iter().enumerate() {
                    if *w != 0.0 {
                        terms.push(((reference, 3 + j), *w));
                    }
                }
                self.add_constraint((id, c), &terms, label)?;
            }
        }
        Ok(())
    }

    /// A weighted-average link (Nastran RBE3, Abaqus/CalculiX distributing coupling): the listed
    /// `components` (0-2 translations; 3-5 rotations if the reference has them) of `reference`
    /// follow the rigid motion fitted by weighted least squares to the translations of the
    /// `nodes` (`(id, weight)`): with `x_c` the weighted centroid and `r_i = x_i - x_c`,
    /// `t = sum w_i u_i / sum w_i`, `theta = A^+ sum w_i r_i x u_i` with
    /// `A = sum w_i (|r_i|^2 I - r_i r_i^T)`, and `u_ref = t + theta x (x_ref - x_c)`
    /// (docs/MATH.md). At the centroid it is the weighted average; a rigid motion of the nodes
    /// moves the reference with it. Only the reference is constrained: the nodes keep their
    /// stiffness and gain none.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::Constraint`] for no nodes, a weight that is not
    /// positive and finite, or a component out of range.
    pub fn add_weighted_average(
        &mut self,
        reference: u64,
        components: &[usize],
        nodes: &[(u64, f64)],
        label: &str,
    ) -> Result<(), FemError> {
        let bad = |reason: String| FemError::Constraint {
            label: label.into(),
            reason,
        };
        let r = self.node(reference)?;
        let mut idx = Vec::with_capacity(nodes.len());
        for &(id, w) in nodes {
            if !(w.is_finite() && w > 0.0) {
                return Err(bad(format!(
                    "node {id} has weight {w}: weights must be positive"
                )));
            }
            let m = self.node(id)?;
            if m == r {
                return Err(bad(format!(
                    "the reference node {reference} is also one of the averaged nodes"
                )));
            }
            idx.push((id, m, w));
        }
        if idx.is_empty() {
            return Err(bad("no nodes to average".into()));
        }
        let coords = self.mesh.coords();
        let wsum: f64 = idx.iter().map(|p| p.2).sum();
        let mut xc = [0.0; 3];
        for &(_, m, w) in &idx {
            for i in 0..3 {
                xc[i] += w * coords[m][i] / wsum;
            }
        }
        let rel: Vec<[f64; 3]> = idx
            .iter()
            .map(|&(_, m, _)| std::array::from_fn(|i| coords[m][i] - xc[i]))
            .collect();
        let mut a = nalgebra::Matrix3::<f64>::zeros();
        for (&(_, _, w), ri) in idx.iter().zip(&rel) {
            let v = nalgebra::Vector3::from(*ri);
            a += w * (nalgebra::Matrix3::identity() * v.dot(&v) - v * v.transpose());
        }
        // pseudo-inverse: rotations about a line through collinear nodes are not determined
        let eig = a.symmetric_eigen();
        let top = eig.eigenvalues.max().max(0.0);
        let mut a_pinv = nalgebra::Matrix3::<f64>::zeros();
        for k in 0..3 {
            let l = eig.eigenvalues[k];
            if l > 1e-12 * top && top > 0.0 {
                let v = eig.eigenvectors.column(k);
                a_pinv += (v * v.transpose()) / l;
            }
        }
        let skew = |v: &[f64; 3]| {
            nalgebra::Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
        };
        let xr = coords[r];
        let d = [xr[0] - xc[0], xr[1] - xc[1], xr[2] - xc[2]];
        // theta = sum_i w_i A^+ S(r_i) u_i; u_ref = t - S(d) theta
        let sd = skew(&d);
        let blocks: Vec<(nalgebra::Matrix3<f64>, nalgebra::Matrix3<f64>)> = idx
            .iter()
            .zip(&rel)
            .map(|(&(_, _, w), ri)| {
                let th = w * a_pinv * skew(ri);
                (nalgebra::Matrix3::identity() * (w / wsum) - sd * th, th)
            })
            .collect();
        let scale = blocks
            .iter()
            .flat_map(|(b, _)| b.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for &c in components {
            if c > 5 || (c > 2 && !self.has_rotation[r]) {
                return Err(bad(format!(
                    "node {reference} has no DOF {} to make dependent",
                    c + 1
                )));
            }
            let mut terms = Vec::new();
            for ((id, _, _), (bt, bth)) in idx.iter().zip(&blocks) {
                let row = if c < 3 { bt.row(c) } else { bth.row(c - 3) };
                for j in 0..3 {
                    if row[j].abs() > 1e-14 * scale {
                        terms.push(((*id, j), row[j]));
                    }
                }
            }
            self.add_constraint((reference, c), &terms, label)?;
        }
        Ok(())
    }

    /// The multipoint constraints as given (internal node indices).
    pub fn constraints(&self) -> &[LinearConstraint] {
        &self.constraints
    }

    /// Whether node `n` (internal index) appears in a multipoint constraint.
    pub fn constrained_nodes(&self) -> Vec<bool> {
        let mut v = vec![false; self.mesh.node_count()];
        for c in &self.constraints {
            v[c.dependent.0] = true;
            for ((n, _), _) in &c.terms {
                v[*n] = true;
            }
        }
        v
    }

    /// The DOF map of the current boundary conditions and multipoint constraints.
    ///
    /// Rotations of a reference node that no constraint term reaches (a rigid link to nodes on
    /// one line through it) have neither stiffness nor mass: they are fixed here (every other
    /// direction is kept).
    ///
    /// # Errors
    /// [`FemError::Constraint`]: a DOF dependent twice or also fixed, a cycle of dependencies.
    pub fn dof_map(&self) -> Result<DofMap, FemError> {
        let (more_fixed, more_constraints) = self.rotation_closure();
        let mut fixed: Vec<(usize, usize)> = self.fixed.iter().copied().collect();
        fixed.extend(more_fixed);
        let mut cons = self.constraints.clone();
        cons.extend(more_constraints);
        DofMap::with_constraints(
            self.mesh.node_count(),
            fixed,
            &self.rotation_nodes,
            &cons,
            |n| self.mesh.node_id(n),
        )
    }

    /// What [`Model::dof_map`] adds for reference rotations that no linked node feels: the
    /// rotations to fix (nothing reaches the node's rotations) and the constraints `v . theta = 0`
    /// (some directions are reached), so that writers can state the same model.
    pub fn rotation_closure(&self) -> (Vec<(usize, usize)>, Vec<LinearConstraint>) {
        let grams = self.rotation_grams();
        (
            Self::unreached_rotations(&grams),
            self.null_rotation_constraints(&grams),
        )
    }

    /// Per rotation node, the Gram matrix of the rotation coefficients of the constraints that use
    /// its rotations as terms, when all three rotations are free and independent.
    ///
    /// A structural element that acts on the node's rotations adds its stiffness block there,
    /// `K_rr / max |K_rr|`: a direction no element stiffens and no constraint reaches (the bending
    /// rotations of a rod's node with torsion, a spring on one rotation) is a mechanism, fixed as
    /// Nastran's AUTOSPC fixes it.
    fn rotation_grams(&self) -> Vec<(usize, nalgebra::Matrix3<f64>)> {
        let mut out = Vec::new();
        let elastic = self.structural_rotation_blocks();
        // one pass over the fixed DOFs and the constraints (a model may have a rotation node per
        // shell node and thousands of links): nodes with a fixed or dependent rotation, and each
        // node's Gram matrix of the rotation coefficients of the constraints using it
        let mut busy = vec![false; self.mesh.node_count()];
        for &(n, c) in &self.fixed {
            busy[n] |= c >= 3;
        }
        let mut grams: std::collections::HashMap<usize, nalgebra::Matrix3<f64>> =
            std::collections::HashMap::new();
        for k in &self.constraints {
            busy[k.dependent.0] |= k.dependent.1 >= 3;
            let mut rows: BTreeMap<usize, nalgebra::Vector3<f64>> = BTreeMap::new();
            for ((m, c), w) in &k.terms {
                if *c >= 3 {
                    rows.entry(*m).or_insert_with(nalgebra::Vector3::zeros)[*c - 3] += w;
                }
            }
            for (m, a) in rows {
                *grams.entry(m).or_insert_with(nalgebra::Matrix3::zeros) += a * a.transpose();
            }
        }
        for &n in &self.rotation_nodes {
            if busy[n] {
                continue;
            }
            let mut g = grams
                .get(&n)
                .copied()
                .unwrap_or_else(nalgebra::Matrix3::zeros);
            let top = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if top > 0.0 {
                g /= top;
            }
            if let Some(k) = elastic.get(&n) {
                g += k;
            }
            out.push((n, g));
        }
        out
    }

    /// Per node whose rotations a structural element acts on, the sum of the elements' stiffness
    /// blocks on those rotations, each divided by its largest entry.
    fn structural_rotation_blocks(&self) -> BTreeMap<usize, nalgebra::Matrix3<f64>> {
        let mut out: BTreeMap<usize, nalgebra::Matrix3<f64>> = BTreeMap::new();
        for s in &self.structural {
            // a beam or a shell stiffens all three rotations of each of its nodes (torsion and two
            // bending planes; two bending rotations and the drilling one): no need to form it (a
            // membrane reaches no rotation)
            if matches!(s.kind, crate::structural::StructuralKind::Beam(_))
                || matches!(&s.kind, crate::structural::StructuralKind::Shell(sh) if sh.bending > 0.0)
            {
                for n in &s.nodes {
                    *out.entry(*n).or_insert_with(nalgebra::Matrix3::zeros) +=
                        nalgebra::Matrix3::identity();
                }
                continue;
            }
            // the element was checked when it was added: its matrices exist (direct stiffness
            // entries on one node's rotations are added after the elements)
            let Ok(sm) = s.matrices(self.mesh.coords(), crate::assembly::MassKind::Lumped) else {
                continue;
            };
            let nd = 3 * sm.parts.len();
            for (b, (n, part)) in sm.parts.iter().enumerate() {
                if *part != Part::Rotations {
                    continue;
                }
                let block = nalgebra::Matrix3::from_fn(|i, j| sm.k[(3 * b + i) * nd + 3 * b + j]);
                let top = block.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if top > 0.0 {
                    *out.entry(*n).or_insert_with(nalgebra::Matrix3::zeros) += block / top;
                }
            }
        }
        // a direct stiffness matrix reaches the rotations its diagonal blocks stiffen
        let mut direct: BTreeMap<usize, nalgebra::Matrix3<f64>> = BTreeMap::new();
        for e in &self.direct_stiffness {
            if e.a.0 == e.b.0 && e.a.1 > 2 && e.b.1 > 2 {
                let m = direct.entry(e.a.0).or_insert_with(nalgebra::Matrix3::zeros);
                m[(e.a.1 - 3, e.b.1 - 3)] += e.value;
                if e.a.1 != e.b.1 {
                    m[(e.b.1 - 3, e.a.1 - 3)] += e.value;
                }
            }
        }
        for (n, block) in direct {
            let top = block.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if top > 0.0 {
                *out.entry(n).or_insert_with(nalgebra::Matrix3::zeros) += block / top;
            }
        }
        out
    }

    /// The rotation directions nobody reaches: `(node, component)` to fix when the whole node's
    /// rotations are unreached, else nothing (partial null spaces become constraints).
    fn unreached_rotations(grams: &[(usize, nalgebra::Matrix3<f64>)]) -> Vec<(usize, usize)> {
        grams
            .iter()
            .filter(|(_, g)| g.iter().all(|v| *v == 0.0))
            .flat_map(|(n, _)| [(*n, 3), (*n, 4), (*n, 5)])
            .collect()
    }

    /// For rotation nodes whose Gram matrix is singular but not zero: `v . theta = 0` for every
    /// null direction `v`, solved for the largest component of an echelon form.
    fn null_rotation_constraints(
        &self,
        grams: &[(usize, nalgebra::Matrix3<f64>)],
    ) -> Vec<LinearConstraint> {
        let mut out = Vec::new();
        for &(n, g) in grams {
            let top = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if top == 0.0 {
                continue;
            }
            let eig = g.symmetric_eigen();
            let mut null: Vec<nalgebra::Vector3<f64>> = (0..3)
                .filter(|k| eig.eigenvalues[*k] <= 1e-10 * top)
                .map(|k| eig.eigenvectors.column(k).into_owned())
                .collect();
            // echelon form: each null vector eliminates one pivot component from the others
            let mut used = [false; 3];
            for i in 0..null.len() {
                let Some(p) = (0..3)
                    .filter(|c| !used[*c])
                    .max_by(|a, b| null[i][*a].abs().total_cmp(&null[i][*b].abs()))
                else {
                    break;
                };
                used[p] = true;
                let v = null[i] / null[i][p];
                for (j, w) in null.iter_mut().enumerate() {
                    if j != i {
                        *w -= v * w[p];
                    }
                }
                null[i] = v;
            }
            for v in &null {
                let Some(p) = (0..3).find(|c| (v[*c] - 1.0).abs() < 1e-12 && used[*c]) else {
                    continue;
                };
                let terms = (0..3)
                    .filter(|c| *c != p && v[*c] != 0.0 && !used[*c])
                    .map(|c| ((n, 3 + c), -v[c]))
                    .collect();
                out.push(LinearConstraint {
                    dependent: (n, 3 + p),
                    terms,
                    label: format!(
                        "(rotation of node {} that no linked node feels, eliminated)",
                        self.mesh.node_id(n)
                    ),
                });
            }
        }
        out
    }

    /// Total mass `sum_e rho_e V_e` plus the point masses (kg; a point mass counts the mean of
    /// its three directional masses, as does a direct mass matrix its masses under the three
    /// rigid translations).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] or a geometry error.
    pub fn total_mass(&self) -> Result<f64, FemError> {
        let mut x = Vec::new();
        let mut m = 0.0;
        for e in 0..self.mesh.element_count() {
            self.mesh.element_coords(e, &mut x);
            let el = self.mesh.element(e);
            let v = crate::kernel::element_volume(el.kind, &x).map_err(|b| {
                FemError::InvertedElement {
                    element: el.id,
                    det_j: b.det,
                    point: b.point,
                }
            })?;
            m += v * self.material_of(e)?.density;
        }
        // a point mass moves with its node: its mass in one direction, the mean of the three
        for p in &self.point_masses {
            m += (p.mass[0][0] + p.mass[1][1] + p.mass[2][2]) / 3.0;
        }
        m += self.rigid_masses.iter().map(|r| r.mass).sum::<f64>();
        for s in &self.structural {
            m += s.mass(self.mesh.coords());
        }
        // a direct mass matrix: its mass under a rigid translation along each axis, `d^T M d`
        // with `d` that translation on every node, the mean of the three
        let along: f64 = self
            .direct_mass
            .iter()
            .filter(|e| e.a.1 < 3 && e.a.1 == e.b.1)
            .map(|e| if e.a == e.b { e.value } else { 2.0 * e.value })
            .sum();
        m += along / 3.0;
        Ok(m)
    }
}
