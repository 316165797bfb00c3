//! `RBE2`, `RBAR` and `RBAR1` (rigid links), `RBE1` (a rigid body on six independent DOFs),
//! `RROD` (rigid pin-ended rods) and `RBE3` (weighted averages) as multipoint constraints.

use super::cards::Card;
use crate::{IoError, Warning};
use femu_fem::model::Model;
use std::collections::HashMap;

/// Components `1-6` of a field as 0-based indices.
pub(super) fn components(c: &Card, i: usize, what: &str) -> Result<Vec<usize>, IoError> {
    let t = c.field(i);
    let mut out = Vec::new();
    for ch in t.chars() {
        match ch {
            '1'..='6' => {
                let k = ch as usize - '1' as usize;
                if !out.contains(&k) {
                    out.push(k);
                }
            }
            _ => {
                return Err(c.err(format!(
                    "field {} ({what}): {t:?} is not a list of components 1-6",
                    i + 2
                )));
            }
        }
    }
    if out.is_empty() {
        return Err(c.err(format!("field {} ({what}) is missing", i + 2)));
    }
    Ok(out)
}

/// An RBAR or RBAR1 as the rigid link it is: its reference grid (all six components
/// independent), its dependent components and grid (QRG RBAR: `EID GA GB CNA CNB CMA CMB`, the
/// dependent components by default those of the six not independent; RBAR1: `EID GA GB CB`, GA
/// independent). An RBAR whose independent components are split between its ends is refused:
/// femu links one grid's rigid motion to another.
fn bar_link(c: &Card) -> Result<(u64, Vec<usize>, u64), IoError> {
    let eid = c.id(0, "EID")?;
    let (ga, gb) = (c.id(1, "GA")?, c.id(2, "GB")?);
    if ga == gb {
        return Err(c.err(format!("{} {eid}: GA and GB are both GRID {ga}", c.name)));
    }
    if c.name == "RBAR1" {
        return Ok((ga, components(c, 3, "CB")?, gb));
    }
    let opt = |i: usize, what: &str| -> Result<Vec<usize>, IoError> {
        let t = c.field(i).trim();
        if t.is_empty() || t == "0" {
            Ok(Vec::new())
        } else {
            components(c, i, what)
        }
    };
    let (cna, cnb, cma, cmb) = (
        opt(3, "CNA")?,
        opt(4, "CNB")?,
        opt(5, "CMA")?,
        opt(6, "CMB")?,
    );
    let all = |v: &[usize]| v.len() == 6;
    let (reference, dependent, (own, other), cm) = match (all(&cna), all(&cnb)) {
        (true, false) if cnb.is_empty() => (ga, gb, (&cma, "CMA"), cmb),
        (false, true) if cna.is_empty() => (gb, ga, (&cmb, "CMB"), cma),
        _ => {
            return Err(c.err(format!(
                "RBAR {eid}: independent components CNA {:?} and CNB {:?}: femu links one end's six components to the other's (CNA = 123456 with CNB blank, or the reverse)",
                c.field(3),
                c.field(4)
            )));
        }
    };
    if !own.is_empty() {
        return Err(c.err(format!(
            "RBAR {eid}: {other} {:?} makes components of the independent GRID {reference} dependent",
            c.field(if other == "CMA" { 5 } else { 6 })
        )));
    }
    let cm = if cm.is_empty() { (0..6).collect() } else { cm };
    Ok((reference, cm, dependent))
}

/// An RBE1 (QRG RBE1: `EID GN1 CN1 ... GN6 CN6`, then `UM GM1 CM1 ...` and `ALPHA`): a rigid body
/// whose motion six independent DOFs fix (`CNi` on `GNi`, six in all), and the dependent DOFs
/// `CMj` on `GMj` that follow it. Each DOF is a row of the rigid motion `(t, theta)` at GN1,
/// `e_c . (t + theta x (x - x_GN1))` for a translation and `theta_c` for a rotation; the six
/// independent rows make a matrix `A`, and each dependent DOF is `row A^-1` of the independent
/// ones. Refused: other than six independent DOFs, six that do not fix a rigid motion (`A`
/// singular: collinear grids, a repeated direction), a DOF both independent and dependent, no
/// dependent DOF, an independent rotation of a grid without rotations, turned displacement frames.
/// A dependent rotation of a grid without rotations is left out with a warning (as for RBE2).
fn rigid_body(
    c: &Card,
    eid: u64,
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    label: &str,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    // (grid, component) pairs before and after UM, ALPHA (a real) ending the card
    let (mut independent, mut dependent) = (Vec::new(), Vec::new());
    let mut after_um = false;
    let mut pending: Option<u64> = None;
    for i in 1..c.fields.len() {
        let t = c.field(i).trim();
        if t.is_empty() {
            continue;
        }
        if t.eq_ignore_ascii_case("UM") {
            if pending.is_some() {
                return Err(c.err(format!("{eid}: a grid without its components before UM")));
            }
            after_um = true;
            continue;
        }
        if after_um && pending.is_none() && (t.contains('.') || t.contains(['E', 'e'])) {
            break; // ALPHA
        }
        match pending.take() {
            None => {
                let g = t.parse::<u64>().ok().filter(|g| *g > 0).ok_or_else(|| {
                    c.err(format!("{eid}: {t:?} (field {}) is not a grid id", i + 2))
                })?;
                pending = Some(g);
            }
            Some(g) => {
                let comps = components(c, i, "components")?;
                let list = if after_um {
                    &mut dependent
                } else {
                    &mut independent
                };
                list.extend(comps.into_iter().map(|k| (g, k)));
            }
        }
    }
    if let Some(g) = pending {
        return Err(c.err(format!("{eid}: GRID {g} has no components after it")));
    }
    if independent.len() != 6 {
        return Err(c.err(format!(
            "{eid}: {} independent DOFs: an RBE1's rigid motion takes exactly six",
            independent.len()
        )));
    }
    if dependent.is_empty() {
        return Err(c.err(format!("{eid}: no dependent DOFs (UM GM1 CM1 ...)")));
    }
    if let Some((g, k)) = dependent.iter().find(|d| independent.contains(d)) {
        return Err(c.err(format!(
            "{eid}: component {} of GRID {g} is both independent and dependent",
            k + 1
        )));
    }
    let place = |model: &Model, g: u64| -> Result<([f64; 3], bool), IoError> {
        let n = model.mesh().node_index(g).ok_or_else(|| {
            c.err(format!(
                "RBE1 {eid} names GRID {g}, which the deck does not define"
            ))
        })?;
        if let Some(cd) = turned.get(&g) {
            return Err(c.err(format!(
                "{eid}: GRID {g}'s displacement frame {cd} is turned: femu's constraints are in the basic frame"
            )));
        }
        Ok((model.mesh().coords()[n], model.has_rotations(n)))
    };
    // each DOF's row of the rigid motion (t, theta) at the first independent grid
    let mut places = Vec::new();
    for &(g, k) in &independent {
        let (x, rot) = place(model, g)?;
        if k >= 3 && !rot {
            return Err(c.err(format!(
                "{eid}: independent rotation {} of GRID {g}, which has no rotations (only grids of beams, shells and rigid links' references have)",
                k + 1
            )));
        }
        places.push(x);
    }
    let origin = places[0];
    let row = |x: [f64; 3], k: usize| -> [f64; 6] {
        let mut r = [0.0; 6];
        r[k] = 1.0;
        if k < 3 {
            // e_k . (theta x d) = theta . (d x e_k)
            let d = [x[0] - origin[0], x[1] - origin[1], x[2] - origin[2]];
            let mut e = [0.0; 3];
            e[k] = 1.0;
            r[3] = d[1] * e[2] - d[2] * e[1];
            r[4] = d[2] * e[0] - d[0] * e[2];
            r[5] = d[0] * e[1] - d[1] * e[0];
        }
        r
    };
    let a: Vec<[f64; 6]> = independent
        .iter()
        .zip(&places)
        .map(|(&(_, k), x)| row(*x, k))
        .collect();
    let inverse = invert6(&a).ok_or_else(|| {
        c.err(format!(
            "{eid}: its six independent DOFs do not fix a rigid motion (collinear grids or a repeated direction)"
        ))
    })?;
    let mut warned = false;
    for &(g, k) in &dependent {
        let (x, rot) = place(model, g)?;
        if k >= 3 && !rot {
            if !warned {
                warned = true;
                warnings.push(Warning {
                    path: c.path.clone(),
                    line: c.line,
                    message: format!(
                        "RBE1 {eid}: components 4-6 of grids without rotations are ignored (GRID {g} has none; the rigid body acts on its translations)"
                    ),
                });
            }
            continue;
        }
        let r = row(x, k);
        // the dependent DOF is r q with q = A^-1 u_N
        let terms: Vec<((u64, usize), f64)> = (0..6)
            .map(|j| {
                (
                    independent[j],
                    (0..6).map(|p| r[p] * inverse[p][j]).sum::<f64>(),
                )
            })
            .filter(|(_, w)| w.abs() > 1e-14)
            .collect();
        model
            .add_constraint((g, k), &terms, label)
            .map_err(c.located())?;
    }
    Ok(())
}

/// The inverse of a 6x6 matrix given by rows, by Gauss-Jordan elimination with partial
/// pivoting; `None` when a pivot falls below 1e-10 of the matrix's largest entry (singular).
fn invert6(a: &[[f64; 6]]) -> Option<[[f64; 6]; 6]> {
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut m: Vec<[f64; 12]> = a
        .iter()
        .enumerate()
        .map(|(i, r)| {
            std::array::from_fn(|j| {
                if j < 6 {
                    r[j]
                } else if j - 6 == i {
                    1.0
                } else {
                    0.0
                }
            })
        })
        .collect();
    for col in 0..6 {
        let p = (col..6).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if !(m[p][col].abs() > 1e-10 * scale) {
            return None;
        }
        m.swap(col, p);
        let pivot = m[col][col];
        for v in m[col].iter_mut() {
            *v /= pivot;
        }
        for i in 0..6 {
            if i != col {
                let f = m[i][col];
                if f != 0.0 {
                    let pr = m[col];
                    for (v, q) in m[i].iter_mut().zip(pr) {
                        *v -= f * q;
                    }
                }
            }
        }
    }
    Some(std::array::from_fn(|i| {
        std::array::from_fn(|j| m[i][6 + j])
    }))
}

/// An RROD (QRG RROD: `EID GA GB CMA CMB ALPHA`): the rod between GA and GB keeps its length,
/// `e . (u_B - u_A) = 0` with `e` the unit vector from GA to GB, solved for the one dependent
/// translation `CMA` of GA or `CMB` of GB (the other blank). The grids' displacement frames must
/// be basic (the constraint's coefficients are basic components), and the dependent component
/// must lie along the rod enough to be solved for (`|e_k|` at least 1e-6: Nastran asks for the
/// component of the largest direction cosine). `ALPHA` (thermal expansion) has no effect on modes.
fn rigid_rod(
    c: &Card,
    eid: u64,
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    label: &str,
) -> Result<(), IoError> {
    let (ga, gb) = (c.id(1, "GA")?, c.id(2, "GB")?);
    if ga == gb {
        return Err(c.err(format!("{eid}: GA = GB = {ga}: a rod joins two grids")));
    }
    let mut x = [[0.0; 3]; 2];
    for (k, g) in [ga, gb].into_iter().enumerate() {
        let n = model.mesh().node_index(g).ok_or_else(|| {
            c.err(format!(
                "RROD {eid} names GRID {g}, which the deck does not define"
            ))
        })?;
        if let Some(cd) = turned.get(&g) {
            return Err(c.err(format!(
                "{eid}: GRID {g}'s displacement frame {cd} is turned: femu's constraints are in the basic frame"
            )));
        }
        x[k] = model.mesh().coords()[n];
    }
    let d = [x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(len > 0.0) {
        return Err(c.err(format!(
            "{eid}: GA {ga} and GB {gb} coincide: the rod has no direction"
        )));
    }
    let e = d.map(|v| v / len);
    let one = |i: usize, what: &str| -> Result<Option<usize>, IoError> {
        let t = c.field(i).trim();
        if t.is_empty() || t == "0" {
            return Ok(None);
        }
        match t {
            "1" | "2" | "3" => Ok(Some(t.as_bytes()[0] as usize - b'1' as usize)),
            _ => Err(c.err(format!(
                "{eid}: {what} = {t:?}: the dependent DOF is one translation, 1, 2 or 3"
            ))),
        }
    };
    let (dependent_grid, k) = match (one(3, "CMA")?, one(4, "CMB")?) {
        (Some(k), None) => (ga, k),
        (None, Some(k)) => (gb, k),
        _ => {
            return Err(c.err(format!(
                "{eid}: one of CMA and CMB names the dependent translation, and the other is blank"
            )));
        }
    };
    if e[k].abs() < 1e-6 {
        return Err(c.err(format!(
            "{eid}: component {} of GRID {dependent_grid} is across the rod (direction cosine {:.1e}): the dependent DOF must lie along it (choose the largest cosine)",
            k + 1,
            e[k]
        )));
    }
    // e . (u_B - u_A) = 0 solved for the dependent term: the sign of GB's terms is +, GA's -
    let sign = |g: u64| if g == gb { 1.0 } else { -1.0 };
    let own = sign(dependent_grid) * e[k];
    let mut terms = Vec::with_capacity(5);
    for g in [ga, gb] {
        for (i, ei) in e.iter().enumerate() {
            if (g == dependent_grid && i == k) || *ei == 0.0 {
                continue;
            }
            terms.push(((g, i), -sign(g) * ei / own));
        }
    }
    model
        .add_constraint((dependent_grid, k), &terms, label)
        .map_err(c.located())
}

/// RBE2, RBAR and RBAR1 (rigid links) and RBE3 (weighted averages) into the model's multipoint
/// constraints (docs/MATH.md, "Multipoint constraints"). Reference grids of the rigid links get
/// rotations first, so that chains of links, RBE3 references with rotational components and SPCs
/// on 4-6 find them.
pub(super) fn read_links(
    links: &[&Card],
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    turned_axes: &HashMap<u64, [[f64; 3]; 3]>,
    warnings: &mut Vec<Warning>,
) -> Result<HashMap<u64, (u64, Vec<usize>)>, IoError> {
    let mut dependents: HashMap<u64, (u64, Vec<usize>)> = HashMap::new();
    let grid = |model: &Model, c: &Card, g: u64| -> Result<usize, IoError> {
        model.mesh().node_index(g).ok_or_else(|| {
            c.err(format!(
                "{} names GRID {g}, which the deck does not define",
                c.field(0)
            ))
        })
    };
    for c in links
        .iter()
        .filter(|c| !matches!(c.name.as_str(), "RBE3" | "RROD" | "RBE1"))
    {
        let gn = if c.name == "RBE2" {
            c.id(1, "GN")?
        } else {
            bar_link(c)?.0
        };
        grid(model, c, gn)?;
        model.add_rotations(gn).map_err(c.located())?;
    }
    let mut noted_rotations = false;
    for c in links {
        let eid = c.id(0, "EID")?;
        let label = format!("{} {eid} ({} line {})", c.name, c.path.display(), c.line);
        if c.name == "RROD" {
            rigid_rod(c, eid, model, turned, &label)?;
            continue;
        }
        if c.name == "RBE1" {
            rigid_body(c, eid, model, turned, &label, warnings)?;
            continue;
        }
        if c.name != "RBE3" {
            let (gn, cm, gm) = if c.name == "RBE2" {
                let gn = c.id(1, "GN")?;
                let cm = components(c, 2, "CM")?;
                let mut gm = Vec::new();
                for t in c
                    .fields
                    .get(3..)
                    .unwrap_or_default()
                    .iter()
                    .map(|s| s.trim())
                {
                    if t.is_empty() {
                        continue;
                    }
                    // the optional ALPHA (and TREF) after the grids are reals
                    if t.contains('.') || t.contains(['E', 'e']) {
                        break;
                    }
                    let g = t.parse::<u64>().ok().filter(|g| *g > 0).ok_or_else(|| {
                        c.err(format!("{eid}: dependent grid {t:?} is not an id"))
                    })?;
                    grid(model, c, g)?;
                    gm.push(g);
                }
                if gm.is_empty() {
                    return Err(c.err(format!("{eid} has no dependent grids (GMi)")));
                }
                (gn, cm, gm)
            } else {
                let (gn, cm, g) = bar_link(c)?;
                grid(model, c, g)?;
                (gn, cm, vec![g])
            };
            // the dependent components are in each dependent grid's displacement frame: in a
            // turned one they must be the basic components of the same numbers
            for g in &gm {
                // a grid without rotations (a solid's) ignores components 4-6
                let has_rot = model.has_rotations(grid(model, c, *g)?);
                let mine: Vec<usize> = cm.iter().copied().filter(|k| *k < 3 || has_rot).collect();
                let basic = super::constraints::basic_components(turned, turned_axes, *g, &mine);
                if basic.as_ref() != Ok(&mine) {
                    return Err(c.err(format!(
                        "{eid}: components {} of GRID {g} are in its displacement frame {}, which is turned: femu links the basic components of the same numbers only (all three translations or rotations, or those of axes the frame leaves in place)",
                        cm.iter().map(|k| (k + 1).to_string()).collect::<String>(),
                        turned[g]
                    )));
                }
            }
            let trans: Vec<usize> = cm.iter().copied().filter(|k| *k < 3).collect();
            model
                .add_rigid_link(gn, &gm, &trans, &label)
                .map_err(c.located())?;
            for &g in &gm {
                dependents.insert(g, (gn, cm.clone()));
            }
            // rotations of dependents that carry them (another link's reference) follow GN's
            let rot: Vec<usize> = cm.iter().copied().filter(|k| *k >= 3).collect();
            for &g in &gm {
                let gi = grid(model, c, g)?;
                if model.has_rotations(gi) {
                    for &k in &rot {
                        model
                            .add_constraint((g, k), &[((gn, k), 1.0)], &label)
                            .map_err(c.located())?;
                    }
                } else if !rot.is_empty() && !noted_rotations {
                    noted_rotations = true;
                    warnings.push(Warning {
                        path: c.path.clone(),
                        line: c.line,
                        message: format!(
                            "{} {eid}: components 4-6 of solid grids are ignored (they have no rotations; the rigid link acts on their translations)",
                            c.name
                        ),
                    });
                }
            }
        } else {
            // RBE3 EID, blank, REFGRID, REFC, then groups WTi Ci Gi,j ..., then UM / ALPHA
            let refgrid = c.id(2, "REFGRID")?;
            let refi = grid(model, c, refgrid)?;
            let refc = components(c, 3, "REFC")?;
            let mut nodes: Vec<(u64, f64)> = Vec::new();
            let mut k = 4;
            while k < c.fields.len() {
                let t = c.field(k).to_ascii_uppercase();
                if t.is_empty() {
                    k += 1;
                    continue;
                }
                if t == "UM" {
                    return Err(c.err(format!(
                        "{eid}: UM (other dependent DOFs) is not supported; femu makes REFGRID's REFC dependent"
                    )));
                }
                if t == "ALPHA" || t == "TREF" {
                    break;
                }
                let w = c.real(k, "WT")?.filter(|w| *w > 0.0).ok_or_else(|| {
                    c.err(format!(
                        "{eid}: field {} should be a positive weight WTi, got {t:?}",
                        k + 2
                    ))
                })?;
                let ci = components(c, k + 1, "Ci")?;
                if !(0..3).all(|j| ci.contains(&j)) {
                    return Err(c.err(format!(
                        "{eid}: components {} of a weight group: femu averages all three translations (C = 123 or 123456)",
                        c.field(k + 1)
                    )));
                }
                k += 2;
                let before = nodes.len();
                while k < c.fields.len() {
                    let t = c.field(k);
                    if t.is_empty() {
                        k += 1;
                        continue;
                    }
                    if t.contains('.') || t.chars().any(|ch| ch.is_ascii_alphabetic()) {
                        break;
                    }
                    let g = c.id(k, "Gi,j")?;
                    grid(model, c, g)?;
                    nodes.push((g, w));
                    k += 1;
                }
                if nodes.len() == before {
                    return Err(c.err(format!("{eid}: weight {w} has no grids")));
                }
            }
            let has_rot = model.has_rotations(refi);
            let comps: Vec<usize> = refc.iter().copied().filter(|k| *k < 3 || has_rot).collect();
            // REFC is in the reference grid's displacement frame
            let comps = super::constraints::basic_components(turned, turned_axes, refgrid, &comps)
                .map_err(|(part, mine, cd)| {
                    c.err(format!(
                        "{eid}: REFC's {part} {mine:?} of GRID {refgrid} are in its displacement frame {cd}, whose axes for them are not along basic ones: femu averages along basic components"
                    ))
                })?;
            model
                .add_weighted_average(refgrid, &comps, &nodes, &label)
                .map_err(c.located())?;
        }
    }
    Ok(dependents)
}
