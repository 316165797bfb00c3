//! JSON test modes for people without UFF: the rows of the CSV format as objects,
//! `[{"mode": 1, "frequency_hz": 1520.5, "node": 7, "direction": "y", "value": 0.25,
//! "damping": 0.002}, ...]` (or `{"rows": [...]}`); `direction` is `"x"`, `"-y"`, ... or three
//! numbers `[dx, dy, dz]`. Syntax errors name the JSON line and column; content errors the row
//! (1-based), with the same checks as the CSV reader.

use crate::IoError;
use crate::csv::{TestData, parse_test_csv};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Row {
    mode: u64,
    frequency_hz: f64,
    node: u64,
    direction: Direction,
    value: f64,
    #[serde(default)]
    damping: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Direction {
    Axis(String),
    Vector([f64; 3]),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Doc {
    Rows(Vec<Row>),
    Wrapped { rows: Vec<Row> },
}

/// Parses JSON test modes (`path` names the file in messages).
///
/// # Errors
/// [`IoError::Parse`]: a JSON syntax or shape error (with the JSON line), or a content error of the
/// CSV reader's kind (line 0, the row named in the message).
pub fn parse_test_json(text: &str, path: impl AsRef<Path>) -> Result<TestData, IoError> {
    let path = path.as_ref();
    let doc: Doc = serde_json::from_str(text).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        reason: format!("column {}: {e}", e.column()),
    })?;
    let rows = match doc {
        Doc::Rows(r) | Doc::Wrapped { rows: r } => r,
    };
    // the CSV reader holds every check: write the rows as CSV, map its line back to the row
    let mut csv = String::from("mode,frequency_hz,node,direction,value,damping\n");
    for r in &rows {
        let dir = match &r.direction {
            Direction::Axis(s) => s.replace(',', " "),
            Direction::Vector(v) => format!("{:e} {:e} {:e}", v[0], v[1], v[2]),
        };
        let damping = r.damping.map(|d| format!("{d:e}")).unwrap_or_default();
        let _ = writeln!(
            csv,
            "{},{:e},{},{},{:e},{}",
            r.mode, r.frequency_hz, r.node, dir, r.value, damping
        );
    }
    parse_test_csv(&csv, path).map_err(|e| match e {
        IoError::Parse { line, reason, .. } => IoError::Parse {
            path: path.to_path_buf(),
            line: 0,
            reason: if line >= 2 {
                format!("row {}: {reason}", line - 1)
            } else {
                reason
            },
        },
        other => other,
    })
}

/// Reads JSON test modes from a file.
///
/// # Errors
/// [`IoError::Io`], and as [`parse_test_json`].
pub fn read_test_json(path: impl AsRef<Path>) -> Result<TestData, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    parse_test_json(&text, path)
}
