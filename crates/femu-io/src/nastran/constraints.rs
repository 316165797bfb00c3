//! Single-point constraints: the `SPC`, `SPC1` and `SPCADD` set the case control selects, and the
//! permanent constraints of `GRID` field 8 (`PS`, or `GRDSET`'s).

use super::cards::Card;
use super::case_control::Selected;
use super::geometry::Geometry;
use crate::{IoError, Warning};
use femu_fem::model::Model;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

fn warn(warnings: &mut Vec<Warning>, c: &Card, message: String) {
    warnings.push(Warning {
        path: c.path.clone(),
        line: c.line,
        message,
    });
}

/// Fixes components `comps` (0-based, 0-5) of GRID `g` for card `c`: rotations only where the
/// grid has them (rigid links' reference grids; solid grids have none to fix); partial components
/// of a grid whose displacement frame is turned are refused (femu constrains basic components).
pub(super) fn fix_components(
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    turned_axes: &HashMap<u64, [[f64; 3]; 3]>,
    c: &Card,
    g: u64,
    comps: &[usize],
) -> Result<(), IoError> {
    let Some(gi) = model.mesh().node_index(g) else {
        return Err(c.err(format!(
            "constrains GRID {g}, which the deck does not define"
        )));
    };
    let has_rotations = model.has_rotations(gi);
    let comps: Vec<usize> = comps
        .iter()
        .copied()
        .filter(|k| *k < 3 || has_rotations)
        .collect();
    let basic = basic_components(turned, turned_axes, g, &comps).map_err(|(part, mine, cd)| {
        c.err(format!(
            "constrains the {part} {mine:?} of GRID {g} in its displacement frame {cd}, whose axes for them are not along basic ones: femu constrains basic components (a constraint along a turned direction is not built)"
        ))
    })?;
    model.fix_node_dofs(g, &basic).map_err(c.located())
}

/// The basic components (0-5) that act as components `comps` (0-5) of grid `g` in its
/// displacement frame: the same for a grid in the basic orientation; for a turned frame, the
/// translations and the rotations each must span the same directions as some basic axes (all
/// three, two turned about the third, or one along a basic axis), whose components they are.
/// Else the part (`"translations"` or `"rotations"`), its components (1-6) and the frame.
pub(super) fn basic_components(
    turned: &HashMap<u64, i64>,
    turned_axes: &HashMap<u64, [[f64; 3]; 3]>,
    g: u64,
    comps: &[usize],
) -> Result<Vec<usize>, (&'static str, Vec<usize>, i64)> {
    let (Some(cd), Some(axes)) = (turned.get(&g), turned_axes.get(&g)) else {
        return Ok(comps.to_vec());
    };
    let mut basic = Vec::new();
    for (offset, part) in [(0, "translations"), (3, "rotations")] {
        let mine: Vec<usize> = comps
            .iter()
            .filter(|k| (offset..offset + 3).contains(*k))
            .map(|k| k - offset)
            .collect();
        match coordinate_span(axes, &mine) {
            Some(keep) => basic.extend(keep.into_iter().map(|k| k + offset)),
            None => return Err((part, mine.iter().map(|k| k + offset + 1).collect(), *cd)),
        }
    }
    Ok(basic)
}

/// The basic axes whose span is the span of the frame's axes `chosen` (`axes`' columns), when
/// there are such: the projector `sum e_c e_c^T` is then diagonal with ones and zeros.
fn coordinate_span(axes: &[[f64; 3]; 3], chosen: &[usize]) -> Option<Vec<usize>> {
    let mut p = [[0.0; 3]; 3];
    for &c in chosen {
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] += axes[i][c] * axes[j][c];
            }
        }
    }
    let mut keep = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j && (p[i][i] - 1.0).abs() < 1e-9 {
                1.0
            } else {
                0.0
            };
            if (p[i][j] - want).abs() > 1e-9 {
                return None;
            }
        }
        if p[i][i] > 0.5 {
            keep.push(i);
        }
    }
    Some(keep)
}

/// The permanent single-point constraints of the grids (QRG GRID field 8, `PS`: "permanent
/// single-point constraints", in the grid's displacement frame; blank takes GRDSET's):
/// `fix(card, grid, components)` for each grid that has them.
///
/// # Errors
/// A malformed component list, partial components in a turned frame.
pub(super) fn apply_permanent(
    grids: &[&Card],
    geometry: &Geometry<'_>,
    fix: &mut impl FnMut(&Card, u64, &[usize]) -> Result<(), IoError>,
) -> Result<usize, IoError> {
    let mut count = 0;
    for g in grids {
        let source = geometry.grid_field(g, 6);
        let t = source.field(6);
        if t.is_empty() || t == "0" {
            continue;
        }
        let comps = super::links::components(source, 6, "PS")?;
        let id = g.id(0, "ID")?;
        fix(g, id, &comps)?;
        count += 1;
    }
    Ok(count)
}

/// Applies the SPC set the case control selects (`selected`), or the deck's only set when it has
/// no case control: `fix(card, grid, components)` for each grid it constrains (components
/// 0-based).
///
/// # Errors
/// A selected set nothing defines, several sets and no selection, malformed cards, and `fix`'s.
#[allow(clippy::too_many_arguments)]
pub(super) fn apply_spc(
    spcs: &[&Card],
    selected: Option<&Selected>,
    has_case_control: bool,
    geometry: &Geometry<'_>,
    path: &Path,
    warnings: &mut Vec<Warning>,
    fix: &mut impl FnMut(&Card, u64, &[usize]) -> Result<(), IoError>,
) -> Result<(), IoError> {
    // constraints: the case control's SPC set, or the only one a bulk-only file has
    let sets = by_set(spcs)?;
    let chosen = match selected.map(|s| s.id) {
        Some(s) => Some(s),
        None if has_case_control => {
            if let Some(c) = spcs.first() {
                warn(
                    warnings,
                    c,
                    "the case control selects no SPC set: the model is free (unconstrained)".into(),
                );
            }
            None
        }
        None => match sets.keys().copied().collect::<Vec<_>>().as_slice() {
            [] => None,
            [one] => {
                warn(
                    warnings,
                    spcs[0],
                    format!("no case control: the deck's only SPC set {one} is applied"),
                );
                Some(*one)
            }
            many => {
                return Err(IoError::Parse {
                    path: spcs[0].path.clone(),
                    line: spcs[0].line,
                    reason: format!(
                        "the deck defines SPC sets {many:?} and no case control selects one (SPC = n before BEGIN BULK)"
                    ),
                });
            }
        },
    };
    if let Some(sid) = chosen {
        for c in union_cards(&sets, sid, selected, path, ("SPC", "SPC, SPC1 or SPCADD"))? {
            let comps = |c: &Card, i: usize| -> Result<Vec<usize>, IoError> {
                let t = c.field(i);
                let mut out = Vec::new();
                for ch in t.chars() {
                    match ch {
                        '1'..='6' => out.push(ch as usize - '1' as usize),
                        '0' => {}
                        _ => return Err(c.err(format!("component {t:?} is not a list of 1-6"))),
                    }
                }
                Ok(out)
            };
            match c.name.as_str() {
                "SPC" => {
                    for k in 0..2 {
                        let base = 1 + 3 * k;
                        if c.field(base).is_empty() {
                            continue;
                        }
                        let g = c.id(base, "G")?;
                        let cs = comps(c, base + 1)?;
                        if c.real(base + 2, "D")?.is_some_and(|d| d != 0.0) {
                            warn(
                                warnings,
                                c,
                                "an enforced value is read as 0 (modal analysis)".into(),
                            );
                        }
                        fix(c, g, &cs)?;
                    }
                }
                "SPC1" => {
                    let cs = comps(c, 1)?;
                    let rest: Vec<String> = c
                        .fields
                        .get(2..)
                        .unwrap_or_default()
                        .iter()
                        .map(|s| s.trim().to_ascii_uppercase())
                        .filter(|s| !s.is_empty())
                        .collect();
                    let mut grids_here = Vec::new();
                    if rest.len() == 3 && rest[1] == "THRU" {
                        let (a, b) = (rest[0].parse::<u64>(), rest[2].parse::<u64>());
                        match (a, b) {
                            (Ok(a), Ok(b)) if a <= b => {
                                // the defined grids in the range (not every id of it: a
                                // range may span billions of ids)
                                let mut ids: Vec<u64> = geometry
                                    .grid_of
                                    .keys()
                                    .copied()
                                    .filter(|g| (a..=b).contains(g))
                                    .collect();
                                ids.sort_unstable();
                                grids_here.extend(ids);
                            }
                            _ => return Err(c.err(format!("THRU range {rest:?} is invalid"))),
                        }
                    } else {
                        for t in &rest {
                            grids_here.push(
                                t.parse::<u64>()
                                    .map_err(|_| c.err(format!("grid {t:?} is not an id")))?,
                            );
                        }
                    }
                    if rest.is_empty() {
                        return Err(c.err("names no grid (SPC1 SID C G1 G2 ...)".into()));
                    }
                    for g in grids_here {
                        fix(c, g, &cs)?;
                    }
                }
                _ => unreachable!("union_cards returns the sets' own cards"),
            }
        }
    }
    Ok(())
}

/// The `MPC` set the case control selects (`MPC = n`; a deck without case control, its only set)
/// as linear constraints of the model (QRG MPC: `SID G1 C1 A1 G2 C2 A2`, then `G3 C3 A3 G4 C4 A4`
/// on each continuation after a blank field; `sum_j A_j u_j = 0` with the first term's DOF the
/// dependent one, `u_1 = -sum_{j>1} (A_j / A_1) u_j`; `MPCADD SID S1 S2 ...` the union of sets).
/// Components are those of the grid's displacement frame: femu's constraints are in the basic
/// frame, so a term on a grid whose frame is turned is refused, as are scalar points (component 0)
/// and a first coefficient of zero. A term on a rotation needs a grid with rotations (a beam's,
/// a shell's, a rigid link's reference).
///
/// # Errors
/// A malformed card, one of the above, a set the case control selects that no card defines, and
/// what [`Model::add_constraint`] refuses (an unknown grid), each with the card's line.
pub(super) fn apply_mpc(
    mpcs: &[&Card],
    selected: Option<&Selected>,
    has_case_control: bool,
    model: &mut Model,
    turned: &HashMap<u64, i64>,
    path: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    let sets = by_set(mpcs)?;
    let chosen = match selected.map(|s| s.id) {
        Some(s) => s,
        None => {
            let Some(first) = mpcs.first() else {
                return Ok(());
            };
            let ids: Vec<i64> = sets.keys().copied().collect();
            if has_case_control || ids.len() > 1 {
                warn(
                    warnings,
                    first,
                    format!(
                        "MPC sets {ids:?} are defined and {}: none is applied, as Nastran applies only the set MPC = n selects",
                        if has_case_control {
                            "the case control selects none"
                        } else {
                            "no case control selects one"
                        }
                    ),
                );
                return Ok(());
            }
            warn(
                warnings,
                first,
                format!(
                    "no case control: the deck's only MPC set {} is applied",
                    ids[0]
                ),
            );
            ids[0]
        }
    };
    for c in union_cards(&sets, chosen, selected, path, ("MPC", "MPC or MPCADD"))? {
        let s = c.int(0, "SID")?.unwrap_or(chosen);
        // the terms: fields 1-3 and 4-6 of the first line, 8k+1.. and 8k+4.. after
        let mut terms: Vec<((u64, usize), f64)> = Vec::new();
        let mut at = 1;
        while at < c.fields.len() {
            for start in [at, at + 3] {
                if (start..start + 3).all(|i| c.field(i).trim().is_empty()) {
                    continue;
                }
                let g = c.id(start, "G")?;
                let comp = c.int(start + 1, "C")?.unwrap_or(0);
                if !(1..=6).contains(&comp) {
                    return Err(c.err(format!(
                        "component {comp} of GRID {g} is not 1 to 6 (scalar points are not modelled)"
                    )));
                }
                if let Some(cd) = turned.get(&g) {
                    return Err(c.err(format!(
                        "GRID {g}'s component {comp} is in its displacement frame {cd}, which is turned: femu's constraints are in the basic frame"
                    )));
                }
                let a = c.real(start + 2, "A")?.ok_or_else(|| {
                    c.err(format!("GRID {g} component {comp} has no coefficient A"))
                })?;
                terms.push(((g, comp as usize - 1), a));
            }
            at += 8;
        }
        let Some((&(dependent, a1), rest)) = terms.split_first() else {
            return Err(c.err("has no term (MPC SID G1 C1 A1 ...)".into()));
        };
        if !(a1.is_finite() && a1 != 0.0) {
            return Err(c.err(format!(
                "the first term's coefficient A1 is {a1}: it is the dependent DOF's (u1 = -sum Aj uj / A1) and must not be zero"
            )));
        }
        let weights: Vec<((u64, usize), f64)> = rest.iter().map(|&(d, a)| (d, -a / a1)).collect();
        let label = format!("MPC {s} ({} line {})", c.path.display(), c.line);
        model
            .add_constraint(dependent, &weights, &label)
            .map_err(c.located())?;
    }
    Ok(())
}

/// The cards by their set id (field 1, `SID`).
fn by_set<'c>(cards: &[&'c Card]) -> Result<BTreeMap<i64, Vec<&'c Card>>, IoError> {
    let mut sets: BTreeMap<i64, Vec<&Card>> = BTreeMap::new();
    for c in cards {
        let sid = c
            .int(0, "SID")?
            .ok_or_else(|| c.err("needs a set id (SID)".into()))?;
        sets.entry(sid).or_default().push(c);
    }
    Ok(sets)
}

/// The cards of set `sid` and of the sets its `SPCADD`/`MPCADD` cards name, recursively (each set
/// once), without the union cards themselves. `what` is the set's kind and the cards that define
/// one, for the error naming a set nothing defines (at the case control's line when it selected
/// it).
fn union_cards<'c>(
    sets: &BTreeMap<i64, Vec<&'c Card>>,
    sid: i64,
    selected: Option<&Selected>,
    path: &Path,
    (kind, defined_by): (&str, &str),
) -> Result<Vec<&'c Card>, IoError> {
    let mut out = Vec::new();
    let mut todo = vec![sid];
    let mut seen = Vec::new();
    while let Some(s) = todo.pop() {
        if seen.contains(&s) {
            continue;
        }
        seen.push(s);
        let cards = sets.get(&s).cloned().unwrap_or_default();
        if cards.is_empty() {
            return Err(match selected.filter(|sel| sel.id == s) {
                Some(sel) => IoError::Parse {
                    path: sel.path.clone(),
                    line: sel.line,
                    reason: format!("{kind} = {s} selects a set that no {defined_by} defines"),
                },
                None => IoError::Content {
                    path: path.to_path_buf(),
                    reason: format!("{kind} set {s} is selected but no {defined_by} defines it"),
                },
            });
        }
        for c in cards {
            if !c.name.ends_with("ADD") {
                out.push(c);
                continue;
            }
            // SPCADD / MPCADD SID S1 S2 ...
            let ids: Vec<&str> = c
                .fields
                .get(1..)
                .unwrap_or_default()
                .iter()
                .map(|s| s.trim())
                .filter(|s| !s.is_empty())
                .collect();
            if ids.is_empty() {
                return Err(c.err(format!("names no set ({} SID S1 S2 ...)", c.name)));
            }
            for t in ids {
                todo.push(
                    t.parse::<i64>()
                        .map_err(|_| c.err(format!("set {t:?} is not an id")))?,
                );
            }
        }
    }
    Ok(out)
}
