//! Design relations of an optimisation deck (SOL 200) at its initial design. SOL 200 analyses the
//! properties a `DVPREL1` makes of the design variables, `P = C0 + sum COEF_i XINIT_i` (QRG
//! DVPREL1, DESVAR); femu reads the bulk data as the analysis model gives it. A relation whose
//! value at `XINIT` is the property's own is read past (the two models agree); one that is not
//! is refused with both values, since the analysis SOL 200 runs first is not the deck femu would
//! build.

use super::cards::Card;
use super::{Warning, warn};
use crate::IoError;
use std::collections::HashMap;

/// The property fields a `DVPREL1` may name, with the field's index (0-based after the card's
/// name: the QRG's field 4 is 2) and its value when blank; `None` where a blank has no single
/// value to compare with.
const FIELDS: &[(&str, &str, usize, Option<f64>)] = &[
    ("PSHELL", "T", 2, None),
    ("PSHELL", "12I/T**3", 4, Some(1.0)),
    ("PSHELL", "TS/T", 6, Some(0.833_333)),
    ("PSHELL", "NSM", 7, Some(0.0)),
    ("PROD", "A", 2, None),
    ("PROD", "J", 3, Some(0.0)),
    ("PROD", "C", 4, Some(0.0)),
    ("PROD", "NSM", 5, Some(0.0)),
    ("PBAR", "A", 2, None),
    ("PBAR", "I1", 3, Some(0.0)),
    ("PBAR", "I2", 4, Some(0.0)),
    ("PBAR", "J", 5, Some(0.0)),
    ("PBAR", "NSM", 6, Some(0.0)),
    ("PBEAM", "A", 2, None),
    ("PBEAM", "I1", 3, Some(0.0)),
    ("PBEAM", "I2", 4, Some(0.0)),
    ("PBEAM", "I12", 5, Some(0.0)),
    ("PBEAM", "J", 6, Some(0.0)),
    ("PBEAM", "NSM", 7, Some(0.0)),
    ("PELAS", "K1", 1, None),
    ("PELAS", "GE1", 2, Some(0.0)),
    ("PMASS", "M1", 1, None),
    ("PDAMP", "B1", 1, None),
    ("PVISC", "CE1", 1, Some(0.0)),
    ("PVISC", "CR1", 2, Some(0.0)),
    ("PBUSH", "K1", 2, Some(0.0)),
    ("PBUSH", "K2", 3, Some(0.0)),
    ("PBUSH", "K3", 4, Some(0.0)),
    ("PBUSH", "K4", 5, Some(0.0)),
    ("PBUSH", "K5", 6, Some(0.0)),
    ("PBUSH", "K6", 7, Some(0.0)),
];

/// Checks every `DVPREL1` against the property it relates, at the `DESVAR`s' initial values:
/// read past (one warning for all) when each gives its property's value to 1e-6, refused with
/// card, line and both values otherwise.
pub(super) fn check_dvprel1(
    cards: &[Card],
    dvprels: &[&Card],
    warnings: &mut Vec<Warning>,
) -> Result<(), IoError> {
    if dvprels.is_empty() {
        return Ok(());
    }
    let mut xinit: HashMap<u64, f64> = HashMap::new();
    let mut properties: HashMap<(&str, u64), &Card> = HashMap::new();
    for c in cards {
        if c.name == "DESVAR" {
            let id = c.id(0, "ID")?;
            let x = c
                .real(2, "XINIT")?
                .ok_or_else(|| c.err(format!("{id}: field 4 (XINIT) is missing")))?;
            if xinit.insert(id, x).is_some() {
                return Err(c.err(format!("{id} is defined twice")));
            }
        } else if FIELDS.iter().any(|f| f.0 == c.name)
            && let Ok(pid) = c.id(0, "PID")
        {
            properties.entry((c.name.as_str(), pid)).or_insert(c);
        }
    }
    for d in dvprels {
        let id = d.id(0, "ID")?;
        let kind = d.field(1).to_ascii_uppercase();
        let pid = d.id(2, "PID")?;
        let pname = d.field(3).to_ascii_uppercase();
        let c0 = d.real(6, "C0")?.unwrap_or(0.0);
        let mut value = c0;
        let mut terms = 0;
        let mut i = 8;
        while i < d.fields.len() {
            if d.field(i).is_empty() && d.field(i + 1).is_empty() {
                i += 2;
                continue;
            }
            let dv = d.id(i, "DVID")?;
            let coef = d
                .real(i + 1, "COEF")?
                .ok_or_else(|| d.err(format!("{id}: design variable {dv} has no COEF")))?;
            let x = xinit.get(&dv).ok_or_else(|| {
                d.err(format!(
                    "{id} refers to design variable {dv}, which no DESVAR defines"
                ))
            })?;
            value += coef * x;
            terms += 1;
            i += 2;
        }
        if terms == 0 {
            return Err(d.err(format!(
                "{id} relates no design variable (DVID1 is missing)"
            )));
        }
        let field = if let Ok(fid) = pname.parse::<i64>() {
            // a field position (QRG DVPREL1, PNAME/FID): 3 to 9 of the first line
            FIELDS
                .iter()
                .find(|f| f.0 == kind && f.2 as i64 + 2 == fid)
                .ok_or_else(|| {
                    d.err(format!(
                        "{id}: FID {fid} of {kind} is not a property femu can compare at the initial design (name it: {})",
                        names(&kind)
                    ))
                })?
        } else {
            FIELDS
                .iter()
                .find(|f| f.0 == kind && f.1 == pname)
                .ok_or_else(|| {
                    d.err(format!(
                        "{id}: {kind} {pname} is not a property femu can compare at the initial design ({})",
                        names(&kind)
                    ))
                })?
        };
        let p = properties.get(&(field.0, pid)).ok_or_else(|| {
            d.err(format!(
                "{id} relates {kind} {pid}, which the deck does not define"
            ))
        })?;
        let given = p.real(field.2, field.1)?.or(field.3).ok_or_else(|| {
            d.err(format!(
                "{id} sets {kind} {pid}'s {pname} (blank on its card at line {}) to {value:e} at the initial design: SOL 200 analyses that value, femu reads the analysis model as given; write it on the {kind}",
                p.line
            ))
        })?;
        if (value - given).abs() > 1e-6 * value.abs().max(given.abs()) {
            return Err(d.err(format!(
                "{id} sets {kind} {pid}'s {pname} to {value:e} at the initial design (C0 + sum COEF XINIT), where its card at line {} gives {given:e}: SOL 200 analyses the design's value, femu reads the analysis model as given (make the {kind} agree with its design relation)",
                p.line
            )));
        }
    }
    let message = match dvprels.len() {
        1 => "1 DVPREL1 relation agrees with its property card".to_string(),
        n => format!("{n} DVPREL1 relations agree with their property cards"),
    };
    warn(
        warnings,
        dvprels[0],
        format!(
            "{message} at the initial design (DESVAR XINIT): femu analyses that design, as the cards give it"
        ),
    );
    Ok(())
}

/// The property names femu compares for a property type.
fn names(kind: &str) -> String {
    let known: Vec<&str> = FIELDS.iter().filter(|f| f.0 == kind).map(|f| f.1).collect();
    if known.is_empty() {
        let kinds: Vec<&str> = FIELDS.iter().map(|f| f.0).fold(Vec::new(), |mut v, k| {
            if !v.contains(&k) {
                v.push(k);
            }
            v
        });
        format!("femu compares {}", kinds.join(", "))
    } else {
        format!("femu compares its {}", known.join(", "))
    }
}
