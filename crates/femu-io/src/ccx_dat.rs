//! CalculiX's printed output (`job.dat`), read for the modes of a `*FREQUENCY` step: its
//! eigenvalue table and the displacements `*NODE PRINT` (with `U`) prints for each mode, another
//! solver's modes as the model side of a correlation (docs/ARCHITECTURE.md, "Models solved
//! elsewhere"). It holds no coordinates: the nodes come from the deck beside it.
//!
//! The layout is CalculiX's (its `.dat` output, the same for every version read here): the table
//! opens with `E I G E N V A L U E   O U T P U T` and lists, per mode, its number, the eigenvalue
//! (rad^2/time^2), the frequency in rad/time and in cycles/time, and the imaginary part; each
//! mode's results follow `E I G E N V A L U E    N U M B E R  k`, a displacement block opening
//! with `displacements (vx,vy,vz) for set NAME and time ...` and listing a node id and three
//! values per line (`E13.6`: seven significant digits, one more than the `.frd`'s).
//!
//! Other blocks (stresses, forces, participation factors, effective masses, the displacements of
//! a step before the frequency step) are skipped and counted; a second
//! eigenvalue table (another frequency step), a complex eigenvalue, a mode without displacements
//! and a node printed twice are refused with their line. A `.dat` is also a Nastran deck's
//! extension: [`looks_like_calculix`] tells them apart by CalculiX's headers.

use crate::IoError;
use std::path::Path;

/// One mode of the frequency step.
#[derive(Debug, Clone, PartialEq)]
pub struct DatMode {
    /// The mode's number in the eigenvalue table.
    pub number: usize,
    /// Frequency, Hz (cycles per time unit).
    pub frequency_hz: f64,
    /// The eigenvalue (rad/time)^2, as printed.
    pub eigenvalue: f64,
    /// Translations `(node, [u1, u2, u3])` in the order printed.
    pub shape: Vec<(u64, [f64; 3])>,
    /// The line of the mode's `E I G E N V A L U E    N U M B E R` header.
    pub line: usize,
}

/// What femu reads of a CalculiX `.dat` file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CalculixDat {
    /// The modes, in the table's order.
    pub modes: Vec<DatMode>,
    /// Result blocks skipped (other than displacements), by their title's first words, with counts.
    pub skipped: Vec<(String, usize)>,
}

/// A row of the eigenvalue table: mode, eigenvalue, frequency in cycles per time.
type Row = (usize, f64, f64);
/// A mode's printed displacements, node by node.
type Shape = Vec<(u64, [f64; 3])>;

const TABLE: &str = "E I G E N V A L U E   O U T P U T";
const MODE: &str = "E I G E N V A L U E    N U M B E R";

/// Whether `head` (a file's first few kilobytes) is CalculiX's printed output rather than a
/// Nastran deck: its first line with text is one of CalculiX's spaced headers (`E I G E N V A L U
/// E   O U T P U T`, `S T E P`, ...) or a result block's title (`displacements (vx,vy,vz) for set`).
pub fn looks_like_calculix(head: &str) -> bool {
    let Some(first) = head.lines().map(str::trim).find(|l| !l.is_empty()) else {
        return false;
    };
    // single capitals one space apart (a number may follow: `S T E P       1`)
    let words: Vec<&str> = first.split_whitespace().collect();
    let letters = words
        .iter()
        .take_while(|w| w.len() == 1 && w.chars().all(|c| c.is_ascii_uppercase()))
        .count();
    let spaced = letters >= 4
        && words[letters..]
            .iter()
            .all(|w| w.chars().all(|c| c.is_ascii_digit()))
        && words.len() <= letters + 1;
    spaced || first.starts_with("displacements (vx,vy,vz) for set")
}

fn perr(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

fn number(path: &Path, line: usize, s: &str) -> Result<f64, IoError> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(perr(path, line, format!("{s:?} is not a finite number"))),
    }
}

/// Reads a CalculiX `.dat` file ([`parse_calculix_dat`]).
///
/// # Errors
/// [`IoError::Io`], and [`parse_calculix_dat`]'s.
pub fn read_calculix_dat(path: impl AsRef<Path>) -> Result<CalculixDat, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    parse_calculix_dat(&text, path)
}

/// Parses a CalculiX `.dat` file's eigenvalue table and the displacements printed for its modes.
///
/// # Errors
/// No eigenvalue table, a second one (another frequency step), a complex eigenvalue, a line of the
/// table or of a displacement block that is not numbers, a mode without displacements (with the
/// keywords that print them), displacements of a mode the table lacks, a node printed twice for
/// one mode, modes printed at different nodes.
pub fn parse_calculix_dat(text: &str, path: &Path) -> Result<CalculixDat, IoError> {
    let lines: Vec<&str> = text.lines().collect();
    // the table's line and its rows (mode, eigenvalue, cycles per time)
    let mut table: Option<(usize, Vec<Row>)> = None;
    // per mode printed: its number, its header's line and its displacements
    let mut shapes: Vec<(usize, usize, Shape)> = Vec::new();
    let mut skipped: Vec<(String, usize)> = Vec::new();
    let mut current: Option<(usize, usize)> = None;
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim();
        let ln = i + 1;
        if t == TABLE {
            if let Some((at, _)) = &table {
                return Err(perr(
                    path,
                    ln,
                    format!(
                        "a second eigenvalue table (the first at line {at}): femu reads the modes of one frequency step"
                    ),
                ));
            }
            // the data lines: mode, eigenvalue, rad/time, cycles/time, imaginary part
            let mut rows = Vec::new();
            i += 1;
            while i < lines.len() {
                let f: Vec<&str> = lines[i].split_whitespace().collect();
                let first = f.first().map(|w| w.parse::<usize>());
                match first {
                    Some(Ok(n)) if f.len() == 5 => {
                        let v: Vec<f64> = f[1..]
                            .iter()
                            .map(|s| number(path, i + 1, s))
                            .collect::<Result<_, _>>()?;
                        if v[3] != 0.0 {
                            return Err(perr(
                                path,
                                i + 1,
                                format!(
                                    "mode {n} has the imaginary part {:e}: femu reads real modes",
                                    v[3]
                                ),
                            ));
                        }
                        rows.push((n, v[0], v[2]));
                    }
                    Some(Ok(_)) => {
                        return Err(perr(
                            path,
                            i + 1,
                            format!(
                                "an eigenvalue line needs five numbers (mode, eigenvalue, rad/time, cycles/time, imaginary part), found {}",
                                f.len()
                            ),
                        ));
                    }
                    // headers before the rows; a blank line or the next title after them
                    _ if rows.is_empty() => {}
                    _ => break,
                }
                i += 1;
            }
            table = Some((ln, rows));
            continue;
        }
        if let Some(rest) = t.strip_prefix(MODE) {
            let n = rest.trim().parse::<usize>().map_err(|_| {
                perr(
                    path,
                    ln,
                    format!("{rest:?} after the mode header is not a mode number"),
                )
            })?;
            current = Some((n, ln));
            i += 1;
            continue;
        }
        if let (true, Some((n, at))) = (t.starts_with("displacements (vx,vy,vz) for set"), current)
        {
            let mut shape = Vec::new();
            i += 1;
            while i < lines.len() {
                let f: Vec<&str> = lines[i].split_whitespace().collect();
                match f.first().map(|w| w.parse::<u64>()) {
                    Some(Ok(node)) => {
                        if f.len() != 4 {
                            return Err(perr(
                                path,
                                i + 1,
                                format!(
                                    "a displacement line needs a node and three values, found {} fields",
                                    f.len()
                                ),
                            ));
                        }
                        let v = [
                            number(path, i + 1, f[1])?,
                            number(path, i + 1, f[2])?,
                            number(path, i + 1, f[3])?,
                        ];
                        shape.push((node, v));
                    }
                    Some(Err(_)) => break,
                    None if shape.is_empty() => {}
                    None => break,
                }
                i += 1;
            }
            if let Some(prev) = shapes.iter_mut().find(|s| s.0 == n) {
                // a second block for the same mode (another node set printed): joined
                prev.2.extend(shape);
            } else {
                shapes.push((n, at, shape));
            }
            continue;
        }
        // another result block's title (stresses, forces, ...), or displacements of another
        // step (a static one before the frequency step): skipped
        if t.contains(" for set ") && t.contains(" and time ") {
            let name = t.split(" for set ").next().unwrap_or(t).to_string();
            match skipped.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1 += 1,
                None => skipped.push((name, 1)),
            }
        }
        i += 1;
    }
    let Some((_, rows)) = table else {
        return Err(perr(
            path,
            1,
            format!("no eigenvalue table ({TABLE}): femu reads the modes of a *FREQUENCY step"),
        ));
    };
    let mut modes = Vec::with_capacity(rows.len());
    for (number, eigenvalue, frequency_hz) in rows {
        let Some(k) = shapes.iter().position(|s| s.0 == number) else {
            return Err(perr(
                path,
                1,
                format!(
                    "mode {number} has no displacements: print them with *NODE PRINT and U in the *FREQUENCY step"
                ),
            ));
        };
        let (_, line, shape) = shapes.swap_remove(k);
        let mut ids: Vec<u64> = shape.iter().map(|s| s.0).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(perr(
                path,
                line,
                format!("mode {number} prints node {} twice", w[0]),
            ));
        }
        if let Some(first) = modes.first().map(|m: &DatMode| &m.shape) {
            let same =
                first.len() == shape.len() && first.iter().zip(&shape).all(|(a, b)| a.0 == b.0);
            if !same {
                return Err(perr(
                    path,
                    line,
                    format!("mode {number} is printed at other nodes than mode 1"),
                ));
            }
        }
        modes.push(DatMode {
            number,
            frequency_hz,
            eigenvalue,
            shape,
            line,
        });
    }
    if let Some((n, line, _)) = shapes.first() {
        return Err(perr(
            path,
            *line,
            format!("displacements of mode {n}, which the eigenvalue table does not list"),
        ));
    }
    Ok(CalculixDat { modes, skipped })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_tell_calculix_from_nastran() {
        assert!(looks_like_calculix(
            "\n     E I G E N V A L U E   O U T P U T\n\n MODE NO"
        ));
        assert!(looks_like_calculix("\n  S T E P       1\n"));
        assert!(!looks_like_calculix("SOL 103\nCEND\nBEGIN BULK\n"));
        assert!(!looks_like_calculix("$ a comment\nGRID,1,,0.,0.,0.\n"));
        assert!(!looks_like_calculix("   \n  \n"));
        assert!(!looks_like_calculix("ID A B\nSOL 103\n"));
    }

    const HEAD: &str = "\n     E I G E N V A L U E   O U T P U T\n\n MODE NO    EIGENVALUE\n\n      1   0.4000000E+02   0.6324555E+01   0.1006584E+01   0.0000000E+00\n\n";
    const MODE1: &str = "                    E I G E N V A L U E    N U M B E R     1\n\n\n displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n         1  1.000000E+00 -2.000000E-01  0.000000E+00\n         2  5.000000E-01  0.000000E+00  3.000000E-02\n";

    /// A table and a mode read as written; each malformed case refused with its line.
    #[test]
    fn a_small_dat_and_its_refusals() {
        let p = Path::new("job.dat");
        let d = parse_calculix_dat(&format!("{HEAD}{MODE1}"), p).unwrap();
        assert_eq!(d.modes.len(), 1);
        let m = &d.modes[0];
        assert_eq!(
            (m.number, m.eigenvalue, m.frequency_hz),
            (1, 40.0, 1.006584)
        );
        assert_eq!(m.shape, vec![(1, [1.0, -0.2, 0.0]), (2, [0.5, 0.0, 0.03])]);
        let bad = |text: String, what: &str, line: usize| {
            let e = parse_calculix_dat(&text, p).unwrap_err().to_string();
            assert!(
                e.contains(what) && e.contains(&format!("job.dat:{line}")),
                "{e}"
            );
        };
        // a static step's displacements before the frequency step: skipped, counted
        let stat = " displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n         1  1.0E+00  0.0E+00  0.0E+00\n";
        let d = parse_calculix_dat(&format!("{stat}{HEAD}{MODE1}"), p).unwrap();
        assert_eq!(d.modes.len(), 1);
        assert_eq!(d.skipped, vec![("displacements (vx,vy,vz)".to_string(), 1)]);
        bad(HEAD.to_string(), "print them with *NODE PRINT", 1);
        bad(MODE1.to_string(), "no eigenvalue table", 1);
        bad(
            format!("{HEAD}{MODE1}{HEAD}"),
            "second eigenvalue table",
            16,
        );
        bad(
            HEAD.replace("0.0000000E+00\n", "0.1000000E+01\n") + MODE1,
            "imaginary part",
            6,
        );
        bad(
            format!("{HEAD}{MODE1}")
                .replace("         2  5.000000E-01", "         1  5.000000E-01"),
            "node 1 twice",
            8,
        );
        bad(
            format!("{HEAD}{MODE1}").replace("-2.000000E-01", "-2.0000x0E-01"),
            "not a finite number",
            13,
        );
        bad(
            format!(
                "{HEAD}{MODE1}{}",
                MODE1.replace("N U M B E R     1", "N U M B E R     2")
            ),
            "mode 2, which the eigenvalue table does not list",
            15,
        );
    }
}
