//! Structural elements on nodes with rotations: two-node beams (Timoshenko, with Euler-Bernoulli
//! as the shear-rigid limit) and three-node beams ([`crate::beam3`]), rods, scalar springs and
//! bushings (docs/MATH.md, "Beams, springs and bushings"), and shells ([`crate::shell`],
//! [`crate::shell8`]).
//!
//! Each element's matrices are formed in closed form (beams: the exact stiffness of a uniform
//! Timoshenko beam and the consistent mass of its interdependent interpolation) on the DOFs it
//! reaches: `(node, translations)` and `(node, rotations)` pairs, which the assembly maps to the
//! DOF map's points ([`crate::dof::DofMap::rotation_point`]). Everything is in the basic frame.
//!
//! Nodes a structural element turns get three rotations ([`crate::model::Model::add_rotations`]),
//! so the DOF map, constraints, point masses with inertia ([`crate::model::RigidMass`]) and
//! sensors see them as they see a rigid link's reference node.

use crate::FemError;
use crate::assembly::MassKind;

/// Which three DOFs of a node an element reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The translations `u_x, u_y, u_z`.
    Translations,
    /// The rotations `theta_x, theta_y, theta_z` (radians).
    Rotations,
}

/// A beam section: area, second moments, torsion constant, shear factors and mass per length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSection {
    /// Area `A` (m^2).
    pub area: f64,
    /// `I1`: the second moment for bending in plane 1, the element's x-y plane (about local z;
    /// Nastran's I1, Abaqus' I11 for its 1-direction), m^4.
    pub i1: f64,
    /// `I2`: the second moment for bending in plane 2, the x-z plane (about local y), m^4.
    pub i2: f64,
    /// Torsion constant `J` (m^4).
    pub j: f64,
    /// Shear area factors `(K1, K2)` of planes 1 and 2 (the shear area is `K A`); `None`: no
    /// shear flexibility and no rotary inertia, the Euler-Bernoulli beam.
    pub shear: Option<[f64; 2]>,
    /// Non-structural mass per length (kg/m).
    pub nsm: f64,
}

/// A beam: material, section, the orientation of its cross-section and rigid offsets (two-node
/// beams; a three-node beam has none, nor releases, and needs shear factors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Young's modulus (Pa).
    pub e: f64,
    /// Shear modulus (Pa).
    pub g: f64,
    /// Density (kg/m^3).
    pub rho: f64,
    /// The section (at end A when the beam is tapered).
    pub section: BeamSection,
    /// End B's section of a tapered two-node beam (`None`: prismatic). `A`, `I1`, `I2`, `J` and
    /// the non-structural mass vary linearly from end A's to end B's; the shear factors are end
    /// A's, which end B's must repeat (docs/MATH.md, "Tapered beams").
    pub taper: Option<BeamSection>,
    /// A vector (basic frame) in plane 1, not parallel to the axis: local `z = x cross v`,
    /// `y = z cross x` (Nastran's orientation vector `v`, Abaqus' `n1` direction).
    pub orientation: [f64; 3],
    /// The offsets (basic frame) from each node to its end of the beam, rigid.
    pub offsets: [[f64; 3]; 2],
    /// Whether the lumped mass carries the section's polar inertia `rho (I1 + I2) L / 2` on each
    /// end's rotation about the axis (Nastran's CBEAM does, its CBAR does not); the lumped mass
    /// never carries bending rotary inertia.
    pub lumped_torsion: bool,
    /// Whether the consistent mass carries the polar inertia `rho (I1 + I2)` along the axis
    /// (Nastran's CBEAM and Abaqus' beams do; Nastran's CBAR does not: pyNastran's `pt145`,
    /// MSC Nastran's 30 eigenvalues of CBARs under COUPMASS to their seven printed digits
    /// without it, its torsion modes 5e-4 off with it).
    pub coupled_torsion: bool,
    /// The DOFs released at each end (`[end][c]`, `c` the element frame's x, y, z translations
    /// then rotations): the end no longer passes that force or moment to its node (Nastran's
    /// pin flags PA and PB; docs/MATH.md, "Beams"). The released DOFs are condensed out of the
    /// element's stiffness; a released DOF must carry no mass (a rotation under the lumped mass,
    /// torsion only without `lumped_torsion`), and the releases must leave the element no
    /// mechanism of its own.
    pub releases: [[bool; 6]; 2],
}

/// A rod: axial stiffness `E A` and, when `J > 0`, torsion `G J`; no bending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rod {
    /// Young's modulus (Pa).
    pub e: f64,
    /// Shear modulus (Pa).
    pub g: f64,
    /// Density (kg/m^3).
    pub rho: f64,
    /// Area (m^2).
    pub area: f64,
    /// Torsion constant (m^4); 0 for none.
    pub j: f64,
    /// Non-structural mass per length (kg/m).
    pub nsm: f64,
}

/// One end of a scalar spring: a node's translations or rotations along a direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringEnd {
    /// Internal node index.
    pub node: usize,
    /// Which DOFs.
    pub part: Part,
    /// The unit direction (basic frame): the spring acts on `direction . u`.
    pub direction: [f64; 3],
}

/// A scalar spring `k (d_a . u_a - d_b . u_b)^2 / 2` between two DOFs, or to ground (Nastran
/// CELAS1/CELAS2, Abaqus SPRING1/SPRING2), a scalar damper `c` on the same relative motion
/// (Nastran CDAMP1/CDAMP2: `k = 0`), or a scalar mass `m` with kinetic energy
/// `m (d_a . v_a - d_b . v_b)^2 / 2` (Nastran CMASS1/CMASS2: `k = 0`): each the matrix
/// `g g^T` with `g = (d_a, -d_b)` times its value (docs/MATH.md, "Beams, springs and bushings").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// Stiffness (N/m or N m/rad); 0 for a damper alone.
    pub k: f64,
    /// Structural damping coefficient (`GE`), kept for frequency responses.
    pub ge: f64,
    /// Viscous damping coefficient (N s/m or N m s/rad), for frequency responses and damped
    /// modes; 0 for none.
    pub viscous: f64,
    /// Scalar mass (kg or kg m^2) on the same relative motion; 0 for none.
    pub mass: f64,
    /// The first end.
    pub a: SpringEnd,
    /// The second end; `None`: grounded.
    pub b: Option<SpringEnd>,
}

/// A bushing: six stiffnesses along and about the axes of a frame, between two nodes or one node
/// and ground, acting at a point on the line between them (Nastran CBUSH with PBUSH).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bushing {
    /// Stiffnesses `K1..K3` (N/m) along and `K4..K6` (N m/rad) about the frame's axes.
    pub k: [f64; 6],
    /// Viscous damping `B1..B6` (N s/m, N m s/rad), kept for frequency responses.
    pub b: [f64; 6],
    /// Structural damping `GE`.
    pub ge: f64,
    /// The frame's axes in basic components (`axes[i]`: axis `i`).
    pub axes: [[f64; 3]; 3],
    /// Where the spring acts (basic frame), joined to each node by a rigid arm (so that the
    /// nodes' rotations take part); `None`: at the nodes themselves, on their relative motion.
    pub point: Option<[f64; 3]>,
}

/// What a structural element is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StructuralKind {
    /// A two-node beam, or a three-node one (ends, then the middle node; [`crate::beam3`]).
    Beam(Beam),
    /// A two-node rod.
    Rod(Rod),
    /// A scalar spring.
    Spring(Spring),
    /// A bushing.
    Bushing(Bushing),
    /// A shell: 3 nodes (MITC3), 4 (MITC4; [`crate::shell`]) or 8 (curved; [`crate::shell8`]).
    Shell(crate::shell::Shell),
}

impl StructuralKind {
    /// What the element is, in a word or two: `"beam"`, `"rod"`, `"spring"`, `"damper"`,
    /// `"scalar mass"`, `"bushing"`, `"shell"`.
    pub fn name(&self) -> &'static str {
        match self {
            StructuralKind::Beam(_) => "beam",
            StructuralKind::Rod(_) => "rod",
            StructuralKind::Spring(s) if s.k == 0.0 && s.viscous == 0.0 => "scalar mass",
            StructuralKind::Spring(s) if s.k == 0.0 => "damper",
            StructuralKind::Spring(_) => "spring",
            StructuralKind::Bushing(_) => "bushing",
            StructuralKind::Shell(_) => "shell",
        }
    }
}

/// A structural element: the user's id, its nodes (internal indices) and what it is.
#[derive(Debug, Clone, PartialEq)]
pub struct StructuralElement {
    /// The user's element id (shared with the mesh's solid elements: ids are unique in a model).
    pub id: u64,
    /// Internal node indices: two for rods, two or three for beams (ends, then the middle node),
    /// one or two for springs and bushings, three, four or eight for shells.
    pub nodes: Vec<usize>,
    /// The element.
    pub kind: StructuralKind,
}

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: V3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// The local axes of a line element from `a` to `b` with orientation vector `v`: rows x, y, z.
///
/// # Errors
/// A message for a zero length or a `v` parallel to the axis (within 1e-6 radians).
pub fn line_axes(a: V3, b: V3, v: V3) -> Result<(f64, [V3; 3]), String> {
    let d = sub(b, a);
    let l = norm(d);
    if !(l > 0.0 && l.is_finite()) {
        return Err(format!("its ends coincide (length {l:e})"));
    }
    let x = scale(d, 1.0 / l);
    let nv = norm(v);
    let z = cross(x, v);
    let nz = norm(z);
    if !(nv > 0.0 && nz > 1e-6 * nv) {
        return Err(format!(
            "its orientation vector {v:?} is parallel to its axis {x:?} (or zero): the cross-section's axes are undefined"
        ));
    }
    let z = scale(z, 1.0 / nz);
    let y = cross(z, x);
    Ok((l, [x, y, z]))
}

/// The interdependent shape functions of a two-node Timoshenko beam in one plane, at `xi = x / L`
/// with `phi = 12 E I / (k G A L^2)`: the deflection `w` and the section rotation `theta` (with
/// `theta = dw/dx` when `phi = 0`) against the DOFs `(w_1, theta_1, w_2, theta_2)`. They solve
/// the homogeneous beam equations exactly, so the stiffness they give is the exact one.
pub fn timoshenko_shape(xi: f64, l: f64, phi: f64) -> ([f64; 4], [f64; 4]) {
    let c = 1.0 / (1.0 + phi);
    let (x2, x3) = (xi * xi, xi * xi * xi);
    let w = [
        c * (2.0 * x3 - 3.0 * x2 - phi * xi + 1.0 + phi),
        c * l * (x3 - (2.0 + phi / 2.0) * x2 + (1.0 + phi / 2.0) * xi),
        -c * (2.0 * x3 - 3.0 * x2 - phi * xi),
        c * l * (x3 - (1.0 - phi / 2.0) * x2 - phi / 2.0 * xi),
    ];
    let t = [
        6.0 * c / l * (x2 - xi),
        c * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + phi),
        -6.0 * c / l * (x2 - xi),
        c * (3.0 * x2 - (2.0 - phi) * xi),
    ];
    (w, t)
}

/// The plane stiffness and consistent mass of a uniform Timoshenko beam on `(w_1, theta_1, w_2,
/// theta_2)`: `K = E I / ((1 + phi) L^3) [[12, 6L, -12, 6L], [6L, (4 + phi) L^2, -6L, (2 - phi)
/// L^2], ...]`, and `M = int (m N_w^T N_w + r N_theta^T N_theta) dx` for mass per length `m` and
/// rotary inertia per length `r`, integrated exactly (the integrands are of degree 6; four Gauss
/// points).
fn plane_matrices(ei: f64, phi: f64, l: f64, m: f64, r: f64) -> ([[f64; 4]; 4], [[f64; 4]; 4]) {
    let c = ei / ((1.0 + phi) * l * l * l);
    let k = [
        [12.0, 6.0 * l, -12.0, 6.0 * l],
        [6.0 * l, (4.0 + phi) * l * l, -6.0 * l, (2.0 - phi) * l * l],
        [-12.0, -6.0 * l, 12.0, -6.0 * l],
        [6.0 * l, (2.0 - phi) * l * l, -6.0 * l, (4.0 + phi) * l * l],
    ]
    .map(|row| row.map(|v| c * v));
    let mut mm = [[0.0; 4]; 4];
    let (gp, gw) = crate::quadrature::gauss_legendre(4);
    for (x, w) in gp.iter().zip(&gw) {
        let xi = 0.5 * (x + 1.0);
        let (nw, nt) = timoshenko_shape(xi, l, phi);
        let f = 0.5 * w * l;
        for i in 0..4 {
            for j in 0..4 {
                mm[i][j] += f * (m * nw[i] * nw[j] + r * nt[i] * nt[j]);
            }
        }
    }
    (k, mm)
}

/// `[[I, -S(w)], [0, I]]`: the rigid offset `w` from a node to an element's end, on the node's
/// translations and rotations (`u_end = u + theta x w`).
fn offset_map(w: V3) -> [[f64; 6]; 6] {
    let mut t = [[0.0; 6]; 6];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    // -S(w): theta x w = -w x theta
    let s = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            t[i][3 + j] = -s[i][j];
        }
    }
    t
}

/// `B^T A B` for square `A` (`n x n`) and `B` (`n x m`), row-major, exactly symmetric.
pub(crate) fn congruence(a: &[f64], b: &[f64], n: usize, m: usize) -> Vec<f64> {
    let mut ab = vec![0.0; n * m];
    for i in 0..n {
        for k in 0..n {
            let v = a[i * n + k];
            if v != 0.0 {
                for j in 0..m {
                    ab[i * m + j] += v * b[k * m + j];
                }
            }
        }
    }
    let mut out = vec![0.0; m * m];
    for k in 0..n {
        for i in 0..m {
            let v = b[k * m + i];
            if v != 0.0 {
                for j in 0..m {
                    out[i * m + j] += v * ab[k * m + j];
                }
            }
        }
    }
    // exactly symmetric, as the assembly requires
    for i in 0..m {
        for j in 0..i {
            let s = 0.5 * (out[i * m + j] + out[j * m + i]);
            out[i * m + j] = s;
            out[j * m + i] = s;
        }
    }
    out
}

/// An element's matrices on the DOF groups it reaches.
#[derive(Debug, Clone, PartialEq)]
pub struct StructuralMatrices {
    /// `(internal node, part)` of each block of three DOFs, in the matrices' order.
    pub parts: Vec<(usize, Part)>,
    /// Stiffness, row-major, `3 parts` square.
    pub k: Vec<f64>,
    /// Mass (diagonal for a lumped mass), row-major, `3 parts` square.
    pub m: Vec<f64>,
}

fn check_positive(element: u64, what: &str, v: f64, allow_zero: bool) -> Result<(), FemError> {
    if !v.is_finite() || v < 0.0 || (!allow_zero && v == 0.0) {
        return Err(FemError::InvalidStructural {
            element,
            reason: format!(
                "{what} is {v}; it must be {}",
                if allow_zero {
                    "zero or positive"
                } else {
                    "positive"
                }
            ),
        });
    }
    Ok(())
}

impl StructuralElement {
    /// Checks the element's values: positive moduli, areas and stiffnesses where they act,
    /// finite everything.
    ///
    /// # Errors
    /// [`FemError::InvalidStructural`] naming the element and the value.
    pub fn validate(&self) -> Result<(), FemError> {
        let id = self.id;
        let count = self.nodes.len();
        let wanted = match &self.kind {
            StructuralKind::Beam(_) => {
                (count == 2 || count == 3)
                    && (0..count).all(|i| (0..i).all(|j| self.nodes[i] != self.nodes[j]))
            }
            StructuralKind::Rod(_) => count == 2,
            StructuralKind::Spring(s) => {
                let mut ends = vec![s.a.node];
                ends.extend(s.b.map(|b| b.node));
                ends.iter().all(|n| self.nodes.contains(n)) && (1..=2).contains(&count)
            }
            StructuralKind::Bushing(_) => (1..=2).contains(&count),
            StructuralKind::Shell(_) => {
                matches!(count, 3 | 4 | 6 | 8)
                    && (0..count).all(|i| (0..i).all(|j| self.nodes[i] != self.nodes[j]))
            }
        };
        if !wanted {
            return Err(FemError::InvalidStructural {
                element: id,
                reason: format!(
                    "{count} nodes {:?} do not fit the element (beams two or three distinct, rods two, springs and bushings one or two, a spring's ends among them, shells three, four, six or eight distinct)",
                    self.nodes
                ),
            });
        }
        match &self.kind {
            StructuralKind::Shell(s) => s.validate(id)?,
            StructuralKind::Beam(b) => {
                check_positive(id, "Young's modulus E", b.e, false)?;
                check_positive(id, "the shear modulus G", b.g, false)?;
                check_positive(id, "the density", b.rho, true)?;
                let s = &b.section;
                for (end, s) in [("", s)]
                    .into_iter()
                    .chain(b.taper.iter().map(|t| (" at end B", t)))
                {
                    check_positive(id, &format!("the area A{end}"), s.area, false)?;
                    check_positive(id, &format!("I1{end}"), s.i1, true)?;
                    check_positive(id, &format!("I2{end}"), s.i2, true)?;
                    check_positive(id, &format!("the torsion constant J{end}"), s.j, true)?;
                    check_positive(id, &format!("the non-structural mass{end}"), s.nsm, true)?;
                }
                if let Some(t) = &b.taper
                    && (count == 3 || t.shear != s.shear)
                {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: format!(
                            "a tapered beam has two nodes and one pair of shear factors (end A's {:?}, end B's {:?}, {count} nodes)",
                            s.shear, t.shear
                        ),
                    });
                }
                if let Some(k) = s.shear
                    && !(k[0] > 0.0 && k[1] > 0.0)
                {
                    // an infinite factor is a shear-rigid plane
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: format!("its shear factors {k:?} must be positive"),
                    });
                }
                if b.orientation
                    .iter()
                    .chain(b.offsets.iter().flatten())
                    .any(|v| !v.is_finite())
                {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: "its orientation vector or offsets are not finite".into(),
                    });
                }
                if count == 3
                    && (s.shear.is_none()
                        || b.offsets.iter().flatten().any(|v| *v != 0.0)
                        || b.releases.iter().flatten().any(|r| *r))
                {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: "a three-node beam is shear-flexible (its section needs shear factors) and has neither offsets nor released DOFs".into(),
                    });
                }
            }
            StructuralKind::Rod(r) => {
                check_positive(id, "Young's modulus E", r.e, false)?;
                check_positive(id, "the density", r.rho, true)?;
                check_positive(id, "the area A", r.area, false)?;
                check_positive(id, "the torsion constant J", r.j, true)?;
                check_positive(id, "the non-structural mass", r.nsm, true)?;
                if r.j > 0.0 {
                    check_positive(id, "the shear modulus G", r.g, false)?;
                }
            }
            StructuralKind::Spring(s) => {
                if !(s.k.is_finite()
                    && s.ge.is_finite()
                    && s.viscous.is_finite()
                    && s.mass.is_finite())
                    || (s.k == 0.0 && s.viscous == 0.0 && s.mass == 0.0)
                {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: format!(
                            "its stiffness is {} (GE {}, viscous damping {}, mass {}): a spring needs a finite, non-zero stiffness, a damper a finite, non-zero damping, a scalar mass a finite, non-zero mass",
                            s.k, s.ge, s.viscous, s.mass
                        ),
                    });
                }
            }
            StructuralKind::Bushing(b) => {
                if b.k.iter().chain(&b.b).any(|v| !v.is_finite() || *v < 0.0)
                    || !b.ge.is_finite()
                    || b.point.iter().flatten().any(|v| !v.is_finite())
                {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: format!(
                            "stiffnesses {:?} and damping {:?} must be finite and not negative",
                            b.k, b.b
                        ),
                    });
                }
                // a damper alone (B without K) is a valid bushing: it acts in frequency responses
                if b.k.iter().chain(&b.b).all(|v| *v == 0.0) {
                    return Err(FemError::InvalidStructural {
                        element: id,
                        reason: "it has neither stiffness nor damping (K1 to K6 and B1 to B6 all zero or blank)".into(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The `(node, part)` blocks the element reaches, in its matrices' order (nodes as given, and
    /// rotations only where the element acts on them).
    pub fn parts(&self) -> Vec<(usize, Part)> {
        let both = |n: usize| [(n, Part::Translations), (n, Part::Rotations)];
        match &self.kind {
            StructuralKind::Shell(s) if s.bending == 0.0 => self
                .nodes
                .iter()
                .map(|n| (*n, Part::Translations))
                .collect(),
            StructuralKind::Beam(_) | StructuralKind::Shell(_) => {
                self.nodes.iter().flat_map(|n| both(*n)).collect()
            }
            StructuralKind::Rod(r) => {
                if r.j > 0.0 {
                    self.nodes.iter().flat_map(|n| both(*n)).collect()
                } else {
                    self.nodes
                        .iter()
                        .map(|n| (*n, Part::Translations))
                        .collect()
                }
            }
            StructuralKind::Spring(s) => {
                let mut v = vec![(s.a.node, s.a.part)];
                v.extend(s.b.map(|b| (b.node, b.part)));
                v
            }
            StructuralKind::Bushing(b) => {
                if self.bushing_needs_rotations(b) {
                    self.nodes.iter().flat_map(|n| both(*n)).collect()
                } else {
                    self.nodes
                        .iter()
                        .map(|n| (*n, Part::Translations))
                        .collect()
                }
            }
        }
    }

    /// A bushing reaches its nodes' rotations when it has a rotational stiffness or damping, or
    /// acts at a point joined to them by rigid arms.
    fn bushing_needs_rotations(&self, b: &Bushing) -> bool {
        b.k[3..].iter().chain(&b.b[3..]).any(|v| *v != 0.0) || b.point.is_some()
    }

    /// The positions of a three-node element's nodes.
    fn three(&self, coords: &[[f64; 3]]) -> [[f64; 3]; 3] {
        std::array::from_fn(|a| coords[self.nodes[a]])
    }

    /// Checks the element's values ([`StructuralElement::validate`]) and geometry at node
    /// positions `coords` (coincident ends, an orientation vector along the axis, a degenerate,
    /// inverted or warped shell) without forming its matrices.
    ///
    /// # Errors
    /// [`FemError::InvalidStructural`] naming the element.
    pub fn check_geometry(&self, coords: &[[f64; 3]]) -> Result<(), FemError> {
        self.validate()?;
        let bad = |reason: String| FemError::InvalidStructural {
            element: self.id,
            reason,
        };
        match &self.kind {
            StructuralKind::Beam(b) if self.nodes.len() == 3 => {
                crate::beam3::check(b, &self.three(coords)).map_err(bad)
            }
            StructuralKind::Beam(b) => line_axes(
                add(coords[self.nodes[0]], b.offsets[0]),
                add(coords[self.nodes[1]], b.offsets[1]),
                b.orientation,
            )
            .map(|_| ())
            .map_err(bad),
            StructuralKind::Rod(_) => {
                let l = norm(sub(coords[self.nodes[1]], coords[self.nodes[0]]));
                if l > 0.0 {
                    Ok(())
                } else {
                    Err(bad(format!("its ends coincide (length {l:e})")))
                }
            }
            StructuralKind::Shell(_) => {
                let x: Vec<[f64; 3]> = self.nodes.iter().map(|n| coords[*n]).collect();
                crate::shell::check(&x).map_err(bad)
            }
            StructuralKind::Spring(_) | StructuralKind::Bushing(_) => Ok(()),
        }
    }

    /// The element's mass (kg): `(rho A + nsm) L` for beams and rods (between the nodes, offsets
    /// aside); for a scalar mass the mean over the three directions of its mass in a rigid
    /// translation, `m |g_t|^2 / 3` with `g_t` the translational part of `(d_a, -d_b)` (a
    /// point mass's convention, [`crate::model::Model::total_mass`]); zero for springs and
    /// bushings.
    pub fn mass(&self, coords: &[[f64; 3]]) -> f64 {
        let length = || norm(sub(coords[self.nodes[1]], coords[self.nodes[0]]));
        match &self.kind {
            StructuralKind::Beam(b) if self.nodes.len() == 3 => {
                (b.rho * b.section.area + b.section.nsm) * crate::beam3::length(&self.three(coords))
            }
            StructuralKind::Beam(b) => {
                let l = norm(sub(
                    add(coords[self.nodes[1]], b.offsets[1]),
                    add(coords[self.nodes[0]], b.offsets[0]),
                ));
                // linear along a tapered beam: the mean of the ends
                let b_end = b.taper.as_ref().unwrap_or(&b.section);
                let per_length = |s: &BeamSection| b.rho * s.area + s.nsm;
                0.5 * (per_length(&b.section) + per_length(b_end)) * l
            }
            StructuralKind::Rod(r) => (r.rho * r.area + r.nsm) * length(),
            StructuralKind::Spring(s) => {
                let translation = |e: &SpringEnd| match e.part {
                    Part::Translations => e.direction,
                    Part::Rotations => [0.0; 3],
                };
                let g = sub(
                    translation(&s.a),
                    s.b.as_ref().map_or([0.0; 3], translation),
                );
                s.mass * (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / 3.0
            }
            StructuralKind::Bushing(_) => 0.0,
            StructuralKind::Shell(s) => {
                (s.rho * s.t + s.nsm) * self.shell_area(coords).unwrap_or(0.0)
            }
        }
    }

    /// A shell's mid-surface area (a quadrilateral's as its two triangles, a six-node triangle's
    /// as its four, an 8-node shell's by its own rule); `None` for an element that is not a shell.
    pub fn shell_area(&self, coords: &[[f64; 3]]) -> Option<f64> {
        if !matches!(self.kind, StructuralKind::Shell(_)) {
            return None;
        }
        let x = |i: usize| coords[self.nodes[i]];
        let tri = |a: V3, b: V3, c: V3| 0.5 * norm(cross(sub(b, a), sub(c, a)));
        Some(match self.nodes.len() {
            8 => crate::shell8::area8(&std::array::from_fn::<_, 8, _>(x)),
            6 => crate::shell::SIX_NODE_TRIANGLES
                .iter()
                .map(|t| tri(x(t[0]), x(t[1]), x(t[2])))
                .sum(),
            4 => tri(x(0), x(1), x(2)) + tri(x(0), x(2), x(3)),
            _ => tri(x(0), x(1), x(2)),
        })
    }

    /// A shell's matrices with their parts scaled (`crate::shell::Scales`); a membrane's on its
    /// nodes' translations alone.
    fn shell_matrices(
        &self,
        s: &crate::shell::Shell,
        coords: &[[f64; 3]],
        mass: MassKind,
        sc: crate::shell::Scales,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let (k, m) = self.shell_matrices_six(s, coords, mass, sc)?;
        if s.bending > 0.0 {
            return Ok((k, m));
        }
        // a membrane: no term reaches the rotations (no bending, shear, drilling or rotary
        // inertia), so its translations' block is the element
        let n = 6 * self.nodes.len();
        let keep: Vec<usize> = (0..n).filter(|i| i % 6 < 3).collect();
        let block = |a: &[f64]| -> Vec<f64> {
            keep.iter()
                .flat_map(|&r| keep.iter().map(move |&c| a[r * n + c]))
                .collect()
        };
        Ok((block(&k), block(&m)))
    }

    /// A shell's matrices on all six DOFs of its nodes.
    fn shell_matrices_six(
        &self,
        s: &crate::shell::Shell,
        coords: &[[f64; 3]],
        mass: MassKind,
        sc: crate::shell::Scales,
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        if self.nodes.len() == 3 {
            let x: [[f64; 3]; 3] = std::array::from_fn(|i| coords[self.nodes[i]]);
            crate::shell::matrices3_scaled(s, &x, mass, sc)
        } else if self.nodes.len() == 6 {
            // a six-node triangle as four flat three-node triangles on its corners and midside
            // nodes (docs/MATH.md, "Six-node triangles")
            let (mut k, mut m) = (vec![0.0; 36 * 36], vec![0.0; 36 * 36]);
            for sub in crate::shell::SIX_NODE_TRIANGLES {
                let x: [[f64; 3]; 3] = std::array::from_fn(|i| coords[self.nodes[sub[i]]]);
                let (ks, ms) = crate::shell::matrices3_scaled(s, &x, mass, sc)?;
                for a in 0..18 {
                    let ra = 6 * sub[a / 6] + a % 6;
                    for b in 0..18 {
                        let cb = 6 * sub[b / 6] + b % 6;
                        k[ra * 36 + cb] += ks[a * 18 + b];
                        m[ra * 36 + cb] += ms[a * 18 + b];
                    }
                }
            }
            Ok((k, m))
        } else if self.nodes.len() == 8 {
            let x: [[f64; 3]; 8] = std::array::from_fn(|i| coords[self.nodes[i]]);
            crate::shell8::matrices8_scaled(s, &x, mass, sc)
        } else {
            let x: [[f64; 3]; 4] = std::array::from_fn(|i| coords[self.nodes[i]]);
            crate::shell::matrices_scaled(s, &x, mass, sc)
        }
    }

    /// A shell's matrices split by how they depend on its thickness `t`: the part linear in `t`
    /// (membrane, transverse shear and drilling stiffness; the mass `rho t`) and the part cubic
    /// in it (bending stiffness; rotary inertia), the non-structural mass in neither. At
    /// thickness `t (1 + p)` the element's stiffness is `(1 + p) K_1 + (1 + p)^3 K_3` and its
    /// mass `(1 + p) M_1 + (1 + p)^3 M_3 + M_nsm` (docs/MATH.md, "Thickness parameters").
    /// `None` for an element that is not a shell.
    ///
    /// # Errors
    /// As [`StructuralElement::matrices`].
    pub fn thickness_parts(
        &self,
        coords: &[[f64; 3]],
        mass: MassKind,
    ) -> Result<Option<[StructuralMatrices; 2]>, FemError> {
        let StructuralKind::Shell(s) = &self.kind else {
            return Ok(None);
        };
        self.validate()?;
        let bad = |reason: String| FemError::InvalidStructural {
            element: self.id,
            reason,
        };
        let part = |linear: f64, cubic: f64| -> Result<StructuralMatrices, FemError> {
            let sc = crate::shell::Scales {
                linear,
                cubic,
                nsm: 0.0,
            };
            let (k, m) = self.shell_matrices(s, coords, mass, sc).map_err(bad)?;
            Ok(StructuralMatrices {
                parts: self.parts(),
                k,
                m,
            })
        };
        Ok(Some([part(1.0, 0.0)?, part(0.0, 1.0)?]))
    }

    /// A two-node beam's stiffness split by section property ([`SectionPart`]; docs/MATH.md,
    /// "Beam section parameters"): in the beam's frame the axial, torsional and the two bending
    /// planes' DOFs are uncoupled, so the element stiffness is the sum of the four parts, each
    /// turned to the basic frame with the offsets as the whole is. `None` for an element that is
    /// not a two-node beam.
    ///
    /// # Errors
    /// As [`StructuralElement::matrices`]; a beam with end releases (their condensation couples
    /// the parts, whose sum is then not the element's stiffness).
    pub fn section_part(
        &self,
        coords: &[[f64; 3]],
        part: SectionPart,
    ) -> Result<Option<Vec<f64>>, FemError> {
        let StructuralKind::Beam(b) = &self.kind else {
            return Ok(None);
        };
        if self.nodes.len() != 2 {
            return Ok(None);
        }
        self.validate()?;
        let bad = |reason: String| FemError::InvalidStructural {
            element: self.id,
            reason,
        };
        if b.releases.iter().flatten().any(|r| *r) {
            return Err(bad(
                "its end releases couple the section's stiffnesses: a section parameter needs a beam without releases".into(),
            ));
        }
        let ends = [
            add(coords[self.nodes[0]], b.offsets[0]),
            add(coords[self.nodes[1]], b.offsets[1]),
        ];
        let (l, axes) = line_axes(ends[0], ends[1], b.orientation).map_err(bad)?;
        let (kl, _) = beam_local(b, l, MassKind::Consistent);
        let keep = part.local_dofs();
        let mut masked = vec![0.0; 144];
        for &i in keep {
            for &j in keep {
                masked[i * 12 + j] = kl[i * 12 + j];
            }
        }
        Ok(Some(congruence(&masked, &beam_transform(b, &axes), 12, 12)))
    }

    /// Whether the element acts on its nodes' rotations (so they must carry them).
    pub fn needs_rotations(&self) -> bool {
        self.parts().iter().any(|(_, p)| *p == Part::Rotations)
    }

    /// The element's stiffness and mass (`mass` lumped: half the mass on each node's
    /// translations, none on rotations, Nastran's lumped convention) at node positions `coords`
    /// (indexed by internal node).
    ///
    /// # Errors
    /// [`FemError::InvalidStructural`]: invalid values, coincident ends, an orientation vector
    /// parallel to the axis.
    pub fn matrices(
        &self,
        coords: &[[f64; 3]],
        mass: MassKind,
    ) -> Result<StructuralMatrices, FemError> {
        self.validate()?;
        let bad = |reason: String| FemError::InvalidStructural {
            element: self.id,
            reason,
        };
        let parts = self.parts();
        let nd = 3 * parts.len();
        match &self.kind {
            StructuralKind::Shell(s) => {
                let (k, m) = self
                    .shell_matrices(s, coords, mass, crate::shell::Scales::ALL)
                    .map_err(bad)?;
                Ok(StructuralMatrices { parts, k, m })
            }
            StructuralKind::Beam(b) if self.nodes.len() == 3 => {
                let (k, m) = crate::beam3::matrices(b, &self.three(coords), mass).map_err(bad)?;
                Ok(StructuralMatrices { parts, k, m })
            }
            StructuralKind::Beam(b) => {
                let ends = [
                    add(coords[self.nodes[0]], b.offsets[0]),
                    add(coords[self.nodes[1]], b.offsets[1]),
                ];
                let (l, axes) = line_axes(ends[0], ends[1], b.orientation).map_err(bad)?;
                let (mut kl, ml) = beam_local(b, l, mass);
                release(&mut kl, &ml, &b.releases).map_err(bad)?;
                let t = beam_transform(b, &axes);
                let k = congruence(&kl, &t, 12, 12);
                let m = match mass {
                    MassKind::Consistent => congruence(&ml, &t, 12, 12),
                    // a lumped translational mass is the same in every frame; the torsional
                    // inertia turns with the axis (its diagonal in the basic frame is kept, the
                    // lumped mass being diagonal)
                    MassKind::Lumped => {
                        let mut d = ml;
                        if b.lumped_torsion {
                            for end in 0..2 {
                                let j = d[(6 * end + 3) * 12 + 6 * end + 3];
                                for i in 0..3 {
                                    d[(6 * end + 3 + i) * 12 + 6 * end + 3 + i] =
                                        j * axes[0][i] * axes[0][i];
                                }
                            }
                        }
                        d
                    }
                };
                Ok(StructuralMatrices { parts, k, m })
            }
            StructuralKind::Rod(r) => {
                let (a, bpos) = (coords[self.nodes[0]], coords[self.nodes[1]]);
                let d = sub(bpos, a);
                let l = norm(d);
                if !(l > 0.0) {
                    return Err(bad(format!("its ends coincide (length {l:e})")));
                }
                let x = scale(d, 1.0 / l);
                let mut k = vec![0.0; nd * nd];
                let mut m = vec![0.0; nd * nd];
                let ea = r.e * r.area / l;
                let mass_total = (r.rho * r.area + r.nsm) * l;
                let torsion = r.j > 0.0;
                // block offsets of node a's and b's translations (and rotations)
                let (ta, tb) = if torsion { (0, 6) } else { (0, 3) };
                for i in 0..3 {
                    for j in 0..3 {
                        let v = ea * x[i] * x[j];
                        k[(ta + i) * nd + ta + j] += v;
                        k[(tb + i) * nd + tb + j] += v;
                        k[(ta + i) * nd + tb + j] -= v;
                        k[(tb + i) * nd + ta + j] -= v;
                        if torsion {
                            let gj = r.g * r.j / l * x[i] * x[j];
                            k[(3 + i) * nd + 3 + j] += gj;
                            k[(9 + i) * nd + 9 + j] += gj;
                            k[(3 + i) * nd + 9 + j] -= gj;
                            k[(9 + i) * nd + 3 + j] -= gj;
                        }
                    }
                    match mass {
                        MassKind::Consistent => {
                            m[(ta + i) * nd + ta + i] += mass_total / 3.0;
                            m[(tb + i) * nd + tb + i] += mass_total / 3.0;
                            m[(ta + i) * nd + tb + i] += mass_total / 6.0;
                            m[(tb + i) * nd + ta + i] += mass_total / 6.0;
                        }
                        MassKind::Lumped => {
                            m[(ta + i) * nd + ta + i] += mass_total / 2.0;
                            m[(tb + i) * nd + tb + i] += mass_total / 2.0;
                        }
                    }
                }
                if torsion && mass == MassKind::Consistent {
                    // polar moment of a rod's section: J stands for it (a circular section)
                    let ip = r.rho * r.j * l;
                    for i in 0..3 {
                        for j in 0..3 {
                            let v = ip * x[i] * x[j];
                            m[(3 + i) * nd + 3 + j] += v / 3.0;
                            m[(9 + i) * nd + 9 + j] += v / 3.0;
                            m[(3 + i) * nd + 9 + j] += v / 6.0;
                            m[(9 + i) * nd + 3 + j] += v / 6.0;
                        }
                    }
                }
                Ok(StructuralMatrices { parts, k, m })
            }
            StructuralKind::Spring(s) => {
                let mut g = vec![0.0; nd];
                g[..3].copy_from_slice(&s.a.direction);
                if let Some(b) = &s.b {
                    for i in 0..3 {
                        g[3 + i] = -b.direction[i];
                    }
                }
                let k: Vec<f64> = (0..nd * nd)
                    .map(|ij| s.k * g[ij / nd] * g[ij % nd])
                    .collect();
                // a scalar mass is the same matrix whatever the mass formulation (Nastran adds a
                // CMASS's whole matrix to the lumped mass too)
                let m: Vec<f64> = (0..nd * nd)
                    .map(|ij| s.mass * g[ij / nd] * g[ij % nd])
                    .collect();
                Ok(StructuralMatrices { parts, k, m })
            }
            StructuralKind::Bushing(b) => {
                // relative motion at the spring point in the bushing's axes:
                // delta = R [(u_b + theta_b x (P - x_b)) - (u_a + theta_a x (P - x_a))],
                // delta_theta = R (theta_b - theta_a); grounded: the b terms are absent
                let rot = parts.len() == 2 * self.nodes.len();
                let mut bm = vec![0.0; 6 * nd];
                for (end, &n) in self.nodes.iter().enumerate() {
                    let sign = if end == 0 { -1.0 } else { 1.0 };
                    let e = offset_map(b.point.map_or([0.0; 3], |p| sub(p, coords[n])));
                    let cols = if rot { 6 } else { 3 };
                    let base = end * cols;
                    for i in 0..3 {
                        for j in 0..cols {
                            let (mut vt, mut vr) = (0.0, 0.0);
                            for kx in 0..3 {
                                vt += b.axes[i][kx] * e[kx][j];
                                vr += b.axes[i][kx] * e[3 + kx][j];
                            }
                            bm[i * nd + base + j] += sign * vt;
                            bm[(3 + i) * nd + base + j] += sign * vr;
                        }
                    }
                }
                let d: Vec<f64> = (0..36)
                    .map(|ij| if ij / 6 == ij % 6 { b.k[ij / 6] } else { 0.0 })
                    .collect();
                let k = congruence(&d, &bm, 6, nd);
                Ok(StructuralMatrices {
                    parts,
                    k,
                    m: vec![0.0; nd * nd],
                })
            }
        }
    }
}

/// A beam's local stiffness and mass (12 x 12 on `(u, v, w, theta_x, theta_y, theta_z)` of each
/// end, local axes): axial, torsion and the two bending planes. Plane 1 (x-y) bends with `I1`
/// and `theta_z = dv/dx`; plane 2 (x-z) with `I2` and `theta_y = -dw/dx`.
/// A two-node beam's map from its nodes' DOFs (basic frame) to its frame's end DOFs, the offsets
/// included: local `(R u_end, R theta)` with `u_end = u + theta x w`.
fn beam_transform(b: &Beam, axes: &[V3; 3]) -> Vec<f64> {
    let mut t = vec![0.0; 144];
    for end in 0..2 {
        let e = offset_map(b.offsets[end]);
        for blk in 0..2 {
            for i in 0..3 {
                for j in 0..6 {
                    let v: f64 = (0..3).map(|k| axes[i][k] * e[3 * blk + k][j]).sum();
                    t[(6 * end + 3 * blk + i) * 12 + 6 * end + j] = v;
                }
            }
        }
    }
    t
}

/// A part of a beam's stiffness by section property, for updating (docs/MATH.md, "Beam section
/// parameters"): a factor `1 + p` on it scales `E A`, `G J`, or one bending plane's `E I` with
/// its transverse shear stiffness `k G A` (the plane's shear parameter `phi` kept).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SectionPart {
    /// Axial stiffness `E A`.
    Axial,
    /// Torsional stiffness `G J`.
    Torsion,
    /// Bending in the plane of the local y axis (`E I1`, femu's `i1`) with its shear.
    Bending1,
    /// Bending in the plane of the local z axis (`E I2`) with its shear.
    Bending2,
}

impl SectionPart {
    /// The beam's frame DOFs (`6 end + component`) the part acts on.
    fn local_dofs(self) -> &'static [usize] {
        match self {
            SectionPart::Axial => &[0, 6],
            SectionPart::Torsion => &[3, 9],
            SectionPart::Bending1 => &[1, 5, 7, 11],
            SectionPart::Bending2 => &[2, 4, 8, 10],
        }
    }

    /// The prefix naming a set's part in a group name (`"EI1:SPARS"`).
    pub fn prefix(self) -> &'static str {
        match self {
            SectionPart::Axial => "EA:",
            SectionPart::Torsion => "GJ:",
            SectionPart::Bending1 => "EI1:",
            SectionPart::Bending2 => "EI2:",
        }
    }

    /// Every part, in the order of [`SectionPart::prefix`]'s names.
    pub const ALL: [SectionPart; 4] = [
        SectionPart::Axial,
        SectionPart::Torsion,
        SectionPart::Bending1,
        SectionPart::Bending2,
    ];
}

/// Condenses the released DOFs (`releases[end][c]`, local index `6 end + c`) out of the local
/// stiffness `k` (12 x 12): `K <- K - K_:r K_r: / K_rr` for each in turn, which leaves the
/// released rows and columns zero (static condensation: the released end DOF follows the rest
/// without force). Refused: a released DOF with mass in `m` (its inertia would be lost), and one
/// the element has no stiffness left on (a mechanism within the element, such as torsion released
/// at both ends).
fn release(k: &mut [f64], m: &[f64], releases: &[[bool; 6]; 2]) -> Result<(), String> {
    const NAMES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
    let top = (0..12).map(|i| k[i * 12 + i].abs()).fold(0.0, f64::max);
    for end in 0..2 {
        for c in 0..6 {
            if !releases[end][c] {
                continue;
            }
            let r = 6 * end + c;
            let what = format!(
                "its released DOF {} ({}) at end {}",
                c + 1,
                NAMES[c],
                ["A", "B"][end]
            );
            if (0..12).any(|j| m[r * 12 + j] != 0.0) {
                return Err(format!(
                    "{what} carries mass in this mass matrix, which a release would lose: femu releases DOFs without mass (rotations under the lumped mass)"
                ));
            }
            let pivot = k[r * 12 + r];
            if !(pivot > 1e-12 * top) {
                return Err(format!(
                    "{what} leaves the element a mechanism (no stiffness left on it: a DOF released at both ends, or one the section does not resist)"
                ));
            }
            let col: Vec<f64> = (0..12).map(|i| k[i * 12 + r]).collect();
            for i in 0..12 {
                for j in 0..12 {
                    k[i * 12 + j] -= col[i] * col[j] / pivot;
                }
            }
            for i in 0..12 {
                k[i * 12 + r] = 0.0;
                k[r * 12 + i] = 0.0;
            }
        }
    }
    Ok(())
}

fn beam_local(b: &Beam, l: f64, mass: MassKind) -> (Vec<f64>, Vec<f64>) {
    if let Some(end_b) = &b.taper {
        return tapered_local(b, end_b, l, mass);
    }
    let s = &b.section;
    let mut k = vec![0.0; 144];
    let mut m = vec![0.0; 144];
    let mpl = b.rho * s.area + s.nsm;
    let put = |a: &mut Vec<f64>, i: usize, j: usize, v: f64| a[i * 12 + j] += v;
    let ea = b.e * s.area / l;
    let gj = b.g * s.j / l;
    for (i, j, sign) in [(0, 0, 1.0), (6, 6, 1.0), (0, 6, -1.0), (6, 0, -1.0)] {
        put(&mut k, i, j, sign * ea);
        put(&mut k, i + 3, j + 3, sign * gj);
    }
    match mass {
        MassKind::Lumped => {
            for end in 0..2 {
                for i in 0..3 {
                    put(&mut m, 6 * end + i, 6 * end + i, mpl * l / 2.0);
                }
                if b.lumped_torsion {
                    put(
                        &mut m,
                        6 * end + 3,
                        6 * end + 3,
                        b.rho * (s.i1 + s.i2) * l / 2.0,
                    );
                }
            }
        }
        MassKind::Consistent => {
            let ip = if b.coupled_torsion {
                b.rho * (s.i1 + s.i2)
            } else {
                0.0
            };
            for (i, j, f) in [(0, 0, 2.0), (6, 6, 2.0), (0, 6, 1.0), (6, 0, 1.0)] {
                put(&mut m, i, j, f * mpl * l / 6.0);
                put(&mut m, i + 3, j + 3, f * ip * l / 6.0);
            }
        }
    }
    // plane 1: (v1, theta_z1, v2, theta_z2) = DOFs (1, 5, 7, 11), signs +
    // plane 2: (w1, -theta_y1, w2, -theta_y2) = DOFs (2, 4, 8, 10), signs (+, -, +, -)
    let planes = [
        (s.i1, 0, [1usize, 5, 7, 11], [1.0, 1.0, 1.0, 1.0]),
        (s.i2, 1, [2usize, 4, 8, 10], [1.0, -1.0, 1.0, -1.0]),
    ];
    for (i_plane, p, dofs, signs) in planes {
        let (phi, rotary) = match s.shear {
            Some(kf) => (12.0 * b.e * i_plane / (kf[p] * b.g * s.area * l * l), true),
            None => (0.0, false),
        };
        let r = if rotary { b.rho * i_plane } else { 0.0 };
        let (kp, mp) = plane_matrices(b.e * i_plane, phi, l, mpl, r);
        for a in 0..4 {
            for c in 0..4 {
                let sg = signs[a] * signs[c];
                put(&mut k, dofs[a], dofs[c], sg * kp[a][c]);
                if mass == MassKind::Consistent {
                    put(&mut m, dofs[a], dofs[c], sg * mp[a][c]);
                }
            }
        }
    }
    (k, m)
}

/// A tapered two-node beam's stiffness and mass in its frame (docs/MATH.md, "Tapered beams"):
/// `A`, `I1`, `I2`, `J` and the non-structural mass linear from end A's section to `end_b`. The
/// stiffness is exact for the tapered Timoshenko beam: each plane's flexibility of the beam
/// clamped at end A, `F = int [[(L - x)^2 / E I + 1 / k G A, (L - x) / E I], [(L - x) / E I, 1 /
/// E I]] dx`, inverted and carried to end A by equilibrium; the axial and torsional stiffnesses
/// are `1 / int dx / (E A)` and `1 / int dx / (G J)`; the integrals in closed form
/// ([`inverse_moments`]). A property zero at an end leaves no stiffness of its kind (the integral
/// diverges). The consistent mass integrates the varying mass and rotary inertia over the
/// prismatic beam's shape functions at the mean section; the lumped mass puts each end's share
/// `int m (1 - x/L) dx` and `int m x/L dx` on its translations.
fn tapered_local(b: &Beam, end_b: &BeamSection, l: f64, mass: MassKind) -> (Vec<f64>, Vec<f64>) {
    let a = &b.section;
    let at = |t: f64, f: fn(&BeamSection) -> f64| f(a) + (f(end_b) - f(a)) * t;
    let mut k = vec![0.0; 144];
    let mut m = vec![0.0; 144];
    let put = |mat: &mut Vec<f64>, i: usize, j: usize, v: f64| mat[i * 12 + j] += v;
    // the mass's integrands are polynomials of degree 7 at most: 8 points are exact
    let (gp, gw) = crate::quadrature::gauss_legendre(8);
    let points: Vec<(f64, f64)> = gp
        .iter()
        .zip(&gw)
        .map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w * l))
        .collect();
    let integral = |f: &dyn Fn(f64) -> f64| points.iter().map(|(t, w)| w * f(*t)).sum::<f64>();
    // int_0^1 t^k / (c f(t)) dt for a property f linear between the ends, k = 0, 1, 2; None
    // when f is zero at an end
    let moments = |c: f64, f: fn(&BeamSection) -> f64| -> Option<[f64; 3]> {
        (f(a) > 0.0 && f(end_b) > 0.0).then(|| inverse_moments(c * f(a), c * (f(end_b) - f(a))))
    };
    let stiffness = |m: Option<[f64; 3]>| m.map_or(0.0, |m| 1.0 / (l * m[0]));
    let ea = stiffness(moments(b.e, |s| s.area));
    let gj = stiffness(moments(b.g, |s| s.j));
    for (i, j, sign) in [(0, 0, 1.0), (6, 6, 1.0), (0, 6, -1.0), (6, 0, -1.0)] {
        put(&mut k, i, j, sign * ea);
        put(&mut k, i + 3, j + 3, sign * gj);
    }
    let mpl = |t: f64| b.rho * at(t, |s| s.area) + at(t, |s| s.nsm);
    let polar = |t: f64| b.rho * (at(t, |s| s.i1) + at(t, |s| s.i2));
    match mass {
        MassKind::Lumped => {
            let share = [integral(&|t| mpl(t) * (1.0 - t)), integral(&|t| mpl(t) * t)];
            let spin = [
                integral(&|t| polar(t) * (1.0 - t)),
                integral(&|t| polar(t) * t),
            ];
            for end in 0..2 {
                for i in 0..3 {
                    put(&mut m, 6 * end + i, 6 * end + i, share[end]);
                }
                if b.lumped_torsion {
                    put(&mut m, 6 * end + 3, 6 * end + 3, spin[end]);
                }
            }
        }
        MassKind::Consistent => {
            for (t, w) in &points {
                let n = [1.0 - t, *t];
                let ip = if b.coupled_torsion { polar(*t) } else { 0.0 };
                for (x, nx) in n.iter().enumerate() {
                    for (y, ny) in n.iter().enumerate() {
                        put(&mut m, 6 * x, 6 * y, w * mpl(*t) * nx * ny);
                        put(&mut m, 6 * x + 3, 6 * y + 3, w * ip * nx * ny);
                    }
                }
            }
        }
    }
    // each plane: its second moment, shear factor index, DOFs and their signs (as beam_local)
    type Plane = (fn(&BeamSection) -> f64, usize, [usize; 4], [f64; 4]);
    let planes: [Plane; 2] = [
        (|s| s.i1, 0, [1, 5, 7, 11], [1.0, 1.0, 1.0, 1.0]),
        (|s| s.i2, 1, [2, 4, 8, 10], [1.0, -1.0, 1.0, -1.0]),
    ];
    for (inertia, p, dofs, signs) in planes {
        let shear = a.shear.map(|kf| kf[p]);
        // an infinite shear factor: rigid in shear
        let slide = match shear {
            Some(kf) if kf.is_finite() => moments(kf * b.g, |s| s.area).map_or(0.0, |m| l * m[0]),
            _ => 0.0,
        };
        let kbb = match moments(b.e, inertia) {
            Some(m) => {
                let f11 = l.powi(3) * (m[0] - 2.0 * m[1] + m[2]) + slide;
                let f12 = l * l * (m[0] - m[1]);
                let f22 = l * m[0];
                let det = f11 * f22 - f12 * f12;
                [[f22 / det, -f12 / det], [-f12 / det, f11 / det]]
            }
            None => [[0.0; 2]; 2],
        };
        // d_B - R d_A with R = [[1, L], [0, 1]] (w_B = w_A + L theta_A rigidly)
        let r = [[1.0, l], [0.0, 1.0]];
        let mut bmat = [[0.0; 4]; 2];
        for i in 0..2 {
            for j in 0..2 {
                bmat[i][j] = -r[i][j];
            }
            bmat[i][2 + i] = 1.0;
        }
        let mut kp = [[0.0; 4]; 4];
        for (x, row) in kp.iter_mut().enumerate() {
            for (y, v) in row.iter_mut().enumerate() {
                *v = (0..2)
                    .map(|i| {
                        (0..2)
                            .map(|j| bmat[i][x] * kbb[i][j] * bmat[j][y])
                            .sum::<f64>()
                    })
                    .sum();
            }
        }
        // mass: the prismatic shape functions at the mean section
        let mean = |f: fn(&BeamSection) -> f64| 0.5 * (f(a) + f(end_b));
        let phi = shear.map_or(0.0, |kf| {
            12.0 * b.e * mean(inertia) / (kf * b.g * mean(|s| s.area) * l * l)
        });
        let mut mp = [[0.0; 4]; 4];
        if mass == MassKind::Consistent {
            for (t, w) in &points {
                let (nw, nt) = timoshenko_shape(*t, l, phi);
                let rotary = if shear.is_some() {
                    b.rho * at(*t, inertia)
                } else {
                    0.0
                };
                for i in 0..4 {
                    for j in 0..4 {
                        mp[i][j] += w * (mpl(*t) * nw[i] * nw[j] + rotary * nt[i] * nt[j]);
                    }
                }
            }
        }
        for x in 0..4 {
            for y in 0..4 {
                let sg = signs[x] * signs[y];
                put(&mut k, dofs[x], dofs[y], sg * kp[x][y]);
                put(&mut m, dofs[x], dofs[y], sg * mp[x][y]);
            }
        }
    }
    (k, m)
}

/// `int_0^1 t^k / (a + b t) dt` for `k = 0, 1, 2` (`a > 0`, `a + b > 0`), to round-off for any
/// ratio of the ends: by the series of `1 / (a + b t)` in `b t / a` when `|b| <= a / 2`, else
/// `ln(1 + b/a) / b` and the recurrence `I_k = (1/k - a I_(k-1)) / b`, which then loses at most a
/// factor `(a / |b|)^2 <= 4` (docs/MATH.md, "Tapered beams").
pub fn inverse_moments(a: f64, b: f64) -> [f64; 3] {
    let r = b / a;
    if r.abs() <= 0.5 {
        let mut out = [0.0; 3];
        for (k, slot) in out.iter_mut().enumerate() {
            let mut power = 1.0;
            let mut sum = 0.0;
            for n in 0..200 {
                let term = power / (n + k + 1) as f64;
                sum += term;
                if term.abs() < 1e-18 * sum.abs() {
                    break;
                }
                power *= -r;
            }
            *slot = sum / a;
        }
        out
    } else {
        let i0 = r.ln_1p() / b;
        let i1 = (1.0 - a * i0) / b;
        let i2 = (0.5 - a * i1) / b;
        [i0, i1, i2]
    }
}
