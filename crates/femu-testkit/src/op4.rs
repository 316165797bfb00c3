//! A writer of Nastran `OUTPUT4` files for tests, written from the format's description (the
//! DMAP Programmer's Guide's OUTPUT4, as `fixtures/nastran/pynastran/op4/` shows Nastran writes
//! it) and sharing no code with femu's reader: real double-precision matrices, text or binary in
//! either byte order, dense columns, sparse strings, or sparse strings with `BIGMAT` headers.

/// A real matrix to write: its columns' `(row, value)` pairs, rows 0-based and increasing.
pub struct Op4Out<'a> {
    /// Up to 8 characters.
    pub name: &'a str,
    /// Rows.
    pub rows: usize,
    /// `NF`: 1 square, 2 rectangular, 6 symmetric.
    pub form: i64,
    /// Each column's `(row, value)`, rows increasing; zero values are written where given.
    pub columns: Vec<Vec<(usize, f64)>>,
}

/// How the columns are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op4Layout {
    /// From each column's first to its last given row, zeros between.
    Dense,
    /// Strings of consecutive given rows, a one-word header `IROW + 65536 (L + 1)`.
    Sparse,
    /// Strings with the two-word header `L + 1, IROW`, the row count negative.
    BigMat,
}

/// `v` as Fortran's `1PE23.16`: ` 1.2345678901234567E+02`.
pub fn fortran_e23(v: f64) -> String {
    let s = format!("{v:.16E}");
    let (m, e) = s.split_once('E').expect("an exponent");
    let e: i32 = e.parse().expect("an integer exponent");
    let sign = if e < 0 { '-' } else { '+' };
    format!("{:>23}", format!("{m}E{sign}{:02}", e.abs()))
}

/// The strings of a column: `(first row, values)` of consecutive rows.
fn strings(col: &[(usize, f64)]) -> Vec<(usize, Vec<f64>)> {
    let mut out: Vec<(usize, Vec<f64>)> = Vec::new();
    for &(r, v) in col {
        match out.last_mut() {
            Some((first, vals)) if *first + vals.len() == r => vals.push(v),
            _ => out.push((r, vec![v])),
        }
    }
    out
}

/// The dense run of a column: its first row and the values to its last, zeros between.
fn dense(col: &[(usize, f64)]) -> (usize, Vec<f64>) {
    let first = col[0].0;
    let last = col[col.len() - 1].0;
    let mut vals = vec![0.0; last - first + 1];
    for &(r, v) in col {
        vals[r - first] = v;
    }
    (first, vals)
}

/// Three values a line, `1P,3E23.16`.
fn value_lines(vals: &[f64], out: &mut String) {
    for chunk in vals.chunks(3) {
        for v in chunk {
            out.push_str(&fortran_e23(*v));
        }
        out.push('\n');
    }
}

/// The text file of `matrices`.
pub fn op4_text(matrices: &[Op4Out<'_>], layout: Op4Layout) -> String {
    let mut s = String::new();
    for m in matrices {
        let nrow = if layout == Op4Layout::BigMat {
            -(m.rows as i64)
        } else {
            m.rows as i64
        };
        s.push_str(&format!(
            "{:8}{:8}{:8}{:8}{:<8}1P,3E23.16\n",
            m.columns.len(),
            nrow,
            m.form,
            2,
            m.name
        ));
        for (c, col) in m.columns.iter().enumerate() {
            if col.is_empty() {
                continue;
            }
            match layout {
                Op4Layout::Dense => {
                    let (first, vals) = dense(col);
                    s.push_str(&format!("{:8}{:8}{:8}\n", c + 1, first + 1, vals.len()));
                    value_lines(&vals, &mut s);
                }
                Op4Layout::Sparse | Op4Layout::BigMat => {
                    let st = strings(col);
                    let header_words = if layout == Op4Layout::BigMat { 2 } else { 1 };
                    let nw: usize = st.iter().map(|(_, v)| header_words + 2 * v.len()).sum();
                    s.push_str(&format!("{:8}{:8}{:8}\n", c + 1, 0, nw));
                    for (first, vals) in st {
                        let l = 2 * vals.len();
                        if layout == Op4Layout::BigMat {
                            s.push_str(&format!("{:8}{:8}\n", l + 1, first + 1));
                        } else {
                            s.push_str(&format!("{:12}\n", first + 1 + 65_536 * (l + 1)));
                        }
                        value_lines(&vals, &mut s);
                    }
                }
            }
        }
        s.push_str(&format!("{:8}{:8}{:8}\n", m.columns.len() + 1, 1, 1));
        s.push_str(&fortran_e23(1.0));
        s.push('\n');
    }
    s
}

/// The binary file of `matrices`: Fortran records of 4-byte integers and 8-byte values.
pub fn op4_binary(matrices: &[Op4Out<'_>], layout: Op4Layout, little: bool) -> Vec<u8> {
    let int = |v: i64| -> [u8; 4] {
        let v = v as i32;
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let real = |v: f64| -> [u8; 8] {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let mut out = Vec::new();
    let mut record = |bytes: &[u8]| {
        out.extend(int(bytes.len() as i64));
        out.extend(bytes);
        out.extend(int(bytes.len() as i64));
    };
    for m in matrices {
        let nrow = if layout == Op4Layout::BigMat {
            -(m.rows as i64)
        } else {
            m.rows as i64
        };
        let mut h = Vec::new();
        for v in [m.columns.len() as i64, nrow, m.form, 2] {
            h.extend(int(v));
        }
        h.extend(format!("{:<8}", m.name).as_bytes());
        record(&h);
        for (c, col) in m.columns.iter().enumerate() {
            if col.is_empty() {
                continue;
            }
            let mut r = Vec::new();
            match layout {
                Op4Layout::Dense => {
                    let (first, vals) = dense(col);
                    for v in [c as i64 + 1, first as i64 + 1, 2 * vals.len() as i64] {
                        r.extend(int(v));
                    }
                    for v in vals {
                        r.extend(real(v));
                    }
                }
                Op4Layout::Sparse | Op4Layout::BigMat => {
                    let st = strings(col);
                    let header_words = if layout == Op4Layout::BigMat { 2 } else { 1 };
                    let nw: usize = st.iter().map(|(_, v)| header_words + 2 * v.len()).sum();
                    for v in [c as i64 + 1, 0, nw as i64] {
                        r.extend(int(v));
                    }
                    for (first, vals) in st {
                        let l = 2 * vals.len() as i64;
                        if layout == Op4Layout::BigMat {
                            r.extend(int(l + 1));
                            r.extend(int(first as i64 + 1));
                        } else {
                            r.extend(int(first as i64 + 1 + 65_536 * (l + 1)));
                        }
                        for v in vals {
                            r.extend(real(v));
                        }
                    }
                }
            }
            record(&r);
        }
        let mut last = Vec::new();
        for v in [m.columns.len() as i64 + 1, 1, 1] {
            last.extend(int(v));
        }
        last.extend(real(1.0));
        record(&last);
    }
    out
}

/// The columns of a square matrix given by `(row, column, value)` entries, both triangles.
pub fn columns_of(
    n: usize,
    entries: impl Iterator<Item = (usize, usize, f64)>,
) -> Vec<Vec<(usize, f64)>> {
    let mut cols = vec![Vec::new(); n];
    for (r, c, v) in entries {
        cols[c].push((r, v));
    }
    for c in &mut cols {
        c.sort_by_key(|e| e.0);
    }
    cols
}
