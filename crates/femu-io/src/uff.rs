//! Universal File Format (what test systems export): datasets 15 (nodes), 164 (units) and 55
//! (modal data: real normal modes and complex modes), read and written. Other datasets are
//! skipped with a warning naming their number and line. Fortran `D` exponents, CRLF line ends and
//! fields run together by fixed widths of whitespace are accepted; a file written by femu reads
//! back to the same text.

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
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    parse_uff(&text, path)
}

/// Parses universal-file text (`path` names it in errors).
///
/// # Errors
/// [`IoError::Parse`] with the line for malformed content.
pub fn parse_uff(text: &str, path: &Path) -> Result<Universal, IoError> {
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let mut out = Universal::default();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim().is_empty() {
            i += 1;
            continue;
        }
        if lines[i].trim() != "-1" {
            return Err(perr(
                path,
                i + 1,
                format!(
                    "expected the dataset delimiter '-1', found '{}'",
                    lines[i].trim()
                ),
            ));
        }
        let start = i + 1;
        let end = (start..lines.len())
            .find(|&j| lines[j].trim() == "-1")
            .ok_or_else(|| perr(path, i + 1, "dataset without its closing '-1'"))?;
        if start == end {
            return Err(perr(path, start, "empty dataset"));
        }
        let kind = int(
            path,
            start + 1,
            lines[start].split_whitespace().next().unwrap_or(""),
        )?;
        let body: Vec<(usize, &str)> = (start + 1..end).map(|j| (j + 1, lines[j])).collect();
        match kind {
            15 => parse_15(path, &body, &mut out)?,
            2411 => parse_2411(path, &body, &mut out)?,
            2412 => parse_2412(path, &body, &mut out)?,
            164 => parse_164(path, &body, &mut out)?,
            55 => parse_55(path, &body, &mut out)?,
            other => out.warnings.push(Warning {
                path: path.to_path_buf(),
                line: start + 1,
                message: format!("dataset {other} is not read by femu (skipped)"),
            }),
        }
        i = end + 1;
    }
    Ok(out)
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
    if ndv < 3 {
        return Err(perr(
            path,
            l6,
            format!("{ndv} values per node: need at least 3 translations"),
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
    // Fortran 1PE13.5: d.ddddde+xx, right-aligned in 13, with a leading blank always: a
    // three-digit exponent (beyond Fortran's E13.5) would otherwise run into the previous field
    // (found by the fuzzer). Non-finite values are written as they are (the reader refuses them,
    // naming the line).
    let s = format!("{v:.5E}");
    match s.split_once('E').map(|(m, e)| (m, e.parse::<i32>())) {
        Some((m, Ok(e))) => format!(
            " {:>12}",
            format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
        ),
        _ => format!(" {s:>12}"),
    }
}

/// Writes units, nodes and real normal modes as datasets 164, 15 and 55 (SI units).
pub fn uff_string(u: &Universal) -> String {
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

/// Writes [`uff_string`] to a file.
///
/// # Errors
/// [`IoError::Io`].
pub fn write_uff(path: impl AsRef<Path>, u: &Universal) -> Result<(), IoError> {
    let path = path.as_ref();
    std::fs::write(path, uff_string(u)).map_err(|e| IoError::io(path, e))
}

impl Universal {
    /// The femu mesh of the file's nodes and linear solid elements (descriptors 111 tetrahedron,
    /// 112 wedge, 115 brick, whose node orders are Abaqus'); other elements (shells, beams) are
    /// skipped and counted in the returned warnings; quadratic solids (116, 113, 118) are refused:
    /// their interleaved node orders are not converted yet.
    ///
    /// # Errors
    /// A quadratic solid (element label), a mesh error (duplicate or missing node), no solid.
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
            let kind = match e.descriptor {
                111 => ElementKind::Tet4,
                112 => ElementKind::Penta6,
                115 => ElementKind::Hex8,
                113 | 116 | 118 => {
                    return Err(IoError::Parse {
                        path: path.to_path_buf(),
                        line: 0,
                        reason: format!(
                            "element {}: quadratic solid descriptor {} is not read by femu yet",
                            e.id, e.descriptor
                        ),
                    });
                }
                _ => {
                    skipped += 1;
                    continue;
                }
            };
            mesh.add_element(e.id, kind, &e.nodes).map_err(model_err)?;
        }
        if mesh.element_count() == 0 {
            return Err(IoError::Parse {
                path: path.to_path_buf(),
                line: 0,
                reason: "no solid element (descriptors 111, 112, 115) in dataset 2412".into(),
            });
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
