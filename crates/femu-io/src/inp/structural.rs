//! Beams and springs of an Abaqus/CalculiX deck: `B31` (shear-flexible) and `B33`
//! (Euler-Bernoulli) two-node beams and `B32` three-node beams (shear-flexible, possibly curved;
//! nodes end, middle, end) with `*BEAM SECTION` (`RECT`, `CIRC`, `PIPE`) or `*BEAM
//! GENERAL SECTION` (`GENERAL`), `SPRING1`, `SPRING2`, `SPRINGA` with `*SPRING` and `DASHPOT1`,
//! `DASHPOT2`, `DASHPOTA` with `*DASHPOT` (the same layout, a dashpot coefficient), as the
//! Abaqus Keywords Reference defines them, into femu's structural elements
//! (docs/MATH.md, "Beams, springs and bushings").
//!
//! Section axes: Abaqus' `n1` (the second data line; `(0, 0, -1)` when omitted, Abaqus' default)
//! is femu's orientation vector, so femu's local `y` is the section's 1-axis and `z` its 2-axis;
//! femu's `I1` (bending with displacement along `y`) is Abaqus' `I22`, its `I2` is `I11`.

use super::{Location, Material};
use crate::IoError;
use femu_fem::material::Elasticity;
use femu_fem::model::Model;
use femu_fem::structural::{
    Beam, BeamSection, Part, Rod, Spring, SpringEnd, StructuralElement, StructuralKind,
};
use std::collections::{BTreeMap, HashMap};
use std::f64::consts::PI;

/// The three kinds of Abaqus spring and dashpot: to ground on one DOF, between two DOFs, axial.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SpringKind {
    /// `SPRING1`, `DASHPOT1`.
    One,
    /// `SPRING2`, `DASHPOT2`.
    Two,
    /// `SPRINGA`, `DASHPOTA`.
    Axial,
}

/// The structural element types femu reads from a deck.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum StructuralType {
    /// Shear-flexible two-node beam.
    B31,
    /// Euler-Bernoulli two-node beam.
    B33,
    /// Shear-flexible three-node beam (B32, B32H, CalculiX's B32R).
    B32,
    /// A two-node truss (T3D2, T3D2H) of a `*SOLID SECTION`: a rod without torsion.
    T3D2,
    /// A spring from a DOF to ground.
    Spring1,
    /// A spring between two DOFs.
    Spring2,
    /// An axial spring between two nodes.
    SpringA,
    /// A dashpot (`DASHPOT1`, `DASHPOT2`, `DASHPOTA` of a `*DASHPOT`): the spring of that kind
    /// with a viscous coefficient in place of its stiffness.
    Dashpot(SpringKind),
    /// A 4-node shell (S4, and S4R built fully integrated), with the incompatible-mode membrane.
    S4,
    /// A 3-node shell (S3, S3R).
    S3,
    /// An 8-node shell (S8R, and S8 built the same way).
    S8,
    /// A 6-node triangular shell (CalculiX's S6, Abaqus's STRI65), built as four three-node
    /// triangles on its nodes (docs/MATH.md, "Six-node triangles").
    S6,
    /// A membrane (M3D4 and M3D4R built fully integrated, M3D3, M3D8R and M3D8 as the 8-node
    /// shell's membrane) of `*MEMBRANE SECTION`, with its node count.
    Membrane(usize),
}

impl StructuralType {
    /// The type of an `*ELEMENT, TYPE=` and its node count; `Err` with the reason for a beam,
    /// pipe or truss type femu does not read; `Ok(None)` for any other type.
    pub(super) fn of(ty: &str) -> Result<Option<(Self, usize)>, String> {
        Ok(Some(match ty.to_ascii_uppercase().as_str() {
            "B31" | "B31H" => (Self::B31, 2),
            "B33" | "B33H" => (Self::B33, 2),
            "B32" | "B32H" | "B32R" => (Self::B32, 3),
            "T3D2" | "T3D2H" => (Self::T3D2, 2),
            "SPRING1" => (Self::Spring1, 1),
            "SPRING2" => (Self::Spring2, 2),
            "SPRINGA" => (Self::SpringA, 2),
            "DASHPOT1" => (Self::Dashpot(SpringKind::One), 1),
            "DASHPOT2" => (Self::Dashpot(SpringKind::Two), 2),
            "DASHPOTA" => (Self::Dashpot(SpringKind::Axial), 2),
            "S4" | "S4R" => (Self::S4, 4),
            "S3" | "S3R" => (Self::S3, 3),
            "S8R" | "S8" => (Self::S8, 8),
            "S6" | "STRI65" => (Self::S6, 6),
            "M3D6" => (Self::Membrane(6), 6),
            "M3D4" | "M3D4R" => (Self::Membrane(4), 4),
            "M3D3" => (Self::Membrane(3), 3),
            "M3D8R" | "M3D8" => (Self::Membrane(8), 8),
            t @ ("S8R5" | "S4R5" | "S9R5" | "STRI3" | "M3D9R" | "SC8R") => {
                return Err(format!(
                    "element type {t} is not read: femu's shells are S4, S4R, S3, S3R, S6, STRI65, S8R and S8, its membranes M3D3, M3D4, M3D4R, M3D6, M3D8 and M3D8R (9-node, thin-only and continuum shells are not built)"
                ));
            }
            t @ ("B31OS" | "B32OS" | "PIPE31" | "PIPE32" | "B21" | "B22" | "B23" | "T3D3"
            | "T3D3H" | "T2D2" | "T2D3") => {
                return Err(format!(
                    "element type {t} is not read: femu's beams are B31, B32 and B33 in space and its trusses T3D2 (open-section, pipe, planar beams and three-node or planar trusses are not built)"
                ));
            }
            _ => return Ok(None),
        }))
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Self::B31 => "B31",
            Self::B33 => "B33",
            Self::B32 => "B32",
            Self::T3D2 => "T3D2",
            Self::Spring1 => "SPRING1",
            Self::Spring2 => "SPRING2",
            Self::SpringA => "SPRINGA",
            Self::Dashpot(SpringKind::One) => "DASHPOT1",
            Self::Dashpot(SpringKind::Two) => "DASHPOT2",
            Self::Dashpot(SpringKind::Axial) => "DASHPOTA",
            Self::S4 => "S4",
            Self::S3 => "S3",
            Self::S8 => "S8R",
            Self::S6 => "S6",
            Self::Membrane(3) => "M3D3",
            Self::Membrane(4) => "M3D4",
            Self::Membrane(6) => "M3D6",
            Self::Membrane(_) => "M3D8R",
        }
    }
}

/// A `*BEAM SECTION` or `*BEAM GENERAL SECTION` with its data lines.
#[derive(Debug, Clone)]
pub(super) struct BeamSectionCard {
    pub(super) elset: String,
    pub(super) material: Option<String>,
    pub(super) section: String,
    pub(super) general: bool,
    pub(super) density: Option<f64>,
    /// Whether it states `LUMPED=NO` (Abaqus' consistent beam mass); absent, Abaqus/Standard
    /// lumps a linear Timoshenko beam's mass in frequency extraction.
    pub(super) lumped_stated: bool,
    pub(super) lines: Vec<Vec<String>>,
    pub(super) line: Location,
}

/// A `*SPRING` with its data lines.
#[derive(Debug, Clone)]
pub(super) struct SpringCard {
    pub(super) elset: String,
    /// A `*DASHPOT` (its coefficient a viscous one), not a `*SPRING`.
    pub(super) dashpot: bool,
    pub(super) lines: Vec<Vec<String>>,
    pub(super) line: Location,
}

/// A `*SHELL SECTION` with its data lines (the thickness first).
#[derive(Debug, Clone)]
pub(super) struct ShellSectionCard {
    pub(super) elset: String,
    pub(super) material: String,
    /// `OFFSET`: the nodes' surface from the midsurface, a fraction of the thickness.
    pub(super) offset: f64,
    /// `COMPOSITE`: one data line a ply (thickness, section points, material, angle).
    pub(super) composite: bool,
    /// `SYMMETRIC`: the plies given are the lower half, mirrored.
    pub(super) symmetric: bool,
    /// A `*MEMBRANE SECTION` (for membrane elements): the thickness alone.
    pub(super) membrane: bool,
    /// `ORIENTATION=`: the `*ORIENTATION` (upper case) of its material axes.
    pub(super) orientation: Option<String>,
    pub(super) lines: Vec<Vec<String>>,
    pub(super) line: Location,
}

/// The structural records of a deck: elements `(id, type, node ids, where)`, sections,
/// springs and the sets of structural element ids.
#[derive(Debug, Clone, Default)]
pub(super) struct StructuralRecords {
    pub(super) elements: Vec<(u64, StructuralType, Vec<u64>, Location)>,
    pub(super) sections: Vec<BeamSectionCard>,
    pub(super) shell_sections: Vec<ShellSectionCard>,
    pub(super) springs: Vec<SpringCard>,
    pub(super) sets: BTreeMap<String, Vec<u64>>,
}

pub(super) fn at_err(l: &Location, reason: String) -> IoError {
    IoError::Parse {
        path: l.path.clone(),
        line: l.line,
        reason,
    }
}

fn number(l: &Location, what: &str, s: &str) -> Result<f64, IoError> {
    super::parse_f64(s).ok_or_else(|| at_err(l, format!("{what}: {s:?} is not a number")))
}

/// `(E, G, rho)` of a material.
fn moduli(m: &Material) -> Result<(f64, f64, f64), String> {
    match m.elasticity {
        Elasticity::Isotropic { e, nu } => Ok((e, e / (2.0 * (1.0 + nu)), m.density)),
        _ => Err(format!(
            "material {} is anisotropic: a beam takes an isotropic *ELASTIC",
            m.name
        )),
    }
}

/// The section properties `(A, femu I1, femu I2, J, shear factors)` of an Abaqus `*BEAM
/// SECTION` shape: `RECT` (`a` along the 1-direction, `b` along the 2-direction; J by the
/// thin-rectangle series, shear factors 5/6), `CIRC` (`r`; 0.9), `PIPE` (`r`, wall `t`; 1/2).
///
/// # Errors
/// Another shape, too few or non-positive dimensions, a pipe wall not thinner than its radius.
pub fn section_shape(shape: &str, dims: &[f64]) -> Result<(f64, f64, f64, f64, [f64; 2]), String> {
    let need = |n: usize| -> Result<(), String> {
        if dims.len() != n || dims.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
            Err(format!(
                "{shape} needs {n} positive dimension{}, got {dims:?}",
                if n == 1 { "" } else { "s" }
            ))
        } else {
            Ok(())
        }
    };
    match shape {
        "RECT" => {
            need(2)?;
            // a along the 1-axis (femu's y), b along the 2-axis
            let (a, b) = (dims[0], dims[1]);
            let (long, short) = if a > b { (a, b) } else { (b, a) };
            let j = long
                * short.powi(3)
                * (1.0 / 3.0 - 0.21 * short / long * (1.0 - short.powi(4) / (12.0 * long.powi(4))));
            Ok((
                a * b,
                b * a.powi(3) / 12.0,
                a * b.powi(3) / 12.0,
                j,
                [5.0 / 6.0; 2],
            ))
        }
        "CIRC" => {
            need(1)?;
            let r = dims[0];
            let i = PI * r.powi(4) / 4.0;
            Ok((PI * r * r, i, i, 2.0 * i, [0.9; 2]))
        }
        "PIPE" => {
            need(2)?;
            let (r, t) = (dims[0], dims[1]);
            if t >= r {
                return Err(format!("PIPE wall {t} is not thinner than its radius {r}"));
            }
            let ri = r - t;
            let i = PI * (r.powi(4) - ri.powi(4)) / 4.0;
            Ok((PI * (r * r - ri * ri), i, i, 2.0 * i, [0.5; 2]))
        }
        other => Err(format!(
            "section shape {other}: femu reads RECT, CIRC and PIPE"
        )),
    }
}

/// A section's `(A, femu I1, femu I2, J, shear factors)` and its material `(E, G, rho)`.
type SectionValues = ((f64, f64, f64, f64, [f64; 2]), (f64, f64, f64));

fn section_values(
    c: &BeamSectionCard,
    materials: &BTreeMap<String, Material>,
) -> Result<SectionValues, IoError> {
    let l = &c.line;
    let dims: Vec<f64> = c
        .lines
        .first()
        .ok_or_else(|| {
            at_err(
                l,
                "the section's dimensions (its first data line) are missing".into(),
            )
        })?
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| number(l, "a section dimension", s))
        .collect::<Result<_, _>>()?;
    let need = |n: usize| -> Result<(), IoError> {
        if dims.len() < n || dims[..n].iter().any(|d| !(*d > 0.0)) {
            return Err(at_err(
                l,
                format!(
                    "SECTION={} needs {n} positive values on its first data line, got {dims:?}",
                    c.section
                ),
            ));
        }
        Ok(())
    };
    let material = |name: &Option<String>| -> Result<(f64, f64, f64), IoError> {
        let name = name
            .as_ref()
            .ok_or_else(|| at_err(l, "*BEAM SECTION without MATERIAL=".into()))?;
        let m = materials.get(name).ok_or_else(|| {
            at_err(
                l,
                format!("*BEAM SECTION names material {name}, which no *MATERIAL defines"),
            )
        })?;
        moduli(m).map_err(|r| at_err(l, r))
    };
    let values = match (c.general, c.section.as_str()) {
        (false, shape @ ("RECT" | "CIRC" | "PIPE")) => {
            let n = if shape == "CIRC" { 1 } else { 2 };
            need(n)?;
            (
                section_shape(shape, &dims[..n]).map_err(|r| at_err(l, r))?,
                material(&c.material)?,
            )
        }
        (true, "GENERAL") => {
            // A, I11, I12, I22, J; then n1; then E, G
            if dims.len() < 5
                || [dims[0], dims[1], dims[3], dims[4]]
                    .iter()
                    .any(|d| !(*d > 0.0))
            {
                return Err(at_err(
                    l,
                    format!(
                        "SECTION=GENERAL needs A, I11, I12, I22, J (positive but I12), got {dims:?}"
                    ),
                ));
            }
            if dims[2] != 0.0 {
                return Err(at_err(
                    l,
                    format!(
                        "I12 = {} couples the bending planes; femu builds beams on principal axes",
                        dims[2]
                    ),
                ));
            }
            let eg: Vec<f64> = c
                .lines
                .get(2)
                .ok_or_else(|| {
                    at_err(
                        l,
                        "SECTION=GENERAL needs E and G on its third data line".into(),
                    )
                })?
                .iter()
                .filter(|s| !s.is_empty())
                .map(|s| number(l, "E or G", s))
                .collect::<Result<_, _>>()?;
            let [e, g, ..] = eg[..] else {
                return Err(at_err(
                    l,
                    "SECTION=GENERAL needs E and G on its third data line".into(),
                ));
            };
            let rho = c.density.unwrap_or(0.0);
            ((dims[0], dims[3], dims[1], dims[4], [1.0; 2]), (e, g, rho))
        }
        (general, other) => {
            return Err(at_err(
                l,
                format!(
                    "{} SECTION={other} is not read (femu reads {})",
                    if general {
                        "*BEAM GENERAL SECTION,"
                    } else {
                        "*BEAM SECTION,"
                    },
                    if general {
                        "GENERAL"
                    } else {
                        "RECT, CIRC and PIPE"
                    }
                ),
            ));
        }
    };
    Ok(values)
}

/// The section's `n1` (its second data line), or Abaqus' default `(0, 0, -1)`.
fn n1(c: &BeamSectionCard) -> Result<[f64; 3], IoError> {
    let Some(line) = c.lines.get(1) else {
        return Ok([0.0, 0.0, -1.0]);
    };
    let v: Vec<f64> = line
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| number(&c.line, "a component of n1", s))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [a, b, c3, ..] => Ok([a, b, c3]),
        _ => Err(at_err(
            &c.line,
            format!("n1 needs three components, got {v:?}"),
        )),
    }
}

/// Adds the deck's beams and springs to `model` and their element sets.
///
/// # Errors
/// An element without a section (or spring definition), an unknown material, a bad value, and
/// the model's errors, each with the line that defined it.
pub(super) fn add_structural(
    records: &StructuralRecords,
    solid_sections: &[super::Section],
    materials: &BTreeMap<String, Material>,
    material_damping: &BTreeMap<String, super::MaterialDamping>,
    laminae: &BTreeMap<String, Lamina>,
    orientations: &BTreeMap<String, super::orientation::OrientationCard>,
    model: &mut Model,
) -> Result<(), IoError> {
    // the section (or spring card) of each element, by its set
    let mut section_of: HashMap<u64, usize> = HashMap::new();
    for (k, c) in records.sections.iter().enumerate() {
        let ids = records.sets.get(&c.elset).ok_or_else(|| {
            at_err(
                &c.line,
                format!(
                    "the section names element set {}, which holds no beam of the deck",
                    c.elset
                ),
            )
        })?;
        for id in ids {
            section_of.entry(*id).or_insert(k);
        }
    }
    let mut spring_of: HashMap<u64, usize> = HashMap::new();
    for (k, c) in records.springs.iter().enumerate() {
        let ids = records.sets.get(&c.elset).ok_or_else(|| {
            at_err(
                &c.line,
                format!(
                    "*SPRING names element set {}, which holds no spring of the deck",
                    c.elset
                ),
            )
        })?;
        for id in ids {
            spring_of.entry(*id).or_insert(k);
        }
    }
    let mut shell_of: HashMap<u64, usize> = HashMap::new();
    for (k, c) in records.shell_sections.iter().enumerate() {
        let ids = records.sets.get(&c.elset).ok_or_else(|| {
            at_err(
                &c.line,
                format!(
                    "*SHELL SECTION names element set {}, which holds no shell of the deck",
                    c.elset
                ),
            )
        })?;
        for id in ids {
            shell_of.entry(*id).or_insert(k);
        }
    }
    // a truss's *SOLID SECTION (the first that names a set holding it)
    let mut truss_of: HashMap<u64, usize> = HashMap::new();
    for (k, c) in solid_sections.iter().enumerate() {
        for id in records.sets.get(&c.elset).into_iter().flatten() {
            truss_of.entry(*id).or_insert(k);
        }
    }
    let mut values: HashMap<usize, SectionValues> = HashMap::new();
    for (id, ty, node_ids, l) in &records.elements {
        let nodes = node_ids
            .iter()
            .map(|n| {
                model.mesh().node_index(*n).ok_or_else(|| {
                    at_err(
                        l,
                        format!("element {id} refers to node {n}, which the deck does not define"),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        // the damping of the element's material
        let mut damping = super::MaterialDamping::default();
        let kind = match ty {
            StructuralType::T3D2 => {
                let c = &solid_sections[*truss_of.get(id).ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "T3D2 element {id} has no *SOLID SECTION (none names a set that holds it)"
                        ),
                    )
                })?];
                let m = materials.get(&c.material).ok_or_else(|| {
                    at_err(
                        &c.line,
                        format!(
                            "*SOLID SECTION names material {}, which no *MATERIAL defines",
                            c.material
                        ),
                    )
                })?;
                damping = material_damping
                    .get(&c.material)
                    .copied()
                    .unwrap_or_default();
                let (e, g, rho) = moduli(m).map_err(|r| at_err(&c.line, r))?;
                // Abaqus assumes a unit area where the data line gives none
                let area = match c.area.as_deref().map(str::trim) {
                    None | Some("") => 1.0,
                    Some(a) => number(&c.line, "the truss's cross-sectional area", a)?,
                };
                StructuralKind::Rod(Rod {
                    e,
                    g,
                    rho,
                    area,
                    j: 0.0,
                    nsm: 0.0,
                })
            }
            StructuralType::B31 | StructuralType::B33 | StructuralType::B32 => {
                let k = *section_of.get(id).ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "{} element {id} has no *BEAM SECTION (none names a set that holds it)",
                            ty.name()
                        ),
                    )
                })?;
                let c = &records.sections[k];
                if let Some(m) = &c.material {
                    damping = material_damping.get(m).copied().unwrap_or_default();
                }
                let ((area, i1, i2, j, kf), (e, g, rho)) = match values.entry(k) {
                    std::collections::hash_map::Entry::Occupied(v) => *v.get(),
                    std::collections::hash_map::Entry::Vacant(v) => {
                        *v.insert(section_values(c, materials)?)
                    }
                };
                StructuralKind::Beam(Beam {
                    e,
                    g,
                    rho,
                    section: BeamSection {
                        area,
                        i1,
                        i2,
                        j,
                        shear: (*ty != StructuralType::B33).then_some(kf),
                        nsm: 0.0,
                    },
                    taper: None,
                    orientation: n1(c)?,
                    offsets: [[0.0; 3]; 2],
                    lumped_torsion: false,
                    coupled_torsion: true,
                    releases: [[false; 6]; 2],
                })
            }
            StructuralType::S4
            | StructuralType::S3
            | StructuralType::S6
            | StructuralType::S8
            | StructuralType::Membrane(_) => {
                let membrane = matches!(ty, StructuralType::Membrane(_));
                let keyword = if membrane {
                    "*MEMBRANE SECTION"
                } else {
                    "*SHELL SECTION"
                };
                let k = *shell_of.get(id).ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "{} element {id} has no {keyword} (none names a set that holds it)",
                            ty.name()
                        ),
                    )
                })?;
                let card = &records.shell_sections[k];
                if card.membrane != membrane {
                    return Err(at_err(
                        l,
                        format!(
                            "{} element {id} is given a {} (line {}): a membrane element takes a *MEMBRANE SECTION, a shell a *SHELL SECTION",
                            ty.name(),
                            if card.membrane {
                                "*MEMBRANE SECTION"
                            } else {
                                "*SHELL SECTION"
                            },
                            card.line.line
                        ),
                    ));
                }
                let x: Vec<[f64; 3]> = nodes.iter().map(|n| model.mesh().coords()[*n]).collect();
                damping = shell_damping(card, material_damping)?;
                let node = |nid: u64| {
                    model
                        .mesh()
                        .node_index(nid)
                        .map(|i| model.mesh().coords()[i])
                };
                let axes = super::orientation::ShellAxes {
                    normal: super::orientation::shell_normal(&x),
                    at: super::orientation::At {
                        element: *id,
                        x: &x,
                        node: &node,
                    },
                    orientations,
                    line: &card.line,
                };
                let mut kind = shell(card, materials, laminae, &axes)?;
                // a membrane: no bending, no transverse shear (docs/MATH.md, "Shells")
                if let (true, StructuralKind::Shell(s)) = (membrane, &mut kind) {
                    s.bending = 0.0;
                    s.shear = None;
                }
                kind
            }
            _ => {
                let dashpot = matches!(ty, StructuralType::Dashpot(_));
                let keyword = if dashpot { "*DASHPOT" } else { "*SPRING" };
                let k = *spring_of.get(id).ok_or_else(|| {
                    at_err(
                        l,
                        format!(
                            "{} element {id} has no {keyword} (none names a set that holds it)",
                            ty.name()
                        ),
                    )
                })?;
                let card = &records.springs[k];
                if card.dashpot != dashpot {
                    return Err(at_err(
                        l,
                        format!(
                            "{} element {id} takes a {keyword}, and the set that holds it is given a {} (line {})",
                            ty.name(),
                            if card.dashpot { "*DASHPOT" } else { "*SPRING" },
                            card.line.line
                        ),
                    ));
                }
                spring(card, *ty, *id, &nodes, model)?
            }
        };
        // B32's nodes are end, middle, end; femu's the ends, then the middle
        let nodes = match ty {
            StructuralType::B32 => vec![nodes[0], nodes[2], nodes[1]],
            _ => nodes,
        };
        model
            .add_structural(StructuralElement {
                id: *id,
                nodes,
                kind,
            })
            .and_then(|_| damping.apply(model, *id))
            .map_err(|source| IoError::Model {
                path: l.path.clone(),
                line: l.line,
                source,
            })?;
    }
    for (name, ids) in &records.sets {
        model
            .add_structural_set(name.clone(), ids)
            .map_err(|e| IoError::Content {
                path: records
                    .elements
                    .first()
                    .map(|e| e.3.path.clone())
                    .unwrap_or_default(),
                reason: e.to_string(),
            })?;
    }
    Ok(())
}

/// The damping of a `*SHELL SECTION`'s material; for a composite section, its plies' (one value:
/// femu damps an element by one set of coefficients, so plies of materials damped differently are
/// refused with the section's line).
fn shell_damping(
    c: &ShellSectionCard,
    material_damping: &BTreeMap<String, super::MaterialDamping>,
) -> Result<super::MaterialDamping, IoError> {
    let ge = |m: &str| {
        material_damping
            .get(&m.to_ascii_uppercase())
            .copied()
            .unwrap_or_default()
    };
    if !c.composite {
        return Ok(ge(&c.material));
    }
    let plies: Vec<(String, super::MaterialDamping)> = c
        .lines
        .iter()
        .filter_map(|f| f.get(2))
        .map(|m| (m.to_ascii_uppercase(), ge(m)))
        .collect();
    match plies.iter().find(|(_, g)| *g != plies[0].1) {
        Some((m, g)) => Err(at_err(
            &c.line,
            format!(
                "the plies' materials are damped differently ({} {:?}, {m} {g:?}): femu damps a shell by one set of coefficients",
                plies[0].0, plies[0].1
            ),
        )),
        None => Ok(plies.first().map_or_else(Default::default, |p| p.1)),
    }
}

/// A shell of a `*SHELL SECTION`: its material's `E`, `nu`, density and the thickness on its
/// first data line; the transverse shear factor 5/6 of a homogeneous section; `OFFSET` (a
/// fraction of the thickness, `SPOS` 0.5, `SNEG` -0.5) puts the nodes that far above the
/// midsurface.
fn shell(
    c: &ShellSectionCard,
    materials: &BTreeMap<String, Material>,
    laminae: &BTreeMap<String, Lamina>,
    axes: &super::orientation::ShellAxes,
) -> Result<StructuralKind, IoError> {
    let l = &c.line;
    if c.composite {
        return composite_shell(c, materials, laminae, axes);
    }
    let keyword = if c.membrane {
        "*MEMBRANE SECTION"
    } else {
        "*SHELL SECTION"
    };
    let t = c
        .lines
        .first()
        .and_then(|r| r.first())
        .filter(|s| !s.is_empty())
        .ok_or_else(|| at_err(l, format!("{keyword} needs the thickness on its data line")))
        .and_then(|s| number(l, "the thickness", s))?;
    if let Some(lam) = laminae.get(&c.material) {
        // a LAMINA or ENGINEERING CONSTANTS: one orthotropic ply, in the section's material axes
        let mut s = femu_fem::shell::laminate(&[lam.ply(t, 0.0)])
            .map_err(|e| at_err(l, format!("{keyword}: {e}")))?;
        if let Some(m) = s.material.as_mut() {
            m.axis = axes.axis(c.orientation.as_deref())?;
        }
        s.offset = -c.offset * t;
        s.membrane = if c.membrane {
            femu_fem::shell::Membrane::Full
        } else {
            femu_fem::shell::Membrane::Incompatible
        };
        return Ok(StructuralKind::Shell(s));
    }
    if let Some(name) = &c.orientation {
        // an isotropic material has no axes: the orientation is only checked to exist
        super::orientation::named(axes.orientations, name, l)?;
    }
    let m = materials.get(&c.material).ok_or_else(|| {
        at_err(
            l,
            format!(
                "{keyword} names material {}, which no *MATERIAL defines",
                c.material
            ),
        )
    })?;
    let Elasticity::Isotropic { e, nu } = m.elasticity else {
        return Err(at_err(
            l,
            format!(
                "material {} is anisotropic: femu's shells take an isotropic *ELASTIC",
                m.name
            ),
        ));
    };
    Ok(StructuralKind::Shell(femu_fem::shell::Shell {
        e,
        nu,
        rho: m.density,
        t,
        bending: 1.0,
        shear: Some(5.0 / 6.0),
        nsm: 0.0,
        material: None,
        // the nodes OFFSET t above the midsurface: the midsurface is -OFFSET t from them
        offset: -c.offset * t,
        // S4's assumed-strain membrane is free of in-plane shear locking (the incompatible
        // modes'); M3D4 is the bilinear membrane (CalculiX's frequencies on the same deck)
        membrane: if c.membrane {
            femu_fem::shell::Membrane::Full
        } else {
            femu_fem::shell::Membrane::Incompatible
        },
    }))
}

/// A ply material of `*ELASTIC, TYPE=LAMINA` (Abaqus's plane-stress orthotropic material of a
/// shell's layer: `E1 E2 NU12 G12 G13 G23`) and its `*DENSITY`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lamina {
    /// Modulus along the ply's first axis (Pa).
    pub e1: f64,
    /// Modulus along its second axis (Pa).
    pub e2: f64,
    /// Poisson's ratio `nu12`.
    pub nu12: f64,
    /// In-plane shear modulus (Pa).
    pub g12: f64,
    /// Transverse shear modulus in the 1-3 plane (Pa).
    pub g13: f64,
    /// Transverse shear modulus in the 2-3 plane (Pa).
    pub g23: f64,
    /// Density (kg/m^3).
    pub density: f64,
}

impl Lamina {
    /// Refuses moduli that are not positive and a `nu12` that makes no material (`1 - nu12 nu21
    /// <= 0`).
    pub(super) fn check(&self, at: &Location, name: &str) -> Result<(), IoError> {
        let moduli = [self.e1, self.e2, self.g12, self.g13, self.g23];
        if !moduli.iter().all(|v| v.is_finite() && *v > 0.0) || !self.density.is_finite() {
            return Err(at_err(
                at,
                format!(
                    "material {name}: a LAMINA's E1, E2, G12, G13 and G23 must be positive, got {moduli:?}"
                ),
            ));
        }
        if !(1.0 - self.nu12 * self.nu12 * self.e2 / self.e1 > 0.0) {
            return Err(at_err(
                at,
                format!(
                    "material {name}: NU12 = {} with E1 = {:e} and E2 = {:e} is not a material",
                    self.nu12, self.e1, self.e2
                ),
            ));
        }
        Ok(())
    }

    /// The ply of `t` at `theta` degrees: its plane-stress `Q` and transverse shear `(G13, G23)`.
    fn ply(&self, t: f64, theta: f64) -> femu_fem::shell::Ply {
        let den = 1.0 - self.nu12 * self.nu12 * self.e2 / self.e1;
        let q12 = self.nu12 * self.e2 / den;
        femu_fem::shell::Ply {
            q: [
                [self.e1 / den, q12, 0.0],
                [q12, self.e2 / den, 0.0],
                [0.0, 0.0, self.g12],
            ],
            shear: Some([[self.g13, 0.0], [0.0, self.g23]]),
            rho: self.density,
            t,
            theta,
        }
    }
}

/// A shell of a `*SHELL SECTION, COMPOSITE`: one data line a layer, `thickness, section points,
/// material, orientation angle (degrees)`, from the bottom (`SYMMETRIC`: the lower half, mirrored
/// about the midsurface), each material a LAMINA ([`Lamina`]) or an isotropic `*ELASTIC`; the
/// section of classical lamination theory ([`femu_fem::shell::laminate`], docs/MATH.md,
/// "Laminates"), whose material axis is a shell's default local 1-direction: the global x axis
/// projected onto the shell, or the global z axis where x is within 0.1 degree of its normal.
/// A layer's orientation given by name (an `*ORIENTATION`) is refused.
fn composite_shell(
    c: &ShellSectionCard,
    materials: &BTreeMap<String, Material>,
    laminae: &BTreeMap<String, Lamina>,
    axes: &super::orientation::ShellAxes,
) -> Result<StructuralKind, IoError> {
    let l = &c.line;
    let axis = axes.axis(c.orientation.as_deref())?;
    let mut plies = Vec::with_capacity(c.lines.len());
    for (k, row) in c.lines.iter().enumerate() {
        let field = |i: usize| row.get(i).map(String::as_str).unwrap_or("").trim();
        let t = number(l, "a layer's thickness", field(0))?;
        let name = field(2).to_ascii_uppercase();
        // an angle from the section's material axis, or an orientation's name (that
        // orientation's own material axis)
        let theta = match field(3) {
            "" => 0.0,
            s => match super::parse_f64(s) {
                Some(v) if v.is_finite() => v,
                _ => axes
                    .angle_from(axis, &s.to_ascii_uppercase())
                    .map_err(|e| match e {
                        IoError::Parse { path, line, reason } => IoError::Parse {
                            path,
                            line,
                            reason: format!("layer {}: {reason}", k + 1),
                        },
                        e => e,
                    })?,
            },
        };
        let ply = if let Some(lam) = laminae.get(&name) {
            lam.ply(t, theta)
        } else if let Some(m) = materials.get(&name) {
            let Elasticity::Isotropic { e, nu } = m.elasticity else {
                return Err(at_err(
                    l,
                    format!(
                        "layer {} names material {name}, whose *ELASTIC is neither isotropic nor a LAMINA",
                        k + 1
                    ),
                ));
            };
            let d = e / (1.0 - nu * nu);
            let g = e / (2.0 * (1.0 + nu));
            femu_fem::shell::Ply {
                q: [[d, d * nu, 0.0], [d * nu, d, 0.0], [0.0, 0.0, g]],
                shear: Some([[g, 0.0], [0.0, g]]),
                rho: m.density,
                t,
                theta,
            }
        } else {
            return Err(at_err(
                l,
                format!(
                    "*SHELL SECTION, COMPOSITE: layer {} names material {name:?}, which no *MATERIAL defines",
                    k + 1
                ),
            ));
        };
        plies.push(ply);
    }
    if c.symmetric {
        let mirrored: Vec<_> = plies.iter().rev().copied().collect();
        plies.extend(mirrored);
    }
    let mut s = femu_fem::shell::laminate(&plies)
        .map_err(|e| at_err(l, format!("*SHELL SECTION, COMPOSITE: {e}")))?;
    if let Some(m) = s.material.as_mut() {
        m.axis = axis;
    }
    s.offset = -c.offset * s.t;
    Ok(StructuralKind::Shell(s))
}

/// A spring element from its `*SPRING`: SPRING1 (a DOF to ground) and SPRING2 (two DOFs) take the
/// DOFs on the first data line and the stiffness on the second; SPRINGA (along the line between
/// its nodes) its stiffness on the one data line (an empty first line is not kept).
fn spring(
    c: &SpringCard,
    ty: StructuralType,
    id: u64,
    nodes: &[usize],
    model: &Model,
) -> Result<StructuralKind, IoError> {
    let l = &c.line;
    let keyword = if c.dashpot { "*DASHPOT" } else { "*SPRING" };
    let value = |row: usize, k: usize, what: &str| -> Result<&str, IoError> {
        c.lines
            .get(row)
            .and_then(|r| r.get(k))
            .map(String::as_str)
            .filter(|s| !s.is_empty())
            .ok_or_else(|| {
                at_err(
                    l,
                    format!("{keyword} for element {id} ({}) lacks {what}", ty.name()),
                )
            })
    };
    let dof = |k: usize| -> Result<(Part, [f64; 3]), IoError> {
        let s = value(0, k, "its degree of freedom")?;
        let d: usize = s
            .parse()
            .ok()
            .filter(|d| (1..=6).contains(d))
            .ok_or_else(|| {
                at_err(
                    l,
                    format!("{keyword}: degree of freedom {s:?} is not 1 to 6"),
                )
            })?;
        let mut dir = [0.0; 3];
        dir[(d - 1) % 3] = 1.0;
        Ok((
            if d > 3 {
                Part::Rotations
            } else {
                Part::Translations
            },
            dir,
        ))
    };
    let (what, its) = if c.dashpot {
        ("the dashpot coefficient", "its dashpot coefficient")
    } else {
        ("the stiffness", "its stiffness")
    };
    let (a, b, k) = match ty {
        StructuralType::Spring1 | StructuralType::Dashpot(SpringKind::One) => {
            let (p, d) = dof(0)?;
            let k = number(l, what, value(1, 0, its)?)?;
            ((p, d), None, k)
        }
        StructuralType::Spring2 | StructuralType::Dashpot(SpringKind::Two) => {
            let (pa, da) = dof(0)?;
            let (pb, db) = dof(1)?;
            let k = number(l, what, value(1, 0, its)?)?;
            ((pa, da), Some((pb, db)), k)
        }
        _ => {
            let x = model.mesh().coords();
            let (xa, xb) = (x[nodes[0]], x[nodes[1]]);
            let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if !(n > 0.0) {
                return Err(at_err(
                    l,
                    format!(
                        "{} element {id}: its nodes coincide, so it has no axis",
                        ty.name()
                    ),
                ));
            }
            let d = [d[0] / n, d[1] / n, d[2] / n];
            let row = c.lines.len().saturating_sub(1);
            let k = number(l, what, value(row, 0, its)?)?;
            ((Part::Translations, d), Some((Part::Translations, d)), k)
        }
    };
    let (k, viscous) = if c.dashpot { (0.0, k) } else { (k, 0.0) };
    Ok(StructuralKind::Spring(Spring {
        k,
        ge: 0.0,
        viscous,
        mass: 0.0,
        a: SpringEnd {
            node: nodes[0],
            part: a.0,
            direction: a.1,
        },
        b: b.map(|(part, direction)| SpringEnd {
            node: *nodes.last().expect("two nodes"),
            part,
            direction,
        }),
    }))
}
