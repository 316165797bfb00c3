//! CalculiX's result file (`.frd`, ASCII), read for its nodes and the mode shapes of its
//! frequency steps: another solver's modes as the model side of a correlation (docs/ARCHITECTURE.md,
//! "Models solved elsewhere").
//!
//! The format is CalculiX GraphiX's (its manual, "Result Format"); records are fixed columns:
//! - `    2C` opens the nodes, each `-1` + node id + three coordinates (`E12.5`), up to `-3`; the
//!   block's format flag says whether ids take 5 columns (0, short) or 10 (1, long); 2 (binary)
//!   is refused;
//! - `  100C` opens a result block: its set name (columns 7-12), value (13-24: the frequency in
//!   cycles per time for a frequency step), node count, type, step number (59-63), analysis name
//!   (64-73: `MODAL` for a `*FREQUENCY` step) and format flag (74-75); then `-4` names the result (`DISP`), `-5` its components, and `-1` records
//!   hold a node id and its values, which may touch (`-1.2E-02-3.4E-03`), up to `-3`.
//!
//! femu reads every `DISP` block of a `MODAL` analysis; the other blocks (stresses, static steps)
//! are skipped, and `DISPI` (the imaginary part of a complex mode) is refused.

use crate::IoError;
use std::collections::HashMap;
use std::path::Path;

/// One mode of a frequency step.
#[derive(Debug, Clone, PartialEq)]
pub struct FrdMode {
    /// The mode's number in its step (the block's step number).
    pub number: usize,
    /// Frequency, Hz (cycles per time unit).
    pub frequency_hz: f64,
    /// Translations `[u1, u2, u3]` per node, in the order of [`Frd::nodes`]; nodes the block does
    /// not list are zero.
    pub shape: Vec<[f64; 3]>,
    /// The line of the block's header.
    pub line: usize,
}

/// What femu reads of a `.frd` file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frd {
    /// Node ids and coordinates, in file order.
    pub nodes: Vec<(u64, [f64; 3])>,
    /// The modes of its frequency steps, in file order.
    pub modes: Vec<FrdMode>,
    /// Result blocks skipped (not displacements of a frequency step), by name, with counts.
    pub skipped: Vec<(String, usize)>,
}

fn parse_error(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// Columns `a..b` (0-based, clipped to the line), trimmed.
fn field(t: &str, a: usize, b: usize) -> &str {
    let b = b.min(t.len());
    if a >= b {
        return "";
    }
    t.get(a..b).unwrap_or("").trim()
}

/// A `-1` record: the id (`id_width` columns after ` -1`) and `count` values of 12 columns each.
fn record(
    t: &str,
    id_width: usize,
    count: usize,
    path: &Path,
    line: usize,
) -> Result<(u64, Vec<f64>), IoError> {
    let id = field(t, 3, 3 + id_width);
    let id = id.parse::<u64>().map_err(|_| {
        parse_error(
            path,
            line,
            format!(
                "a node record needs an id in columns 4-{}, got {id:?}",
                3 + id_width
            ),
        )
    })?;
    let mut values = Vec::with_capacity(count);
    for k in 0..count {
        let a = 3 + id_width + 12 * k;
        let s = field(t, a, a + 12);
        let v = s
            .replace(['D', 'd'], "E")
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                parse_error(
                    path,
                    line,
                    format!(
                        "value {} of node {id} (columns {}-{}) is {s:?}, not a finite number",
                        k + 1,
                        a + 1,
                        a + 12
                    ),
                )
            })?;
        values.push(v);
    }
    Ok((id, values))
}

/// The id width of a block's format flag: 0 short (5), 1 long (10); 2 (binary) refused.
fn id_width(flag: &str, path: &Path, line: usize) -> Result<usize, IoError> {
    match flag {
        "" | "0" => Ok(5),
        "1" => Ok(10),
        other => Err(parse_error(
            path,
            line,
            format!(
                "format {other:?}: femu reads ASCII .frd files (format 0 or 1); write the results as ASCII (CalculiX's default)"
            ),
        )),
    }
}

/// Reads a CalculiX `.frd` file's nodes and frequency-step mode shapes.
///
/// # Errors
/// [`IoError::Io`] if unreadable; [`IoError::Parse`] with the line for a malformed record, a binary
/// block, a complex mode (`DISPI`), a result on a node the file does not define, a node defined
/// twice; [`IoError::Content`] for a file without nodes or without a frequency step's
/// displacements.
pub fn read_frd(path: impl AsRef<Path>) -> Result<Frd, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_frd(&String::from_utf8_lossy(&bytes), path)
}

/// Parses `.frd` text (`path` names it in messages).
///
/// # Errors
/// As [`read_frd`].
pub fn parse_frd(text: &str, path: &Path) -> Result<Frd, IoError> {
    let mut frd = Frd::default();
    let mut index: HashMap<u64, usize> = HashMap::new();
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let mut skipped: HashMap<String, usize> = HashMap::new();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i];
        let line = i + 1;
        if t.starts_with("    2C") {
            let width = id_width(field(t, 73, 74), path, line)?;
            i += 1;
            while i < lines.len() && !lines[i].starts_with(" -3") {
                if lines[i].starts_with(" -1") {
                    let (id, x) = record(lines[i], width, 3, path, i + 1)?;
                    if index.insert(id, frd.nodes.len()).is_some() {
                        return Err(parse_error(
                            path,
                            i + 1,
                            format!("node {id} is defined twice"),
                        ));
                    }
                    frd.nodes.push((id, [x[0], x[1], x[2]]));
                }
                i += 1;
            }
        } else if t.starts_with("  100C") {
            let value = field(t, 12, 24);
            let step = field(t, 58, 63);
            let analysis = field(t, 63, 73);
            let width = id_width(field(t, 73, 75), path, line)?;
            // the -4 record names the result
            let name_line = i + 1;
            let name = lines
                .get(name_line)
                .map_or("", |l| field(l, 5, 13))
                .to_string();
            if name == "DISPI" && analysis.eq_ignore_ascii_case("MODAL") {
                return Err(parse_error(
                    path,
                    name_line + 1,
                    "DISPI: the imaginary part of a complex mode; femu reads real modes of a *FREQUENCY step".into(),
                ));
            }
            let wanted = analysis.eq_ignore_ascii_case("MODAL") && name == "DISP";
            if !wanted {
                *skipped
                    .entry(format!(
                        "{name} ({})",
                        if analysis.is_empty() { "-" } else { analysis }
                    ))
                    .or_default() += 1;
            }
            let mut mode = wanted
                .then(|| -> Result<FrdMode, IoError> {
                    let frequency_hz = value
                        .parse::<f64>()
                        .ok()
                        .filter(|f| f.is_finite() && *f >= 0.0)
                        .ok_or_else(|| {
                            parse_error(
                                path,
                                line,
                                format!(
                                    "the block's value (columns 13-24, the frequency) is {value:?}"
                                ),
                            )
                        })?;
                    let number = step.parse::<usize>().map_err(|_| {
                        parse_error(
                            path,
                            line,
                            format!("the block's step number (columns 59-63) is {step:?}"),
                        )
                    })?;
                    Ok(FrdMode {
                        number,
                        frequency_hz,
                        shape: vec![[0.0; 3]; frd.nodes.len()],
                        line,
                    })
                })
                .transpose()?;
            i += 1;
            while i < lines.len() && !lines[i].starts_with(" -3") {
                if let (Some(m), true) = (mode.as_mut(), lines[i].starts_with(" -1")) {
                    let (id, u) = record(lines[i], width, 3, path, i + 1)?;
                    let n = *index.get(&id).ok_or_else(|| {
                        parse_error(
                            path,
                            i + 1,
                            format!("a displacement of node {id}, which the file's nodes (2C) do not define"),
                        )
                    })?;
                    m.shape[n] = [u[0], u[1], u[2]];
                }
                i += 1;
            }
            frd.modes.extend(mode);
        }
        i += 1;
    }
    if frd.nodes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no nodes (no 2C block)".into(),
        });
    }
    if frd.modes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no mode shapes: no DISP block of a frequency step (MODAL); ask CalculiX for them with *NODE FILE, U in the *FREQUENCY step".into(),
        });
    }
    let mut skipped: Vec<(String, usize)> = skipped.into_iter().collect();
    skipped.sort();
    frd.skipped = skipped;
    Ok(frd)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nodes_header(count: usize, flag: u8) -> String {
        format!("    2C{:18}{count:>12}{:37}{flag}\n", "", "")
    }

    fn block_header(value: &str, nodes: usize, step: usize, analysis: &str, flag: u8) -> String {
        format!(
            "  100CL  101{value:>12}{nodes:>12}{:20}{:>2}{step:>5}{analysis:<10}{flag:>2}\n",
            "", 2
        )
    }

    fn node(id: u64, v: [&str; 3]) -> String {
        format!(" -1{id:>10}{:>12}{:>12}{:>12}\n", v[0], v[1], v[2])
    }

    /// Two nodes, values that touch, a static step's displacements and a stress block skipped,
    /// and a block in the short format (5-column ids).
    #[test]
    fn records_by_columns() {
        let text = [
            "    1C\n".to_string(),
            nodes_header(2, 1),
            node(7, ["1.00000E+00", "0.00000E+00", "-2.50000E-01"]),
            node(12, ["0.00000E+00", "2.00000E+00", "0.00000E+00"]),
            " -3\n".into(),
            block_header("12.50000000", 2, 1, "MODAL", 1),
            " -4  DISP        4    1\n -5  D1          1    2    1    0\n".into(),
            node(7, ["-1.00000E-02", "2.00000E-02", "-3.00000E-02"]),
            node(12, ["4.00000E-01", "0.00000E+00", "0.00000E+00"]),
            " -3\n".into(),
            block_header("0.00000E+00", 2, 1, "STATIC", 1),
            " -4  DISP        4    1\n".into(),
            node(7, ["1.0", "1.0", "1.0"]),
            " -3\n".into(),
            block_header("12.50000000", 2, 1, "MODAL", 0),
            " -4  STRESS      6    1\n -1    7 1.00000E+00 2.00000E+00 3.00000E+00\n -3\n".into(),
            block_header("31.25", 2, 2, "MODAL", 0),
            " -4  DISP        4    1\n -1   12 1.00000E+00 2.00000E+00 3.00000E+00\n -3\n 9999\n"
                .into(),
        ]
        .concat();
        assert!(text.contains("-1.00000E-02 2.00000E-02-3.00000E-02"));
        let f = parse_frd(&text, Path::new("a.frd")).unwrap();
        assert_eq!(f.nodes, [(7, [1.0, 0.0, -0.25]), (12, [0.0, 2.0, 0.0])]);
        assert_eq!(f.modes.len(), 2);
        assert_eq!(f.modes[0].frequency_hz, 12.5);
        assert_eq!(f.modes[0].number, 1);
        assert_eq!(f.modes[0].shape, [[-0.01, 0.02, -0.03], [0.4, 0.0, 0.0]]);
        assert_eq!(f.modes[1].number, 2);
        assert_eq!(f.modes[1].shape, [[0.0; 3], [1.0, 2.0, 3.0]]);
        assert_eq!(
            f.skipped,
            [
                ("DISP (STATIC)".to_string(), 1),
                ("STRESS (MODAL)".to_string(), 1)
            ]
        );
    }

    /// Each malformed file is refused with its line.
    #[test]
    fn refusals() {
        let nodes = [
            nodes_header(1, 1),
            node(7, ["1.00000E+00", "0.00000E+00", "0.00000E+00"]),
            " -3\n".into(),
        ]
        .concat();
        let head = block_header("12.50000000", 1, 1, "MODAL", 1);
        let cases = [
            (
                format!("{nodes}{head} -4  DISPI       4    1\n -3\n"),
                "a.frd:5: DISPI",
            ),
            (
                format!(
                    "{nodes}{head} -4  DISP        4    1\n{}",
                    node(9, ["1.0", "0.0", "0.0"])
                ),
                "a.frd:6: a displacement of node 9",
            ),
            (
                format!(
                    "{nodes}{head} -4  DISP        4    1\n{}",
                    node(7, ["1.0", "abc", "0.0"])
                ),
                "a.frd:6: value 2 of node 7",
            ),
            (nodes_header(1, 2), "a.frd:1: format \"2\""),
            (format!("{nodes} 9999\n"), "no mode shapes"),
            ("    1C\n".to_string(), "no nodes"),
        ];
        for (text, want) in cases {
            let e = parse_frd(&text, Path::new("a.frd"))
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{e}\nwanted {want}");
        }
    }
}
