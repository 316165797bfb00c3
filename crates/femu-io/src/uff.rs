//! Universal File Format (what test systems export), read and written: datasets 15 and 2411
//! (nodes), 2412 (elements), 164 (units), 55 (modal data: real normal modes and complex modes),
//! 58 and its binary variant 58b (functions at nodal DOFs: FRFs, time histories, spectra), 82
//! (trace lines) and 2477 (permanent groups: the sets of [`Universal::to_mesh`]). Other datasets are skipped with a warning naming their number and line. Fortran
//! `D` exponents and CRLF line ends are read; a file written by femu reads back to the same bytes.
//!
//! Dataset 58b: records 1-11 as text, then the values as raw IEEE numbers in the byte order of
//! the header (little or big endian), 4 bytes each for single-precision data (ordinate types 2,
//! 5) and 8 for double (4, 6), an uneven abscissa in the same precision as the ordinate (as
//! pyuff and the files it reads do). The byte count is computed from record 7 (points, type,
//! spacing); a header that says otherwise gets a warning.

use crate::{IoError, Warning};
use faer::Mat;
use femu_correlate::{Sensor, TestModes};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Units of dataset 164.
#[derive(Debug, Clone, PartialEq)]
pub struct UffUnits {
    /// Unit system code (1 = SI: m, N, s).
    pub code: i64,
    /// Description.
    pub description: String,
    /// Length, force, temperature factors to SI.
    pub factors: [f64; 3],
}

/// One node of dataset 15.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UffNode {
    /// Node label.
    pub id: u64,
    /// Coordinates.
    pub x: [f64; 3],
}

/// One mode of dataset 55.
#[derive(Debug, Clone, PartialEq)]
pub struct UffMode {
    /// Mode number (record 7).
    pub number: i64,
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Viscous damping ratio.
    pub damping: f64,
    /// Modal mass (0 when not given).
    pub modal_mass: f64,
    /// Per node: the translations (x, y, z); for complex data the real-normalised values (each
    /// mode rotated by the phase of its largest component, then the real part).
    pub values: Vec<(u64, [f64; 3])>,
    /// Whether the file stored complex values.
    pub complex: bool,
}

/// The supported content of a universal file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Universal {
    /// Dataset 164, if present.
    pub units: Option<UffUnits>,
    /// Nodes of dataset 15 (single precision) or 2411 (double precision).
    pub nodes: Vec<UffNode>,
    /// Whether the nodes came from (and are written as) dataset 2411 instead of 15.
    pub nodes_2411: bool,
    /// Dataset 2412 elements.
    pub elements: Vec<UffElement>,
    /// Dataset 55 modes.
    pub modes: Vec<UffMode>,
    /// Dataset 58/58b functions (FRFs, time histories, ...).
    pub functions: Vec<UffFunction>,
    /// Dataset 82 trace lines.
    pub trace_lines: Vec<UffTraceLine>,
    /// Dataset 2477 (and 2467) permanent groups.
    pub groups: Vec<UffGroup>,
    /// Skipped datasets and approximations.
    pub warnings: Vec<Warning>,
}

/// One element of dataset 2412.
#[derive(Debug, Clone, PartialEq)]
pub struct UffElement {
    /// Element label.
    pub id: u64,
    /// FE descriptor id (111 linear tetrahedron, 112 linear wedge, 115 linear brick, ...).
    pub descriptor: i64,
    /// Node labels in the file's order.
    pub nodes: Vec<u64>,
}

/// An axis of dataset 58 (records 8-11: abscissa, ordinate numerator, ordinate denominator,
/// z axis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UffAxis {
    /// Specific data type (0 unknown, 1 general, 8 displacement, 12 acceleration, 13 excitation
    /// force, 17 time, 18 frequency, ...).
    pub data_type: i64,
    /// Length, force and temperature unit exponents.
    pub exponents: [i64; 3],
    /// Axis label (20 characters at most when written).
    pub label: String,
    /// Units label (20 characters at most when written).
    pub units: String,
}

/// The abscissa of a dataset 58 function.
#[derive(Debug, Clone, PartialEq)]
pub enum Abscissa {
    /// `min + k step` (record 7; written with 6 significant digits, as the format has them).
    Even {
        /// First abscissa.
        min: f64,
        /// Increment.
        step: f64,
    },
    /// One abscissa per point, stored with the values.
    Uneven(Vec<f64>),
}

/// The ordinate values of a dataset 58 function.
#[derive(Debug, Clone, PartialEq)]
pub enum Ordinate {
    /// Real values.
    Real(Vec<f64>),
    /// Complex values as (real, imaginary).
    Complex(Vec<(f64, f64)>),
}

impl Ordinate {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Ordinate::Real(v) => v.len(),
            Ordinate::Complex(v) => v.len(),
        }
    }

    /// Whether there is no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A response or reference DOF of dataset 58 (record 6).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct UffDof {
    /// Entity name (10 characters at most when written).
    pub entity: String,
    /// Node label (0 when none).
    pub node: u64,
    /// Direction: 1-3 translations X-Z, 4-6 rotations, negative for the opposite sense, 0 scalar.
    pub direction: i64,
}

/// One function of dataset 58 (ASCII) or 58b (binary).
#[derive(Debug, Clone, PartialEq)]
pub struct UffFunction {
    /// Records 1-5: identification lines (record 3 is usually the date).
    pub ids: [String; 5],
    /// Function type (0 general, 1 time response, 2 auto spectrum, 3 cross spectrum, 4 frequency
    /// response function, 6 coherence, 9 power spectral density, ...).
    pub function_type: i64,
    /// Function identification number, version number, load case.
    pub numbers: [i64; 3],
    /// Response DOF.
    pub response: UffDof,
    /// Reference DOF.
    pub reference: UffDof,
    /// Whether the values are double precision (ordinate data types 4 and 6) or single (2, 5).
    pub double: bool,
    /// Abscissa.
    pub abscissa: Abscissa,
    /// Z-axis value (record 7).
    pub z_value: f64,
    /// Records 8-11.
    pub axes: [UffAxis; 4],
    /// Values.
    pub ordinate: Ordinate,
    /// Read from, and written as, binary 58b.
    pub binary: bool,
}

impl UffFunction {
    /// The abscissa of each point.
    pub fn abscissa_values(&self) -> Vec<f64> {
        match &self.abscissa {
            Abscissa::Even { min, step } => (0..self.ordinate.len())
                .map(|k| min + k as f64 * step)
                .collect(),
            Abscissa::Uneven(x) => x.clone(),
        }
    }

    /// Ordinate data type of record 7: 2 real single, 4 real double, 5 complex single, 6 complex
    /// double.
    fn data_type(&self) -> i64 {
        match (&self.ordinate, self.double) {
            (Ordinate::Real(_), false) => 2,
            (Ordinate::Real(_), true) => 4,
            (Ordinate::Complex(_), false) => 5,
            (Ordinate::Complex(_), true) => 6,
        }
    }

    /// Values stored per point (abscissa included when uneven).
    fn per_point(&self) -> usize {
        let even = matches!(self.abscissa, Abscissa::Even { .. });
        match (&self.ordinate, even) {
            (Ordinate::Real(_), true) => 1,
            (Ordinate::Real(_), false) | (Ordinate::Complex(_), true) => 2,
            (Ordinate::Complex(_), false) => 3,
        }
    }

    /// The stored values in file order.
    fn stored(&self) -> Vec<f64> {
        let x = match &self.abscissa {
            Abscissa::Uneven(x) => Some(x),
            Abscissa::Even { .. } => None,
        };
        let mut v = Vec::with_capacity(self.ordinate.len() * self.per_point());
        for k in 0..self.ordinate.len() {
            if let Some(x) = x {
                v.push(x.get(k).copied().unwrap_or(0.0));
            }
            match &self.ordinate {
                Ordinate::Real(y) => v.push(y[k]),
                Ordinate::Complex(y) => v.extend([y[k].0, y[k].1]),
            }
        }
        v
    }
}

/// One permanent group of dataset 2477: named lists of nodes and elements (what FE
/// pre-processors and Gmsh's physical groups write), the sets of [`Universal::to_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct UffGroup {
    /// Group number.
    pub number: i64,
    /// Group name (40 characters at most when written).
    pub name: String,
    /// Node labels (entity type 7).
    pub nodes: Vec<u64>,
    /// Element labels (entity type 8).
    pub elements: Vec<u64>,
}

/// One trace line of dataset 82: a polyline through nodes, `0` lifting the pen.
#[derive(Debug, Clone, PartialEq)]
pub struct UffTraceLine {
    /// Trace line number.
    pub number: i64,
    /// Colour number.
    pub color: i64,
    /// Identification line.
    pub id: String,
    /// Node labels, `0` for "move to the next node without drawing".
    pub nodes: Vec<u64>,
}

/// I-DEAS parabolic solids list each face's nodes corner, mid-edge, corner, ... : femu
/// (Abaqus) order `femu[k] = unv[PERM[k]]`. Tetrahedron 118: corners 0 2 4 9, mid-edges 1 (0-2),
/// 3 (2-4), 5 (4-0), 6 (0-9), 7 (2-9), 8 (4-9).
const UNV_TET10: [usize; 10] = [0, 2, 4, 9, 1, 3, 5, 6, 7, 8];
/// Wedge 113: bottom loop 0-5, vertical mid-edges 6 7 8, top loop 9-14.
const UNV_PENTA15: [usize; 15] = [0, 2, 4, 9, 11, 13, 1, 3, 5, 10, 12, 14, 6, 7, 8];
/// Brick 116: bottom loop 0-7, vertical mid-edges 8-11, top loop 12-19.
const UNV_HEX20: [usize; 20] = [
    0, 2, 4, 6, 12, 14, 16, 18, 1, 3, 5, 7, 13, 15, 17, 19, 8, 9, 10, 11,
];

/// Beam descriptors carry an extra orientation record in dataset 2412.
fn is_beam(descriptor: i64) -> bool {
    matches!(descriptor, 11 | 21..=24)
}

fn perr(path: &Path, line: usize, reason: impl Into<String>) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason: reason.into(),
    }
}

fn num(path: &Path, line: usize, tok: &str) -> Result<f64, IoError> {
    let t = tok.replace(['D', 'd'], "E");
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(perr(path, line, format!("'{tok}' is not a finite number"))),
    }
}

fn int(path: &Path, line: usize, tok: &str) -> Result<i64, IoError> {
    tok.parse::<i64>()
        .map_err(|_| perr(path, line, format!("'{tok}' is not an integer")))
}

/// Numbers of a line; `want` of them at least.
fn nums(path: &Path, line: usize, text: &str, want: usize) -> Result<Vec<f64>, IoError> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|t| num(path, line, t))
        .collect::<Result<_, _>>()?;
    if v.len() < want {
        return Err(perr(
            path,
            line,
            format!("expected {want} numbers, found {}", v.len()),
        ));
    }
    Ok(v)
}

fn ints(path: &Path, line: usize, text: &str, want: usize) -> Result<Vec<i64>, IoError> {
    let v: Vec<i64> = text
        .split_whitespace()
        .map(|t| int(path, line, t))
        .collect::<Result<_, _>>()?;
    if v.len() < want {
        return Err(perr(
            path,
            line,
            format!("expected {want} integers, found {}", v.len()),
        ));
    }
    Ok(v)
}

/// Reads a universal file.
///
/// # Errors
/// [`IoError::Io`] when the file cannot be read; [`IoError::Parse`] with the line for malformed
/// content.
pub fn read_uff(path: impl AsRef<Path>) -> Result<Universal, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_uff_bytes(&bytes, path)
}

/// Parses universal-file text (`path` names it in errors). Binary datasets (58b) need
/// [`parse_uff_bytes`].
///
/// # Errors
/// [`IoError::Parse`] with the line for malformed content.
pub fn parse_uff(text: &str, path: &Path) -> Result<Universal, IoError> {
    parse_uff_bytes(text.as_bytes(), path)
}

/// Lines of a byte buffer with their 1-based numbers; binary blocks are taken by length.
struct ByteLines<'a> {
    b: &'a [u8],
    at: usize,
    line: usize,
}

impl<'a> ByteLines<'a> {
    /// The next line (without `\r\n`), its number, as text (invalid UTF-8 replaced).
    fn next_line(&mut self) -> Option<(usize, std::borrow::Cow<'a, str>)> {
        if self.at >= self.b.len() {
            return None;
        }
        let start = self.at;
        let end = self.b[start..]
            .iter()
            .position(|c| *c == b'\n')
            .map_or(self.b.len(), |p| start + p);
        self.at = if end < self.b.len() { end + 1 } else { end };
        self.line += 1;
        let raw = &self.b[start..end];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        Some((self.line, String::from_utf8_lossy(raw)))
    }
}

/// Parses a universal file's bytes, text and binary datasets (`path` names it in errors).
///
/// # Errors
/// [`IoError::Parse`] with the line (and byte offset in binary data) for malformed content.
pub fn parse_uff_bytes(bytes: &[u8], path: &Path) -> Result<Universal, IoError> {
    let mut src = ByteLines {
        b: bytes,
        at: 0,
        line: 0,
    };
    let mut out = Universal::default();
    while let Some((ln, l)) = src.next_line() {
        if l.trim().is_empty() {
            continue;
        }
        if l.trim() != "-1" {
            return Err(perr(
                path,
                ln,
                format!(
                    "expected the dataset delimiter '-1', found '{}'",
                    l.trim().chars().take(40).collect::<String>()
                ),
            ));
        }
        let (start, head) = src
            .next_line()
            .ok_or_else(|| perr(path, ln, "dataset without its closing '-1'"))?;
        if head.trim() == "-1" {
            return Err(perr(path, start, "empty dataset"));
        }
        let number = head.split_whitespace().next().unwrap_or("").to_string();
        if let Some(base) = number.strip_suffix(['b', 'B']) {
            if base != "58" {
                return Err(perr(
                    path,
                    start,
                    format!("binary dataset {number}: femu reads binary 58b only"),
                ));
            }
            out.functions
                .push(parse_58b(path, &mut src, start, &head, &mut out.warnings)?);
            // the closing delimiter follows the binary block
            loop {
                let (l2, t) = src
                    .next_line()
                    .ok_or_else(|| perr(path, start, "dataset 58b without its closing '-1'"))?;
                match t.trim() {
                    "" => continue,
                    "-1" => break,
                    other => {
                        return Err(perr(
                            path,
                            l2,
                            format!(
                                "expected '-1' after the binary data of dataset 58b, found '{}'",
                                other.chars().take(40).collect::<String>()
                            ),
                        ));
                    }
                }
            }
            continue;
        }
        let kind = int(path, start, &number)?;
        let mut owned: Vec<(usize, String)> = Vec::new();
        loop {
            let (l2, t) = src
                .next_line()
                .ok_or_else(|| perr(path, ln, "dataset without its closing '-1'"))?;
            if t.trim() == "-1" {
                break;
            }
            owned.push((l2, t.into_owned()));
        }
        let body: Vec<(usize, &str)> = owned.iter().map(|(l2, t)| (*l2, t.as_str())).collect();
        match kind {
            15 => parse_15(path, &body, &mut out)?,
            2411 => parse_2411(path, &body, &mut out)?,
            2412 => parse_2412(path, &body, &mut out)?,
            164 => parse_164(path, &body, &mut out)?,
            55 => parse_55(path, &body, &mut out)?,
            58 => {
                let (f, count) = parse_58_header(path, &body, start)?;
                let values = parse_58_ascii(path, &body[11..], &f)?;
                out.functions
                    .push(finish_58(path, f, values, count, start)?);
            }
            82 => parse_82(path, &body, &mut out)?,
            2467 | 2477 => parse_2477(path, &body, &mut out)?,
            other => out.warnings.push(Warning {
                path: path.to_path_buf(),
                line: start,
                message: format!("dataset {other} is not read by femu (skipped)"),
            }),
        }
    }
    Ok(out)
}

/// A fixed-width field of a record (blank when the line is shorter).
fn col(l: &str, from: usize, to: usize) -> &str {
    let to = to.min(l.len());
    if from >= to {
        return "";
    }
    l.get(from..to).unwrap_or("")
}

/// An integer field of fixed columns (blank = 0).
fn col_int(path: &Path, ln: usize, l: &str, from: usize, to: usize) -> Result<i64, IoError> {
    match col(l, from, to).trim() {
        "" => Ok(0),
        t => int(path, ln, t),
    }
}

/// Dataset 58 records 1-11, as a function without values, and the count of stored values.
fn parse_58_header(
    path: &Path,
    body: &[(usize, &str)],
    start: usize,
) -> Result<(UffFunction, usize), IoError> {
    if body.len() < 11 {
        return Err(perr(
            path,
            start,
            format!("dataset 58 needs 11 header records, found {}", body.len()),
        ));
    }
    let ids: [String; 5] = std::array::from_fn(|k| body[k].1.trim_end().to_string());
    let (l6, r6) = body[5];
    let dof = |name: (usize, usize),
               node: (usize, usize),
               dir: (usize, usize)|
     -> Result<UffDof, IoError> {
        let n = col_int(path, l6, r6, node.0, node.1)?;
        if n < 0 {
            return Err(perr(
                path,
                l6,
                format!("node label {n} must not be negative"),
            ));
        }
        Ok(UffDof {
            entity: col(r6, name.0, name.1).trim().to_string(),
            node: n as u64,
            direction: col_int(path, l6, r6, dir.0, dir.1)?,
        })
    };
    let function_type = col_int(path, l6, r6, 0, 5)?;
    let numbers = [
        col_int(path, l6, r6, 5, 15)?,
        col_int(path, l6, r6, 15, 20)?,
        col_int(path, l6, r6, 20, 30)?,
    ];
    let response = dof((31, 41), (41, 51), (51, 55))?;
    let reference = dof((56, 66), (66, 76), (76, 80))?;
    let (l7, r7) = body[6];
    let t = ints_then_nums(path, l7, r7)?;
    let (data_type, points, spacing) = (t.0[0], t.0[1], t.0[2]);
    let (min, step, z_value) = (t.1[0], t.1[1], t.1[2]);
    let (double, complex) = match data_type {
        2 => (false, false),
        4 => (true, false),
        5 => (false, true),
        6 => (true, true),
        o => {
            return Err(perr(
                path,
                l7,
                format!("ordinate data type {o}: expected 2, 4 (real) or 5, 6 (complex)"),
            ));
        }
    };
    if !(0..=100_000_000).contains(&points) || !(spacing == 0 || spacing == 1) {
        return Err(perr(
            path,
            l7,
            format!(
                "{points} points with abscissa spacing {spacing}: need 0..1e8 points and spacing 0 (uneven) or 1 (even)"
            ),
        ));
    }
    let axes: [UffAxis; 4] = {
        let mut a: [UffAxis; 4] = Default::default();
        for (k, axis) in a.iter_mut().enumerate() {
            let (ln, l) = body[7 + k];
            *axis = UffAxis {
                data_type: col_int(path, ln, l, 0, 10)?,
                exponents: [
                    col_int(path, ln, l, 10, 15)?,
                    col_int(path, ln, l, 15, 20)?,
                    col_int(path, ln, l, 20, 25)?,
                ],
                label: col(l, 26, 46).trim().to_string(),
                units: col(l, 47, 67).trim().to_string(),
            };
        }
        a
    };
    let even = spacing == 1;
    let f = UffFunction {
        ids,
        function_type,
        numbers,
        response,
        reference,
        double,
        abscissa: if even {
            Abscissa::Even { min, step }
        } else {
            Abscissa::Uneven(Vec::new())
        },
        z_value,
        axes,
        ordinate: if complex {
            Ordinate::Complex(Vec::new())
        } else {
            Ordinate::Real(Vec::new())
        },
        binary: false,
    };
    let per_point = match (complex, even) {
        (false, true) => 1,
        (true, false) => 3,
        _ => 2,
    };
    let count = points as usize * per_point;
    Ok((f, count))
}

/// Record 7: three integers (I10) then three reals (E13.5), by columns, or separated by blanks.
fn ints_then_nums(path: &Path, ln: usize, l: &str) -> Result<([i64; 3], [f64; 3]), IoError> {
    let by_columns = || -> Result<([i64; 3], [f64; 3]), IoError> {
        let mut r = [0.0; 3];
        for (k, v) in r.iter_mut().enumerate() {
            *v = match col(l, 30 + 13 * k, 43 + 13 * k).trim() {
                "" => 0.0,
                t => num(path, ln, t)?,
            };
        }
        Ok((
            [
                col_int(path, ln, l, 0, 10)?,
                col_int(path, ln, l, 10, 20)?,
                col_int(path, ln, l, 20, 30)?,
            ],
            r,
        ))
    };
    by_columns().or_else(|e| {
        let t: Vec<&str> = l.split_whitespace().collect();
        if t.len() != 6 {
            return Err(e);
        }
        Ok((
            [
                int(path, ln, t[0])?,
                int(path, ln, t[1])?,
                int(path, ln, t[2])?,
            ],
            [
                num(path, ln, t[3])?,
                num(path, ln, t[4])?,
                num(path, ln, t[5])?,
            ],
        ))
    })
}

/// The values of record 12 as text: blank-separated numbers, or fields of 13 and 20 columns run
/// together (the widths of the data type).
fn parse_58_ascii(
    path: &Path,
    body: &[(usize, &str)],
    f: &UffFunction,
) -> Result<Vec<f64>, IoError> {
    let widths: &[usize] = match (f.data_type(), f.per_point()) {
        (2 | 5, _) => &[13],
        (4, 2) => &[13, 20],
        (6, 3) => &[13, 20, 20],
        _ => &[20],
    };
    let mut v = Vec::new();
    for &(ln, l) in body {
        if l.trim().is_empty() {
            continue;
        }
        match nums(path, ln, l, 1) {
            Ok(x) => v.extend(x),
            Err(e) => {
                // fields run together: cut by the format's widths
                let (mut at, mut k) = (0, 0);
                let mut any = false;
                while at < l.len() {
                    let w = widths[k % widths.len()];
                    let t = col(l, at, at + w).trim();
                    if !t.is_empty() {
                        v.push(num(path, ln, t)?);
                        any = true;
                    }
                    at += w;
                    k += 1;
                }
                if !any {
                    return Err(e);
                }
            }
        }
    }
    Ok(v)
}

/// Puts the stored values into the function, checking their count.
fn finish_58(
    path: &Path,
    mut f: UffFunction,
    values: Vec<f64>,
    count: usize,
    start: usize,
) -> Result<UffFunction, IoError> {
    let per = f.per_point();
    if values.len() != count || count == 0 {
        return Err(perr(
            path,
            start,
            format!(
                "dataset 58: record 7 announces {} points ({count} values), {} values found",
                count / per,
                values.len()
            ),
        ));
    }
    let points = values.len() / per;
    let complex = matches!(f.ordinate, Ordinate::Complex(_));
    let off = usize::from(matches!(f.abscissa, Abscissa::Uneven(_)));
    if off == 1 {
        f.abscissa = Abscissa::Uneven((0..points).map(|k| values[k * per]).collect());
    }
    f.ordinate = if complex {
        Ordinate::Complex(
            (0..points)
                .map(|k| (values[k * per + off], values[k * per + off + 1]))
                .collect(),
        )
    } else {
        Ordinate::Real((0..points).map(|k| values[k * per + off]).collect())
    };
    Ok(f)
}

/// Dataset 58b: the header line's fields, the 11 text records, then the binary values.
fn parse_58b(
    path: &Path,
    src: &mut ByteLines<'_>,
    start: usize,
    head: &str,
    warnings: &mut Vec<Warning>,
) -> Result<UffFunction, IoError> {
    let h: Vec<i64> = head
        .split_whitespace()
        .skip(1)
        .map(|t| int(path, start, t))
        .collect::<Result<_, _>>()?;
    if h.len() < 4 {
        return Err(perr(
            path,
            start,
            "dataset 58b header: expected byte order, number format, text lines and bytes",
        ));
    }
    let big = match h[0] {
        1 => false,
        2 => true,
        o => {
            return Err(perr(
                path,
                start,
                format!("byte order {o}: expected 1 (little endian) or 2 (big endian)"),
            ));
        }
    };
    if h[1] != 2 {
        return Err(perr(
            path,
            start,
            format!("number format {}: femu reads IEEE 754 (2) only", h[1]),
        ));
    }
    if h[2] != 11 {
        return Err(perr(
            path,
            start,
            format!("{} text records: dataset 58b has 11", h[2]),
        ));
    }
    let mut owned = Vec::with_capacity(11);
    for _ in 0..11 {
        let (l, t) = src
            .next_line()
            .ok_or_else(|| perr(path, start, "dataset 58b ends inside its 11 text records"))?;
        owned.push((l, t.into_owned()));
    }
    // a delimiter among the text records is a truncated dataset, not an identification line
    if let Some((l, _)) = owned.iter().find(|(_, t)| t.trim() == "-1") {
        return Err(perr(
            path,
            *l,
            "dataset 58b ends inside its 11 text records",
        ));
    }
    let body: Vec<(usize, &str)> = owned.iter().map(|(l, t)| (*l, t.as_str())).collect();
    let (mut f, count) = parse_58_header(path, &body, start)?;
    let size = if f.double { 8 } else { 4 };
    let bytes = count * size;
    if h[3] != bytes as i64 {
        warnings.push(Warning {
            path: path.to_path_buf(),
            line: start,
            message: format!(
                "dataset 58b: the header says {} bytes, record 7 needs {bytes} ({count} values of {size} bytes); read {bytes}",
                h[3]
            ),
        });
    }
    let at = src.at;
    if src.b.len() - at < bytes {
        return Err(perr(
            path,
            src.line + 1,
            format!(
                "dataset 58b: {bytes} bytes of values expected, the file has {} left (byte offset {at})",
                src.b.len() - at
            ),
        ));
    }
    let data = &src.b[at..at + bytes];
    let mut values = Vec::with_capacity(count);
    for (k, c) in data.chunks_exact(size).enumerate() {
        let v = if f.double {
            let a: [u8; 8] = c.try_into().expect("8 bytes");
            if big {
                f64::from_be_bytes(a)
            } else {
                f64::from_le_bytes(a)
            }
        } else {
            let a: [u8; 4] = c.try_into().expect("4 bytes");
            (if big {
                f32::from_be_bytes(a)
            } else {
                f32::from_le_bytes(a)
            }) as f64
        };
        if !v.is_finite() {
            return Err(perr(
                path,
                src.line + 1,
                format!(
                    "dataset 58b: value {k} is {v} (byte offset {})",
                    at + k * size
                ),
            ));
        }
        values.push(v);
    }
    // the newlines inside the binary block still count as lines for later messages
    src.line += data.iter().filter(|c| **c == b'\n').count();
    src.at = at + bytes;
    f.binary = true;
    finish_58(path, f, values, count, start)
}

/// Dataset 2477: per group a header (8I10, the last the entity count), the name, then entities
/// as (type, tag, 0, 0) quadruples, two per line; types other than nodes (7) and elements (8)
/// are skipped with a warning.
fn parse_2477(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    let mut k = 0;
    while k < body.len() {
        let (ln, l) = body[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        let h = ints(path, ln, l, 8)?;
        let (number, count) = (h[0], h[7]);
        if !(0..=100_000_000).contains(&count) {
            return Err(perr(path, ln, format!("group {number}: {count} entities")));
        }
        let name = body
            .get(k + 1)
            .ok_or_else(|| perr(path, ln, format!("group {number} without its name")))?
            .1
            .trim()
            .to_string();
        k += 2;
        let mut group = UffGroup {
            number,
            name,
            nodes: Vec::new(),
            elements: Vec::new(),
        };
        let mut read = 0;
        let mut other = 0;
        while read < count {
            let (ln2, l2) = *body.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!("group {number}: {count} entities announced, {read} found"),
                )
            })?;
            let v = ints(path, ln2, l2, 4)?;
            for q in v.chunks(4) {
                if q.len() < 4 {
                    return Err(perr(
                        path,
                        ln2,
                        "an entity needs 4 integers (type, tag, 0, 0)",
                    ));
                }
                if read == count {
                    return Err(perr(
                        path,
                        ln2,
                        format!("group {number}: more than the {count} entities announced"),
                    ));
                }
                if q[1] <= 0 {
                    return Err(perr(
                        path,
                        ln2,
                        format!("entity tag {} must be positive", q[1]),
                    ));
                }
                match q[0] {
                    7 => group.nodes.push(q[1] as u64),
                    8 => group.elements.push(q[1] as u64),
                    _ => other += 1,
                }
                read += 1;
            }
            k += 1;
        }
        if other > 0 {
            out.warnings.push(Warning {
                path: path.to_path_buf(),
                line: ln,
                message: format!(
                    "group {}: {other} entities neither nodes nor elements skipped",
                    group.name
                ),
            });
        }
        out.groups.push(group);
    }
    Ok(())
}

fn parse_82(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    if body.len() < 2 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 82 needs a header, an identification line and node labels",
        ));
    }
    let (ln, l) = body[0];
    let h = ints(path, ln, l, 3)?;
    let (number, count, color) = (h[0], h[1], h[2]);
    let mut nodes = Vec::new();
    for &(ln2, l2) in &body[2..] {
        if l2.trim().is_empty() {
            continue;
        }
        for v in ints(path, ln2, l2, 1)? {
            if v < 0 {
                return Err(perr(
                    path,
                    ln2,
                    format!("node label {v} must not be negative"),
                ));
            }
            nodes.push(v as u64);
        }
    }
    if count < 0 || nodes.len() != count as usize {
        return Err(perr(
            path,
            ln,
            format!(
                "trace line {number}: {count} node labels announced, {} found",
                nodes.len()
            ),
        ));
    }
    out.trace_lines.push(UffTraceLine {
        number,
        color,
        id: body[1].1.trim_end().to_string(),
        nodes,
    });
    Ok(())
}

fn parse_15(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    for &(ln, l) in body {
        if l.trim().is_empty() {
            continue;
        }
        let t: Vec<&str> = l.split_whitespace().collect();
        if t.len() < 7 {
            return Err(perr(
                path,
                ln,
                format!("a dataset 15 node needs 7 fields, found {}", t.len()),
            ));
        }
        let id = int(path, ln, t[0])?;
        if id <= 0 {
            return Err(perr(path, ln, format!("node label {id} must be positive")));
        }
        let x = [
            num(path, ln, t[4])?,
            num(path, ln, t[5])?,
            num(path, ln, t[6])?,
        ];
        out.nodes.push(UffNode { id: id as u64, x });
    }
    Ok(())
}

fn parse_2411(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    let lines: Vec<(usize, &str)> = body
        .iter()
        .copied()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    if !lines.len().is_multiple_of(2) {
        return Err(perr(
            path,
            lines.last().map_or(0, |l| l.0),
            "dataset 2411: a node without its coordinate record",
        ));
    }
    for pair in lines.chunks(2) {
        let (ln, l) = pair[0];
        let h = ints(path, ln, l, 4)?;
        if h[0] <= 0 {
            return Err(perr(
                path,
                ln,
                format!("node label {} must be positive", h[0]),
            ));
        }
        let x = nums(path, pair[1].0, pair[1].1, 3)?;
        out.nodes.push(UffNode {
            id: h[0] as u64,
            x: [x[0], x[1], x[2]],
        });
    }
    out.nodes_2411 = true;
    Ok(())
}

fn parse_2412(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    let lines: Vec<(usize, &str)> = body
        .iter()
        .copied()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    let mut k = 0;
    while k < lines.len() {
        let (ln, l) = lines[k];
        let h = ints(path, ln, l, 6)?;
        let (id, descriptor, count) = (h[0], h[1], h[5]);
        if id <= 0 || !(1..=27).contains(&count) {
            return Err(perr(
                path,
                ln,
                format!("element {id}: label must be positive and node count 1-27, found {count}"),
            ));
        }
        k += 1;
        if is_beam(descriptor) {
            k += 1; // orientation record
        }
        let mut nodes = Vec::with_capacity(count as usize);
        while nodes.len() < count as usize {
            let (ln2, l2) = *lines.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!(
                        "element {id}: {count} node labels expected, found {}",
                        nodes.len()
                    ),
                )
            })?;
            for v in ints(path, ln2, l2, 1)? {
                if v <= 0 {
                    return Err(perr(
                        path,
                        ln2,
                        format!("element {id}: node label {v} must be positive"),
                    ));
                }
                nodes.push(v as u64);
            }
            k += 1;
        }
        if nodes.len() != count as usize {
            return Err(perr(
                path,
                ln,
                format!(
                    "element {id}: {count} node labels expected, found {}",
                    nodes.len()
                ),
            ));
        }
        out.elements.push(UffElement {
            id: id as u64,
            descriptor,
            nodes,
        });
    }
    Ok(())
}

fn parse_164(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    if body.len() < 2 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 164 needs 2 records",
        ));
    }
    let (ln, l) = body[0];
    let code = int(path, ln, l.get(..10).unwrap_or(l).trim())?;
    let description = l.get(10..30).unwrap_or("").trim().to_string();
    let f = nums(path, body[1].0, body[1].1, 3)?;
    out.units = Some(UffUnits {
        code,
        description,
        factors: [f[0], f[1], f[2]],
    });
    Ok(())
}

fn parse_55(path: &Path, body: &[(usize, &str)], out: &mut Universal) -> Result<(), IoError> {
    if body.len() < 8 {
        return Err(perr(
            path,
            body.first().map_or(0, |b| b.0),
            "dataset 55 needs at least 8 records",
        ));
    }
    let (l6, r6) = body[5];
    let h = ints(path, l6, r6, 6)?;
    let (analysis, characteristic, data_type, ndv) = (h[1], h[2], h[4], h[5]);
    if !(characteristic == 2 || characteristic == 3) {
        return Err(perr(
            path,
            l6,
            format!("data characteristic {characteristic}: femu reads translations (2 or 3)"),
        ));
    }
    let complex = match data_type {
        2 => false,
        5 => true,
        o => {
            return Err(perr(
                path,
                l6,
                format!("data type {o}: expected 2 (real) or 5 (complex)"),
            ));
        }
    };
    // 3 translations, or 6 with rotations; an absurd count is an error, not an allocation
    if !(3..=6).contains(&ndv) {
        return Err(perr(
            path,
            l6,
            format!("{ndv} values per node: expected 3 (translations) to 6 (with rotations)"),
        ));
    }
    let (l7, r7) = body[6];
    let r7v = ints(path, l7, r7, 4)?;
    let (nint, nrdv) = (r7v[0], r7v[1]);
    let number = r7v.get(3).copied().unwrap_or(0);
    // the real parameters may wrap over several lines of 6
    let per_line = 6usize;
    let rec8_lines = (nrdv.max(0) as usize).div_ceil(per_line).max(1);
    let _ = nint;
    let mut reals = Vec::new();
    for k in 0..rec8_lines {
        let (ln, l) = *body
            .get(7 + k)
            .ok_or_else(|| perr(path, l7, "record 8 is missing"))?;
        reals.extend(nums(path, ln, l, 1)?);
    }
    let (frequency_hz, modal_mass, damping) = match analysis {
        2 => {
            if reals.len() < 3 {
                return Err(perr(
                    path,
                    body[7].0,
                    "a normal mode needs frequency, modal mass and damping",
                ));
            }
            (reals[0], reals[1], reals[2])
        }
        3 => {
            if reals.len() < 2 {
                return Err(perr(path, body[7].0, "a complex mode needs its eigenvalue"));
            }
            let (re, im) = (reals[0], reals[1]);
            let w = re.hypot(im);
            (
                w / (2.0 * std::f64::consts::PI),
                0.0,
                if w > 0.0 { -re / w } else { 0.0 },
            )
        }
        o => {
            return Err(perr(
                path,
                l6,
                format!("analysis type {o}: femu reads normal (2) and complex (3) modes"),
            ));
        }
    };
    if !(frequency_hz > 0.0) {
        return Err(perr(
            path,
            body[7].0,
            format!("frequency {frequency_hz} Hz must be positive"),
        ));
    }
    let width = if complex {
        2 * ndv as usize
    } else {
        ndv as usize
    };
    let mut values = Vec::new();
    let mut raw: Vec<(u64, Vec<f64>)> = Vec::new();
    let mut k = 7 + rec8_lines;
    while k < body.len() {
        let (ln, l) = body[k];
        if l.trim().is_empty() {
            k += 1;
            continue;
        }
        let node = int(path, ln, l.split_whitespace().next().unwrap_or(""))?;
        if node <= 0 {
            return Err(perr(
                path,
                ln,
                format!("node label {node} must be positive"),
            ));
        }
        let mut v = Vec::with_capacity(width);
        k += 1;
        while v.len() < width {
            let (ln2, l2) = *body.get(k).ok_or_else(|| {
                perr(
                    path,
                    ln,
                    format!("node {node}: {width} values expected, found {}", v.len()),
                )
            })?;
            v.extend(nums(path, ln2, l2, 1)?);
            k += 1;
        }
        if v.len() != width {
            return Err(perr(
                path,
                ln,
                format!("node {node}: {width} values expected, found {}", v.len()),
            ));
        }
        raw.push((node as u64, v));
    }
    if complex {
        // rotate by the phase of the largest component: a real mode stored as complex comes back exactly
        let (mut best, mut phase) = (0.0, 0.0);
        for (_, v) in &raw {
            for c in 0..3 {
                let (re, im) = (v[2 * c], v[2 * c + 1]);
                if re.hypot(im) > best {
                    best = re.hypot(im);
                    phase = im.atan2(re);
                }
            }
        }
        let (cs, sn) = (phase.cos(), phase.sin());
        for (n, v) in raw {
            let r = |c: usize| v[2 * c] * cs + v[2 * c + 1] * sn;
            values.push((n, [r(0), r(1), r(2)]));
        }
    } else {
        for (n, v) in raw {
            values.push((n, [v[0], v[1], v[2]]));
        }
    }
    out.modes.push(UffMode {
        number,
        frequency_hz,
        damping,
        modal_mass,
        values,
        complex,
    });
    Ok(())
}

fn e13(v: f64) -> String {
    efmt(v, 13, 5)
}

/// Fortran `1PEw.d`: `d.dddde+xx`, right-aligned in `w`, with a leading blank always: a
/// three-digit exponent (beyond Fortran's) would otherwise run into the previous field (found by
/// the fuzzer). Non-finite values are written as they are (the reader refuses them, naming the
/// line).
fn efmt(v: f64, w: usize, d: usize) -> String {
    let s = format!("{v:.d$E}");
    let body = match s.split_once('E').map(|(m, e)| (m, e.parse::<i32>())) {
        Some((m, Ok(e))) => format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs()),
        _ => s,
    };
    format!(" {body:>width$}", width = w - 1)
}

/// ASCII only, at most `n` characters (fixed-width text fields); a text that would read as the
/// dataset delimiter `-1` is bracketed (found by the fuzzer: an identification line of
/// non-ASCII bytes around "-1" became the delimiter when written).
fn field(text: &str, n: usize) -> String {
    let t = text
        .chars()
        .filter(|c| c.is_ascii_graphic() || *c == ' ')
        .take(n)
        .collect::<String>()
        .trim()
        .to_string();
    if t == "-1" { "(-1)".into() } else { t }
}

/// Dataset 58 records 1-11 (after the header line).
fn function_records(f: &UffFunction, s: &mut String) {
    for id in &f.ids {
        let _ = writeln!(s, "{}", field(id, 80));
    }
    let dof = |d: &UffDof| {
        format!(
            " {:<10}{:>10}{:>4}",
            field(&d.entity, 10),
            d.node,
            d.direction
        )
    };
    let _ = writeln!(
        s,
        "{:>5}{:>10}{:>5}{:>10}{}{}",
        f.function_type,
        f.numbers[0],
        f.numbers[1],
        f.numbers[2],
        dof(&f.response),
        dof(&f.reference)
    );
    let (spacing, min, step) = match f.abscissa {
        Abscissa::Even { min, step } => (1, min, step),
        Abscissa::Uneven(_) => (0, 0.0, 0.0),
    };
    let _ = writeln!(
        s,
        "{:>10}{:>10}{:>10}{}{}{}",
        f.data_type(),
        f.ordinate.len(),
        spacing,
        e13(min),
        e13(step),
        e13(f.z_value)
    );
    for a in &f.axes {
        let _ = writeln!(
            s,
            "{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}",
            a.data_type,
            a.exponents[0],
            a.exponents[1],
            a.exponents[2],
            field(&a.label, 20),
            field(&a.units, 20)
        );
    }
}

/// Dataset 58 (ASCII) or 58b (binary, little endian) of one function.
fn function_bytes(f: &UffFunction, binary: bool, out: &mut Vec<u8>) {
    let values = f.stored();
    let mut s = String::from("    -1\n");
    let size = if f.double { 8 } else { 4 };
    if binary {
        let _ = writeln!(
            s,
            "{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}",
            58,
            1,
            2,
            11,
            values.len() * size,
            0,
            0,
            0,
            0
        );
    } else {
        s.push_str("    58\n");
    }
    function_records(f, &mut s);
    if binary {
        out.extend(s.as_bytes());
        for v in &values {
            if f.double {
                out.extend(v.to_le_bytes());
            } else {
                out.extend((*v as f32).to_le_bytes());
            }
        }
        out.extend(b"    -1\n");
        return;
    }
    // record 12: the widths of the data type, as many per line as the format has
    let (widths, per_line): (&[usize], usize) = match (f.data_type(), f.per_point()) {
        (2 | 5, _) => (&[13], 6),
        (4, 2) => (&[13, 20], 4),
        (6, 3) => (&[13, 20, 20], 3),
        _ => (&[20], 4),
    };
    for row in values.chunks(per_line) {
        for (k, v) in row.iter().enumerate() {
            let w = widths[k % widths.len()];
            s.push_str(&efmt(*v, w, if w == 13 { 5 } else { 12 }));
        }
        s.push('\n');
    }
    s.push_str("    -1\n");
    out.extend(s.as_bytes());
}

/// Dataset 82.
fn trace_line_text(t: &UffTraceLine, s: &mut String) {
    s.push_str("    -1\n    82\n");
    let _ = writeln!(s, "{:>10}{:>10}{:>10}", t.number, t.nodes.len(), t.color);
    let _ = writeln!(s, "{}", field(&t.id, 80));
    for chunk in t.nodes.chunks(8) {
        let row: Vec<String> = chunk.iter().map(|n| format!("{n:>10}")).collect();
        let _ = writeln!(s, "{}", row.concat());
    }
    s.push_str("    -1\n");
}

/// The whole file as bytes: [`uff_string`]'s datasets, with the functions marked binary as 58b.
pub fn uff_bytes(u: &Universal) -> Vec<u8> {
    let mut out = head_text(u).into_bytes();
    for f in &u.functions {
        function_bytes(f, f.binary, &mut out);
    }
    let mut s = String::new();
    for t in &u.trace_lines {
        trace_line_text(t, &mut s);
    }
    out.extend(s.as_bytes());
    out
}

/// Writes units, nodes, elements, real normal modes, functions and trace lines as datasets 164,
/// 2411 or 15, 2412, 55, 58 and 82, all as text (functions read from 58b included: use
/// [`uff_bytes`] to keep them binary).
pub fn uff_string(u: &Universal) -> String {
    let mut bytes = head_text(u).into_bytes();
    for f in &u.functions {
        function_bytes(f, false, &mut bytes);
    }
    let mut s = String::from_utf8(bytes).expect("text datasets are ASCII");
    for t in &u.trace_lines {
        trace_line_text(t, &mut s);
    }
    s
}

/// Datasets 164, 2411/15, 2412 and 55.
fn head_text(u: &Universal) -> String {
    let mut s = String::new();
    if let Some(units) = &u.units {
        s.push_str("    -1\n   164\n");
        // fixed columns I10, 20A1, I10: the description as the reader sees it (ASCII, 20 chars)
        let description: String = units
            .description
            .chars()
            .filter(|c| c.is_ascii_graphic() || *c == ' ')
            .take(20)
            .collect();
        let _ = writeln!(s, "{:>10}{:<20}{:>10}", units.code, description.trim(), 2);
        let _ = writeln!(
            s,
            " {:>24.17E} {:>24.17E} {:>24.17E}",
            units.factors[0], units.factors[1], units.factors[2]
        )
        .map(|_| ());
        s.push_str(&format!(" {:>24.17E}\n", 273.15));
        s.push_str("    -1\n");
    }
    if !u.nodes.is_empty() && u.nodes_2411 {
        s.push_str("    -1\n  2411\n");
        for n in &u.nodes {
            let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9}", n.id, 1, 1, 11);
            let _ = writeln!(
                s,
                " {:>24.16E} {:>24.16E} {:>24.16E}",
                n.x[0], n.x[1], n.x[2]
            );
        }
        s.push_str("    -1\n");
    }
    if !u.elements.is_empty() {
        s.push_str("    -1\n  2412\n");
        for e in &u.elements {
            let _ = writeln!(
                s,
                " {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
                e.id,
                e.descriptor,
                1,
                1,
                7,
                e.nodes.len()
            );
            if is_beam(e.descriptor) {
                let _ = writeln!(s, " {:>9} {:>9} {:>9}", 0, 1, 1);
            }
            for chunk in e.nodes.chunks(8) {
                let row: Vec<String> = chunk.iter().map(|n| format!(" {n:>9}")).collect();
                let _ = writeln!(s, "{}", row.concat());
            }
        }
        s.push_str("    -1\n");
    }
    if !u.groups.is_empty() {
        s.push_str("    -1\n  2477\n");
        for g in &u.groups {
            let entities: Vec<(i64, u64)> = g
                .nodes
                .iter()
                .map(|n| (7, *n))
                .chain(g.elements.iter().map(|e| (8, *e)))
                .collect();
            let _ = writeln!(
                s,
                "{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}",
                g.number,
                0,
                0,
                0,
                0,
                0,
                0,
                entities.len()
            );
            let _ = writeln!(s, "{}", field(&g.name, 40));
            for pair in entities.chunks(2) {
                let row: Vec<String> = pair
                    .iter()
                    .map(|(t, n)| format!("{t:>10}{n:>10}{:>10}{:>10}", 0, 0))
                    .collect();
                let _ = writeln!(s, "{}", row.concat());
            }
        }
        s.push_str("    -1\n");
    }
    if !u.nodes.is_empty() && !u.nodes_2411 {
        s.push_str("    -1\n    15\n");
        for n in &u.nodes {
            let _ = writeln!(
                s,
                " {:>9} {:>9} {:>9} {:>9}{}{}{}",
                n.id,
                0,
                0,
                11,
                e13(n.x[0]),
                e13(n.x[1]),
                e13(n.x[2])
            );
        }
        s.push_str("    -1\n");
    }
    for m in &u.modes {
        s.push_str("    -1\n    55\n");
        for line in [
            format!("mode {}", m.number),
            "femu".to_string(),
            "NONE".to_string(),
            "NONE".to_string(),
            "NONE".to_string(),
        ] {
            let _ = writeln!(s, "{line}");
        }
        let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}", 1, 2, 2, 8, 2, 3);
        let _ = writeln!(s, " {:>9} {:>9} {:>9} {:>9}", 2, 4, 1, m.number);
        let _ = writeln!(
            s,
            "{}{}{}{}",
            e13(m.frequency_hz),
            e13(m.modal_mass),
            e13(m.damping),
            e13(0.0)
        );
        for (n, v) in &m.values {
            let _ = writeln!(s, "{n:>10}");
            let _ = writeln!(s, "{}{}{}", e13(v[0]), e13(v[1]), e13(v[2]));
        }
        s.push_str("    -1\n");
    }
    s
}

/// Writes [`uff_bytes`] to a file.
///
/// # Errors
/// [`IoError::Io`].
pub fn write_uff(path: impl AsRef<Path>, u: &Universal) -> Result<(), IoError> {
    let path = path.as_ref();
    std::fs::write(path, uff_bytes(u)).map_err(|e| IoError::io(path, e))
}

impl Universal {
    /// The femu mesh of the file's nodes and solid elements: linear (descriptors 111 tetrahedron,
    /// 112 wedge, 115 brick, whose node orders are Abaqus') and parabolic (118, 113, 116, whose
    /// I-DEAS orders interleave corners and mid-edge nodes around each face: converted, see
    /// `UNV_HEX20`); other elements (shells, beams) are skipped and counted in the returned
    /// warnings.
    ///
    /// # Errors
    /// A wrong node count (element label), a mesh error (duplicate or missing node), no solid.
    pub fn to_mesh(&self, path: &Path) -> Result<(femu_fem::mesh::Mesh, Vec<Warning>), IoError> {
        use femu_fem::element::ElementKind;
        let model_err = |source| IoError::Model {
            path: path.to_path_buf(),
            line: 0,
            source,
        };
        let mut mesh = femu_fem::mesh::Mesh::new();
        for n in &self.nodes {
            mesh.add_node(n.id, n.x).map_err(model_err)?;
        }
        let mut skipped = 0;
        for e in &self.elements {
            let (kind, order): (ElementKind, &[usize]) = match e.descriptor {
                111 => (ElementKind::Tet4, &[0, 1, 2, 3]),
                112 => (ElementKind::Penta6, &[0, 1, 2, 3, 4, 5]),
                115 => (ElementKind::Hex8, &[0, 1, 2, 3, 4, 5, 6, 7]),
                118 => (ElementKind::Tet10, &UNV_TET10),
                113 => (ElementKind::Penta15, &UNV_PENTA15),
                116 => (ElementKind::Hex20, &UNV_HEX20),
                _ => {
                    skipped += 1;
                    continue;
                }
            };
            if e.nodes.len() != order.len() {
                return Err(IoError::Parse {
                    path: path.to_path_buf(),
                    line: 0,
                    reason: format!(
                        "element {}: descriptor {} needs {} nodes, found {}",
                        e.id,
                        e.descriptor,
                        order.len(),
                        e.nodes.len()
                    ),
                });
            }
            let nodes: Vec<u64> = order.iter().map(|&k| e.nodes[k]).collect();
            mesh.add_element(e.id, kind, &nodes).map_err(model_err)?;
        }
        if mesh.element_count() == 0 {
            return Err(IoError::Parse {
                path: path.to_path_buf(),
                line: 0,
                reason: "no solid element (descriptors 111-118) in dataset 2412".into(),
            });
        }
        // groups: solid elements make an element set; every element (shells and beams too) and
        // node of a group puts its nodes in the node set of that name (where clamps and sensors
        // go), as Gmsh does with physical groups
        let by_id: std::collections::HashMap<u64, &UffElement> =
            self.elements.iter().map(|e| (e.id, e)).collect();
        for g in &self.groups {
            let mut nodes: Vec<u64> = g.nodes.clone();
            let mut solids = Vec::new();
            for id in &g.elements {
                let e = by_id.get(id).ok_or_else(|| IoError::Parse {
                    path: path.to_path_buf(),
                    line: 0,
                    reason: format!("group {}: element {id} is not in dataset 2412", g.name),
                })?;
                nodes.extend(&e.nodes);
                if mesh.element_index(*id).is_some() {
                    solids.push(*id);
                }
            }
            nodes.sort_unstable();
            nodes.dedup();
            let set_err = |e| IoError::Parse {
                path: path.to_path_buf(),
                line: 0,
                reason: format!("group {}: {e}", g.name),
            };
            if !solids.is_empty() {
                mesh.add_element_set(g.name.clone(), &solids)
                    .map_err(set_err)?;
            }
            if !nodes.is_empty() {
                mesh.add_node_set(g.name.clone(), &nodes).map_err(set_err)?;
            }
        }
        let mut warnings = Vec::new();
        if skipped > 0 {
            warnings.push(Warning {
                path: path.to_path_buf(),
                line: 0,
                message: format!("{skipped} non-solid elements (shells, beams) skipped"),
            });
        }
        Ok((mesh, warnings))
    }

    /// The test modes and sensors of the file's dataset-55 modes: one sensor per node and axis
    /// whose value is non-zero in some mode (test systems write unmeasured directions as zeros),
    /// in node order then x, y, z. `path` names the file in errors.
    ///
    /// # Errors
    /// No modes, modes on different node lists, no non-zero value, invalid frequencies.
    pub fn test_data(&self, path: &Path) -> Result<crate::csv::TestData, IoError> {
        let bad = |reason: String| IoError::Parse {
            path: PathBuf::from(path),
            line: 0,
            reason,
        };
        let first = self
            .modes
            .first()
            .ok_or_else(|| bad("no dataset 55 (modal data) in the file".into()))?;
        let nodes: Vec<u64> = first.values.iter().map(|(n, _)| *n).collect();
        for m in &self.modes {
            let these: Vec<u64> = m.values.iter().map(|(n, _)| *n).collect();
            if these != nodes {
                return Err(bad(format!(
                    "mode {} is given on other nodes than mode {}",
                    m.number, first.number
                )));
            }
        }
        let mut sensors = Vec::new();
        let mut rows = Vec::new();
        for (k, n) in nodes.iter().enumerate() {
            for c in 0..3 {
                if self.modes.iter().any(|m| m.values[k].1[c] != 0.0) {
                    sensors.push(Sensor::axis(*n, c));
                    rows.push((k, c));
                }
            }
        }
        if sensors.is_empty() {
            return Err(bad("every mode shape value is zero".into()));
        }
        let shapes = Mat::from_fn(rows.len(), self.modes.len(), |r, j| {
            let (k, c) = rows[r];
            self.modes[j].values[k].1[c]
        });
        let damping = self.modes.iter().map(|m| m.damping).collect();
        let modes = TestModes::new(
            self.modes.iter().map(|m| m.frequency_hz).collect(),
            Some(damping),
            shapes,
        )
        .map_err(|e| bad(e.to_string()))?;
        Ok(crate::csv::TestData { sensors, modes })
    }
}
