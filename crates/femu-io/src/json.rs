//! JSON test modes for people without UFF: the rows of the CSV format as objects,
//! `[{"mode": 1, "frequency_hz": 1520.5, "node": 7, "direction": "y", "value": 0.25,
//! "damping": 0.002}, ...]` (or `{"rows": [...]}`); `direction` is `"x"`, `"-y"`, ... or three
//! numbers `[dx, dy, dz]`. Optional `"x"`, `"y"`, `"z"` give the test node's coordinates in the
//! test's frame (on every row, or on none). Syntax errors name the JSON line and column; content errors the row
//! (1-based), with the same checks as the CSV reader.

use crate::IoError;
use crate::TestData;
use crate::csv::parse_test_csv;
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
    /// The node's coordinates in the test's frame (all three or none).
    #[serde(default)]
    x: Option<f64>,
    #[serde(default)]
    y: Option<f64>,
    #[serde(default)]
    z: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Direction {
    Axis(String),
    Vector([f64; 3]),
}

/// Parses JSON test modes (`path` names the file in messages).
///
/// # Errors
/// [`IoError::Parse`] for a JSON syntax error (with the JSON line and column);
/// [`IoError::Content`] for an empty file, a document that is not a list of rows, and a row with
/// an unknown or missing field or a content error of the CSV reader's kind (the row named, 1-based).
pub fn parse_test_json(text: &str, path: impl AsRef<Path>) -> Result<TestData, IoError> {
    let path = path.as_ref();
    let whole = |reason: String| IoError::Content {
        path: path.to_path_buf(),
        reason,
    };
    if text.trim().is_empty() {
        return Err(whole(
            "the file is empty: JSON test modes are a list of rows [{\"mode\": 1, \"frequency_hz\": ..., \"node\": ..., \"direction\": \"y\", \"value\": ...}, ...]".into(),
        ));
    }
    let doc: serde_json::Value = serde_json::from_str(text).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        reason: format!("column {}: {e}", e.column()),
    })?;
    let items = match doc {
        serde_json::Value::Array(items) => items,
        serde_json::Value::Object(mut o) if o.len() == 1 && o.contains_key("rows") => {
            match o.remove("rows") {
                Some(serde_json::Value::Array(items)) => items,
                _ => return Err(whole("\"rows\" must be a list of rows".into())),
            }
        }
        _ => {
            return Err(whole(
                "expected a list of rows, or an object {\"rows\": [...]}".into(),
            ));
        }
    };
    let rows = items
        .into_iter()
        .enumerate()
        .map(|(i, v)| {
            serde_json::from_value::<Row>(v).map_err(|e| whole(format!("row {}: {e}", i + 1)))
        })
        .collect::<Result<Vec<Row>, IoError>>()?;
    if rows.is_empty() {
        return Err(whole(
            "no test modes in the file: the list of rows is empty".into(),
        ));
    }
    // the CSV reader holds every check: write the rows as CSV, map its line back to the row
    let with_xyz = rows
        .iter()
        .any(|r| r.x.is_some() || r.y.is_some() || r.z.is_some());
    let mut csv = String::from(if with_xyz {
        "mode,frequency_hz,node,direction,value,damping,x,y,z\n"
    } else {
        "mode,frequency_hz,node,direction,value,damping\n"
    });
    for r in &rows {
        let dir = match &r.direction {
            Direction::Axis(s) => s.replace(',', " "),
            Direction::Vector(v) => format!("{:e} {:e} {:e}", v[0], v[1], v[2]),
        };
        let damping = r.damping.map(|d| format!("{d:e}")).unwrap_or_default();
        let xyz = if with_xyz {
            let c = |v: Option<f64>| v.map(|v| format!(",{v:e}")).unwrap_or_else(|| ",".into());
            format!("{}{}{}", c(r.x), c(r.y), c(r.z))
        } else {
            String::new()
        };
        let _ = writeln!(
            csv,
            "{},{:e},{},{},{:e},{}{}",
            r.mode, r.frequency_hz, r.node, dir, r.value, damping, xyz
        );
    }
    parse_test_csv(&csv, path).map_err(|e| match e {
        IoError::Parse { line, reason, .. } => whole(if line >= 2 {
            format!("row {}: {reason}", line - 1)
        } else {
            reason
        }),
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
