//! Bars, beams, rods, springs, bushings and shells: `CBAR` (`PBAR`, `PBARL`), `CBEAM` (`PBEAM`,
//! `PBEAML`, prismatic), `CROD` (`PROD`), `CONROD`, `CELAS1` (`PELAS`), `CELAS2`, `CDAMP1`
//! (`PDAMP`), `CDAMP2`, `CVISC` (`PVISC`), `CBUSH`
//! (`PBUSH`), `CQUAD4`, `CQUAD8` (all eight grids), `CTRIA3` and `CTRIA6` (all six grids, as four three-node triangles) (`PSHELL` of MAT1, MAT2 or MAT8 materials, THETA or MCID
//! material axes), with `BAROR` and
//! `BEAMOR` defaults, read as the Quick Reference Guide defines them
//! (cited by card) into femu's structural elements ([`femu_fem::structural`]). What femu cannot
//! represent is refused with card and line: pin flags on translations, tapered beams, warping, shear-centre and
//! mass offsets, products of inertia, offsets in the element frame, scalar points.

use super::cards::Card;
use super::geometry::Geometry;
use crate::{IoError, Warning};
use femu_fem::model::Model;
use femu_fem::structural::{
    Beam, BeamSection, Bushing, Part, Rod, Spring, SpringEnd, StructuralElement, StructuralKind,
};
use std::collections::{BTreeMap, HashMap};
use std::f64::consts::PI;

/// The structural cards of a deck, sorted.
#[derive(Default)]
pub(super) struct StructuralCards<'a> {
    /// `CBAR`, `CBEAM`, `CROD`, `CONROD`, `CELAS1`, `CELAS2`, `CBUSH` in file order.
    pub(super) elements: Vec<&'a Card>,
    /// `PBAR`, `PBARL`, `PBEAM`, `PBEAML`, `PROD`, `PELAS`, `PBUSH` by property id (a `PELAS`
    /// may define two).
    pub(super) properties: HashMap<u64, &'a Card>,
    /// `BAROR` and `BEAMOR`.
    pub(super) bar_defaults: Option<&'a Card>,
    pub(super) beam_defaults: Option<&'a Card>,
}

/// The structural element card names.
pub(super) const ELEMENTS: &[&str] = &[
    "CBAR", "CBEAM", "CROD", "CONROD", "CELAS1", "CELAS2", "CDAMP1", "CDAMP2", "CMASS1", "CMASS2",
    "CVISC", "CBUSH", "CQUAD4", "CTRIA3", "CQUAD8", "CTRIA6", "CTUBE", "CBUSH1D",
];
/// The structural property card names.
pub(super) const PROPERTIES: &[&str] = &[
    "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PELAS", "PDAMP", "PMASS", "PVISC", "PBUSH",
    "PSHELL", "PCOMP", "PCOMPG", "PTUBE", "PBUSH1D",
];

impl<'a> StructuralCards<'a> {
    /// Files one card if it is structural; `false` otherwise.
    pub(super) fn take(&mut self, c: &'a Card) -> Result<bool, IoError> {
        let name = c.name.as_str();
        if ELEMENTS.contains(&name) {
            self.elements.push(c);
        } else if matches!(name, "PELAS" | "PDAMP" | "PMASS" | "PVISC") {
            // QRG PELAS: two properties per card, fields 1-4 and 5-8; PDAMP and PMASS: four,
            // fields 1-2, 3-4, 5-6 and 7-8; PVISC: two, fields 1-3 and 5-7
            let width = match name {
                "PELAS" | "PVISC" => 4,
                _ => 2,
            };
            for first in (0..8).step_by(width) {
                if first > 0 && c.field(first).is_empty() {
                    break;
                }
                let pid = c.id(first, "PID")?;
                self.property(pid, c)?;
            }
        } else if PROPERTIES.contains(&name) {
            let pid = c.id(0, "PID")?;
            self.property(pid, c)?;
        } else if name == "BAROR" || name == "BEAMOR" {
            let slot = if name == "BAROR" {
                &mut self.bar_defaults
            } else {
                &mut self.beam_defaults
            };
            if let Some(first) = slot.replace(c) {
                return Err(c.err(format!(
                    "appears twice (first at line {}): a deck has one",
                    first.line
                )));
            }
        } else {
            return Ok(false);
        }
        Ok(true)
    }

    fn property(&mut self, pid: u64, c: &'a Card) -> Result<(), IoError> {
        if let Some(first) = self.properties.insert(pid, c) {
            return Err(c.err(format!(
                "{pid} is defined twice (first by {} at line {})",
                first.name, first.line
            )));
        }
        Ok(())
    }
}

/// What the reader needs beside the cards.
pub(super) struct Context<'g, 'a> {
    pub(super) geometry: &'g mut Geometry<'a>,
    pub(super) materials: &'g HashMap<u64, &'a Card>,
    /// Grids whose displacement frame is turned, with the frame.
    pub(super) turned: &'g HashMap<u64, i64>,
    pub(super) wtmass: f64,
    /// MAT1s read so far: `(E, G, rho)`, each read (and warned about) once.
    pub(super) mat1: HashMap<u64, (f64, f64, f64)>,
}

/// `E`, `G` and `rho` of a MAT1 (QRG MAT1: one of `E`, `G`, `NU` blank is completed from the
/// other two; `RHO` times `WTMASS`).
fn mat1(ctx: &mut Context<'_, '_>, mid: u64, by: &Card) -> Result<(f64, f64, f64), IoError> {
    if let Some(v) = ctx.mat1.get(&mid) {
        return Ok(*v);
    }
    let m = ctx.materials.get(&mid).ok_or_else(|| {
        by.err(format!(
            "{} refers to MAT1 {mid}, which the deck does not define",
            by.field(0)
        ))
    })?;
    if m.name != "MAT1" {
        return Err(by.err(format!(
            "{} refers to {} {mid}: beams, rods and bars take a MAT1",
            by.field(0),
            m.name
        )));
    }
    // a beam uses E and G as given (its torsion and shear take G, its bending and axial E);
    // a blank one is completed from the other and NU (QRG MAT1, remarks)
    let (e, g, nu) = (m.real(1, "E")?, m.real(2, "G")?, m.real(3, "NU")?);
    let (e, g) = match (e, g, nu) {
        (Some(e), Some(g), _) => (e, g),
        (Some(e), None, Some(nu)) => (e, e / (2.0 * (1.0 + nu))),
        (None, Some(g), Some(nu)) => (2.0 * g * (1.0 + nu), g),
        _ => {
            return Err(m.err(format!(
                "{mid}: a beam or rod needs E and G (or one of them with NU); Nastran sets the blank pair to 0, a material with no stiffness in torsion or tension"
            )));
        }
    };
    let rho = m.real(4, "RHO")?.unwrap_or(0.0) * ctx.wtmass;
    ctx.mat1.insert(mid, (e, g, rho));
    Ok((e, g, rho))
}

/// The axes of grid `g`'s displacement frame at its position, columns the axes (the identity for
/// the basic frame).
fn cd_axes(
    ctx: &mut Context<'_, '_>,
    model: &Model,
    g: u64,
    by: &Card,
) -> Result<[[f64; 3]; 3], IoError> {
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let Some(cd) = ctx.turned.get(&g) else {
        return Ok(identity);
    };
    let n = model
        .mesh()
        .node_index(g)
        .expect("turned grids are in the mesh");
    let x = model.mesh().coords()[n];
    Ok(ctx.geometry.frame(*cd, by)?.axes_at(x))
}

fn apply(a: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|j| a[i][j] * v[j]).sum())
}

fn node(model: &Model, g: u64, c: &Card, what: &str) -> Result<usize, IoError> {
    model.mesh().node_index(g).ok_or_else(|| {
        c.err(format!(
            "{}: {what} is GRID {g}, which the deck does not define (scalar points are not modelled)",
            c.field(0)
        ))
    })
}

/// A section's properties from a `PBARL` or `PBEAML` shape (QRG PBARL, figure of the types; the
/// section's `y` axis along `DIM2` of a BAR, its height): `(A, I1, I2, J, [K1, K2])`.
///
/// Torsion constants: exact for ROD and TUBE, Roark's series for a rectangle, Bredt's for the
/// BOX's closed wall, `sum b t^3 / 3` for the open walls of I and CHAN. Shear factors: 0.9 for a
/// ROD (Nastran's own, as its PBAR replacing a PBARL says), 5/6 for a rectangle, 1/2 for a thin
/// tube, and the web's (or flanges') share of the area for I, CHAN and BOX. Nastran computes its
/// own factors for the other types; they change the shear deflection only, a small share of a
/// slender beam's.
fn shape(c: &Card, kind: &str, d: &[f64]) -> Result<(f64, f64, f64, f64, [f64; 2]), IoError> {
    let bad = |reason: String| c.err(format!("{} ({kind}): {reason}", c.field(0)));
    if let Some(v) = d.iter().find(|v| !(**v > 0.0)) {
        return Err(bad(format!("dimension {v} must be positive")));
    }
    Ok(match kind {
        "ROD" => {
            let r = d[0];
            let a = PI * r * r;
            let i = PI * r.powi(4) / 4.0;
            // Nastran's own factor for a ROD (its PBAR replacing a PBARL ROD says 0.9)
            (a, i, i, 2.0 * i, [0.9, 0.9])
        }
        "TUBE" => {
            let (ro, ri) = (d[0], d[1]);
            if ri >= ro {
                return Err(bad(format!(
                    "inner radius {ri} is not below outer radius {ro}"
                )));
            }
            let a = PI * (ro * ro - ri * ri);
            let i = PI * (ro.powi(4) - ri.powi(4)) / 4.0;
            (a, i, i, 2.0 * i, [0.5, 0.5])
        }
        "BAR" => {
            // DIM1 along z, DIM2 along y
            let (bz, hy) = (d[0], d[1]);
            let (long, short) = if bz > hy { (bz, hy) } else { (hy, bz) };
            let j = long
                * short.powi(3)
                * (1.0 / 3.0 - 0.21 * short / long * (1.0 - short.powi(4) / (12.0 * long.powi(4))));
            (
                bz * hy,
                bz * hy.powi(3) / 12.0,
                hy * bz.powi(3) / 12.0,
                j,
                [5.0 / 6.0, 5.0 / 6.0],
            )
        }
        "BOX" => {
            // DIM1 width (z), DIM2 height (y), DIM3 horizontal walls, DIM4 vertical walls
            let (b, h, t1, t2) = (d[0], d[1], d[2], d[3]);
            if 2.0 * t2 >= b || 2.0 * t1 >= h {
                return Err(bad(format!(
                    "walls {t1}, {t2} leave no hollow in {b} x {h}"
                )));
            }
            let (bi, hi) = (b - 2.0 * t2, h - 2.0 * t1);
            let a = b * h - bi * hi;
            let j = 2.0 * t1 * t2 * (b - t2).powi(2) * (h - t1).powi(2)
                / (b * t2 + h * t1 - t2 * t2 - t1 * t1);
            // the shear areas of the walls along each direction, corners in neither (MSC's
            // PBEAML BOX converted to PBEAM: docs/VERIFICATION.md)
            let web = 2.0 * t2 * hi;
            let flanges = 2.0 * t1 * bi;
            (
                a,
                (b * h.powi(3) - bi * hi.powi(3)) / 12.0,
                (h * b.powi(3) - hi * bi.powi(3)) / 12.0,
                j,
                [web / a, flanges / a],
            )
        }
        "I" => {
            // DIM1 height (y), DIM2 bottom flange width, DIM3 top flange width, DIM4 web,
            // DIM5 bottom flange thickness, DIM6 top flange thickness
            let (h, wb, wt, tw, tb, tt) = (d[0], d[1], d[2], d[3], d[4], d[5]);
            let hw = h - tb - tt;
            if hw <= 0.0 {
                return Err(bad(format!("flanges {tb} + {tt} fill the height {h}")));
            }
            // rectangles (width along z, height along y, centre y), from the bottom
            let parts = [
                (wb, tb, tb / 2.0),
                (tw, hw, tb + hw / 2.0),
                (wt, tt, h - tt / 2.0),
            ];
            let (a, i1, i2) = rectangles(&parts, |_| 0.0);
            let j = (wb * tb.powi(3) + wt * tt.powi(3) + hw * tw.powi(3)) / 3.0;
            (a, i1, i2, j, [tw * hw / a, (wb * tb + wt * tt) / a])
        }
        "CHAN" => {
            // DIM1 flange width (z), DIM2 height (y), DIM3 web thickness, DIM4 flange thickness
            let (w, h, tw, tf) = (d[0], d[1], d[2], d[3]);
            let hw = h - 2.0 * tf;
            if hw <= 0.0 || tw >= w {
                return Err(bad(format!(
                    "flanges {tf} or web {tw} fill the section {w} x {h}"
                )));
            }
            let parts = [(w, tf, tf / 2.0), (tw, hw, h / 2.0), (w, tf, h - tf / 2.0)];
            // z centres: the flanges from the web's back, the web at its own mid-thickness
            let zc = [w / 2.0, tw / 2.0, w / 2.0];
            let (a, i1, i2) = rectangles(&parts, |k| zc[k]);
            let j = (2.0 * w * tf.powi(3) + hw * tw.powi(3)) / 3.0;
            (a, i1, i2, j, [tw * hw / a, 2.0 * w * tf / a])
        }
        other => {
            return Err(c.err(format!(
                "{}: section type {other} is not read (femu reads ROD, TUBE, BAR, BOX, I and CHAN)",
                c.field(0)
            )));
        }
    })
}

/// Area and second moments about the centroid of rectangles `(width along z, height along y,
/// centre y)` with centre z `zc(k)`: `(A, I1 = int (y - yc)^2, I2 = int (z - zc)^2)`.
fn rectangles(parts: &[(f64, f64, f64)], zc: impl Fn(usize) -> f64) -> (f64, f64, f64) {
    let a: f64 = parts.iter().map(|p| p.0 * p.1).sum();
    let yc = parts.iter().map(|p| p.0 * p.1 * p.2).sum::<f64>() / a;
    let z0 = parts
        .iter()
        .enumerate()
        .map(|(k, p)| p.0 * p.1 * zc(k))
        .sum::<f64>()
        / a;
    let mut i1 = 0.0;
    let mut i2 = 0.0;
    for (k, &(w, h, y)) in parts.iter().enumerate() {
        i1 += w * h.powi(3) / 12.0 + w * h * (y - yc).powi(2);
        i2 += h * w.powi(3) / 12.0 + w * h * (zc(k) - z0).powi(2);
    }
    (a, i1, i2)
}

/// The number of dimensions of a section type.
fn dims_of(kind: &str) -> Option<usize> {
    Some(match kind {
        "ROD" => 1,
        "TUBE" | "BAR" => 2,
        "BOX" | "CHAN" => 4,
        "I" => 6,
        _ => return None,
    })
}

/// A beam's material and section from its property card: `(E, G, rho, section, end B's section
/// when it tapers)`.
fn beam_property(
    ctx: &mut Context<'_, '_>,
    p: &Card,
    warnings: &mut Vec<Warning>,
    warned: &mut Vec<u64>,
) -> Result<(f64, f64, f64, BeamSection, Option<BeamSection>), IoError> {
    let pid = p.id(0, "PID")?;
    let mid = p.id(1, "MID")?;
    let (e, g, rho) = mat1(ctx, mid, p)?;
    let wt = ctx.wtmass;
    let r = |i: usize, what: &str| -> Result<f64, IoError> { Ok(p.real(i, what)?.unwrap_or(0.0)) };
    let mut taper = None;
    let section = match p.name.as_str() {
        "PBAR" => {
            // QRG PBAR: PID MID A I1 I2 J NSM / C1..F2 / K1 K2 I12
            if r(18, "I12")? != 0.0 {
                return Err(p.err(format!(
                    "{pid}: I12 = {} couples the two bending planes; femu builds beams on principal axes (give I1 and I2 in them, with the orientation vector along axis 1)",
                    r(18, "I12")?
                )));
            }
            // K1, K2 blank: infinite shear stiffness (QRG PBAR, remarks)
            let k1 = p.real(16, "K1")?;
            let k2 = p.real(17, "K2")?;
            let shear = match (k1, k2) {
                (None, None) => None,
                (a, b) => Some([
                    a.filter(|v| *v != 0.0).unwrap_or(f64::INFINITY),
                    b.filter(|v| *v != 0.0).unwrap_or(f64::INFINITY),
                ]),
            };
            BeamSection {
                area: r(2, "A")?,
                i1: r(3, "I1")?,
                i2: r(4, "I2")?,
                j: r(5, "J")?,
                shear,
                nsm: r(6, "NSM")? * wt,
            }
        }
        "PBEAM" => {
            let (a, b) = pbeam(p, pid, wt)?;
            taper = b;
            a
        }
        "PBARL" | "PBEAML" => {
            if !p.field(2).is_empty() && !p.field(2).eq_ignore_ascii_case("MSCBML0") {
                return Err(p.err(format!(
                    "{pid}: GROUP {} is not the standard library MSCBML0 (femu reads its ROD, TUBE, BAR, BOX, I and CHAN)",
                    p.field(2)
                )));
            }
            let kind = p.field(3).to_ascii_uppercase();
            let n = dims_of(&kind).ok_or_else(|| {
                p.err(format!(
                    "{pid}: section type {kind} is not read (femu reads ROD, TUBE, BAR, BOX, I and CHAN)"
                ))
            })?;
            let d = (0..n)
                .map(|k| {
                    p.real(8 + k, "DIM")?
                        .ok_or_else(|| p.err(format!("{pid}: DIM{} of {kind} is missing", k + 1)))
                })
                .collect::<Result<Vec<_>, _>>()?;
            let nsm = r(8 + n, "NSM")?;
            // end B's DIMs and NSM (blank: end A's), from the stations after end A
            let mut end_b: Option<(Vec<f64>, f64)> = None;
            if p.name == "PBEAML" {
                // stations: SO, X/XB, n DIMs, NSM
                let rest: Vec<&str> = (9 + n..p.fields.len()).map(|i| p.field(i)).collect();
                let mut stations = Vec::new();
                let mut k = 0;
                while k < rest.len() {
                    if rest[k].is_empty() {
                        k += 1;
                        continue;
                    }
                    let x = rest
                        .get(k + 1)
                        .and_then(|s| super::cards::real(s))
                        .ok_or_else(|| {
                            p.err(format!(
                                "{pid}: a station (SO {}) without its X/XB",
                                rest[k]
                            ))
                        })?;
                    let values: Vec<f64> = d
                        .iter()
                        .chain([&nsm])
                        .enumerate()
                        .map(|(m, a)| {
                            rest.get(k + 2 + m)
                                .and_then(|s| super::cards::real(s))
                                .unwrap_or(*a)
                        })
                        .collect();
                    stations.push((x, values));
                    k += n + 3;
                }
                let differs = |v: &[f64]| {
                    v.iter()
                        .zip(d.iter().chain([&nsm]))
                        .any(|(v, a)| (v - a).abs() > 1e-12 * a.abs())
                };
                for (x, v) in &stations {
                    if (x - 1.0).abs() < 1e-9 {
                        end_b = differs(v).then(|| (v[..n].to_vec(), v[n]));
                    } else if differs(v) {
                        return Err(p.err(format!(
                            "{pid}: the section changes at the intermediate station X/XB = {x}; femu's tapered beams vary from end A's section to end B's (give the two ends)"
                        )));
                    }
                }
            }
            let (area, i1, i2, j, k) = shape(p, &kind, &d)?;
            if let Some((db, nsm_b)) = &end_b {
                let (area, i1, i2, j, _) = shape(p, &kind, db)?;
                taper = Some(BeamSection {
                    area,
                    i1,
                    i2,
                    j,
                    shear: Some(k),
                    nsm: nsm_b * wt,
                });
            }
            if !warned.contains(&pid) {
                warned.push(pid);
                warnings.push(Warning {
                    path: p.path.clone(),
                    line: p.line,
                    message: format!(
                        "{} {pid} ({kind}): A = {area:.6e}, I1 = {i1:.6e}, I2 = {i2:.6e}, J = {j:.6e}, shear factors K1 = {:.4}, K2 = {:.4} (femu's formulas, docs/MATH.md; Nastran computes its own J and shear factors, which may differ slightly)",
                        p.name, k[0], k[1]
                    ),
                });
            }
            BeamSection {
                area,
                i1,
                i2,
                j,
                shear: Some(k),
                nsm: nsm * wt,
            }
        }
        other => {
            return Err(p.err(format!("{pid} is a {other}, not a bar or beam property")));
        }
    };
    Ok((e, g, rho, section, taper))
}

/// A `PBEAM` (QRG PBEAM): end A's `A I1 I2 I12 J NSM`, the stations after it (blank values:
/// end A's), then `K1 K2` (default 1.0; 0.0 is rigid in shear) and the shear relief, warping
/// and offset fields, which must be blank or zero. Returns end A's section and end B's when the
/// beam tapers (docs/MATH.md, "Tapered beams"); an intermediate station must lie on the line
/// between the ends.
fn pbeam(p: &Card, pid: u64, wt: f64) -> Result<(BeamSection, Option<BeamSection>), IoError> {
    let r = |i: usize| -> Result<f64, IoError> { Ok(p.real(i, "PBEAM field")?.unwrap_or(0.0)) };
    let (a, i1, i2, i12, j, nsm) = (r(2)?, r(3)?, r(4)?, r(5)?, r(6)?, r(7)?);
    if i12 != 0.0 {
        return Err(p.err(format!(
            "{pid}: I12 = {i12} couples the two bending planes; femu builds beams on principal axes"
        )));
    }
    // stations: blocks starting with SO (YES, YESA, NO); 16 fields with SO = YES, else 8
    let end_a = [a, i1, i2, i12, j, nsm];
    let mut stations: Vec<(f64, [f64; 6], usize)> = Vec::new();
    let mut at = 16;
    loop {
        let so = p.field(at).to_ascii_uppercase();
        if !matches!(so.as_str(), "YES" | "YESA" | "NO") {
            break;
        }
        let x = p.real(at + 1, "X/XB")?.ok_or_else(|| {
            p.err(format!(
                "{pid}: a station (SO {so}) without its X/XB (field {})",
                at + 3
            ))
        })?;
        let mut v = end_a;
        for (k, slot) in v.iter_mut().enumerate() {
            if let Some(value) = p.real(at + 2 + k, "station value")? {
                *slot = value;
            }
        }
        stations.push((x, v, at));
        at += if so == "YES" { 16 } else { 8 };
    }
    let end_b = stations
        .iter()
        .find(|s| (s.0 - 1.0).abs() < 1e-9)
        .map_or(end_a, |s| s.1);
    if end_b[3] != 0.0 {
        return Err(p.err(format!(
            "{pid}: end B's I12 = {} couples the two bending planes; femu builds beams on principal axes",
            end_b[3]
        )));
    }
    let names = ["A", "I1", "I2", "I12", "J", "NSM"];
    for (x, v, field) in &stations {
        for k in 0..6 {
            let line = end_a[k] + (end_b[k] - end_a[k]) * x;
            if (v[k] - line).abs() > 1e-6 * v[k].abs().max(line.abs()).max(f64::MIN_POSITIVE) {
                return Err(p.err(format!(
                    "{pid}: at the station X/XB = {x} (field {}), {} = {} is not on the line between the ends ({line}); femu's tapered beams vary linearly from end A to end B",
                    field + 2 + k + 2,
                    names[k],
                    v[k]
                )));
            }
        }
    }
    let k1 = p.real(at, "K1")?.unwrap_or(1.0);
    let k2 = p.real(at + 1, "K2")?.unwrap_or(1.0);
    let names = [
        "S1", "S2", "NSI(A)", "NSI(B)", "CW(A)", "CW(B)", "M1(A)", "M2(A)", "M1(B)", "M2(B)",
        "N1(A)", "N2(A)", "N1(B)", "N2(B)",
    ];
    for (k, name) in names.iter().enumerate() {
        let v = p.real(at + 2 + k, name)?.unwrap_or(0.0);
        if v != 0.0 {
            return Err(p.err(format!(
                "{pid}: {name} = {v} (shear relief, non-structural inertia, warping or an offset of the centre of mass or neutral axis) is not modelled by femu's beams"
            )));
        }
    }
    let rigid = |k: f64| if k == 0.0 { f64::INFINITY } else { k };
    let section = |v: [f64; 6]| BeamSection {
        area: v[0],
        i1: v[1],
        i2: v[2],
        j: v[4],
        shear: Some([rigid(k1), rigid(k2)]),
        nsm: v[5] * wt,
    };
    let tapered = end_b
        .iter()
        .zip(&end_a)
        .any(|(b, a)| (b - a).abs() > 1e-12 * a.abs().max(f64::MIN_POSITIVE));
    Ok((section(end_a), tapered.then(|| section(end_b))))
}

/// The orientation vector of a CBAR or CBEAM (fields 4-6: `X1 X2 X3`, or `G0` as an integer in
/// field 4 and blanks after it), from the element or its `BAROR`/`BEAMOR`, in the basic frame;
/// and the `OFFT` code.
fn orientation(
    ctx: &mut Context<'_, '_>,
    model: &Model,
    c: &Card,
    defaults: Option<&Card>,
    ga: u64,
) -> Result<([f64; 3], String), IoError> {
    let own = (4..7).any(|i| !c.field(i).is_empty());
    let src = if own {
        c
    } else {
        defaults.ok_or_else(|| {
            c.err(format!(
                "{}: no orientation vector (X1, X2, X3 or G0) and no {} default",
                c.field(0),
                if c.name == "CBAR" { "BAROR" } else { "BEAMOR" }
            ))
        })?
    };
    let offt = {
        let own = c.field(7).to_ascii_uppercase();
        if own.is_empty() {
            defaults.map_or(String::new(), |d| d.field(7).to_ascii_uppercase())
        } else {
            own
        }
    };
    let offt = if offt.is_empty() {
        "GGG".to_string()
    } else {
        offt
    };
    let is_g0 = !src.field(4).contains('.')
        && !src.field(4).contains(['e', 'E'])
        && src.field(5).is_empty()
        && src.field(6).is_empty();
    // the older format's flag `F` in OFFT's field: 1, the vector X1 X2 X3, 2, the grid G0, both
    // in GA's displacement frame with offsets in the grids' frames (the OFFT GGG of today's QRG;
    // the GEOM2 table of the DMAP Programmer's Guide still stores F)
    let offt = match offt.as_str() {
        "1" | "2" if (offt == "2") == is_g0 => "GGG".to_string(),
        "1" | "2" => {
            return Err(c.err(format!(
                "{}: the flag F = {offt} in field 9 says the orientation is {}, but fields 5-7 give {}",
                c.field(0),
                if offt == "1" {
                    "a vector X1 X2 X3"
                } else {
                    "a grid G0"
                },
                if is_g0 { "a grid G0" } else { "a vector" }
            )));
        }
        _ => offt,
    };
    let xa = model.mesh().coords()[node(model, ga, c, "GA")?];
    if is_g0 {
        let g0 = src.id(4, "G0")?;
        let x0 = model.mesh().coords()[node(model, g0, c, "G0")?];
        return Ok(([x0[0] - xa[0], x0[1] - xa[1], x0[2] - xa[2]], offt));
    }
    let v = [
        src.real(4, "X1")?.unwrap_or(0.0),
        src.real(5, "X2")?.unwrap_or(0.0),
        src.real(6, "X3")?.unwrap_or(0.0),
    ];
    // QRG CBAR: v in GA's displacement frame unless OFFT starts with B (basic)
    let v = match offt.chars().next() {
        Some('B') => v,
        Some('G') => apply(&cd_axes(ctx, model, ga, c)?, v),
        _ => {
            return Err(c.err(format!(
                "{}: OFFT {offt} is not one of Nastran's codes (GGG, BGG, GGO, BOG, ...)",
                c.field(0)
            )));
        }
    };
    Ok((v, offt))
}

/// The structural damping coefficient `GE` of the materials in fields `at` of `card` (blank or
/// unknown ids are skipped: the element's own reading refuses them): one value, or an error when
/// they differ (femu damps an element by one coefficient).
fn mid_ge(ctx: &Context<'_, '_>, card: &Card, at: &[usize]) -> Result<f64, IoError> {
    let mut found: Option<(u64, f64)> = None;
    for &i in at {
        let Some(mid) = card.int(i, "MID")?.filter(|m| *m > 0) else {
            continue;
        };
        let Some(m) = ctx.materials.get(&(mid as u64)) else {
            continue;
        };
        let ge = super::materials::material_ge(m)?;
        match found {
            Some((other, g)) if g != ge => {
                return Err(card.err(format!(
                    "{}: its materials {other} and {mid} have different structural damping (GE {g} and {ge}): femu damps an element by one coefficient",
                    card.field(0)
                )));
            }
            _ => found = Some((mid as u64, ge)),
        }
    }
    Ok(found.map_or(0.0, |f| f.1))
}

/// The structural damping coefficient `GE` of the elements of property `p`: its material's `GE`
/// (PBAR, PBARL, PBEAM, PBEAML, PROD: MID; PSHELL: MID1, MID2 and MID3, which must agree), a
/// PCOMP's or PCOMPG's own `GE` field (QRG PCOMP: the element's damping, whatever its plies'
/// materials say).
fn property_ge(ctx: &Context<'_, '_>, p: &Card) -> Result<f64, IoError> {
    match p.name.as_str() {
        "PSHELL" => mid_ge(ctx, p, &[1, 3, 5]),
        "PCOMP" | "PCOMPG" => {
            let ge = p.real(6, "GE")?.unwrap_or(0.0);
            if ge.is_finite() && ge >= 0.0 {
                Ok(ge)
            } else {
                Err(p.err(format!(
                    "{}: GE = {ge}: a structural damping coefficient is at least 0",
                    p.field(0)
                )))
            }
        }
        "PBAR" | "PBARL" | "PBEAM" | "PBEAML" | "PROD" | "PTUBE" => mid_ge(ctx, p, &[1]),
        _ => Ok(0.0),
    }
}

/// Reads the structural elements into `model` (each property's into the structural set
/// `PID<n>`); returns how many.
///
/// # Errors
/// A malformed card, an unknown grid, property or material, and what femu cannot represent.
pub(super) fn add_structural(
    cards: &StructuralCards<'_>,
    model: &mut Model,
    ctx: &mut Context<'_, '_>,
    warnings: &mut Vec<Warning>,
) -> Result<usize, IoError> {
    let mut sets: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    let mut warned = Vec::new();
    let mut warned_ctria6 = false;
    for c in &cards.elements {
        let eid = c.id(0, "EID")?;
        let prop = |pid: u64, kinds: &[&str]| -> Result<&Card, IoError> {
            let p = cards.properties.get(&pid).ok_or_else(|| {
                c.err(format!(
                    "{eid} refers to property {pid}, which the deck does not define"
                ))
            })?;
            if !kinds.contains(&p.name.as_str()) {
                return Err(c.err(format!(
                    "{eid} refers to {} {pid}; a {} takes {}",
                    p.name,
                    c.name,
                    kinds.join(" or ")
                )));
            }
            Ok(p)
        };
        let (kind, nodes, pid) = match c.name.as_str() {
            "CBAR" | "CBEAM" => {
                let defaults = if c.name == "CBAR" {
                    cards.bar_defaults
                } else {
                    cards.beam_defaults
                };
                let pid = match c.int(1, "PID")? {
                    Some(p) if p > 0 => p as u64,
                    Some(p) => return Err(c.err(format!("{eid}: PID {p} must be positive"))),
                    None => match defaults.and_then(|d| d.int(1, "PID").ok().flatten()) {
                        Some(p) if p > 0 => p as u64,
                        _ => eid,
                    },
                };
                let kinds: &[&str] = if c.name == "CBAR" {
                    &["PBAR", "PBARL"]
                } else {
                    &["PBEAM", "PBEAML"]
                };
                let p = prop(pid, kinds)?;
                let (ga, gb) = (c.id(2, "GA")?, c.id(3, "GB")?);
                let (na, nb) = (node(model, ga, c, "GA")?, node(model, gb, c, "GB")?);
                let (v, offt) = orientation(ctx, model, c, defaults, ga)?;
                // PA, PB: pin flags, the components (element frame) released at each end
                let mut releases = [[false; 6]; 2];
                for (end, (i, what)) in [(8, "PA"), (9, "PB")].into_iter().enumerate() {
                    let flags = c.field(i);
                    if flags.is_empty() || flags == "0" {
                        continue;
                    }
                    for ch in flags.chars() {
                        let k = match ch.to_digit(10) {
                            Some(k @ 1..=6) => k as usize - 1,
                            _ => {
                                return Err(c.err(format!(
                                    "{eid}: {what} = {flags}: pin flags are components 1 to 6"
                                )));
                            }
                        };
                        if releases[end][k] {
                            return Err(c.err(format!(
                                "{eid}: {what} = {flags} gives component {} twice",
                                k + 1
                            )));
                        }
                        if k < 3 {
                            return Err(c.err(format!(
                                "{eid}: {what} = {flags} releases translation {} at an end, which carries the bar's mass: femu releases rotations (4-6) only",
                                k + 1
                            )));
                        }
                        releases[end][k] = true;
                    }
                }
                if c.name == "CBEAM" && (!c.field(16).is_empty() || !c.field(17).is_empty()) {
                    return Err(c.err(format!(
                        "{eid}: SA, SB are warping scalar points, which femu does not model"
                    )));
                }
                let mut offsets = [[0.0; 3]; 2];
                for (end, (g, first)) in [(ga, 10), (gb, 13)].into_iter().enumerate() {
                    let w = [
                        c.real(first, "W1")?.unwrap_or(0.0),
                        c.real(first + 1, "W2")?.unwrap_or(0.0),
                        c.real(first + 2, "W3")?.unwrap_or(0.0),
                    ];
                    if w.iter().all(|x| *x == 0.0) {
                        continue;
                    }
                    offsets[end] = match offt.chars().nth(1 + end) {
                        Some('G') => apply(&cd_axes(ctx, model, g, c)?, w),
                        Some('B') => w,
                        _ => {
                            return Err(c.err(format!(
                                "{eid}: offsets in the element frame (OFFT {offt}) are not read; give them in the grids' frames (OFFT GGG)"
                            )));
                        }
                    };
                }
                let (e, g, rho, section, taper) = beam_property(ctx, p, warnings, &mut warned)?;
                let kind = StructuralKind::Beam(Beam {
                    e,
                    g,
                    rho,
                    section,
                    taper,
                    orientation: v,
                    offsets,
                    // Nastran's lumped CBEAM mass carries the polar inertia, its CBAR's does not
                    // (the grid point weight of pyNastran's beam_modes run: docs/VERIFICATION.md)
                    lumped_torsion: c.name == "CBEAM",
                    coupled_torsion: c.name == "CBEAM",
                    releases,
                });
                (kind, vec![na, nb], pid)
            }
            "CROD" | "CONROD" => {
                let conrod = c.name == "CONROD";
                let (f1, f2) = if conrod { (1, 2) } else { (2, 3) };
                let (g1, g2) = (c.id(f1, "G1")?, c.id(f2, "G2")?);
                let (n1, n2) = (node(model, g1, c, "G1")?, node(model, g2, c, "G2")?);
                // CONROD: EID G1 G2 MID A J C NSM; PROD: PID MID A J C NSM
                let (src, base, pid) = if conrod {
                    (*c, 3, eid)
                } else {
                    let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                    (prop(pid, &["PROD"])?, 1, pid)
                };
                let mid = src.id(base, "MID")?;
                let (e, g, rho) = mat1(ctx, mid, src)?;
                let r = |i: usize, w: &str| -> Result<f64, IoError> {
                    Ok(src.real(base + i, w)?.unwrap_or(0.0))
                };
                let kind = StructuralKind::Rod(Rod {
                    e,
                    g,
                    rho,
                    area: r(1, "A")?,
                    j: r(2, "J")?,
                    nsm: r(4, "NSM")? * ctx.wtmass,
                });
                (kind, vec![n1, n2], pid)
            }
            "CTUBE" => {
                // CTUBE: EID PID G1 G2; PTUBE: PID MID OD T NSM OD2 (QRG): a rod of the tube's
                // area pi (OD^2 - ID^2) / 4 and torsion constant pi (OD^4 - ID^4) / 32, ID =
                // OD - 2 T, a solid rod for T blank or 0
                let (g1, g2) = (c.id(2, "G1")?, c.id(3, "G2")?);
                let (n1, n2) = (node(model, g1, c, "G1")?, node(model, g2, c, "G2")?);
                let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                let p = prop(pid, &["PTUBE"])?;
                let (e, g, rho) = mat1(ctx, p.id(1, "MID")?, p)?;
                let od = p
                    .real(2, "OD")?
                    .filter(|d| d.is_finite() && *d > 0.0)
                    .ok_or_else(|| p.err(format!("{pid}: a tube needs a positive OD")))?;
                let t = p.real(3, "T")?.filter(|t| *t != 0.0).unwrap_or(od / 2.0);
                if !(t > 0.0 && t <= od / 2.0) {
                    return Err(p.err(format!(
                        "{pid}: T = {t} with OD = {od}: the wall is more than 0 and at most OD / 2"
                    )));
                }
                if let Some(od2) = p.real(5, "OD2")?.filter(|d| *d != od) {
                    return Err(p.err(format!(
                        "{pid}: OD2 = {od2} tapers the tube from OD = {od}, which the QRG gives for heat transfer only; femu's tubes are of one diameter"
                    )));
                }
                let id = od - 2.0 * t;
                let pi = std::f64::consts::PI;
                let kind = StructuralKind::Rod(Rod {
                    e,
                    g,
                    rho,
                    area: pi * (od * od - id * id) / 4.0,
                    j: pi * (od.powi(4) - id.powi(4)) / 32.0,
                    nsm: p.real(4, "NSM")?.unwrap_or(0.0) * ctx.wtmass,
                });
                (kind, vec![n1, n2], pid)
            }
            "CELAS1" | "CELAS2" | "CDAMP1" | "CDAMP2" | "CMASS1" | "CMASS2" => {
                // CELAS1: EID PID G1 C1 G2 C2; CELAS2: EID K G1 C1 G2 C2 GE S; CDAMP1, CMASS1:
                // EID PID G1 C1 G2 C2; CDAMP2: EID B G1 C1 G2 C2; CMASS2: EID M G1 C1 G2 C2 (QRG)
                let damper = c.name.starts_with("CDAMP");
                let scalar_mass = c.name.starts_with("CMASS");
                let (value, ge, pid) = if c.name.ends_with('1') {
                    let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                    let (property, value) = if damper {
                        ("PDAMP", "B")
                    } else if scalar_mass {
                        ("PMASS", "M")
                    } else {
                        ("PELAS", "K")
                    };
                    let p = prop(pid, &[property])?;
                    // the property's own fields: the first PID on the card that is this one
                    let width = if damper || scalar_mass { 2 } else { 4 };
                    let first = (0..8)
                        .step_by(width)
                        .find(|&f| p.int(f, "PID").ok().flatten() == Some(pid as i64))
                        .unwrap_or(0);
                    (
                        p.real(first + 1, value)?.unwrap_or(0.0),
                        if damper || scalar_mass {
                            0.0
                        } else {
                            p.real(first + 2, "GE")?.unwrap_or(0.0)
                        },
                        pid,
                    )
                } else if damper {
                    (c.real(1, "B")?.unwrap_or(0.0), 0.0, eid)
                } else if scalar_mass {
                    (c.real(1, "M")?.unwrap_or(0.0), 0.0, eid)
                } else {
                    (
                        c.real(1, "K")?.unwrap_or(0.0),
                        c.real(6, "GE")?.unwrap_or(0.0),
                        eid,
                    )
                };
                let (k, viscous, mass) = if damper {
                    (0.0, value, 0.0)
                } else if scalar_mass {
                    // PARAM,WTMASS scales every term of the mass matrix (QRG PARAM WTMASS)
                    (0.0, 0.0, value * ctx.wtmass)
                } else {
                    (value, 0.0, 0.0)
                };
                let mut ends = Vec::new();
                for (gf, cf) in [(2, 3), (4, 5)] {
                    let g = c.int(gf, "G")?.unwrap_or(0);
                    if g <= 0 {
                        continue;
                    }
                    let comp = c.int(cf, "C")?.unwrap_or(0);
                    if !(1..=6).contains(&comp) {
                        return Err(c.err(format!(
                            "{eid}: component {comp} of GRID {g} is not 1 to 6 (scalar points are not modelled)"
                        )));
                    }
                    let n = node(model, g as u64, c, "G")?;
                    let axes = cd_axes(ctx, model, g as u64, c)?;
                    let axis = ((comp - 1) % 3) as usize;
                    ends.push(SpringEnd {
                        node: n,
                        part: if comp > 3 {
                            Part::Rotations
                        } else {
                            Part::Translations
                        },
                        direction: [axes[0][axis], axes[1][axis], axes[2][axis]],
                    });
                }
                let Some(a) = ends.first().copied() else {
                    return Err(c.err(format!("{eid}: neither grid is given")));
                };
                let nodes: Vec<usize> = ends.iter().map(|e| e.node).collect();
                let kind = StructuralKind::Spring(Spring {
                    k,
                    ge,
                    viscous,
                    mass,
                    a,
                    b: ends.get(1).copied(),
                });
                (kind, nodes, pid)
            }
            "CQUAD4" | "CTRIA3" | "CQUAD8" | "CTRIA6" => {
                let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                let p = prop(pid, &["PSHELL", "PCOMP", "PCOMPG"])?;
                let (grids, corners) = match c.name.as_str() {
                    "CQUAD8" => (8, 4),
                    "CTRIA6" => (6, 3),
                    "CQUAD4" => (4, 4),
                    _ => (3, 3),
                };
                if let Some(k) = (2 + corners..2 + grids).find(|&i| c.field(i).trim().is_empty()) {
                    return Err(c.err(format!(
                        "{eid}: edge grid G{} is blank; femu builds a {} with all {grids} grids (give the edge grids, or model the element as a {})",
                        k - 1,
                        c.name,
                        if c.name == "CQUAD8" { "CQUAD4" } else { "CTRIA3" }
                    )));
                }
                if c.name == "CTRIA6" && !warned_ctria6 {
                    warned_ctria6 = true;
                    warnings.push(Warning {
                        path: c.path.clone(),
                        line: c.line,
                        message: "CTRIA6: femu builds each as four flat three-node triangles (MITC3) on its six grids, a linear shell mesh twice as fine, not Nastran's quadratic element: its frequencies converge to the same as the mesh is refined (docs/MATH.md, \"Six-node triangles\")".into(),
                    });
                }
                let nodes = (2..2 + grids)
                    .map(|i| node(model, c.id(i, "G")?, c, "a grid"))
                    .collect::<Result<Vec<_>, _>>()?;
                // THETA/MCID and ZOFFS follow the corners: fields 8 and 9 of a CQUAD4, 7 and 8
                // of a CTRIA3; a CQUAD8 has them after T1-T4 on its second line (QRG CQUAD8)
                let (theta_field, zoffs_field, tflag_field, t_field) = match c.name.as_str() {
                    "CQUAD8" => (14, 15, 16, 10),
                    // QRG CTRIA6: THETA/MCID, ZOFFS, T1-T3, TFLAG after the six grids
                    "CTRIA6" => (8, 9, 13, 10),
                    _ => (corners + 2, corners + 3, 10, 11),
                };
                let (mut shell, laminate) = if p.name == "PSHELL" {
                    (pshell(p, pid, ctx)?, None)
                } else {
                    let (s, shift) = pcomp(p, pid, ctx)?;
                    (s, Some(shift))
                };
                let element_offset = zoffs(c, zoffs_field, shell.t)?;
                match laminate {
                    // a laminate's mid-plane is `Z0 + T/2` from its reference plane, which the
                    // element's ZOFFS moves from the grids
                    Some(shift) => shell.offset = shift + element_offset.unwrap_or(0.0),
                    None => {
                        if let Some(z) = element_offset {
                            shell.offset = z;
                        }
                    }
                }
                if let Some(m) = &mut shell.material {
                    let x: Vec<[f64; 3]> =
                        nodes.iter().map(|n| model.mesh().coords()[*n]).collect();
                    m.axis = shell_axis(c, theta_field, &x[..corners], ctx)?;
                    // a CQUAD8's THETA is measured from its xi direction at each point (QRG
                    // CQUAD8, remark 3); femu's material axis is one direction, projected at each
                    // point: the same where xi keeps its direction
                    let by_theta = c.field(theta_field).trim().parse::<i64>().is_err();
                    if c.name == "CQUAD8" && by_theta && !femu_fem::shell8::uniform_xi(&x) {
                        return Err(c.err(format!(
                            "{eid}: its anisotropic material is oriented by THETA, which a CQUAD8 measures from its own xi direction at each point, and that direction turns across this element (curved or not a parallelogram); femu orients a CQUAD8's material by one axis: give an MCID instead"
                        )));
                    }
                }
                // T1-T4: corner thicknesses, refused unless they are the property's
                let tflag = c.int(tflag_field, "TFLAG")?.unwrap_or(0);
                for k in 0..corners {
                    if let Some(tk) = c.real(t_field + k, "T")? {
                        let t = if tflag == 1 { tk * shell.t } else { tk };
                        if (t - shell.t).abs() > 1e-12 * shell.t {
                            return Err(c.err(format!(
                                "{eid}: corner thickness T{} = {t} differs from PSHELL {pid}'s {}; femu's shells have one thickness",
                                k + 1,
                                shell.t
                            )));
                        }
                    }
                }
                (StructuralKind::Shell(shell), nodes, pid)
            }
            "CBUSH" => {
                let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                let p = prop(pid, &["PBUSH"])?;
                let (kind, nodes) = cbush(c, eid, pid, p, model, ctx)?;
                (kind, nodes, pid)
            }
            "CBUSH1D" => {
                let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                let p = prop(pid, &["PBUSH1D"])?;
                let (kind, nodes) = cbush1d(c, eid, pid, p, model, ctx)?;
                (kind, nodes, pid)
            }
            "CVISC" => {
                // QRG CVISC: EID PID G1 G2; PVISC: PID CE CR (PID CE CR): an extensional and a
                // rotational damper along the line G1-G2, a bushing of dampers alone on the
                // grids' relative motion in a frame whose first axis is that line
                let pid = c.int(1, "PID")?.map_or(eid, |v| v.max(0) as u64);
                let p = prop(pid, &["PVISC"])?;
                let first = if p.int(0, "PID")? == Some(pid as i64) {
                    0
                } else {
                    4
                };
                let ce = p.real(first + 1, "CE")?.unwrap_or(0.0);
                let cr = p.real(first + 2, "CR")?.unwrap_or(0.0);
                let (g1, g2) = (c.id(2, "G1")?, c.id(3, "G2")?);
                let (n1, n2) = (node(model, g1, c, "G1")?, node(model, g2, c, "G2")?);
                // the line's axes, with any vector off the line for the two normal to it (only
                // the first axis carries damping)
                let x = model.mesh().coords();
                let d: [f64; 3] = std::array::from_fn(|k| x[n2][k] - x[n1][k]);
                let helper = if d[0].abs() < 0.9 * d.iter().map(|v| v * v).sum::<f64>().sqrt() {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                let (_, [t, y, z]) = femu_fem::structural::line_axes(x[n1], x[n2], helper)
                    .map_err(|_| {
                        c.err(format!(
                            "{eid}: grids {g1} and {g2} coincide, so the damper has no axis"
                        ))
                    })?;
                let kind = StructuralKind::Bushing(Bushing {
                    k: [0.0; 6],
                    b: [ce, 0.0, 0.0, cr, 0.0, 0.0],
                    ge: 0.0,
                    axes: [t, y, z],
                    point: None,
                });
                (kind, vec![n1, n2], pid)
            }
            _ => unreachable!("sorted as structural"),
        };
        let ge = match c.name.as_str() {
            "CONROD" => mid_ge(ctx, c, &[3])?,
            "CELAS1" | "CELAS2" | "CDAMP1" | "CDAMP2" | "CMASS1" | "CMASS2" | "CVISC" | "CBUSH"
            | "CBUSH1D" => 0.0,
            _ => match cards.properties.get(&pid) {
                Some(p) => property_ge(ctx, p)?,
                None => 0.0,
            },
        };
        model
            .add_structural(StructuralElement {
                id: eid,
                nodes,
                kind,
            })
            .and_then(|_| match ge {
                0.0 => Ok(()),
                _ => model.set_element_damping(eid, ge),
            })
            .map_err(c.located())?;
        sets.entry(pid).or_default().push(eid);
    }
    for (pid, ids) in &sets {
        model
            .add_structural_set(format!("PID{pid}"), ids)
            .map_err(|e| IoError::Content {
                path: cards.elements[0].path.clone(),
                reason: e.to_string(),
            })?;
    }
    Ok(cards.elements.len())
}

/// A PSHELL (QRG PSHELL: `PID MID1 T MID2 12I/T^3 MID3 TS/T NSM / Z1 Z2 MID4 MCSID SCSID
/// ZOFFS`; the offset its elements take when theirs is blank): the membrane material MID1, the bending material MID2 (its stiffness `12I/T^3 T^3 /
/// 12` times it), the transverse shear material MID3 (`TS/T T` times it; blank: no shear
/// flexibility), each a MAT1, a MAT2 or a MAT8; the density is MID1's. One MAT1 in all three is
/// the isotropic shell; anything else an anisotropic section whose material axis each element
/// sets (its THETA or MCID: [`shell_axis`]). A membrane or a plate alone, MID4 coupling, a
/// an anisotropic section's MCSID are refused.
fn pshell(
    p: &Card,
    pid: u64,
    ctx: &mut Context<'_, '_>,
) -> Result<femu_fem::shell::Shell, IoError> {
    let mid1 = p.int(1, "MID1")?.filter(|m| *m > 0);
    let raw2 = p.int(3, "MID2")?;
    let mid2 = raw2.filter(|m| *m > 0);
    let mid3 = p.int(5, "MID3")?.filter(|m| *m > 0);
    let mid4 = p.int(10, "MID4")?.filter(|m| *m > 0);
    if raw2 == Some(-1) {
        return Err(p.err(format!(
            "{pid}: MID2 = -1 makes a plane strain element, which femu does not build"
        )));
    }
    // MID1 alone: a membrane (QRG PSHELL: MID3 must then be blank)
    if let (Some(m1), None) = (mid1, mid2) {
        if let Some(m3) = mid3 {
            return Err(p.err(format!(
                "{pid}: MID3 = {m3} with MID2 blank: the QRG asks MID3 to be blank when MID2 is"
            )));
        }
        return membrane_pshell(p, pid, m1, ctx);
    }
    let (Some(m1), Some(m2)) = (mid1, mid2) else {
        return Err(p.err(format!(
            "{pid}: MID1 = {mid1:?} and MID2 = {mid2:?}: a plate without a membrane (MID1 blank) is not built"
        )));
    };
    if let Some(m4) = mid4 {
        return Err(p.err(format!(
            "{pid}: MID4 = {m4} couples membrane and bending, which femu does not model"
        )));
    }
    let t = p
        .real(2, "T")?
        .filter(|t| *t > 0.0)
        .ok_or_else(|| p.err(format!("{pid}: a shell needs a positive thickness T")))?;
    let offset = zoffs(p, 13, t)?.unwrap_or(0.0);
    let card = |mid: i64| -> Result<&Card, IoError> {
        ctx.materials.get(&(mid as u64)).copied().ok_or_else(|| {
            p.err(format!(
                "{pid} refers to material {mid}, which the deck does not define"
            ))
        })
    };
    let bending = p.real(4, "12I/T**3")?.unwrap_or(1.0);
    let ts = p.real(6, "TS/T")?.unwrap_or(0.833_333);
    let nsm = p.real(7, "NSM")?.unwrap_or(0.0) * ctx.wtmass;
    let (c1, c2) = (card(m1)?, card(m2)?);
    let c3 = mid3.map(card).transpose()?;
    let rho = shell_density(c1, pid, p)? * ctx.wtmass;
    if c1.name == "MAT1" && m1 == m2 && mid3.is_none_or(|m3| m3 == m1) {
        let mut scratch = Vec::new();
        let (e, nu) = super::materials::mat1_moduli(c1, &mut scratch)?;
        return Ok(femu_fem::shell::Shell {
            e,
            nu,
            rho,
            t,
            bending,
            shear: mid3.map(|_| ts),
            nsm,
            material: None,
            offset,
            membrane: femu_fem::shell::Membrane::Incompatible,
        });
    }
    if let Some(cs) = p.int(11, "MCSID")?.filter(|c| *c >= 0) {
        return Err(p.err(format!(
            "{pid}: MCSID = {cs} sets the material axes of its anisotropic section for every element, which femu does not read (give THETA or MCID on the elements)"
        )));
    }
    let membrane = plane_material(c1, pid, p)?;
    let bending_m = plane_material(c2, pid, p)?;
    let (shear, ts) = match c3 {
        None => ([[0.0; 2]; 2], None),
        Some(c3) => match shear_material(c3, pid, p)? {
            Some(g) => (g, Some(ts)),
            // a MAT8 with G1Z and G2Z blank: no shear flexibility, as a blank MID3
            None => ([[0.0; 2]; 2], None),
        },
    };
    Ok(femu_fem::shell::Shell {
        e: 0.0,
        nu: 0.0,
        rho,
        t,
        bending,
        shear: ts,
        nsm,
        material: Some(femu_fem::shell::ShellMaterial {
            membrane,
            bending: bending_m,
            shear,
            axis: [1.0, 0.0, 0.0],
        }),
        offset,
        membrane: femu_fem::shell::Membrane::Incompatible,
    })
}

/// A PSHELL of MID1 alone: a membrane of that material (`12I/T**3 = 0`: no bending, no
/// transverse shear, no rotations; [`femu_fem::shell::Shell::bending`]).
fn membrane_pshell(
    p: &Card,
    pid: u64,
    m1: i64,
    ctx: &mut Context<'_, '_>,
) -> Result<femu_fem::shell::Shell, IoError> {
    let t = p
        .real(2, "T")?
        .filter(|t| *t > 0.0)
        .ok_or_else(|| p.err(format!("{pid}: a shell needs a positive thickness T")))?;
    let c1 = ctx.materials.get(&(m1 as u64)).copied().ok_or_else(|| {
        p.err(format!(
            "{pid} refers to material {m1}, which the deck does not define"
        ))
    })?;
    let rho = shell_density(c1, pid, p)? * ctx.wtmass;
    let nsm = p.real(7, "NSM")?.unwrap_or(0.0) * ctx.wtmass;
    let offset = zoffs(p, 13, t)?.unwrap_or(0.0);
    if offset != 0.0 {
        return Err(p.err(format!(
            "{pid}: ZOFFS = {offset} on a membrane (MID2 blank): an offset needs MID1 and MID2 (QRG CQUAD4, remark 6)"
        )));
    }
    if c1.name == "MAT1" {
        let mut scratch = Vec::new();
        let (e, nu) = super::materials::mat1_moduli(c1, &mut scratch)?;
        return Ok(femu_fem::shell::Shell {
            e,
            nu,
            rho,
            t,
            bending: 0.0,
            shear: None,
            nsm,
            material: None,
            offset: 0.0,
            membrane: femu_fem::shell::Membrane::Incompatible,
        });
    }
    let membrane = plane_material(c1, pid, p)?;
    Ok(femu_fem::shell::Shell {
        e: 0.0,
        nu: 0.0,
        rho,
        t,
        bending: 0.0,
        shear: None,
        nsm,
        material: Some(femu_fem::shell::ShellMaterial {
            membrane,
            // no bending: any positive definite placeholder the section scales by zero
            bending: membrane,
            shear: [[0.0; 2]; 2],
            axis: [1.0, 0.0, 0.0],
        }),
        offset: 0.0,
        membrane: femu_fem::shell::Membrane::Incompatible,
    })
}

/// A PCOMP or PCOMPG (QRG PCOMP: `PID Z0 NSM SB FT TREF GE LAM`, then four fields a ply `MIDi
/// Ti THETAi SOUTi`; PCOMPG: one line a ply, `GPLYIDi MIDi Ti THETAi SOUTi`) as the shell section
/// of classical lamination theory ([`femu_fem::shell::laminate`], docs/MATH.md, "Laminates"):
/// each ply's plane-stress material (MAT1, MAT2 or MAT8, [`plane_material`]) and transverse
/// shear ([`shear_material`]) turned by its THETA from the element's material axis, stacked from
/// the bottom surface; the mass per area `sum rho t + NSM`. `LAM = SYM` lists the plies of one
/// half, mirrored about the mid-plane. Returns the section and the mid-plane's offset from the
/// reference plane, `Z0 + T/2` (blank Z0: `-T/2`, no offset).
///
/// Refused, naming the property: `LAM` = MEM, BEND, SMEAR or SMCORE; what
/// [`femu_fem::shell::laminate`] refuses (an unsymmetric laminate, plies of different transverse
/// shear); a ply of no thickness or of another material card.
fn pcomp(
    p: &Card,
    pid: u64,
    ctx: &mut Context<'_, '_>,
) -> Result<(femu_fem::shell::Shell, f64), IoError> {
    let lam = p.field(7).to_ascii_uppercase();
    if !lam.is_empty() && lam != "SYM" {
        return Err(p.err(format!(
            "{pid}: LAM = {lam}: femu reads laminates of all plies (blank) or of one half mirrored (SYM); a membrane-only or bending-only laminate, or a smeared one, is not built"
        )));
    }
    // (MID, T, THETA, line-less card field) of each listed ply, blanks taken from the ply before
    let (first, stride) = if p.name == "PCOMPG" { (9, 8) } else { (8, 4) };
    let mut plies: Vec<(u64, f64, f64)> = Vec::new();
    let mut i = first;
    while i < p.fields.len() {
        let blank = (0..3).all(|k| p.field(i + k).is_empty());
        if blank {
            i += stride;
            continue;
        }
        let mid = match p.int(i, "MID")? {
            Some(m) if m > 0 => m as u64,
            Some(m) => return Err(p.err(format!("{pid}: ply material {m} is not an id"))),
            None => plies
                .last()
                .map(|q| q.0)
                .ok_or_else(|| p.err(format!("{pid}: the first ply needs its material")))?,
        };
        let t = match p.real(i + 1, "T")? {
            Some(t) => t,
            None => plies
                .last()
                .map(|q| q.1)
                .ok_or_else(|| p.err(format!("{pid}: the first ply needs its thickness")))?,
        };
        if !(t > 0.0) {
            return Err(p.err(format!(
                "{pid}: ply {} has thickness {t}; a ply needs a positive one",
                plies.len() + 1
            )));
        }
        let theta = p.real(i + 2, "THETA")?.unwrap_or(0.0);
        plies.push((mid, t, theta));
        i += stride;
    }
    if plies.is_empty() {
        return Err(p.err(format!("{pid}: no ply")));
    }
    if lam == "SYM" {
        let mirrored: Vec<_> = plies.iter().rev().copied().collect();
        plies.extend(mirrored);
    }
    let total: f64 = plies.iter().map(|q| q.1).sum();
    let mut layers = Vec::with_capacity(plies.len());
    for &(mid, t, theta) in &plies {
        let m = ctx.materials.get(&mid).copied().ok_or_else(|| {
            p.err(format!(
                "{pid} refers to material {mid}, which the deck does not define"
            ))
        })?;
        layers.push(femu_fem::shell::Ply {
            q: plane_material(m, pid, p)?,
            shear: shear_material(m, pid, p)?,
            rho: shell_density(m, pid, p)? * ctx.wtmass,
            t,
            theta,
        });
    }
    let mut shell = femu_fem::shell::laminate(&layers).map_err(|e| p.err(format!("{pid}: {e}")))?;
    shell.nsm = p.real(2, "NSM")?.unwrap_or(0.0) * ctx.wtmass;
    let shift = p.real(1, "Z0")?.map_or(0.0, |z| z + total / 2.0);
    Ok((shell, shift))
}

/// A ZOFFS field (QRG CQUAD4, PSHELL): the reference plane's offset from the grids along the
/// element's normal, a number or `TOP` / `BOTTOM` (half the thickness `t` above or below);
/// `None` when blank.
fn zoffs(c: &Card, field: usize, t: f64) -> Result<Option<f64>, IoError> {
    match c.field(field).to_ascii_uppercase().as_str() {
        "" => Ok(None),
        "TOP" => Ok(Some(t / 2.0)),
        "BOTTOM" => Ok(Some(-t / 2.0)),
        _ => c.real(field, "ZOFFS"),
    }
}

/// The density of a shell's membrane material (MAT1 field 5, MAT2 and MAT8 field 8).
fn shell_density(m: &Card, pid: u64, p: &Card) -> Result<f64, IoError> {
    let field = match m.name.as_str() {
        "MAT1" => 4,
        "MAT2" | "MAT8" => 7,
        other => {
            return Err(p.err(format!(
                "{pid} refers to {other} {}: a shell takes a MAT1, a MAT2 or a MAT8",
                m.field(0)
            )));
        }
    };
    Ok(m.real(field, "RHO")?.unwrap_or(0.0))
}

/// A shell's plane-stress material (Pa) on `(eps_11, eps_22, gamma_12)` in the material axes:
/// a MAT1's isotropic one, a MAT2's `G11 G12 G13 G22 G23 G33`, a MAT8's orthotropic `Q` from `E1
/// E2 NU12 G12` (`Q11 = E1 / (1 - NU12 NU21)`, `NU21 = NU12 E2 / E1`).
fn plane_material(m: &Card, pid: u64, p: &Card) -> Result<[[f64; 3]; 3], IoError> {
    let mid = m.field(0);
    match m.name.as_str() {
        "MAT1" => {
            let mut scratch = Vec::new();
            let (e, nu) = super::materials::mat1_moduli(m, &mut scratch)?;
            let d = e / (1.0 - nu * nu);
            Ok([
                [d, d * nu, 0.0],
                [d * nu, d, 0.0],
                [0.0, 0.0, e / (2.0 * (1.0 + nu))],
            ])
        }
        "MAT2" => {
            let g = |i: usize, what: &str| -> Result<f64, IoError> {
                Ok(m.real(i, what)?.unwrap_or(0.0))
            };
            let (g11, g12, g13) = (g(1, "G11")?, g(2, "G12")?, g(3, "G13")?);
            let (g22, g23, g33) = (g(4, "G22")?, g(5, "G23")?, g(6, "G33")?);
            Ok([[g11, g12, g13], [g12, g22, g23], [g13, g23, g33]])
        }
        "MAT8" => {
            let need = |i: usize, what: &str| -> Result<f64, IoError> {
                m.real(i, what)?
                    .filter(|v| *v > 0.0)
                    .ok_or_else(|| m.err(format!("{mid}: {what} must be given and positive")))
            };
            let (e1, e2, g12) = (need(1, "E1")?, need(2, "E2")?, need(4, "G12")?);
            let nu12 = m.real(3, "NU12")?.unwrap_or(0.0);
            let nu21 = nu12 * e2 / e1;
            let den = 1.0 - nu12 * nu21;
            if !(den > 0.0) {
                return Err(m.err(format!(
                    "{mid}: NU12 = {nu12} with E1 = {e1:e} and E2 = {e2:e} is not a material (1 - NU12 NU21 = {den})"
                )));
            }
            Ok([
                [e1 / den, nu12 * e2 / den, 0.0],
                [nu12 * e2 / den, e2 / den, 0.0],
                [0.0, 0.0, g12],
            ])
        }
        other => Err(p.err(format!(
            "{pid} refers to {other} {mid}: a shell takes a MAT1, a MAT2 or a MAT8"
        ))),
    }
}

/// A shell's transverse shear material (Pa) on `(gamma_1z, gamma_2z)`: a MAT1's `G`, a MAT2's `G11
/// G12 G22` (QRG PSHELL, remarks), a MAT8's `G1Z`, `G2Z`; `None` for a MAT8 with both blank
/// (infinite shear moduli: no shear flexibility).
fn shear_material(m: &Card, pid: u64, p: &Card) -> Result<Option<[[f64; 2]; 2]>, IoError> {
    let mid = m.field(0);
    match m.name.as_str() {
        "MAT1" => {
            let mut scratch = Vec::new();
            let (e, nu) = super::materials::mat1_moduli(m, &mut scratch)?;
            let g = e / (2.0 * (1.0 + nu));
            Ok(Some([[g, 0.0], [0.0, g]]))
        }
        "MAT2" => {
            let g = |i: usize, what: &str| -> Result<f64, IoError> {
                Ok(m.real(i, what)?.unwrap_or(0.0))
            };
            let (g11, g12, g22) = (g(1, "G11")?, g(2, "G12")?, g(4, "G22")?);
            Ok(Some([[g11, g12], [g12, g22]]))
        }
        "MAT8" => match (m.real(5, "G1Z")?, m.real(6, "G2Z")?) {
            (None, None) => Ok(None),
            (Some(a), Some(b)) if a > 0.0 && b > 0.0 => Ok(Some([[a, 0.0], [0.0, b]])),
            (a, b) => Err(m.err(format!(
                "{mid}: G1Z = {a:?} and G2Z = {b:?}: as a transverse shear material both must be positive (or both blank: no shear flexibility)"
            ))),
        },
        other => Err(p.err(format!(
            "{pid} refers to {other} {mid}: a shell takes a MAT1, a MAT2 or a MAT8"
        ))),
    }
}

/// The material axis (basic frame) of a shell with an anisotropic section, from its THETA or
/// MCID field (QRG CQUAD4, CTRIA3): a real THETA turns the edge G1-G2 by THETA degrees about the
/// normal (blank: THETA = 0); an integer MCID projects the x axis of coordinate system MCID (at
/// the element's centre) onto the element's plane.
fn shell_axis(
    c: &Card,
    field: usize,
    x: &[[f64; 3]],
    ctx: &mut Context<'_, '_>,
) -> Result<[f64; 3], IoError> {
    let eid = c.field(0);
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let unit = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    // the normal: the triangle's, or the quadrilateral's diagonals'
    let n = if x.len() == 4 {
        unit(cross(sub(x[2], x[0]), sub(x[3], x[1])))
    } else {
        unit(cross(sub(x[1], x[0]), sub(x[2], x[0])))
    };
    let text = c.field(field);
    let is_int = !text.is_empty() && text.parse::<i64>().is_ok();
    if is_int {
        let mcid = c.int(field, "MCID")?.unwrap_or(0);
        let centre: [f64; 3] =
            std::array::from_fn(|k| x.iter().map(|p| p[k]).sum::<f64>() / x.len() as f64);
        let a = if mcid == 0 {
            [1.0, 0.0, 0.0]
        } else {
            let f = ctx.geometry.frame(mcid, c)?.axes_at(centre);
            [f[0][0], f[1][0], f[2][0]]
        };
        let d = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
        let along = [a[0] - d * n[0], a[1] - d * n[1], a[2] - d * n[2]];
        if (along[0].powi(2) + along[1].powi(2) + along[2].powi(2)).sqrt() < 1e-6 {
            return Err(c.err(format!(
                "{eid}: the x axis of MCID {mcid} is normal to the element, so it sets no material axis"
            )));
        }
        return Ok(unit(along));
    }
    let theta = c.real(field, "THETA")?.unwrap_or(0.0).to_radians();
    let e1 = {
        let g = sub(x[1], x[0]);
        let d = g[0] * n[0] + g[1] * n[1] + g[2] * n[2];
        unit([g[0] - d * n[0], g[1] - d * n[1], g[2] - d * n[2]])
    };
    let e2 = cross(n, e1);
    let (cs, sn) = (theta.cos(), theta.sin());
    Ok(std::array::from_fn(|k| cs * e1[k] + sn * e2[k]))
}

/// A CBUSH (QRG CBUSH: `EID PID GA GB GO/X1 X2 X3 CID / S OCID S1 S2 S3`) with its PBUSH's `K`,
/// `B` and `GE` lines. The element axes are `CID`'s when given, else `x` from GA to GB and the
/// orientation vector; the spring acts at `S` (default 0.5) along GA-GB, joined to both grids
/// rigidly, or at the grids themselves when they coincide or GB is blank.
/// A CBUSH1D with its PBUSH1D (QRG: `EID PID GA GB CID`; `PID K C M SA SE`, then the nonlinear
/// `SHOCKA`, `SPRING`, `DAMPER` and `GENER` lines): a spring `K` and a viscous damper `C` along
/// the element's axis, the line GA-GB, or the x-axis of `CID` at GA (needed when the grids
/// coincide or GB is blank: a grounded bushing), on the grids' relative motion along it. A
/// bushing of one stiffness and one damping (the other five zero). Refused: a mass `M` (as a
/// PBUSH's), a nonlinear line, neither `K` nor `C`, negative values.
fn cbush1d(
    c: &Card,
    eid: u64,
    pid: u64,
    p: &Card,
    model: &Model,
    ctx: &mut Context<'_, '_>,
) -> Result<(StructuralKind, Vec<usize>), IoError> {
    let value = |i: usize, what: &str| -> Result<f64, IoError> {
        let v = p.real(i, what)?.unwrap_or(0.0);
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(p.err(format!("{pid}: {what} = {v}: it is finite and at least 0")))
        }
    };
    let (k, damping, mass) = (value(1, "K")?, value(2, "C")?, value(3, "M")?);
    if mass != 0.0 {
        return Err(p.err(format!(
            "{pid}: a bushing mass (M = {mass}) is not read; give it as CONM2 on the grids"
        )));
    }
    if let Some(line) = (8..p.fields.len())
        .step_by(8)
        .map(|i| p.field(i).trim().to_ascii_uppercase())
        .find(|t| !t.is_empty())
    {
        return Err(p.err(format!(
            "{pid}: the {line} line makes the bushing nonlinear, which a modal model does not hold (femu reads K and C)"
        )));
    }
    if k == 0.0 && damping == 0.0 {
        return Err(p.err(format!(
            "{pid}: neither a stiffness K nor a damping C: the bushing does nothing"
        )));
    }
    let ga = c.id(2, "GA")?;
    let na = node(model, ga, c, "GA")?;
    let gb = c.int(3, "GB")?.filter(|g| *g > 0).map(|g| g as u64);
    let nb = gb.map(|g| node(model, g, c, "GB")).transpose()?;
    let xa = model.mesh().coords()[na];
    let axis = match c.int(4, "CID")? {
        Some(0) => [1.0, 0.0, 0.0],
        Some(cid) if cid > 0 => {
            let a = ctx.geometry.frame(cid, c)?.axes_at(xa);
            [a[0][0], a[1][0], a[2][0]]
        }
        _ => {
            let xb = nb.map(|n| model.mesh().coords()[n]);
            let d = xb.map_or([0.0; 3], |b| std::array::from_fn(|i| b[i] - xa[i]));
            if d.iter().map(|v| v * v).sum::<f64>().sqrt() < 1e-4 {
                return Err(c.err(format!(
                    "{eid}: its grids coincide or GB is blank, so its axis needs a CID (field 6)"
                )));
            }
            d
        }
    };
    let tip: [f64; 3] = std::array::from_fn(|i| xa[i] + axis[i]);
    let helper = if axis[0].abs() < 0.9 * axis.iter().map(|v| v * v).sum::<f64>().sqrt() {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let (_, axes) = femu_fem::structural::line_axes(xa, tip, helper)
        .map_err(|r| c.err(format!("{eid}: {r}")))?;
    let mut nodes = vec![na];
    nodes.extend(nb);
    Ok((
        StructuralKind::Bushing(Bushing {
            k: [k, 0.0, 0.0, 0.0, 0.0, 0.0],
            b: [damping, 0.0, 0.0, 0.0, 0.0, 0.0],
            ge: 0.0,
            axes,
            point: None,
        }),
        nodes,
    ))
}

fn cbush(
    c: &Card,
    eid: u64,
    pid: u64,
    p: &Card,
    model: &Model,
    ctx: &mut Context<'_, '_>,
) -> Result<(StructuralKind, Vec<usize>), IoError> {
    let ga = c.id(2, "GA")?;
    let na = node(model, ga, c, "GA")?;
    let gb = c.int(3, "GB")?.filter(|g| *g > 0).map(|g| g as u64);
    let nb = gb.map(|g| node(model, g, c, "GB")).transpose()?;
    let xa = model.mesh().coords()[na];
    let xb = nb.map(|n| model.mesh().coords()[n]);
    let length = xb.map_or(0.0, |b| {
        ((0..3).map(|i| (b[i] - xa[i]).powi(2)).sum::<f64>()).sqrt()
    });
    let cid = c.int(7, "CID")?;
    let axes = match cid {
        Some(cid) if cid >= 0 => {
            let a = if cid == 0 {
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            } else {
                ctx.geometry.frame(cid, c)?.axes_at(xa)
            };
            [
                [a[0][0], a[1][0], a[2][0]],
                [a[0][1], a[1][1], a[2][1]],
                [a[0][2], a[1][2], a[2][2]],
            ]
        }
        _ => {
            // QRG CBUSH: with CID blank the axes come from GA-GB and the orientation vector;
            // coincident grids (closer than 1e-4) or a grounded bushing need a CID
            let Some(b) = xb.filter(|_| length >= 1e-4) else {
                return Err(c.err(format!(
                    "{eid}: its grids coincide or GB is blank, so its axes need a CID (field 9)"
                )));
            };
            if (4..7).all(|i| c.field(i).is_empty()) {
                return Err(c.err(format!(
                    "{eid}: with CID blank, its axes need an orientation vector (GO or X1, X2, X3)"
                )));
            }
            let is_g0 = !c.field(4).contains('.') && c.field(5).is_empty() && c.field(6).is_empty();
            let v = if is_g0 {
                let g0 = c.id(4, "GO")?;
                let x0 = model.mesh().coords()[node(model, g0, c, "GO")?];
                [x0[0] - xa[0], x0[1] - xa[1], x0[2] - xa[2]]
            } else {
                let v = [
                    c.real(4, "X1")?.unwrap_or(0.0),
                    c.real(5, "X2")?.unwrap_or(0.0),
                    c.real(6, "X3")?.unwrap_or(0.0),
                ];
                apply(&cd_axes(ctx, model, ga, c)?, v)
            };
            let (_, axes) = femu_fem::structural::line_axes(xa, b, v)
                .map_err(|r| c.err(format!("{eid}: {r}")))?;
            axes
        }
    };
    let ocid = c.int(9, "OCID")?.unwrap_or(-1);
    if ocid != -1 && (10..13).any(|i| !c.field(i).is_empty()) {
        return Err(c.err(format!(
            "{eid}: a spring location given by OCID {ocid} and S1, S2, S3 is not read (leave OCID blank: the location S along GA-GB)"
        )));
    }
    let s = c.real(8, "S")?.unwrap_or(0.5);
    let point = match xb {
        Some(b) if length >= 1e-4 => Some(std::array::from_fn(|i| xa[i] + s * (b[i] - xa[i]))),
        _ => None,
    };
    // PBUSH: keyword lines K, B, GE, RCV (and M, refused)
    let mut k = [0.0; 6];
    let mut b = [0.0; 6];
    let mut ge = 0.0;
    let mut i = 1;
    while i < p.fields.len() {
        let key = p.field(i).to_ascii_uppercase();
        let values = |from: usize, n: usize| -> Result<Vec<f64>, IoError> {
            (from..from + n)
                .map(|j| Ok(p.real(j, &key)?.unwrap_or(0.0)))
                .collect()
        };
        match key.as_str() {
            "K" => {
                k.copy_from_slice(&values(i + 1, 6)?);
                i += 7;
            }
            "B" => {
                b.copy_from_slice(&values(i + 1, 6)?);
                i += 7;
            }
            "GE" => {
                ge = values(i + 1, 1)?[0];
                i += 7;
            }
            "RCV" => i += 5,
            "M" => {
                return Err(p.err(format!(
                    "{pid}: a bushing mass (M) is not read; give it as CONM2 on the grids"
                )));
            }
            "" => i += 1,
            other => {
                return Err(p.err(format!(
                    "{pid}: {other} is not a PBUSH keyword femu reads (K, B, GE, RCV)"
                )));
            }
        }
    }
    let mut nodes = vec![na];
    nodes.extend(nb);
    Ok((
        StructuralKind::Bushing(Bushing {
            k,
            b,
            ge,
            axes,
            point,
        }),
        nodes,
    ))
}
