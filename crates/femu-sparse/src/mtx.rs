//! MatrixMarket coordinate files: hand `K` and `M` to scipy, SLEPc or MATLAB, and read theirs.
//!
//! Reads `%%MatrixMarket matrix coordinate {real|integer} {general|symmetric}` (Fortran `D`
//! exponents accepted); writes `real symmetric` (lower triangle) or `real general` with 17
//! significant digits, so a write-read round trip is exact.

use crate::{SparseError, SparseMatrix};
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::Path;

fn parse_err(file: &Path, line: usize, reason: impl Into<String>) -> SparseError {
    SparseError::Parse {
        file: file.display().to_string(),
        line,
        reason: reason.into(),
    }
}

/// Reads a MatrixMarket coordinate file into CSC (duplicates summed; symmetric files mirrored).
///
/// # Errors
/// [`SparseError::Io`] if the file cannot be read, [`SparseError::Parse`] with the line number for
/// a bad header, size line or entry (index out of range, missing value, NaN).
pub fn read_matrix_market(path: impl AsRef<Path>) -> Result<SparseMatrix, SparseError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|e| SparseError::Io {
        file: path.display().to_string(),
        reason: e.to_string(),
    })?;
    let mut lines = BufReader::new(file).lines().enumerate();
    let io = |e: std::io::Error| SparseError::Io {
        file: path.display().to_string(),
        reason: e.to_string(),
    };
    let (_, header) = lines
        .next()
        .ok_or_else(|| parse_err(path, 1, "empty file"))?;
    let header = header.map_err(io)?;
    let words: Vec<String> = header
        .split_whitespace()
        .map(|w| w.to_ascii_lowercase())
        .collect();
    if words.len() != 5
        || words[0] != "%%matrixmarket"
        || words[1] != "matrix"
        || words[2] != "coordinate"
    {
        return Err(parse_err(
            path,
            1,
            format!(
                "expected '%%MatrixMarket matrix coordinate <field> <symmetry>', got '{header}'"
            ),
        ));
    }
    if words[3] != "real" && words[3] != "integer" {
        return Err(parse_err(
            path,
            1,
            format!("field '{}' is not supported (real or integer)", words[3]),
        ));
    }
    let symmetric = match words[4].as_str() {
        "general" => false,
        "symmetric" => true,
        other => {
            return Err(parse_err(
                path,
                1,
                format!("symmetry '{other}' is not supported (general or symmetric)"),
            ));
        }
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut entries: Vec<(usize, usize, f64)> = Vec::new();
    let mut count = 0;
    for (i, line) in lines {
        let line = line.map_err(io)?;
        let lineno = i + 1;
        let t = line.trim();
        if t.is_empty() || t.starts_with('%') {
            continue;
        }
        let f: Vec<&str> = t.split_whitespace().collect();
        match size {
            None => {
                let nums: Result<Vec<usize>, _> = f.iter().map(|w| w.parse::<usize>()).collect();
                match nums {
                    Ok(v) if v.len() == 3 => {
                        size = Some((v[0], v[1], v[2]));
                        // the announced count, within reason: a header is not a promise
                        entries.reserve((if symmetric { 2 * v[2] } else { v[2] }).min(1 << 24));
                    }
                    _ => {
                        return Err(parse_err(
                            path,
                            lineno,
                            format!("expected 'rows cols entries', got '{t}'"),
                        ));
                    }
                }
            }
            Some((rows, cols, nnz)) => {
                if f.len() != 3 {
                    return Err(parse_err(
                        path,
                        lineno,
                        format!("expected 'row col value', got '{t}'"),
                    ));
                }
                let idx = |w: &str, n: usize, what: &str| -> Result<usize, SparseError> {
                    match w.parse::<usize>() {
                        Ok(v) if v >= 1 && v <= n => Ok(v - 1),
                        _ => Err(parse_err(
                            path,
                            lineno,
                            format!("{what} index '{w}' is not in 1..={n}"),
                        )),
                    }
                };
                let (r, c) = (idx(f[0], rows, "row")?, idx(f[1], cols, "column")?);
                let v: f64 = f[2].replace(['D', 'd'], "e").parse().map_err(|_| {
                    parse_err(path, lineno, format!("value '{}' is not a number", f[2]))
                })?;
                if !v.is_finite() {
                    return Err(parse_err(
                        path,
                        lineno,
                        format!("value '{}' is not finite", f[2]),
                    ));
                }
                count += 1;
                if count > nnz {
                    return Err(parse_err(
                        path,
                        lineno,
                        format!("more entries than the {nnz} announced"),
                    ));
                }
                entries.push((r, c, v));
                if symmetric && r != c {
                    entries.push((c, r, v));
                }
            }
        }
    }
    match size {
        None => Err(parse_err(path, 1, "no size line")),
        Some((_, _, nnz)) if count != nnz => Err(parse_err(
            path,
            0,
            format!("{count} entries found, {nnz} announced"),
        )),
        Some((rows, cols, _)) => Ok(crate::csc::from_entries(rows, cols, &entries)),
    }
}

/// Writes `a` as a MatrixMarket coordinate file: `symmetric` stores the lower triangle only (the
/// caller asserts symmetry), otherwise every entry.
///
/// # Errors
/// [`SparseError::Io`].
pub fn write_matrix_market(
    path: impl AsRef<Path>,
    a: &SparseMatrix,
    symmetric: bool,
) -> Result<(), SparseError> {
    let path = path.as_ref();
    let io = |e: std::io::Error| SparseError::Io {
        file: path.display().to_string(),
        reason: e.to_string(),
    };
    let mut w = BufWriter::new(std::fs::File::create(path).map_err(io)?);
    let entries: Vec<(usize, usize, f64)> = a
        .iter()
        .filter(|(_, (r, c))| !symmetric || r >= c)
        .map(|(v, (r, c))| (r, c, *v))
        .collect();
    writeln!(
        w,
        "%%MatrixMarket matrix coordinate real {}",
        if symmetric { "symmetric" } else { "general" }
    )
    .map_err(io)?;
    writeln!(w, "% written by femu").map_err(io)?;
    writeln!(w, "{} {} {}", a.rows(), a.cols(), entries.len()).map_err(io)?;
    for (r, c, v) in entries {
        writeln!(w, "{} {} {:.16e}", r + 1, c + 1, v).map_err(io)?;
    }
    w.flush().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A directory of one test's own, removed with what it holds when the test ends (also when
    /// it fails).
    struct Scratch(std::path::PathBuf);

    impl Scratch {
        fn new(test: &str) -> Self {
            let d = std::env::temp_dir().join(format!("femu-mtx-{test}-{}", std::process::id()));
            std::fs::create_dir_all(&d).unwrap();
            Self(d)
        }
        fn file(&self, name: &str) -> std::path::PathBuf {
            self.0.join(name)
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn round_trip_is_exact() {
        let mut t = sprs::TriMat::new((3, 3));
        for (r, c, v) in [
            (0, 0, 1.0 / 3.0),
            (1, 0, -2e-17),
            (0, 1, -2e-17),
            (2, 2, 7.25e11),
            (2, 1, 0.1),
            (1, 2, 0.1),
        ] {
            t.add_triplet(r, c, v);
        }
        let a: SparseMatrix = t.to_csc();
        let dir = Scratch::new("round-trip");
        for sym in [true, false] {
            let p = dir.file(&format!("a{sym}.mtx"));
            write_matrix_market(&p, &a, sym).unwrap();
            let b = read_matrix_market(&p).unwrap();
            assert_eq!(a.to_dense(), b.to_dense());
        }
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases = [
            ("%%MatrixMarket matrix array real general\n2 2\n1\n", 1),
            (
                "%%MatrixMarket matrix coordinate real symmetric\n% c\n2 2 1\n3 1 1.0\n",
                4,
            ),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n2 2 abc\n",
                4,
            ),
            (
                "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 nan\n",
                3,
            ),
            (
                "%%MatrixMarket matrix coordinate complex general\n2 2 1\n1 1 1 0\n",
                1,
            ),
            ("%%MatrixMarket matrix coordinate real general\n2 x 1\n", 2),
        ];
        let dir = Scratch::new("malformed");
        for (i, (text, line)) in cases.iter().enumerate() {
            let p = dir.file(&format!("bad{i}.mtx"));
            std::fs::write(&p, text).unwrap();
            match read_matrix_market(&p) {
                Err(SparseError::Parse { line: l, .. }) => assert_eq!(l, *line, "case {i}"),
                other => panic!("case {i}: {other:?}"),
            }
        }
        // Fortran exponent
        let p = dir.file("d.mtx");
        std::fs::write(
            &p,
            "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1.5D+03\n",
        )
        .unwrap();
        assert_eq!(read_matrix_market(&p).unwrap().get(0, 0), Some(&1500.0));
        assert!(matches!(
            read_matrix_market(dir.file("missing.mtx")),
            Err(SparseError::Io { .. })
        ));
    }
}
