//! Nastran's punch output (`.pch`), read for the real modes of a normal modes run (SOL 103 with
//! `VECTOR(PUNCH)` or `DISPLACEMENT(PUNCH)`): another solver's modes as the model side of a
//! correlation, as the `.f06` and `.op2` are ([`crate::f06`]; docs/ARCHITECTURE.md, "Models
//! solved elsewhere").
//!
//! A punch file is 80-column records; columns 73-80 hold a sequence number. Each result block
//! starts with `$` header records: `$TITLE =`, `$SUBTITLE=`, `$LABEL =`, the block's kind
//! (`$EIGENVECTOR`, `$DISPLACEMENTS`, `$SPCF`, ...), the output form (`$REAL OUTPUT`,
//! `$REAL-IMAGINARY OUTPUT`, `$MAGNITUDE-PHASE OUTPUT`), `$SUBCASE ID =`, and for a mode
//! `$EIGENVALUE = value MODE = n`. A real point is two records: `id  G  T1 T2 T3` and `-CONT-  R1
//! R2 R3`, in the grid's displacement frame (CD).
//!
//! What is read: the `$EIGENVECTOR` blocks with `$REAL OUTPUT` of one subcase, grid points
//! (`G`). Other blocks (displacements, forces, stresses) are passed over; complex eigenvectors,
//! scalar points, a second subcase of eigenvectors and malformed records are refused with the
//! line. A punch file of DMIG matrices is read by [`crate::matrices`] instead
//! ([`looks_like_results`] tells them apart).

use crate::IoError;
use crate::f06::{F06, F06Mode};
use std::path::Path;

/// Whether the head of a `.pch` file is result output (a `$TITLE` or `$EIGENVECTOR` record among
/// its first lines) rather than DMIG matrices.
pub fn looks_like_results(head: &str) -> bool {
    head.lines().take(40).any(|l| {
        let l = l.trim_start();
        l.starts_with("$TITLE") || l.starts_with("$EIGENVECTOR")
    })
}

fn parse_error(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// The record without its sequence number (columns 73-80).
fn record(raw: &str) -> &str {
    let t = raw.trim_end_matches('\r');
    match t.char_indices().nth(72) {
        Some((i, _)) => &t[..i],
        None => t,
    }
}

fn number(s: &str) -> Option<f64> {
    s.replace(['D', 'd'], "E")
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
}

/// The refusal of eigenvectors in an output form other than `$REAL OUTPUT`.
fn not_real(output: &str) -> String {
    format!(
        "eigenvectors in {}: femu reads the real modes of a normal modes run (SOL 103, $REAL OUTPUT), not complex ones",
        if output.is_empty() {
            "no stated output form".to_string()
        } else {
            format!("${output}")
        }
    )
}

/// Reads the real modes of a punch file.
///
/// # Errors
/// [`IoError::Io`] if unreadable; [`IoError::Parse`] with the line for a malformed record,
/// complex eigenvectors, a scalar point, a second subcase of eigenvectors, a mode punched twice;
/// [`IoError::Content`] for a file without real eigenvectors (naming the blocks it holds).
pub fn read_punch_modes(path: impl AsRef<Path>) -> Result<F06, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_punch_modes(&String::from_utf8_lossy(&bytes), path)
}

/// What the header records have said of the block being read.
#[derive(Default)]
struct Header {
    kind: String,
    output: String,
    subcase: Option<u64>,
    eigenvalue: Option<(f64, usize)>,
}

/// Parses punch text (`path` names it in messages).
///
/// # Errors
/// As [`read_punch_modes`].
pub fn parse_punch_modes(text: &str, path: &Path) -> Result<F06, IoError> {
    let mut modes: Vec<F06Mode> = Vec::new();
    let mut header = Header::default();
    // the block's mode being filled, and the grid whose -CONT- record is due
    let mut current: Option<usize> = None;
    let mut pending: Option<(u64, [f64; 3], usize)> = None;
    let mut vector_subcase: Option<(u64, usize)> = None;
    let mut kinds: Vec<String> = Vec::new();
    let mut in_header = false;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let r = record(raw);
        let t = r.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(h) = t.strip_prefix('$') {
            if let Some((grid, _, at)) = pending.take() {
                return Err(parse_error(
                    path,
                    at,
                    format!("grid {grid}'s rotations (its -CONT- record) are missing"),
                ));
            }
            if !in_header {
                // a new block: its headers follow
                header = Header::default();
                current = None;
                in_header = true;
            }
            let (key, value) = match h.split_once('=') {
                Some((k, v)) => (k.trim().to_ascii_uppercase(), Some(v.trim())),
                None => (h.trim().to_ascii_uppercase(), None),
            };
            match (key.as_str(), value) {
                ("TITLE" | "SUBTITLE" | "LABEL", _) => {}
                ("SUBCASE ID", Some(v)) => {
                    header.subcase = Some(v.parse::<u64>().map_err(|_| {
                        parse_error(path, line, format!("subcase id {v:?} is not a number"))
                    })?);
                }
                ("EIGENVALUE", Some(v)) => {
                    // `value MODE = n` (a complex one is `(re, im) MODE = n`)
                    let (value, mode) = v.split_once("MODE").ok_or_else(|| {
                        parse_error(
                            path,
                            line,
                            format!("the EIGENVALUE record {t:?} has no MODE"),
                        )
                    })?;
                    let mode = mode.trim_start_matches([' ', '=']).trim();
                    let mode = mode.parse::<usize>().map_err(|_| {
                        parse_error(path, line, format!("mode number {mode:?} is not a number"))
                    })?;
                    header.eigenvalue = number(value.trim()).map(|v| (v, mode));
                    if header.eigenvalue.is_none() && header.kind == "EIGENVECTOR" {
                        return Err(parse_error(
                            path,
                            line,
                            if header.output == "REAL OUTPUT" {
                                format!("eigenvalue {:?} is not a real number", value.trim())
                            } else {
                                not_real(&header.output)
                            },
                        ));
                    }
                }
                (k, None) if k.ends_with("OUTPUT") => header.output = k.to_string(),
                (k, None) => {
                    header.kind = k.to_string();
                    if !kinds.contains(&header.kind) {
                        kinds.push(header.kind.clone());
                    }
                }
                _ => {}
            }
            continue;
        }
        if in_header {
            in_header = false;
            if header.kind == "EIGENVECTOR" {
                if header.output != "REAL OUTPUT" {
                    return Err(parse_error(path, line, not_real(&header.output)));
                }
                let (eigenvalue, number) = header.eigenvalue.ok_or_else(|| {
                    parse_error(
                        path,
                        line,
                        "an eigenvector block without its $EIGENVALUE = ... MODE = ... record"
                            .into(),
                    )
                })?;
                let subcase = header.subcase.unwrap_or(0);
                match vector_subcase {
                    Some((first, at)) if first != subcase => {
                        return Err(parse_error(
                            path,
                            line,
                            format!(
                                "eigenvectors of subcase {subcase} after those of subcase {first} (line {at}): femu reads the modes of one subcase"
                            ),
                        ));
                    }
                    None => vector_subcase = Some((subcase, line)),
                    _ => {}
                }
                if let Some(m) = modes.iter().find(|m| m.number == number) {
                    return Err(parse_error(
                        path,
                        line,
                        format!("mode {number} is punched twice (first at line {})", m.line),
                    ));
                }
                modes.push(F06Mode {
                    number,
                    eigenvalue,
                    points: Vec::new(),
                    line,
                });
                current = Some(modes.len() - 1);
            }
        }
        let Some(k) = current else {
            continue;
        };
        let f: Vec<&str> = t.split_whitespace().collect();
        let values = |fields: &[&str]| -> Result<[f64; 3], IoError> {
            let v: Vec<f64> = fields.iter().filter_map(|s| number(s)).collect();
            if fields.len() != 3 || v.len() != 3 {
                return Err(parse_error(
                    path,
                    line,
                    format!("a point record holds three numbers after its label, got {t:?}"),
                ));
            }
            Ok([v[0], v[1], v[2]])
        };
        if f.first() == Some(&"-CONT-") {
            let Some((grid, tr, _)) = pending.take() else {
                // a complex or scalar record's later lines never get here: refused above
                return Err(parse_error(
                    path,
                    line,
                    "a -CONT- record without the grid record before it".into(),
                ));
            };
            let rot = values(&f[1..])?;
            modes[k]
                .points
                .push((grid, [tr[0], tr[1], tr[2], rot[0], rot[1], rot[2]]));
            continue;
        }
        if let Some((grid, _, at)) = pending.take() {
            return Err(parse_error(
                path,
                at,
                format!("grid {grid}'s rotations (its -CONT- record) are missing"),
            ));
        }
        let id = f
            .first()
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| parse_error(path, line, format!("{t:?} is not a point record")))?;
        match f.get(1).copied() {
            Some("G") => {}
            Some("S") => {
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "scalar point {id} in mode {}: femu reads grid points only",
                        modes[k].number
                    ),
                ));
            }
            other => {
                return Err(parse_error(
                    path,
                    line,
                    format!("point {id} has type {other:?}; a grid point is G"),
                ));
            }
        }
        pending = Some((id, values(&f[2..])?, line));
    }
    if let Some((grid, _, at)) = pending {
        return Err(parse_error(
            path,
            at,
            format!("grid {grid}'s rotations (its -CONT- record) are missing"),
        ));
    }
    if modes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: format!(
                "no real eigenvectors ($EIGENVECTOR blocks); the file holds {}",
                if kinds.is_empty() {
                    "no result block".to_string()
                } else {
                    kinds
                        .iter()
                        .map(|k| format!("${k}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ),
        });
    }
    modes.sort_by_key(|m| m.number);
    Ok(F06 {
        modes,
        without_vectors: 0,
    })
}
