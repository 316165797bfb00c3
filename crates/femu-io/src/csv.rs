//! Test modes as CSV, for people without Universal Files: one row per mode and sensor.
//!
//! ```text
//! # comments and blank lines are ignored; the header is required
//! mode,frequency_hz,node,direction,value
//! 1,1311.2,101,z,0.0123
//! 1,1311.2,102,x,-0.0020
//! 2,2421.9,101,z,-0.0031
//! 2,2421.9,102,x,0.0150
//! ```
//!
//! `direction` is `x`, `y`, `z` (optionally signed, `-y`) or three numbers separated by spaces
//! (`0.707 0.707 0`). Optional columns after `value`: `damping` (the modal damping ratio) and
//! `x,y,z` (the test node's coordinates in the test's own frame and units, for mapping a test
//! wireframe onto the model; the same on every row of a node). Sensors are the distinct (node,
//! direction) pairs in order of first appearance; every mode must give a value for every sensor,
//! and one frequency.

use crate::IoError;
use femu_correlate::{Sensor, TestModes};
use femu_sparse::faer::Mat;
use std::collections::BTreeMap;
use std::path::Path;

pub use crate::test_data::TestData;

/// One mode's rows: frequency, damping, first line, values by sensor.
type ModeRows = (f64, Option<f64>, usize, BTreeMap<usize, f64>);

fn direction(s: &str) -> Option<[f64; 3]> {
    let t = s.trim().to_ascii_lowercase();
    let (sign, axis) = match t.strip_prefix('-') {
        Some(rest) => (-1.0, rest.to_string()),
        None => (1.0, t.trim_start_matches('+').to_string()),
    };
    let unit = |c: usize| {
        let mut d = [0.0; 3];
        d[c] = sign;
        Some(d)
    };
    match axis.as_str() {
        "x" => unit(0),
        "y" => unit(1),
        "z" => unit(2),
        _ => {
            let v: Vec<f64> = t
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            (v.len() == 3 && t.split_whitespace().count() == 3).then(|| [v[0], v[1], v[2]])
        }
    }
}

/// The columns a CSV test's header announces.
struct Header {
    /// `mode,frequency_hz[,damping]`: frequencies alone.
    frequencies_only: bool,
    /// A damping column.
    damping: bool,
    /// The column of x when the file gives the nodes' coordinates.
    xyz_from: Option<usize>,
}

/// The header line `t` split into fields `f`, or what is wrong with it.
fn parse_header(f: &[&str], t: &str) -> Result<Header, String> {
    let h: Vec<String> = f.iter().map(|s| s.to_ascii_lowercase()).collect();
    if h.len() >= 2
        && h[..2] == ["mode", "frequency_hz"]
        && !h.iter().any(|c| c == "node" || c == "value")
    {
        let damping = match &h[2..] {
            [] => false,
            [d] if d == "damping" => true,
            _ => {
                return Err(format!(
                    "a test of frequencies alone has the header mode,frequency_hz[,damping], got {t:?}"
                ));
            }
        };
        return Ok(Header {
            frequencies_only: true,
            damping,
            xyz_from: None,
        });
    }
    if h.len() < 5 || h[..5] != ["mode", "frequency_hz", "node", "direction", "value"] {
        return Err(format!(
            "expected the header mode,frequency_hz,node,direction,value[,damping][,x,y,z], got {t:?}"
        ));
    }
    let rest: Vec<&str> = h[5..].iter().map(String::as_str).collect();
    let (damping, xyz) = match rest.as_slice() {
        [] => (false, false),
        ["damping"] => (true, false),
        ["x", "y", "z"] => (false, true),
        ["damping", "x", "y", "z"] => (true, true),
        _ => {
            let extra = rest
                .iter()
                .find(|c| !["damping", "x", "y", "z"].contains(c))
                .copied()
                .unwrap_or(rest[0]);
            let hint = crate::spelling::suggestion(extra, ["damping", "x", "y", "z"], "");
            return Err(format!(
                "unknown or misplaced column {extra:?}{hint}: the columns are mode,frequency_hz,node,direction,value, then optionally damping, then optionally x,y,z"
            ));
        }
    };
    Ok(Header {
        frequencies_only: false,
        damping,
        xyz_from: xyz.then_some(5 + usize::from(damping)),
    })
}

/// Parses CSV test modes (`path` names the file in messages). A test of frequencies alone has
/// the header `mode,frequency_hz[,damping]`, or rows with empty node, direction and value: its
/// modes have no shapes ([`TestModes::frequencies_only`]).
///
/// # Errors
/// [`IoError::Parse`] with the line: a missing header, a malformed number, node or direction, two
/// frequencies for one mode, a mode without a value for some sensor (reported at the mode's first
/// line), two values for one sensor and mode; invalid test modes (NaN, zero shapes).
pub fn parse_test_csv(text: &str, path: impl AsRef<Path>) -> Result<TestData, IoError> {
    let path = path.as_ref();
    let err = |line: usize, reason: String| IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut header_seen = false;
    // `mode,frequency_hz[,damping]`: a test of frequencies alone
    let mut frequencies_header = false;
    let mut damping_column = false;
    let mut xyz_from: Option<usize> = None;
    let mut coordinates: BTreeMap<u64, ([f64; 3], usize)> = BTreeMap::new();
    let mut sensors: Vec<Sensor> = Vec::new();
    let mut modes: BTreeMap<u64, ModeRows> = BTreeMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim_end_matches('\r').trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = t.split(',').map(str::trim).collect();
        if !header_seen {
            let header = parse_header(&f, t).map_err(|reason| err(line, reason))?;
            (frequencies_header, damping_column, xyz_from) =
                (header.frequencies_only, header.damping, header.xyz_from);
            header_seen = true;
            continue;
        }
        if f.len() < 5 && !frequencies_header {
            return Err(err(line, format!("expected 5 fields, got {}", f.len())));
        }
        if frequencies_header && f.len() < 2 {
            return Err(err(line, format!("expected mode,frequency_hz, got {t:?}")));
        }
        let mode = f[0]
            .parse::<u64>()
            .ok()
            .filter(|m| *m > 0)
            .ok_or_else(|| err(line, format!("mode {:?} is not a positive integer", f[0])))?;
        let freq = f[1]
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| {
                err(
                    line,
                    format!("frequency {:?} is not a positive number", f[1]),
                )
            })?;
        // a mode with no reading: the frequencies-alone header, or empty node, direction and value
        let bare = frequencies_header
            || (f[2].is_empty()
                && f.get(3).is_none_or(|d| d.is_empty())
                && f.get(4).is_none_or(|v| v.is_empty()));
        if bare {
            let column = if frequencies_header { 2 } else { 5 };
            let damping = match (damping_column, f.get(column)) {
                (true, Some(s)) if !s.is_empty() => Some(
                    s.parse::<f64>()
                        .map_err(|_| err(line, format!("damping {s:?} is not a number")))?,
                ),
                _ => None,
            };
            if let Some(e) = modes.get(&mode) {
                return Err(err(
                    line,
                    format!("mode {mode} is given again (first at line {})", e.2),
                ));
            }
            modes.insert(mode, (freq, damping, line, BTreeMap::new()));
            continue;
        }
        let node = f[2]
            .parse::<u64>()
            .map_err(|_| err(line, format!("node {:?} is not an integer id", f[2])))?;
        let dir = direction(f[3]).ok_or_else(|| {
            err(
                line,
                format!("direction {:?} is not x, y, z or three numbers", f[3]),
            )
        })?;
        let value = f[4]
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| err(line, format!("value {:?} is not a finite number", f[4])))?;
        if let Some(at) = xyz_from {
            let x = row_coordinates(&f, at, node).map_err(|reason| err(line, reason))?;
            match coordinates.get(&node) {
                Some((earlier, at_line)) if *earlier != x => {
                    return Err(err(
                        line,
                        format!(
                            "node {node} is at {x:?} here and at {earlier:?} on line {at_line}"
                        ),
                    ));
                }
                Some(_) => {}
                None => {
                    coordinates.insert(node, (x, line));
                }
            }
        }
        let damping = match (damping_column, f.get(5)) {
            (true, Some(s)) if !s.is_empty() => Some(
                s.parse::<f64>()
                    .map_err(|_| err(line, format!("damping {s:?} is not a number")))?,
            ),
            _ => None,
        };
        let (s, sign) =
            sensor_index(&mut sensors, node, dir).map_err(|reason| err(line, reason))?;
        let entry = modes
            .entry(mode)
            .or_insert((freq, damping, line, BTreeMap::new()));
        if entry.0 != freq {
            return Err(err(
                line,
                format!(
                    "mode {mode} has frequency {freq} here and {} at line {}",
                    entry.0, entry.2
                ),
            ));
        }
        if entry.1.is_none() {
            entry.1 = damping;
        }
        if entry.3.insert(s, sign * value).is_some() {
            return Err(err(
                line,
                format!(
                    "mode {mode} has a second value for node {node} direction {:?}",
                    f[3]
                ),
            ));
        }
    }
    if !header_seen {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "the file is empty: CSV test modes start with the header mode,frequency_hz,node,direction,value[,damping][,x,y,z]".into(),
        });
    }
    if modes.is_empty() {
        return Err(err(
            1,
            "no test modes in the file: the header has no rows below it".into(),
        ));
    }
    let ns = sensors.len();
    let mut shapes = Mat::<f64>::zeros(ns, modes.len());
    let mut freqs = Vec::with_capacity(modes.len());
    let mut damping = Vec::with_capacity(modes.len());
    for (j, (mode, (f, z, first, values))) in modes.iter().enumerate() {
        if values.len() != ns {
            let missing = (0..ns).find(|s| !values.contains_key(s)).unwrap_or(0);
            return Err(err(
                *first,
                format!(
                    "mode {mode} has no value for sensor {} (node {})",
                    missing + 1,
                    sensors[missing].node
                ),
            ));
        }
        for (s, v) in values {
            shapes[(*s, j)] = *v;
        }
        freqs.push(*f);
        damping.push(*z);
    }
    let damping = if damping.iter().all(Option::is_some) {
        Some(damping.into_iter().flatten().collect())
    } else {
        None
    };
    let modes = if ns == 0 {
        TestModes::frequencies_only(freqs, damping)
    } else {
        TestModes::new(freqs, damping, shapes)
    }
    .map_err(|e| err(1, e.to_string()))?;
    Ok(TestData {
        sensors,
        modes,
        coordinates: coordinates.into_iter().map(|(n, (x, _))| (n, x)).collect(),
    })
}

/// The `x, y, z` of a row from column `at`.
fn row_coordinates(f: &[&str], at: usize, node: u64) -> Result<[f64; 3], String> {
    let mut x = [0.0; 3];
    for (c, v) in x.iter_mut().enumerate() {
        let t = f.get(at + c).copied().unwrap_or("");
        *v = t
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                format!(
                    "coordinate {} {t:?} of node {node} is not a finite number",
                    ["x", "y", "z"][c]
                )
            })?;
    }
    Ok(x)
}

/// The sensor of a reading at `node` along `dir` (added when new), and the sign that turns the
/// reading to the sensor's direction: the same sensor is the same node and a parallel direction.
fn sensor_index(
    sensors: &mut Vec<Sensor>,
    node: u64,
    dir: [f64; 3],
) -> Result<(usize, f64), String> {
    let norm = |d: [f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let nd = norm(dir);
    if !(nd > 0.0) {
        return Err("direction is the zero vector".into());
    }
    let mut sign = 1.0;
    let s = match sensors.iter().position(|s| {
        let c = (s.direction[0] * dir[0] + s.direction[1] * dir[1] + s.direction[2] * dir[2])
            / (norm(s.direction) * nd);
        if s.node == node && (c.abs() - 1.0).abs() < 1e-9 {
            sign = c.signum();
            true
        } else {
            false
        }
    }) {
        Some(s) => s,
        None => {
            sensors.push(Sensor::new(node, dir));
            sensors.len() - 1
        }
    };
    Ok((s, sign))
}

/// Reads CSV test modes from a file.
///
/// # Errors
/// As [`parse_test_csv`], or [`IoError::Io`].
pub fn read_test_csv(path: impl AsRef<Path>) -> Result<TestData, IoError> {
    let p = path.as_ref();
    let text = std::fs::read_to_string(p).map_err(|e| IoError::io(p, e))?;
    parse_test_csv(&text, p)
}

/// Writes test modes as CSV (the format read by [`parse_test_csv`]).
pub fn test_csv_string(sensors: &[Sensor], modes: &TestModes) -> String {
    let mut s = String::from("mode,frequency_hz,node,direction,value\n");
    for j in 0..modes.len() {
        for (i, sensor) in sensors.iter().enumerate() {
            let d = sensor.direction;
            let dir = match d {
                [1.0, 0.0, 0.0] => "x".to_string(),
                [0.0, 1.0, 0.0] => "y".to_string(),
                [0.0, 0.0, 1.0] => "z".to_string(),
                _ => format!("{:?} {:?} {:?}", d[0], d[1], d[2]),
            };
            s.push_str(&format!(
                "{},{:?},{},{},{:?}\n",
                j + 1,
                modes.frequencies_hz[j],
                sensor.node,
                dir,
                modes.shapes[(i, j)]
            ));
        }
    }
    s
}
