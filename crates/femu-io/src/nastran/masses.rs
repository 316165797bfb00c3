//! `CONM2` point masses: on a grid with rotations (an RBE2's reference) a rigid mass with its
//! offset and inertia; on a grid an RBE2 moves rigidly in all six components, the same rigid mass
//! carried to the link's reference; elsewhere (a solid's grid, which has no rotations) the
//! translational mass, as Nastran's `AUTOSPC` leaves it once it removes the grid's rotations that
//! nothing but the mass holds.

use super::cards::Card;
use super::geometry::Geometry;
use crate::{IoError, Warning};
use femu_fem::model::Model;
use std::collections::HashMap;

fn warn(warnings: &mut Vec<Warning>, c: &Card, message: String) {
    warnings.push(Warning {
        path: c.path.clone(),
        line: c.line,
        message,
    });
}

/// The CONM2's offset from its grid and its inertia about its centre of gravity, both in basic
/// axes (QRG CONM2: `CID` 0 basic, -1 the offset `X` is the centre of gravity's basic position,
/// `n` a coordinate system; the products of inertia `I21, I31, I32` enter the matrix negated).
fn offset_and_inertia(
    c: &Card,
    xg: [f64; 3],
    geometry: &mut Geometry<'_>,
) -> Result<([f64; 3], [[f64; 3]; 3]), IoError> {
    let cid = c.int(2, "CID")?.unwrap_or(0);
    let x: [f64; 3] = [
        c.real(4, "X1")?.unwrap_or(0.0),
        c.real(5, "X2")?.unwrap_or(0.0),
        c.real(6, "X3")?.unwrap_or(0.0),
    ];
    let v = |i: usize| -> Result<f64, IoError> { Ok(c.real(i, "I")?.unwrap_or(0.0)) };
    let local = [
        [v(8)?, -v(9)?, -v(11)?],
        [-v(9)?, v(10)?, -v(12)?],
        [-v(11)?, -v(12)?, v(13)?],
    ];
    let (d, axes) = match cid {
        -1 => (std::array::from_fn(|i| x[i] - xg[i]), None),
        0 => (x, None),
        cid => {
            let a = geometry.frame(cid, c)?.axes_at(xg);
            (
                std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum()),
                Some(a),
            )
        }
    };
    // inertia in basic axes: R J R^T (R's columns the frame's axes)
    let j: [[f64; 3]; 3] = match axes {
        None => local,
        Some(a) => std::array::from_fn(|i| {
            std::array::from_fn(|k| {
                (0..3)
                    .map(|p| (0..3).map(|q| a[i][p] * local[p][q] * a[k][q]).sum::<f64>())
                    .sum()
            })
        }),
    };
    Ok((d, j))
}

/// A CONM1 (QRG CONM1: `EID G CID M11 M21 M22 M31 M32 M33 M41 ... M66`, the lower triangle of a
/// symmetric 6x6 mass matrix in the axes of `CID`, 0 basic), turned to basic axes
/// (`T M T^T`, `T` the frame's axes twice) and times `wtmass`, a mass set `CONM1_<EID>` of its
/// own: on a grid with rotations the whole matrix; on a grid without (a solid's) its
/// translational block, the rest dropped with a warning as Nastran's `AUTOSPC` drops the
/// rotations nothing but the mass holds; on a grid an RBE2 moves, refused when it has rotational
/// terms (not carried to the link's reference).
#[allow(clippy::too_many_arguments)]
fn conm1(
    c: &Card,
    model: &mut Model,
    geometry: &mut Geometry<'_>,
    wtmass: f64,
    lenient: bool,
    connected: &[bool],
    dependents: &HashMap<u64, (u64, Vec<usize>)>,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    let eid = c.id(0, "EID")?;
    let g = c.id(1, "G")?;
    let Some(gi) = model.mesh().node_index(g) else {
        return Err(c.err(format!("is on GRID {g}, which the deck does not define")));
    };
    if !connected[gi] {
        let text = format!(
            "{eid} is on GRID {g}, which no element or rigid link connects: it would have no stiffness"
        );
        if lenient {
            warn(warnings, c, format!("{text}: left out"));
            return Ok(());
        }
        return Err(c.err(text));
    }
    // the lower triangle, row by row, from field 3
    let mut local = [[0.0; 6]; 6];
    let mut at = 3;
    for i in 0..6 {
        for k in 0..=i {
            let v = c.real(at, &format!("M{}{}", i + 1, k + 1))?.unwrap_or(0.0);
            local[i][k] = v;
            local[k][i] = v;
            at += 1;
        }
    }
    let cid = c.int(2, "CID")?.unwrap_or(0);
    let xg = model.mesh().coords()[gi];
    let a = if cid == 0 {
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    } else {
        geometry.frame(cid, c)?.axes_at(xg)
    };
    // T M T^T with T = diag(R, R), R's columns the frame's axes
    let t = |i: usize, p: usize| -> f64 { if i / 3 == p / 3 { a[i % 3][p % 3] } else { 0.0 } };
    let matrix: [[f64; 6]; 6] = std::array::from_fn(|i| {
        std::array::from_fn(|k| {
            let mut v = 0.0;
            for p in 0..6 {
                for q in 0..6 {
                    v += t(i, p) * local[p][q] * t(k, q);
                }
            }
            v * wtmass
        })
    });
    let rotational = (0..6).any(|i| (3..6).any(|k| matrix[i][k] != 0.0));
    let set = format!("CONM1_{eid}");
    if model.has_rotations(gi) {
        model.add_mass_matrix(g, matrix).map_err(c.located())?;
        let added = model.last_mass(true).into_iter().collect::<Vec<_>>();
        return model.add_mass_set(set, &added).map_err(c.located());
    }
    if rotational {
        if dependents.contains_key(&g) {
            return Err(c.err(format!(
                "{eid}: GRID {g} moves with a rigid link and has no rotations of its own: a CONM1 with rotational terms there is not carried to the link's reference (give the mass on the reference grid)"
            )));
        }
        warn(
            warnings,
            c,
            format!(
                "CONM1 {eid}: GRID {g} has no rotations (only RBE2 reference grids and grids of beams and shells have), so its rotational terms are dropped and the translational block kept, as Nastran's AUTOSPC leaves it"
            ),
        );
    }
    let block: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| matrix[i][k]));
    model.add_point_mass_matrix(g, block).map_err(c.located())?;
    let added = model.last_mass(false).into_iter().collect::<Vec<_>>();
    model.add_mass_set(set, &added).map_err(c.located())
}

/// Adds the CONM2 and CONM1 masses (times `wtmass`) to `model`. `dependents` are the RBE2s' dependent grids
/// with their reference grid and components.
///
/// # Errors
/// A malformed card, a mass on an unknown grid, or on a grid nothing connects (unless lenient).
pub(super) fn add_masses(
    conm2: &[&Card],
    model: &mut Model,
    geometry: &mut Geometry<'_>,
    wtmass: f64,
    lenient: bool,
    dependents: &HashMap<u64, (u64, Vec<usize>)>,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    // point masses, on grids the solids or the links connect (a mass on a free grid would have
    // no stiffness)
    let mut connected = model.constrained_nodes();
    for el in model.mesh().elements() {
        for n in el.nodes {
            connected[*n] = true;
        }
    }
    for s in model.structural() {
        for n in &s.nodes {
            connected[*n] = true;
        }
    }
    for c in conm2 {
        if c.name == "CONM1" {
            conm1(
                c, model, geometry, wtmass, lenient, &connected, dependents, warnings,
            )?;
            continue;
        }
        let eid = c.id(0, "EID")?;
        // each CONM2 is a mass set of its own, `CONM2_<EID>`, for updating its mass
        let set = format!("CONM2_{eid}");
        let g = c.id(1, "G")?;
        let m = c
            .real(3, "M")?
            .filter(|m| *m > 0.0)
            .ok_or_else(|| c.err("needs a positive mass M".into()))?;
        let Some(gi) = model.mesh().node_index(g) else {
            return Err(c.err(format!("is on GRID {g}, which the deck does not define")));
        };
        if !connected[gi] {
            let text = format!(
                "{} is on GRID {g}, which no element or rigid link connects: it would have no stiffness",
                c.field(0)
            );
            if lenient {
                warn(warnings, c, format!("{text}: left out"));
                continue;
            }
            return Err(c.err(text));
        }
        let xg = model.mesh().coords()[gi];
        let (d, j) = offset_and_inertia(c, xg, geometry)?;
        let offset = d.iter().any(|v| *v != 0.0);
        let inertia = j.iter().flatten().any(|v| *v != 0.0);
        let scaled = j.map(|r| r.map(|v| v * wtmass));
        if model.has_rotations(gi) {
            // a rigid link's reference: offset and inertia act on its rotations
            model
                .add_rigid_mass(g, m * wtmass, d, scaled)
                .map_err(c.located())?;
            let added = model.last_mass(true).into_iter().collect::<Vec<_>>();
            model.add_mass_set(set, &added).map_err(c.located())?;
            continue;
        }
        // a grid an RBE2 moves rigidly in all six components: the mass moves with the link's
        // reference, offset from it by where the grid (and the mass's offset) put it
        if let Some((gn, cm)) = dependents.get(&g)
            && (offset || inertia)
            && (0..6).all(|k| cm.contains(&k))
            && let Some(ni) = model.mesh().node_index(*gn)
            && model.has_rotations(ni)
        {
            let xn = model.mesh().coords()[ni];
            let from_reference: [f64; 3] = std::array::from_fn(|i| xg[i] + d[i] - xn[i]);
            model
                .add_rigid_mass(*gn, m * wtmass, from_reference, scaled)
                .map_err(c.located())?;
            let added = model.last_mass(true).into_iter().collect::<Vec<_>>();
            model.add_mass_set(set, &added).map_err(c.located())?;
            continue;
        }
        if offset || inertia {
            warn(
                warnings,
                c,
                format!(
                    "{}: GRID {g} has no rotations (only RBE2 reference grids, and grids an RBE2 moves in all six components, have), so its {} dropped and the translational mass kept, as Nastran's AUTOSPC leaves it",
                    c.field(0),
                    match (offset, inertia) {
                        (true, true) => "offset and rotational inertia are",
                        (true, false) => "offset is",
                        _ => "rotational inertia is",
                    }
                ),
            );
        }
        model.add_point_mass(g, m * wtmass).map_err(c.located())?;
        let added = model.last_mass(false).into_iter().collect::<Vec<_>>();
        model.add_mass_set(set, &added).map_err(c.located())?;
    }
    Ok(())
}
