//! Reading a universal file: the `-1` delimited blocks, the dataset dispatcher, and the
//! fixed-column numeric fields all datasets share.

use super::*;

pub(super) fn perr(path: &Path, line: usize, reason: impl Into<String>) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason: reason.into(),
    }
}

pub(super) fn num(path: &Path, line: usize, tok: &str) -> Result<f64, IoError> {
    let t = tok.replace(['D', 'd'], "E");
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(perr(path, line, format!("'{tok}' is not a finite number"))),
    }
}

pub(super) fn int(path: &Path, line: usize, tok: &str) -> Result<i64, IoError> {
    tok.parse::<i64>()
        .map_err(|_| perr(path, line, format!("'{tok}' is not an integer")))
}

/// A token of fixed-width FORTRAN fields that touch (`4.1E+03-3.1E+03`: a negative number fills
/// its field and leaves no blank before it), split before every sign that follows a digit or a
/// point (a sign after an exponent letter belongs to the exponent).
fn split_touching(tok: &str) -> Vec<&str> {
    let b = tok.as_bytes();
    let mut parts = Vec::new();
    let mut start = 0;
    for i in 1..b.len() {
        if (b[i] == b'-' || b[i] == b'+') && (b[i - 1].is_ascii_digit() || b[i - 1] == b'.') {
            parts.push(&tok[start..i]);
            start = i;
        }
    }
    parts.push(&tok[start..]);
    parts
}

/// Numbers of a line (fields that touch are split, as FORTRAN writers leave them); `want` of them
/// at least.
pub(super) fn nums(path: &Path, line: usize, text: &str, want: usize) -> Result<Vec<f64>, IoError> {
    let v: Vec<f64> = text
        .split_whitespace()
        .flat_map(split_touching)
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

pub(super) fn ints(path: &Path, line: usize, text: &str, want: usize) -> Result<Vec<i64>, IoError> {
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
pub(super) struct ByteLines<'a> {
    pub(super) b: &'a [u8],
    pub(super) at: usize,
    pub(super) line: usize,
}

impl<'a> ByteLines<'a> {
    /// The next line (without `\r\n`), its number, as text (invalid UTF-8 replaced).
    pub(super) fn next_line(&mut self) -> Option<(usize, std::borrow::Cow<'a, str>)> {
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
            18 => parse_18(path, &body, &mut out)?,
            2411 => parse_2411(path, &body, &mut out)?,
            2412 => parse_2412(path, &body, &mut out)?,
            164 => parse_164(path, &body, &mut out)?,
            55 => parse_55(path, &body, &mut out)?,
            151 => {
                // free text: whatever records the writer filled
                let rec = |i: usize| body.get(i).map_or("", |l| l.1.trim()).to_string();
                let program = if rec(5).is_empty() { rec(2) } else { rec(5) };
                out.header = Some(UffHeader {
                    model: rec(0),
                    description: rec(1),
                    program,
                });
            }
            2414 => parse_2414(path, &body, &mut out)?,
            2420 => parse_2420(path, &body, &mut out)?,
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
pub(super) fn col(l: &str, from: usize, to: usize) -> &str {
    let to = to.min(l.len());
    if from >= to {
        return "";
    }
    l.get(from..to).unwrap_or("")
}

/// An integer field of fixed columns (blank = 0).
pub(super) fn col_int(
    path: &Path,
    ln: usize,
    l: &str,
    from: usize,
    to: usize,
) -> Result<i64, IoError> {
    match col(l, from, to).trim() {
        "" => Ok(0),
        t => int(path, ln, t),
    }
}

#[cfg(test)]
mod tests {
    use super::split_touching;

    #[test]
    fn touching_fields_are_split_and_exponents_kept() {
        assert_eq!(
            split_touching("4.111111E+03-3.111111E+03-1.1E-05"),
            ["4.111111E+03", "-3.111111E+03", "-1.1E-05"]
        );
        assert_eq!(split_touching("-1.5D-03"), ["-1.5D-03"]);
        assert_eq!(split_touching("12"), ["12"]);
        assert_eq!(split_touching("1.-2."), ["1.", "-2."]);
    }
}
