//! Nastran's `OUTPUT4` matrices (`.op4`), text or binary, as the DMAP module `OUTPUT4` writes
//! them (MSC Nastran DMAP Programmer's Guide, OUTPUT4; docs/ARCHITECTURE.md, "Models solved
//! elsewhere"). A file holds matrices one after another, each:
//!
//! - a header: `NCOL NROW NF NTYPE NAME` (columns, rows, form: 1 square, 2 rectangular, 6
//!   symmetric, ...; type: 1 real single, 2 real double, 3 complex single, 4 complex double; the
//!   name in 8 characters). A negative `NROW`, or more than 65,535 rows, says the sparse columns
//!   use the `BIGMAT` string headers. In a text file the header line is `4I8, A8` and the values'
//!   Fortran format (`1P,3E23.16`);
//! - its non-null columns in order, each `ICOL IROW NW`:
//!   - `IROW > 0` (dense): `NW` values from row `IROW` on (in a text file `NW` counts the numbers
//!     printed, in a binary one the 4-byte words);
//!   - `IROW = 0` (sparse): `NW` words of strings, each a header and `L` words of consecutive
//!     values: the header is one word `IROW + 65536 (L + 1)`, or with `BIGMAT` two words
//!     `L + 1, IROW`;
//! - a last record `NCOL+1 1 1` and one value, which ends the matrix.
//!
//! A binary file is Fortran records (`length, bytes, length`), little- or big-endian, of 4-byte
//! integers (8-byte integers, the `48`-byte header of a 64-bit build, are refused); a double takes
//! two words, a complex value two numbers. Text values are Fortran `E` fields that may touch
//! (`2.7E+05-2.7E+05`). Every value is kept as `f64`: a single-precision file gives its `f32`
//! values exactly.
//!
//! A symmetric matrix (form 6) is written with both triangles. The reader streams the file (one
//! record or line at a time) into compressed columns, so memory is the matrix's and not the
//! file's twice (docs/SCALING.md, "Reading another solver's matrices").

use crate::IoError;
use std::io::{BufRead, Read};
use std::path::Path;

/// One matrix of an OP4 file, in compressed sparse columns (rows sorted within each column).
#[derive(Debug, Clone, PartialEq)]
pub struct Op4Matrix {
    /// Its name (`KGG`), trimmed.
    pub name: String,
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// `NF`: 1 square, 2 rectangular, 3 diagonal, 4 lower and 5 upper triangular, 6 symmetric,
    /// 8 identity, 9 square (pseudo-identity).
    pub form: i64,
    /// `NTYPE`: 1 real single, 2 real double, 3 complex single, 4 complex double.
    pub kind: i64,
    /// The start of each column in `row_index` (length `cols + 1`).
    pub col_start: Vec<usize>,
    /// Row of each stored value, 0-based.
    pub row_index: Vec<usize>,
    /// Real part of each stored value.
    pub re: Vec<f64>,
    /// Imaginary part of each stored value, for a complex matrix.
    pub im: Option<Vec<f64>>,
    /// Where its header is: the line of a text file, the byte of a binary one.
    pub at: Place,
}

/// A place in a file, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    /// A 1-based line of a text file.
    Line(usize),
    /// A byte offset of a binary file.
    Byte(u64),
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Place::Line(l) => write!(f, "line {l}"),
            Place::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

impl Op4Matrix {
    /// Whether it holds complex values.
    pub fn is_complex(&self) -> bool {
        self.im.is_some()
    }

    /// The type as Nastran names it: `RS`, `RD`, `CS`, `CD`.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            1 => "RS (real, single precision)",
            2 => "RD (real, double precision)",
            3 => "CS (complex, single precision)",
            _ => "CD (complex, double precision)",
        }
    }

    /// The form as Nastran names it.
    pub fn form_name(&self) -> &'static str {
        match self.form {
            1 => "square",
            2 => "rectangular",
            3 => "diagonal",
            4 => "lower triangular",
            5 => "upper triangular",
            6 => "symmetric",
            8 => "identity",
            9 => "pseudo-identity",
            _ => "other",
        }
    }

    /// The stored values `(row, column, real part)`, column by column.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.cols).flat_map(move |c| {
            (self.col_start[c]..self.col_start[c + 1])
                .map(move |k| (self.row_index[k], c, self.re[k]))
        })
    }
}

/// How values are laid out for a matrix's type.
#[derive(Debug, Clone, Copy)]
struct Layout {
    /// 8-byte numbers.
    double: bool,
    /// Two numbers a value.
    complex: bool,
}

impl Layout {
    fn of(kind: i64) -> Option<Self> {
        match kind {
            1 => Some(Layout {
                double: false,
                complex: false,
            }),
            2 => Some(Layout {
                double: true,
                complex: false,
            }),
            3 => Some(Layout {
                double: false,
                complex: true,
            }),
            4 => Some(Layout {
                double: true,
                complex: true,
            }),
            _ => None,
        }
    }
    /// 4-byte words a number takes.
    fn words_per_number(self) -> usize {
        if self.double { 2 } else { 1 }
    }
    /// Numbers a value takes.
    fn numbers_per_value(self) -> usize {
        if self.complex { 2 } else { 1 }
    }
}

/// The matrix being filled, column by column.
struct Builder {
    m: Op4Matrix,
    layout: Layout,
    bigmat: bool,
    /// The last column started (1-based; 0 before the first).
    column: usize,
    /// `(column, start in row_index)` of each column started: the null columns between take no
    /// memory until the matrix is complete (a damaged header's column count costs nothing).
    starts: Vec<(usize, usize)>,
}

impl Builder {
    fn new(
        ncol: i64,
        nrow: i64,
        form: i64,
        kind: i64,
        name: String,
        at: Place,
    ) -> Result<Self, String> {
        let layout = Layout::of(kind)
            .ok_or_else(|| format!("matrix {name:?}: type {kind} is not 1-4 (RS, RD, CS, CD)"))?;
        if ncol < 0 {
            return Err(format!("matrix {name:?}: {ncol} columns"));
        }
        let rows = nrow.unsigned_abs() as usize;
        let cols = ncol as usize;
        Ok(Builder {
            m: Op4Matrix {
                name,
                rows,
                cols,
                form,
                kind,
                col_start: Vec::new(),
                row_index: Vec::new(),
                re: Vec::new(),
                im: layout.complex.then(Vec::new),
                at,
            },
            layout,
            bigmat: nrow < 0 || rows > 65_535,
            column: 0,
            starts: Vec::new(),
        })
    }

    /// Reserves room for `values` values (virtual memory, touched as they arrive, in huge pages
    /// where the system gives them: [`crate::memory::huge_pages`]).
    fn reserve(&mut self, values: usize) {
        self.m.row_index.reserve(values);
        self.m.re.reserve(values);
        crate::memory::huge_pages(&self.m.row_index);
        crate::memory::huge_pages(&self.m.re);
        if let Some(im) = self.m.im.as_mut() {
            im.reserve(values);
            crate::memory::huge_pages(im);
        }
    }

    /// Starts column `icol` (1-based; the columns between are null); a column given again
    /// continues (its rows must follow).
    fn start_column(&mut self, icol: i64) -> Result<(), String> {
        let name = &self.m.name;
        if icol < 1 || icol as usize > self.m.cols {
            return Err(format!(
                "matrix {name}: column {icol} is outside 1..{}",
                self.m.cols
            ));
        }
        let icol = icol as usize;
        if icol < self.column {
            return Err(format!(
                "matrix {name}: column {icol} comes after column {}",
                self.column
            ));
        }
        if icol > self.column {
            self.starts.push((icol, self.m.row_index.len()));
            self.column = icol;
        }
        Ok(())
    }

    /// Stores `count` values from row `irow` (1-based) on, taken from `numbers` (two numbers a
    /// value when complex), straight into the columns.
    fn put(
        &mut self,
        irow: i64,
        count: usize,
        mut numbers: impl Iterator<Item = f64>,
    ) -> Result<(), String> {
        let name = &self.m.name;
        if irow < 1 || irow as usize + count - 1 > self.m.rows {
            return Err(format!(
                "matrix {name}: column {} has rows {irow}..{} outside 1..{}",
                self.column,
                irow + count as i64 - 1,
                self.m.rows
            ));
        }
        let first = irow as usize - 1;
        let start = self.starts.last().map_or(0, |s| s.1);
        if self.m.row_index.len() > start && self.m.row_index.last().is_some_and(|&r| r >= first) {
            return Err(format!(
                "matrix {name}: column {} gives row {irow} after row {}",
                self.column,
                self.m.row_index.last().map_or(0, |r| r + 1)
            ));
        }
        let from = self.m.re.len();
        match self.m.im.as_mut() {
            None => self.m.re.extend(numbers.by_ref().take(count)),
            Some(im) => {
                for _ in 0..count {
                    self.m.re.push(numbers.next().unwrap_or(f64::NAN));
                    im.push(numbers.next().unwrap_or(f64::NAN));
                }
            }
        }
        let bad = self.m.re[from..]
            .iter()
            .chain(self.m.im.as_ref().map_or(&[][..], |im| &im[from..]))
            .position(|v| !v.is_finite());
        if let Some(k) = bad.or((self.m.re.len() != from + count).then_some(0)) {
            return Err(format!(
                "matrix {name}: the value at row {}, column {} is not a finite number",
                first + k % count.max(1) + 1,
                self.column
            ));
        }
        self.m.row_index.extend(first..first + count);
        Ok(())
    }

    /// The matrix, its column starts filled in: a null column starts (and ends) where the next
    /// stored one starts.
    fn finish(mut self) -> Op4Matrix {
        let nnz = self.m.row_index.len();
        let mut col_start = Vec::with_capacity(self.m.cols + 1);
        let mut p = 0;
        for c in 1..=self.m.cols {
            while p < self.starts.len() && self.starts[p].0 < c {
                p += 1;
            }
            col_start.push(self.starts.get(p).map_or(nnz, |s| s.1));
        }
        col_start.push(nnz);
        self.m.col_start = col_start;
        self.m.row_index.shrink_to_fit();
        self.m.re.shrink_to_fit();
        if let Some(im) = self.m.im.as_mut() {
            im.shrink_to_fit();
        }
        self.m
    }
}

/// Reads every matrix of an OP4 file, text or binary (told apart by the first bytes).
///
/// # Errors
/// The file system's; [`IoError::Parse`] (text, with the line) or [`IoError::Content`] (binary,
/// with the byte) for a malformed header or column, a row or column outside the matrix, columns
/// or rows out of order, a string that does not fill its column's words, a truncated file, a
/// value that is not a finite number; 8-byte integers refused.
pub fn read_op4(path: impl AsRef<Path>) -> Result<Vec<Op4Matrix>, IoError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    let len = file.metadata().map_or(0, |m| m.len());
    parse(crate::stream::ReadAhead::new(file), path, len)
}

/// Reads the matrices of an OP4 stream (`path` names it in messages): [`read_op4`] on any
/// reader, a byte slice among them.
///
/// # Errors
/// As [`read_op4`].
pub fn parse_op4(reader: impl BufRead, path: &Path) -> Result<Vec<Op4Matrix>, IoError> {
    parse(reader, path, 0)
}

/// [`parse_op4`] of a stream of `len` bytes (0: unknown): the columns of each matrix are
/// reserved for as many values as the rest of the stream could hold, virtual memory that is
/// touched only as values arrive (and returned when the matrix is complete), so that they are
/// not copied as they grow.
fn parse(mut reader: impl BufRead, path: &Path, len: u64) -> Result<Vec<Op4Matrix>, IoError> {
    let head = reader.fill_buf().map_err(|e| IoError::io(path, e))?;
    let binary = head.len() >= 4 && {
        let w: [u8; 4] = head[..4].try_into().expect("4 bytes");
        [24, 48].contains(&i32::from_le_bytes(w)) || [24, 48].contains(&i32::from_be_bytes(w))
    };
    if binary {
        read_binary(reader, path, len)
    } else {
        read_text(reader, path, len)
    }
}

fn text_error(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// The integers of a text line (`3I8`, `2I8` or one).
fn integers(t: &str) -> Option<Vec<i64>> {
    t.split_whitespace().map(|s| s.parse().ok()).collect()
}

/// Appends the Fortran `E` numbers of `line` to `out`: fields may touch (`1.0E+00-2.0E+00`), a
/// `D` exponent is read as `E`, and an exponent of three digits may drop its letter
/// (`1.0-100`). `None` for a character no number has.
fn fortran_numbers(line: &str, out: &mut Vec<f64>) -> Option<()> {
    let b = line.as_bytes();
    let mut i = 0;
    let mut token = String::new();
    while i < b.len() {
        if b[i].is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        if b[i] == b'+' || b[i] == b'-' {
            i += 1;
        }
        let mantissa = i;
        let mut point = false;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            point |= b[i] == b'.';
            i += 1;
        }
        if i == mantissa {
            return None;
        }
        let mantissa_end = i;
        let letter = i < b.len() && matches!(b[i], b'E' | b'e' | b'D' | b'd');
        let e_letter = letter && matches!(b[i], b'E' | b'e');
        let bare = !letter
            && i + 1 < b.len()
            && matches!(b[i], b'+' | b'-')
            && b[i + 1].is_ascii_digit()
            && point;
        if letter || bare {
            if letter {
                i += 1;
            }
            if i < b.len() && matches!(b[i], b'+' | b'-') {
                i += 1;
            }
            let exponent = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if i == exponent {
                return None;
            }
        }
        // Rust reads `1.5E+03` as it stands; a `D` exponent or a bare one (`1.5+003`) is
        // rewritten with an `E` first
        let value = if !letter && !bare || e_letter {
            line[start..i].parse().ok()?
        } else {
            token.clear();
            token.push_str(&line[start..mantissa_end]);
            token.push('E');
            let exp_from = if letter {
                mantissa_end + 1
            } else {
                mantissa_end
            };
            token.push_str(&line[exp_from..i]);
            token.parse().ok()?
        };
        out.push(value);
    }
    Some(())
}

/// A text file read line by line, counting lines.
struct Lines<R> {
    reader: R,
    buf: String,
    line: usize,
}

impl<R: BufRead> Lines<R> {
    /// The next line's number and text (without its end), `None` at the end of the file.
    fn next(&mut self, path: &Path) -> Result<Option<(usize, &str)>, IoError> {
        self.buf.clear();
        let n = self
            .reader
            .read_line(&mut self.buf)
            .map_err(|e| IoError::io(path, e))?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        Ok(Some((self.line, self.buf.trim_end_matches(['\n', '\r']))))
    }

    /// The next `count` numbers of matrix `name`, over as many lines as they take, into `out`.
    fn numbers(
        &mut self,
        path: &Path,
        count: usize,
        name: &str,
        out: &mut Vec<f64>,
    ) -> Result<(), IoError> {
        out.clear();
        while out.len() < count {
            let Some((l, t)) = self.next(path)? else {
                return Err(text_error(
                    path,
                    self.line,
                    format!("the file ends inside matrix {name}"),
                ));
            };
            if fortran_numbers(t, out).is_none() {
                return Err(text_error(
                    path,
                    l,
                    format!("matrix {name}: not a line of numbers: {:?}", t.trim_end()),
                ));
            }
        }
        if out.len() > count {
            return Err(text_error(
                path,
                self.line,
                format!(
                    "matrix {name}: {} numbers where the record announces {count}",
                    out.len()
                ),
            ));
        }
        Ok(())
    }
}

fn read_text(reader: impl BufRead, path: &Path, len: u64) -> Result<Vec<Op4Matrix>, IoError> {
    let mut lines = Lines {
        reader,
        buf: String::new(),
        line: 0,
    };
    let mut out = Vec::new();
    let mut numbers: Vec<f64> = Vec::new();
    loop {
        // the header, after any blank lines between matrices
        let header = loop {
            match lines.next(path)? {
                None if out.is_empty() => {
                    return Err(IoError::Content {
                        path: path.to_path_buf(),
                        reason: "no matrix in the file".into(),
                    });
                }
                None => return Ok(out),
                Some((_, t)) if t.trim().is_empty() => continue,
                Some((l, t)) => break (l, t.to_string()),
            }
        };
        let (at, header) = header;
        let bad_header = || {
            text_error(
                path,
                at,
                format!(
                    "not an OP4 matrix header (NCOL NROW NF NTYPE NAME in 4I8, A8): {:?}",
                    header.trim_end()
                ),
            )
        };
        let ints = header
            .get(..32.min(header.len()))
            .and_then(integers)
            .filter(|v| v.len() == 4)
            .ok_or_else(bad_header)?;
        let name = header
            .get(32..40.min(header.len()))
            .unwrap_or("")
            .trim()
            .to_string();
        let mut b = Builder::new(ints[0], ints[1], ints[2], ints[3], name, Place::Line(at))
            .map_err(|r| text_error(path, at, r))?;
        // a printed number takes at least 8 characters
        b.reserve((len / 8) as usize);
        let per_number_words = b.layout.words_per_number();
        loop {
            let last = lines.line;
            let Some((here, t)) = lines.next(path)? else {
                return Err(text_error(
                    path,
                    last,
                    format!(
                        "the file ends inside matrix {} (its last record, column {}, is missing)",
                        b.m.name,
                        b.m.cols + 1
                    ),
                ));
            };
            let col = integers(t).filter(|v| v.len() == 3).ok_or_else(|| {
                text_error(
                    path,
                    here,
                    format!(
                        "matrix {}: expected a column's ICOL IROW NW, got {:?}",
                        b.m.name,
                        t.trim_end()
                    ),
                )
            })?;
            let (icol, irow, nw) = (col[0], col[1], col[2]);
            if nw < 0 {
                return Err(text_error(
                    path,
                    here,
                    format!("matrix {}: NW = {nw}", b.m.name),
                ));
            }
            if icol == b.m.cols as i64 + 1 {
                // the last record: one value that ends the matrix
                lines.numbers(path, 1, &b.m.name, &mut numbers)?;
                break;
            }
            b.start_column(icol)
                .map_err(|r| text_error(path, here, r))?;
            if irow > 0 {
                lines.numbers(path, nw as usize, &b.m.name, &mut numbers)?;
                if !numbers.len().is_multiple_of(b.layout.numbers_per_value()) {
                    return Err(text_error(
                        path,
                        here,
                        format!(
                            "matrix {}: {nw} numbers do not make complex pairs",
                            b.m.name
                        ),
                    ));
                }
                let count = numbers.len() / b.layout.numbers_per_value();
                b.put(irow, count, numbers.iter().copied())
                    .map_err(|r| text_error(path, here, r))?;
                continue;
            }
            // sparse: strings until the column's words are used
            let mut left = nw as usize;
            while left > 0 {
                let last = lines.line;
                let Some((sl, t)) = lines.next(path)? else {
                    return Err(text_error(
                        path,
                        last,
                        format!("the file ends inside matrix {}", b.m.name),
                    ));
                };
                let head = integers(t).unwrap_or_default();
                let (words, row, header_words) = match (b.bigmat, head.as_slice()) {
                    (true, [l1, r]) => (*l1 - 1, *r, 2),
                    (false, [is]) => (is / 65_536 - 1, is % 65_536, 1),
                    _ => {
                        return Err(text_error(
                            path,
                            sl,
                            format!(
                                "matrix {}, column {icol}: expected a string header ({}), got {:?}",
                                b.m.name,
                                if b.bigmat {
                                    "L+1 IROW"
                                } else {
                                    "IROW + 65536 (L+1)"
                                },
                                t.trim_end()
                            ),
                        ));
                    }
                };
                let value_words = per_number_words * b.layout.numbers_per_value();
                if words < 1
                    || !(words as usize).is_multiple_of(value_words)
                    || words as usize + header_words > left
                {
                    return Err(text_error(
                        path,
                        sl,
                        format!(
                            "matrix {}, column {icol}: a string of {words} words does not fit the column's {left} words left in values of {value_words} words",
                            b.m.name
                        ),
                    ));
                }
                left -= words as usize + header_words;
                lines.numbers(
                    path,
                    words as usize / per_number_words,
                    &b.m.name,
                    &mut numbers,
                )?;
                let count = numbers.len() / b.layout.numbers_per_value();
                b.put(row, count, numbers.iter().copied())
                    .map_err(|r| text_error(path, sl, r))?;
            }
        }
        out.push(b.finish());
    }
}

/// A binary file's Fortran records, streamed.
struct Records<R> {
    reader: R,
    little: bool,
    offset: u64,
    buf: Vec<u8>,
}

impl<R: Read> Records<R> {
    /// The next record's bytes (in `buf`) and its offset, `None` at the end of the file.
    fn next(&mut self, path: &Path) -> Result<Option<u64>, IoError> {
        let at = self.offset;
        let more = crate::stream::fortran_record(
            &mut self.reader,
            self.little,
            at,
            None,
            &mut self.buf,
            path,
        )?;
        if !more {
            return Ok(None);
        }
        self.offset += 8 + self.buf.len() as u64;
        Ok(Some(at))
    }

    fn int(&self, k: usize) -> i64 {
        let b: [u8; 4] = self.buf[4 * k..4 * k + 4].try_into().expect("4 bytes");
        i64::from(if self.little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        })
    }
}

fn binary_error(path: &Path, at: u64, reason: String) -> IoError {
    IoError::Content {
        path: path.to_path_buf(),
        reason: format!("byte {at}: {reason}"),
    }
}

/// The numbers of `bytes`: 4- or 8-byte floats of the file's byte order.
fn binary_numbers(bytes: &[u8], double: bool, little: bool) -> impl Iterator<Item = f64> + '_ {
    bytes
        .chunks_exact(if double { 8 } else { 4 })
        .map(move |c| match (double, little) {
            (true, true) => f64::from_le_bytes(c.try_into().expect("8 bytes")),
            (true, false) => f64::from_be_bytes(c.try_into().expect("8 bytes")),
            (false, true) => f64::from(f32::from_le_bytes(c.try_into().expect("4 bytes"))),
            (false, false) => f64::from(f32::from_be_bytes(c.try_into().expect("4 bytes"))),
        })
}

fn read_binary(mut reader: impl BufRead, path: &Path, len: u64) -> Result<Vec<Op4Matrix>, IoError> {
    let head = reader.fill_buf().map_err(|e| IoError::io(path, e))?;
    let w: [u8; 4] = head[..4].try_into().expect("4 bytes");
    let little = [24, 48].contains(&i32::from_le_bytes(w));
    let first = if little {
        i32::from_le_bytes(w)
    } else {
        i32::from_be_bytes(w)
    };
    if first == 48 {
        return Err(binary_error(
            path,
            0,
            "8-byte integers (a 64-bit OUTPUT4, header of 48 bytes): femu reads OP4 files of 4-byte words, Nastran's default".into(),
        ));
    }
    let mut recs = Records {
        reader,
        little,
        offset: 0,
        buf: Vec::new(),
    };
    let mut out = Vec::new();
    while let Some(at) = recs.next(path)? {
        if recs.buf.len() != 24 {
            return Err(binary_error(
                path,
                at,
                format!(
                    "a matrix header (24 bytes: NCOL NROW NF NTYPE NAME) was expected, the record has {} bytes",
                    recs.buf.len()
                ),
            ));
        }
        let name = String::from_utf8_lossy(&recs.buf[16..24])
            .trim()
            .to_string();
        let mut b = Builder::new(
            recs.int(0),
            recs.int(1),
            recs.int(2),
            recs.int(3),
            name,
            Place::Byte(at),
        )
        .map_err(|r| binary_error(path, at, r))?;
        let value_bytes = 4 * b.layout.words_per_number() * b.layout.numbers_per_value();
        b.reserve((len.saturating_sub(recs.offset) / value_bytes as u64) as usize);
        let layout = b.layout;
        loop {
            let Some(rat) = recs.next(path)? else {
                return Err(binary_error(
                    path,
                    recs.offset,
                    format!(
                        "the file ends inside matrix {} (its last record, column {}, is missing)",
                        b.m.name,
                        b.m.cols + 1
                    ),
                ));
            };
            if recs.buf.len() < 12 {
                return Err(binary_error(
                    path,
                    rat,
                    format!(
                        "matrix {}: a column record of {} bytes",
                        b.m.name,
                        recs.buf.len()
                    ),
                ));
            }
            let (icol, irow, nw) = (recs.int(0), recs.int(1), recs.int(2));
            if icol == b.m.cols as i64 + 1 {
                break;
            }
            let data_words = (recs.buf.len() - 12) / 4;
            if nw < 0 || nw as usize != data_words || !recs.buf.len().is_multiple_of(4) {
                return Err(binary_error(
                    path,
                    rat,
                    format!(
                        "matrix {}, column {icol}: NW = {nw} words, the record holds {data_words}",
                        b.m.name
                    ),
                ));
            }
            b.start_column(icol)
                .map_err(|r| binary_error(path, rat, r))?;
            let value_words = layout.words_per_number() * layout.numbers_per_value();
            if irow > 0 {
                if !data_words.is_multiple_of(value_words) {
                    return Err(binary_error(
                        path,
                        rat,
                        format!(
                            "matrix {}, column {icol}: {data_words} words are not whole values of {value_words} words",
                            b.m.name
                        ),
                    ));
                }
                let numbers = binary_numbers(&recs.buf[12..], layout.double, little);
                b.put(irow, data_words / value_words, numbers)
                    .map_err(|r| binary_error(path, rat, r))?;
                continue;
            }
            let mut k = 3; // the word after the column's header
            let end = 3 + data_words;
            while k < end {
                let (words, row, header_words) = if b.bigmat {
                    if k + 2 > end {
                        return Err(binary_error(
                            path,
                            rat,
                            format!(
                                "matrix {}, column {icol}: a string header runs past the record",
                                b.m.name
                            ),
                        ));
                    }
                    (recs.int(k) - 1, recs.int(k + 1), 2)
                } else {
                    let is = recs.int(k);
                    (is / 65_536 - 1, is % 65_536, 1)
                };
                if words < 1
                    || !(words as usize).is_multiple_of(value_words)
                    || k + header_words + words as usize > end
                {
                    return Err(binary_error(
                        path,
                        rat,
                        format!(
                            "matrix {}, column {icol}: a string of {words} words does not fit the record ({} words left, values of {value_words} words)",
                            b.m.name,
                            end - k - header_words.min(end - k)
                        ),
                    ));
                }
                let from = 4 * (k + header_words);
                let numbers = binary_numbers(
                    &recs.buf[from..from + 4 * words as usize],
                    layout.double,
                    little,
                );
                b.put(row, words as usize / value_words, numbers)
                    .map_err(|r| binary_error(path, rat, r))?;
                k += header_words + words as usize;
            }
        }
        out.push(b.finish());
    }
    if out.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no matrix in the file".into(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::fortran_numbers;

    /// Fortran `E` fields as printers write them: touching, signed, a `D` exponent, an exponent
    /// of three digits without its letter, a lower-case `e`, a bare mantissa; and what is not a
    /// number.
    #[test]
    fn fortran_fields() {
        let mut out = Vec::new();
        fortran_numbers(
            " 2.708955224E+05-2.708955224E+05 1.0D-03-.5e+01 1.0-100 3. +7.25",
            &mut out,
        )
        .unwrap();
        assert_eq!(
            out,
            vec![
                2.708955224e5,
                -2.708955224e5,
                1.0e-3,
                -5.0,
                1.0e-100,
                3.0,
                7.25
            ]
        );
        for bad in ["1.0E", "abc", "1.0E+0x", "--1.0"] {
            assert_eq!(fortran_numbers(bad, &mut out), None, "{bad}");
        }
    }
}
