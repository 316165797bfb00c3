//! Coordinate systems (`CORD1R/C/S`, `CORD2R/C/S`) and grid positions (`GRID` with its `CP`,
//! `GRDSET`'s defaults), resolved on demand.

use super::cards::Card;
use crate::IoError;
use crate::uff::CoordinateSystem;
use std::collections::HashMap;

/// The system of a `CORD` card through points `a` (origin), `b` (on the z axis) and `c` (in the xz
/// plane), all basic; `kind` 0 rectangular, 1 cylindrical, 2 spherical. Positions in it follow
/// [`CoordinateSystem::point_to_global`], whose cylindrical `(r, theta, z)` and spherical
/// `(r, theta from z, phi)` in degrees are Nastran's.
pub(super) fn frame_through(
    kind: i64,
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> Option<CoordinateSystem> {
    let sub = |p: [f64; 3], q: [f64; 3]| -> [f64; 3] { std::array::from_fn(|i| p[i] - q[i]) };
    let cross = |p: [f64; 3], q: [f64; 3]| {
        [
            p[1] * q[2] - p[2] * q[1],
            p[2] * q[0] - p[0] * q[2],
            p[0] * q[1] - p[1] * q[0],
        ]
    };
    let unit = |p: [f64; 3]| {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        (n > 1e-300).then(|| p.map(|v| v / n))
    };
    let ez = unit(sub(b, a))?;
    let ey = unit(cross(ez, sub(c, a)))?;
    let ex = cross(ey, ez);
    Some(CoordinateSystem {
        name: String::new(),
        kind,
        origin: a,
        axes: std::array::from_fn(|i| [ex[i], ey[i], ez[i]]),
    })
}

/// The kind of a `CORDxR/C/S` card: 0, 1 or 2.
pub(super) fn cord_kind(c: &Card) -> i64 {
    match c.name.chars().last() {
        Some('C') => 1,
        Some('S') => 2,
        _ => 0,
    }
}

/// Coordinate systems and grid positions, resolved on demand: a system may be defined relative
/// to another, or through grids given in a third; a cycle is an error naming it.
pub(super) struct Geometry<'a> {
    pub(super) frames: HashMap<i64, CoordinateSystem>,
    pub(super) cord2: HashMap<i64, (&'a Card, i64)>,
    pub(super) cord1: Vec<(i64, [u64; 3], &'a Card)>,
    pub(super) grid_of: HashMap<u64, &'a Card>,
    pub(super) positions: HashMap<u64, [f64; 3]>,
    pub(super) stack: Vec<i64>,
    /// The GRDSET card, whose CP, CD and PS are the defaults of grids that leave them blank.
    pub(super) grdset: Option<&'a Card>,
}

impl Geometry<'_> {
    /// System `cid` in basic terms (`asked_by` names the card in errors).
    pub(super) fn frame(&mut self, cid: i64, asked_by: &Card) -> Result<CoordinateSystem, IoError> {
        if let Some(f) = self.frames.get(&cid) {
            return Ok(f.clone());
        }
        if self.stack.contains(&cid) {
            return Err(asked_by.err(format!(
                "coordinate systems refer to each other in a cycle: {}",
                self.stack
                    .iter()
                    .chain([&cid])
                    .map(i64::to_string)
                    .collect::<Vec<_>>()
                    .join(" -> ")
            )));
        }
        self.stack.push(cid);
        let frame = if let Some(&(c, rid)) = self.cord2.get(&cid) {
            let reference = self.frame(rid, c)?;
            let mut p = [[0.0; 3]; 3];
            for (k, point) in p.iter_mut().enumerate() {
                for (i, v) in point.iter_mut().enumerate() {
                    *v = c.real(2 + 3 * k + i, "point")?.unwrap_or(0.0);
                }
                *point = reference.point_to_global(*point);
            }
            frame_through(cord_kind(c), p[0], p[1], p[2]).ok_or_else(|| {
                c.err(format!(
                    "{cid}: its points A, B, C do not define axes (coincident or collinear)"
                ))
            })?
        } else if let Some(&(_, g, c)) = self.cord1.iter().find(|e| e.0 == cid) {
            let mut pts = [[0.0; 3]; 3];
            for (k, id) in g.iter().enumerate() {
                pts[k] = self.position(*id, c)?;
            }
            frame_through(cord_kind(c), pts[0], pts[1], pts[2]).ok_or_else(|| {
                c.err(format!(
                    "{cid}: its grids do not define axes (coincident or collinear)"
                ))
            })?
        } else {
            return Err(asked_by.err(format!(
                "refers to coordinate system {cid}, which the deck does not define"
            )));
        };
        self.stack.pop();
        self.frames.insert(cid, frame.clone());
        Ok(frame)
    }

    /// The basic position of GRID `id`.
    pub(super) fn position(&mut self, id: u64, asked_by: &Card) -> Result<[f64; 3], IoError> {
        if let Some(p) = self.positions.get(&id) {
            return Ok(*p);
        }
        let g = *self.grid_of.get(&id).ok_or_else(|| {
            asked_by.err(format!(
                "refers to GRID {id}, which the deck does not define"
            ))
        })?;
        let cp = self.grid_int(g, 1, "CP")?.unwrap_or(0);
        let x: [f64; 3] = [
            g.real(2, "X1")?.unwrap_or(0.0),
            g.real(3, "X2")?.unwrap_or(0.0),
            g.real(4, "X3")?.unwrap_or(0.0),
        ];
        let p = self.frame(cp, g)?.point_to_global(x);
        self.positions.insert(id, p);
        Ok(p)
    }
}

impl<'a> Geometry<'a> {
    /// Field `i` of GRID `g` (`CP` 1, `CD` 5, `PS` 6), or the GRDSET's when the grid leaves it
    /// blank (QRG GRDSET: the defaults of CP, CD, PS and SEID).
    pub(super) fn grid_field(&self, g: &'a Card, i: usize) -> &'a Card {
        match self.grdset {
            Some(d) if g.field(i).is_empty() && !d.field(i).is_empty() => d,
            _ => g,
        }
    }

    /// [`Card::int`] of GRID field `i`, with the GRDSET default.
    pub(super) fn grid_int(
        &self,
        g: &'a Card,
        i: usize,
        what: &str,
    ) -> Result<Option<i64>, IoError> {
        self.grid_field(g, i).int(i, what)
    }

    /// The geometry of the deck's coordinate systems and grids.
    ///
    /// # Errors
    /// A system or grid defined twice, malformed ids, more than one GRDSET.
    pub(super) fn new(
        cords: &[&'a Card],
        grids: &[&'a Card],
        grdset: Option<&'a Card>,
    ) -> Result<Self, IoError> {
        let basic = CoordinateSystem {
            name: "basic".into(),
            kind: 0,
            origin: [0.0; 3],
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let mut geometry = Geometry {
            frames: HashMap::from([(0, basic)]),
            cord2: HashMap::new(),
            cord1: Vec::new(),
            grid_of: HashMap::new(),
            positions: HashMap::new(),
            stack: Vec::new(),
            grdset,
        };
        for c in cords {
            if c.name.starts_with("CORD2") {
                let cid = c.id(0, "CID")? as i64;
                let rid = c.int(1, "RID")?.unwrap_or(0);
                if geometry.cord2.insert(cid, (c, rid)).is_some() {
                    return Err(c.err(format!("{cid} is defined twice")));
                }
            } else {
                // up to two systems per card: CID G1 G2 G3
                for k in 0..2 {
                    let base = 4 * k;
                    if c.field(base).is_empty() {
                        continue;
                    }
                    let cid = c.id(base, "CID")? as i64;
                    let g = [
                        c.id(base + 1, "G1")?,
                        c.id(base + 2, "G2")?,
                        c.id(base + 3, "G3")?,
                    ];
                    geometry.cord1.push((cid, g, c));
                }
            }
        }
        for g in grids {
            let id = g.id(0, "ID")?;
            if geometry.grid_of.insert(id, *g).is_some() {
                return Err(g.err(format!("{id} is defined twice")));
            }
        }
        Ok(geometry)
    }
}
