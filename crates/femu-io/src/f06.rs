//! Nastran's printed output (`.f06`), read for the real modes of a normal modes run (SOL 103):
//! another solver's modes as the model side of a correlation (docs/ARCHITECTURE.md, "Models
//! solved elsewhere").
//!
//! What is read, as Nastran prints it:
//! - the `R E A L   E I G E N V A L U E S` table: mode number, extraction order, eigenvalue,
//!   radians, cycles, generalized mass and stiffness, one mode per row;
//! - each `R E A L   E I G E N V E C T O R   N O .  n` block: rows `POINT ID.  TYPE  T1 T2 T3 R1
//!   R2 R3` for grid points (`G`), in each grid's displacement frame (CD), printed again under
//!   the same title on every page the block takes.
//!
//! A page eject (a line starting with `1`) ends a block until its title is printed again, so the
//! tables that share the row format (single-point forces of constraint, ...) are not read as
//! modes. Complex eigenvectors, scalar points and more than one subcase are refused, with the
//! line.

use crate::IoError;
use std::collections::BTreeMap;
use std::path::Path;

/// One real mode.
#[derive(Debug, Clone, PartialEq)]
pub struct F06Mode {
    /// The mode number.
    pub number: usize,
    /// The eigenvalue `omega^2`, from the eigenvalue table (or, without one, the block's
    /// `EIGENVALUE =` line).
    pub eigenvalue: f64,
    /// `(grid id, [T1, T2, T3, R1, R2, R3])` in the grid's displacement frame, in print order.
    pub points: Vec<(u64, [f64; 6])>,
    /// The line of the block's first title.
    pub line: usize,
}

/// What femu reads of a `.f06` file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct F06 {
    /// The modes with eigenvectors, by number.
    pub modes: Vec<F06Mode>,
    /// Eigenvalues of the table without a printed eigenvector (the case control asked for none).
    pub without_vectors: usize,
}

fn parse_error(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

fn number(s: &str) -> Option<f64> {
    s.replace(['D', 'd'], "E")
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
}

/// Whether a line is a spaced-out title (`F O R C E S   O F ...`): five single capitals in a row.
fn spaced_title(t: &str) -> bool {
    let mut run = 0;
    for w in t.split_whitespace() {
        if w.len() == 1 && w.chars().all(|c| c.is_ascii_uppercase()) {
            run += 1;
            if run >= 5 {
                return true;
            }
        } else {
            run = 0;
        }
    }
    false
}

/// Reads the real modes of a `.f06` file.
///
/// # Errors
/// [`IoError::Io`] if unreadable; [`IoError::Parse`] with the line for a malformed row, complex
/// eigenvectors, a scalar point, a second subcase of eigenvectors, a mode printed twice with
/// different values; [`IoError::Content`] for a file without real eigenvectors.
pub fn read_f06(path: impl AsRef<Path>) -> Result<F06, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_f06(&String::from_utf8_lossy(&bytes), path)
}

/// Parses `.f06` text (`path` names it in messages).
///
/// # Errors
/// As [`read_f06`].
pub fn parse_f06(text: &str, path: &Path) -> Result<F06, IoError> {
    let mut eigenvalues: BTreeMap<usize, f64> = BTreeMap::new();
    let mut modes: BTreeMap<usize, F06Mode> = BTreeMap::new();
    let mut in_table = false;
    let mut current: Option<usize> = None;
    let mut block_eigenvalue: Option<f64> = None;
    let mut subcase: Option<(u64, usize)> = None;
    let mut vector_subcase: Option<(u64, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim_end_matches('\r');
        let trimmed = t.trim();
        if t.starts_with('1') {
            in_table = false;
            current = None;
            continue;
        }
        if trimmed.contains("C O M P L E X   E I G E N V E C T O R") {
            return Err(parse_error(
                path,
                line,
                "complex eigenvectors: femu reads the real modes of a normal modes run (SOL 103)"
                    .into(),
            ));
        }
        if let Some(rest) = trimmed.strip_prefix("0").map(str::trim).or(Some(trimmed))
            && let Some(n) = rest.strip_prefix("SUBCASE")
            && let Ok(n) = n.trim().parse::<u64>()
        {
            subcase = Some((n, line));
            continue;
        }
        if trimmed.contains("R E A L   E I G E N V A L U E S") {
            in_table = true;
            current = None;
            continue;
        }
        if let Some(pos) = trimmed.find("R E A L   E I G E N V E C T O R   N O .") {
            in_table = false;
            let n = trimmed[pos + "R E A L   E I G E N V E C T O R   N O .".len()..].trim();
            let n = n.parse::<usize>().map_err(|_| {
                parse_error(
                    path,
                    line,
                    format!("eigenvector number {n:?} is not a number"),
                )
            })?;
            match (vector_subcase, subcase) {
                (Some((a, first)), Some((b, _))) if a != b => {
                    return Err(parse_error(
                        path,
                        line,
                        format!(
                            "eigenvectors of subcase {b} after those of subcase {a} (line {first}): femu reads the modes of one subcase"
                        ),
                    ));
                }
                (None, s) => vector_subcase = s.or(Some((0, line))),
                _ => {}
            }
            // the table's eigenvalue; `EIGENVALUE = ...`, printed above the title, without one
            let eigenvalue = eigenvalues
                .get(&n)
                .copied()
                .or(block_eigenvalue)
                .ok_or_else(|| {
                    parse_error(
                        path,
                        line,
                        format!("eigenvector {n} has no eigenvalue (no EIGENVALUE = line, no row in the eigenvalue table)"),
                    )
                })?;
            modes.entry(n).or_insert_with(|| F06Mode {
                number: n,
                eigenvalue,
                points: Vec::new(),
                line,
            });
            current = Some(n);
            continue;
        }
        if let Some(v) = trimmed.strip_prefix("EIGENVALUE =") {
            block_eigenvalue = number(v.trim());
            continue;
        }
        if spaced_title(trimmed) {
            in_table = false;
            current = None;
            continue;
        }
        let f: Vec<&str> = trimmed.split_whitespace().collect();
        if in_table {
            if f.len() == 7
                && let (Ok(mode), Ok(_), Some(value)) =
                    (f[0].parse::<usize>(), f[1].parse::<usize>(), number(f[2]))
            {
                eigenvalues.insert(mode, value);
            }
            continue;
        }
        let Some(n) = current else {
            continue;
        };
        let Some(id) = f.first().and_then(|s| s.parse::<u64>().ok()) else {
            continue;
        };
        match f.get(1).copied() {
            Some("G") => {}
            Some("S") => {
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "scalar point {id} in eigenvector {n}: femu places modes on grid points only"
                    ),
                ));
            }
            _ => continue,
        }
        if f.len() != 8 {
            return Err(parse_error(
                path,
                line,
                format!(
                    "grid {id} of eigenvector {n} has {} values, not six (T1 T2 T3 R1 R2 R3)",
                    f.len().saturating_sub(2)
                ),
            ));
        }
        let mut v = [0.0; 6];
        for k in 0..6 {
            v[k] = number(f[k + 2]).ok_or_else(|| {
                parse_error(
                    path,
                    line,
                    format!(
                        "component {} of grid {id} in eigenvector {n} is {:?}, not a number",
                        ["T1", "T2", "T3", "R1", "R2", "R3"][k],
                        f[k + 2]
                    ),
                )
            })?;
        }
        let mode = modes.get_mut(&n).expect("the block's mode was entered");
        if mode.points.iter().any(|(g, _)| *g == id) {
            return Err(parse_error(
                path,
                line,
                format!("grid {id} is printed twice in eigenvector {n}"),
            ));
        }
        mode.points.push((id, v));
    }
    let modes: Vec<F06Mode> = modes
        .into_values()
        .filter(|m| !m.points.is_empty())
        .collect();
    if modes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no real eigenvectors (R E A L   E I G E N V E C T O R): ask Nastran to print them with DISPLACEMENT(PRINT) = ALL in the case control of the SOL 103 run".into(),
        });
    }
    let without_vectors = eigenvalues
        .keys()
        .filter(|k| !modes.iter().any(|m| m.number == **k))
        .count();
    Ok(F06 {
        modes,
        without_vectors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "                                              R E A L   E I G E N V A L U E S\n   MODE    EXTRACTION      EIGENVALUE            RADIANS             CYCLES            GENERALIZED         GENERALIZED\n    NO.       ORDER                                                                       MASS              STIFFNESS\n        1         1        2.005177E+05        4.477921E+02        7.126832E+01        1.000000E+00        2.005177E+05\n        2         2        2.277722E+05        4.772548E+02        7.595746E+01        1.000000E+00        2.277722E+05\n";

    fn block(n: usize, eigenvalue: &str, rows: &str) -> String {
        format!(
            "1    MSC.NASTRAN JOB          PAGE    13\n     DEFAULT\n0                                 SUBCASE 1\n      EIGENVALUE =  {eigenvalue}\n          CYCLES =  7.126832E+01         R E A L   E I G E N V E C T O R   N O .          {n}\n \n      POINT ID.   TYPE          T1             T2             T3             R1             R2             R3\n{rows}"
        )
    }

    /// A block over two pages, the SPC forces' table (same rows) after a page eject not read.
    #[test]
    fn blocks_across_pages() {
        let text = [
            TABLE.to_string(),
            block(1, "2.005177E+05", "             1      G     -2.931720E-01  -5.107800E-01  -1.129750E-01   2.192765E-01  -7.441864E-02  -2.423957E-01\n"),
            block(1, "2.005177E+05", "             5      G     -1.119760E-01  -9.700938E-01   1.571079E-01   0.0            0.0            0.0\n"),
            "1    MSC.NASTRAN JOB          PAGE    15\n0                                 SUBCASE 1\n      F O R C E S   O F   S I N G L E - P O I N T   C O N S T R A I N T\n      POINT ID.   TYPE          T1             T2             T3             R1             R2             R3\n            22      G      1.0            2.0            3.0            4.0            5.0            6.0\n".into(),
        ]
        .concat();
        let f = parse_f06(&text, Path::new("a.f06")).unwrap();
        assert_eq!(f.modes.len(), 1);
        assert_eq!(f.without_vectors, 1);
        let m = &f.modes[0];
        assert_eq!((m.number, m.eigenvalue), (1, 2.005177e5));
        assert_eq!(m.points.len(), 2);
        assert_eq!(
            m.points[1],
            (5, [-0.111976, -0.9700938, 0.1571079, 0.0, 0.0, 0.0])
        );
    }

    /// Each malformed file is refused with its line.
    #[test]
    fn refusals() {
        let row = "             1      G     -2.9E-01  -5.1E-01  -1.1E-01   2.1E-01  -7.4E-02  -2.4E-01\n";
        let cases = [
            (
                block(1, "2.0E+05", "             7      S      1.0\n"),
                "a.f06:8: scalar point 7",
            ),
            (
                block(1, "2.0E+05", "             7      G      1.0  2.0\n"),
                "a.f06:8: grid 7 of eigenvector 1 has 2 values",
            ),
            (
                block(
                    1,
                    "2.0E+05",
                    "             7      G      1.0  2.0  x  0 0 0\n",
                ),
                "a.f06:8: component T3 of grid 7",
            ),
            (
                block(1, "2.0E+05", &format!("{row}{row}")),
                "a.f06:9: grid 1 is printed twice",
            ),
            (
                format!(
                    "{}{}",
                    block(1, "2.0E+05", row),
                    block(2, "3.0E+05", row).replace("SUBCASE 1", "SUBCASE 2")
                ),
                "a.f06:13: eigenvectors of subcase 2 after those of subcase 1",
            ),
            (
                "      C O M P L E X   E I G E N V E C T O R   NO. 1\n".to_string(),
                "a.f06:1: complex eigenvectors",
            ),
            (TABLE.to_string(), "no real eigenvectors"),
        ];
        for (text, want) in cases {
            let e = parse_f06(&text, Path::new("a.f06"))
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{e}\nwanted {want}");
        }
    }
}
