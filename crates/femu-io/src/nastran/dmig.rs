//! Nastran's `DMIG` matrices (QRG DMIG), as a punch file of `PARAM,EXTOUT,DMIGPCH` holds the
//! stiffness `KAAX` and the mass `MAAX`: a header `DMIG NAME 0 IFO TIN TOUT POLAR - NCOL`, then
//! one card per column `DMIG NAME GJ CJ - G1 C1 A1 B1 G2 C2 A2 B2 ...`, each entry labelled by
//! grid and component (small, large-field or free-field cards, continuations as the bulk data
//! reader pairs them).

use super::cards::{self, Card};
use crate::IoError;
use std::collections::BTreeMap;
use std::path::Path;

/// One DMIG matrix: its name, its form (`IFO`: 1 square, 6 symmetric) and its real entries
/// `(row grid, row component, column grid, column component, value, line)`, components 1-6.
#[derive(Debug, Clone, PartialEq)]
pub struct Dmig {
    /// The matrix's name (`KAAX`).
    pub name: String,
    /// `IFO`: 1 square, 6 symmetric (one triangle, or both with each term once).
    pub form: i64,
    /// The entries: row grid, row component (1-6), column grid, column component, value, and
    /// the line of the card that gave it.
    pub entries: Vec<(u64, usize, u64, usize, f64, usize)>,
}

/// The DMIG matrices of a file (other cards are left alone), by name.
///
/// # Errors
/// The file system's; [`IoError::Parse`] with the card's line for a column before its header, a
/// complex (`TIN` 3 or 4) or rectangular matrix, a scalar point (component 0) or a component
/// beyond 6, a malformed field.
pub fn read_dmig(path: &Path) -> Result<BTreeMap<String, Dmig>, IoError> {
    let mut lines = Vec::new();
    cards::load(path, 0, &mut lines)?;
    let deck = cards::deck(&lines)?;
    from_cards(deck.cards.iter())
}

/// The DMIG matrices of `cards` (others are left alone), by name: [`read_dmig`] of cards
/// already read (a bulk data section's).
///
/// # Errors
/// As [`read_dmig`].
pub(super) fn from_cards<'a>(
    cards: impl Iterator<Item = &'a Card>,
) -> Result<BTreeMap<String, Dmig>, IoError> {
    let mut out: BTreeMap<String, Dmig> = BTreeMap::new();
    for c in cards.filter(|c| c.name == "DMIG") {
        let name = c.field(0).to_ascii_uppercase();
        if name.is_empty() {
            return Err(c.err("has no matrix name".into()));
        }
        if c.field(1) == "0" {
            header(c, &name, &mut out)?;
            continue;
        }
        let m = out.get_mut(&name).ok_or_else(|| {
            c.err(format!(
                "{name}: a column before the matrix's header (DMIG {name} 0 IFO TIN ...)"
            ))
        })?;
        let gj = c.id(1, "GJ")?;
        let cj = component(c, 2, "CJ")?;
        let mut i = 4;
        while i < c.fields.len() {
            if c.field(i).is_empty() && c.field(i + 1).is_empty() && c.field(i + 2).is_empty() {
                i += 4;
                continue;
            }
            let g = c.id(i, "G")?;
            let comp = component(c, i + 1, "C")?;
            let a = c.real(i + 2, "A")?.ok_or_else(|| {
                c.err(format!(
                    "{name}: the entry of GRID {g} component {comp} has no value"
                ))
            })?;
            m.entries.push((g, comp, gj, cj, a, c.line));
            i += 4;
        }
    }
    Ok(out)
}

/// The entries of `m` as a symmetric matrix, each unordered pair of DOFs once: `((grid,
/// component 0-5), (grid, component 0-5), value)`. A pair given in both triangles must agree to
/// 1e-10 of the largest entry (its mean is kept); a pair given twice in one triangle is refused.
///
/// # Errors
/// [`IoError::Parse`] with the card's line: a pair repeated, or a square matrix that is not
/// symmetric.
pub(super) fn symmetric_entries(
    m: &Dmig,
    path: &Path,
) -> Result<Vec<femu_fem::model::DirectTerm>, IoError> {
    let scale = m.entries.iter().fold(0.0f64, |a, e| a.max(e.4.abs()));
    // each unordered pair of DOFs: its value, the line that first gave it, whether in the lower
    // triangle
    type Dof = (u64, usize);
    let mut pairs: BTreeMap<(Dof, Dof), (f64, usize, bool)> = BTreeMap::new();
    for &(g, c, gj, cj, v, line) in &m.entries {
        let (r, s) = ((g, c - 1), (gj, cj - 1));
        let key = (r.min(s), r.max(s));
        let lower = r >= s;
        let at = |reason: String| IoError::Parse {
            path: path.to_path_buf(),
            line,
            reason,
        };
        match pairs.get(&key) {
            None => {
                pairs.insert(key, (v, line, lower));
            }
            Some(&(w, first, was_lower)) => {
                if r == s || was_lower == lower {
                    return Err(at(format!(
                        "{}: the entry of GRID {} component {} and GRID {} component {} is given again (first at line {first})",
                        m.name,
                        r.0,
                        r.1 + 1,
                        s.0,
                        s.1 + 1
                    )));
                }
                if (v - w).abs() > 1e-10 * scale {
                    return Err(at(format!(
                        "{}: the matrix is not symmetric: the entry of GRID {} component {} and GRID {} component {} is {v:e} here and {w:e} at line {first}",
                        m.name,
                        r.0,
                        r.1 + 1,
                        s.0,
                        s.1 + 1
                    )));
                }
                pairs.insert(key, (0.5 * (v + w), first, was_lower));
            }
        }
    }
    Ok(pairs
        .into_iter()
        .filter(|(_, (v, _, _))| *v != 0.0)
        .map(|((a, b), (v, _, _))| (a, b, v))
        .collect())
}

/// A matrix's header card: real (`TIN` 1 or 2), square or symmetric.
fn header(c: &Card, name: &str, out: &mut BTreeMap<String, Dmig>) -> Result<(), IoError> {
    let form = c.int(2, "IFO")?.unwrap_or(0);
    let tin = c.int(3, "TIN")?.unwrap_or(0);
    if !matches!(tin, 1 | 2) {
        return Err(c.err(format!(
            "{name}: TIN = {tin} is not a real matrix (1 or 2); femu reads real stiffness and mass"
        )));
    }
    if !matches!(form, 1 | 6) {
        return Err(c.err(format!(
            "{name}: IFO = {form} is not a square (1) or symmetric (6) matrix"
        )));
    }
    if out.contains_key(name) {
        return Err(c.err(format!("{name}: a second header for the matrix")));
    }
    out.insert(
        name.to_string(),
        Dmig {
            name: name.to_string(),
            form,
            entries: Vec::new(),
        },
    );
    Ok(())
}

/// A component 1-6 (a scalar point's 0 is refused).
fn component(c: &Card, i: usize, what: &str) -> Result<usize, IoError> {
    match c.int(i, what)? {
        Some(v @ 1..=6) => Ok(v as usize),
        Some(0) | None => Err(c.err(format!(
            "field {} ({what}): a scalar point (component 0) has no place in femu's model",
            i + 2
        ))),
        Some(v) => Err(c.err(format!(
            "field {} ({what}): component {v} is not 1 to 6",
            i + 2
        ))),
    }
}
