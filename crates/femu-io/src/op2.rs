//! Nastran's binary results (`.op2`), read for the real modes of a normal modes run (SOL 103):
//! the eigenvectors of its `OUGV1` table, the same modes the `.f06` prints ([`crate::f06`]).
//!
//! An OP2 is a sequence of Fortran records (`length, bytes, length`), little- or big-endian, with
//! 4-byte words (MSC's and NX's default; 8-byte words are refused). After the file's header, each
//! table is its name, a trailer, a header record, and then data records, each announced by
//! markers (`-k, 1, 0`) and its length in words, until a length of 0. femu walks every table and
//! reads the data of `OUGV1` (or `BOUGV1`): pairs of records, an identification record of 146
//! words (approach code 2, real eigenvalues; table code 7, eigenvectors; the subcase, the mode
//! number and its eigenvalue; format 1, real; 8 words per point, SORT1) and the points
//! (`10 id + device code`, point type, `T1 T2 T3 R1 R2 R3` in the grid's displacement frame).
//! Complex or SORT2 eigenvectors, scalar points, a second subcase, truncated records and
//! unknown layouts are refused, naming the record.

use crate::IoError;
use crate::f06::{F06, F06Mode};
use std::collections::VecDeque;
use std::io::Read;
use std::path::{Path, PathBuf};

fn content(path: &Path, reason: String) -> IoError {
    IoError::Content {
        path: path.to_path_buf(),
        reason,
    }
}

/// The file's Fortran records, read as they are needed: a window from the first record the
/// parser may still look at, so that memory holds the records of one mode at a time and not the
/// file.
struct Records<R> {
    reader: R,
    path: PathBuf,
    little: bool,
    /// The byte offset of the next record to read.
    pos: usize,
    /// The index of the window's first record.
    base: usize,
    window: VecDeque<(usize, Vec<u8>)>,
    eof: bool,
}

impl<R: Read> Records<R> {
    /// Reads the first record's length to tell the byte order.
    fn new(mut reader: R, path: &Path) -> Result<Self, IoError> {
        let mut first = [0u8; 4];
        if crate::stream::read_full(&mut reader, &mut first).map_err(|e| IoError::io(path, e))? < 4
        {
            return Err(content(path, "shorter than one record".into()));
        }
        let little = match (i32::from_le_bytes(first), i32::from_be_bytes(first)) {
            (4, _) => true,
            (_, 4) => false,
            (8, _) | (_, 8) => {
                return Err(content(
                    path,
                    "8-byte words (a double-precision OP2): femu reads OP2 files of 4-byte words, Nastran's default".into(),
                ));
            }
            _ => {
                return Err(content(
                    path,
                    "not an OP2 file: the first record does not hold one 4-byte word".into(),
                ));
            }
        };
        let mut r = Records {
            reader,
            path: path.to_path_buf(),
            little,
            pos: 0,
            base: 0,
            window: VecDeque::new(),
            eof: false,
        };
        r.read_record(Some(first))?;
        Ok(r)
    }

    /// Reads one record into the window (`length`: its length's bytes, already read).
    fn read_record(&mut self, length: Option<[u8; 4]>) -> Result<(), IoError> {
        let mut data = Vec::new();
        let at = self.pos;
        if !crate::stream::fortran_record(
            &mut self.reader,
            self.little,
            at as u64,
            length,
            &mut data,
            &self.path,
        )? {
            self.eof = true;
            return Ok(());
        }
        self.pos += 8 + data.len();
        self.window.push_back((at, data));
        Ok(())
    }

    /// Record `k` (its offset and bytes), `None` past the end of the file.
    fn get(&mut self, k: usize) -> Result<Option<&(usize, Vec<u8>)>, IoError> {
        while !self.eof && self.base + self.window.len() <= k {
            self.read_record(None)?;
        }
        Ok(self.window.get(k - self.base))
    }

    /// Record `k` as one integer, if it is one word.
    fn int(&mut self, k: usize) -> Result<Option<i32>, IoError> {
        let little = self.little;
        Ok(self.get(k)?.and_then(|r| {
            let b: [u8; 4] = r.1.as_slice().try_into().ok()?;
            Some(if little {
                i32::from_le_bytes(b)
            } else {
                i32::from_be_bytes(b)
            })
        }))
    }

    /// Record `k`'s bytes, taken out of the window.
    fn take(&mut self, k: usize) -> Result<Vec<u8>, IoError> {
        self.get(k)?;
        Ok(self
            .window
            .get_mut(k - self.base)
            .map(|r| std::mem::take(&mut r.1))
            .unwrap_or_default())
    }

    /// Record `k`'s byte offset, or the end of the file.
    fn at(&mut self, k: usize) -> Result<usize, IoError> {
        let end = self.pos;
        Ok(self.get(k)?.map_or(end, |r| r.0))
    }

    /// Forgets the records before `k`.
    fn release(&mut self, k: usize) {
        while self.base < k && !self.window.is_empty() {
            self.window.pop_front();
            self.base += 1;
        }
    }

    /// Whether a table starts at record `k`: `2`, its name, `-1`, `7`.
    fn table_at(&mut self, k: usize) -> Result<bool, IoError> {
        Ok(self.int(k)? == Some(2)
            && self.get(k + 1)?.is_some_and(|r| r.1.len() == 8)
            && self.int(k + 2)? == Some(-1)
            && self.int(k + 3)? == Some(7))
    }
}

/// Reads the real modes of an OP2 file's `OUGV1` table. The file is streamed (read ahead on a
/// second thread), one mode's records in memory at a time (docs/SCALING.md, "Reading another
/// solver's matrices").
///
/// # Errors
/// [`IoError::Io`] if unreadable; [`IoError::Content`] naming the byte offset for a truncated or
/// inconsistent record, 8-byte words, a table whose markers are not where the format puts them,
/// complex or SORT2 eigenvectors, scalar points, a second subcase; no `OUGV1` table of real
/// eigenvectors.
pub fn read_op2(path: impl AsRef<Path>) -> Result<F06, IoError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|e| IoError::io(path, e))?;
    parse(crate::stream::ReadAhead::new(file), path)
}

/// Parses OP2 bytes (`path` names them in messages).
///
/// # Errors
/// As [`read_op2`].
pub fn parse_op2(bytes: &[u8], path: &Path) -> Result<F06, IoError> {
    parse(bytes, path)
}

fn parse(reader: impl Read, path: &Path) -> Result<F06, IoError> {
    let mut recs = Records::new(reader, path)?;
    let little = recs.little;
    let to_i = |w: [u8; 4]| {
        if little {
            i32::from_le_bytes(w)
        } else {
            i32::from_be_bytes(w)
        }
    };
    let mut modes: Vec<F06Mode> = Vec::new();
    let mut subcase: Option<i32> = None;
    let mut k = 0;
    // the header (date, tape code, label) ends at the first table: `2`, its name, `-1`, `7`
    while recs.get(k)?.is_some() && !recs.table_at(k)? {
        k += 1;
    }
    while recs.get(k + 1)?.is_some() {
        recs.release(k);
        let first = recs.int(k)?;
        if first != Some(2) || recs.get(k + 1)?.is_none_or(|r| r.1.len() != 8) {
            // the file's last records (a table count of 0) end it
            if first == Some(0) {
                k += 1;
                continue;
            }
            return Err(content(
                path,
                format!("byte {}: a table's name was expected here", recs.at(k)?),
            ));
        }
        let name = recs
            .get(k + 1)?
            .map(|r| String::from_utf8_lossy(&r.1).trim().to_string())
            .unwrap_or_default();
        // -1, 7, trailer, -2, 1, 0, n, header
        let layout = [Some(-1), Some(7), None, Some(-2), Some(1), Some(0)];
        for (j, want) in layout.iter().enumerate() {
            if recs.get(k + 2 + j)?.is_none() {
                return Err(content(
                    path,
                    format!("table {name} ends inside its header"),
                ));
            }
            if let Some(w) = want
                && recs.int(k + 2 + j)? != Some(*w)
            {
                return Err(content(
                    path,
                    format!(
                        "byte {}: table {name}'s header has no marker {w} where the format puts it",
                        recs.at(k + 2 + j)?
                    ),
                ));
            }
        }
        k += 2 + layout.len() + 2; // past the header's length and the header
        let modes_table = name == "OUGV1" || name == "BOUGV1";
        let mut ident: Option<Vec<u8>> = None;
        loop {
            // -m, 1, 0, n (0 ends the table), data
            let marker = (
                recs.int(k)?,
                recs.int(k + 1)?,
                recs.int(k + 2)?,
                recs.int(k + 3)?,
            );
            match marker {
                (Some(m), Some(1), Some(0), Some(0)) if m < 0 => {
                    k += 4;
                    break;
                }
                (Some(m), Some(1), Some(0), Some(n)) if m < 0 && n > 0 => {
                    let Some(r) = recs.get(k + 4)? else {
                        return Err(content(
                            path,
                            format!("table {name} ends before its data record"),
                        ));
                    };
                    if r.1.len() != 4 * n as usize {
                        return Err(content(
                            path,
                            format!(
                                "byte {}: table {name}'s record holds {} bytes where its length says {} words",
                                r.0,
                                r.1.len(),
                                n
                            ),
                        ));
                    }
                    if modes_table {
                        let data = recs.take(k + 4)?;
                        match ident.take() {
                            None => ident = Some(data),
                            Some(id) => {
                                mode_records(
                                    &id,
                                    &data,
                                    &name,
                                    to_i,
                                    &mut subcase,
                                    &mut modes,
                                    path,
                                )?;
                            }
                        }
                    }
                    k += 5;
                    recs.release(k);
                }
                _ => {
                    return Err(content(
                        path,
                        format!(
                            "byte {}: table {name} has no record marker where the format puts one",
                            recs.at(k)?
                        ),
                    ));
                }
            }
        }
        if ident.is_some() {
            return Err(content(
                path,
                format!("table {name} ends with an identification record without its data"),
            ));
        }
    }
    if modes.is_empty() {
        return Err(content(
            path,
            "no real eigenvectors (an OUGV1 table of a normal modes run): ask Nastran for them with DISPLACEMENT(PLOT) = ALL and PARAM,POST,-1 or -2".into(),
        ));
    }
    modes.sort_by_key(|m| m.number);
    Ok(F06 {
        modes,
        without_vectors: 0,
    })
}

/// One mode of an `OUGV1` table: its identification record (146 words) and its points.
fn mode_records(
    ident: &[u8],
    points: &[u8],
    name: &str,
    to_i: impl Fn([u8; 4]) -> i32,
    subcase: &mut Option<i32>,
    modes: &mut Vec<F06Mode>,
    path: &Path,
) -> Result<(), IoError> {
    let word_at =
        |p: &[u8], k: usize| -> [u8; 4] { p[4 * k..4 * k + 4].try_into().expect("4 bytes") };
    let to_f = |w: [u8; 4]| f64::from(f32::from_bits(to_i(w) as u32));
    if ident.len() < 40 {
        return Err(content(
            path,
            format!(
                "table {name}: an identification record of {} words, not 146",
                ident.len() / 4
            ),
        ));
    }
    let w = |k: usize| to_i(word_at(ident, k));
    let (approach, table, case, number) = (w(0) / 10, w(1), w(3), w(4));
    let (format, width) = (w(8), w(9));
    if approach != 2 || table != 7 {
        // displacements of another analysis: not modes
        return Ok(());
    }
    if format != 1 || width != 8 {
        return Err(content(
            path,
            format!(
                "table {name}, mode {number}: format {format} with {width} words a point; femu reads real SORT1 eigenvectors (format 1, 8 words)"
            ),
        ));
    }
    match *subcase {
        Some(s) if s != case => {
            return Err(content(
                path,
                format!(
                    "table {name}: eigenvectors of subcase {case} after those of subcase {s}: femu reads the modes of one subcase"
                ),
            ));
        }
        _ => *subcase = Some(case),
    }
    let eigenvalue = to_f(word_at(ident, 5));
    if !points.len().is_multiple_of(32) {
        return Err(content(
            path,
            format!("table {name}, mode {number}: a point of fewer than 8 words"),
        ));
    }
    // decoded straight from the record, into room reserved for its points (in huge pages where
    // the system gives them: `crate::memory`)
    let mut pts = Vec::with_capacity(points.len() / 32);
    crate::memory::huge_pages(&pts);
    for p in points.chunks_exact(32) {
        let id = to_i(word_at(p, 0)) / 10;
        match to_i(word_at(p, 1)) {
            1 => {}
            t => {
                return Err(content(
                    path,
                    format!(
                        "table {name}, mode {number}: point {id} of type {t} (a scalar or extra point); femu places modes on grid points only"
                    ),
                ));
            }
        }
        let v: [f64; 6] = std::array::from_fn(|c| to_f(word_at(p, 2 + c)));
        pts.push((u64::try_from(id).unwrap_or(0), v));
    }
    let number = usize::try_from(number).unwrap_or(0);
    match modes.iter_mut().find(|m| m.number == number) {
        Some(m) => m.points.extend(pts),
        None => modes.push(F06Mode {
            number,
            eigenvalue,
            points: pts,
            line: 0,
        }),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Records written from the layout (`femu_testkit::op2`), both byte orders: the header, an
    /// empty table to skip, and OUGV1 with one mode of two grids.
    #[test]
    fn tables_by_hand() {
        for little in [true, false] {
            let b = femu_testkit::op2::op2_modes(
                &[7, 9],
                &[(
                    1.5e5,
                    vec![
                        [0.25, 0.5, 0.5, 0.5, 0.5, 0.5],
                        [-1.0, 0.5, 0.5, 0.5, 0.5, 0.5],
                    ],
                )],
                little,
            );
            let f = parse_op2(&b, Path::new("a.op2")).unwrap();
            assert_eq!(f.modes.len(), 1);
            assert_eq!(f.modes[0].eigenvalue, 1.5e5);
            assert_eq!(f.modes[0].points[0], (7, [0.25, 0.5, 0.5, 0.5, 0.5, 0.5]));
            assert_eq!(f.modes[0].points[1].0, 9);
            // truncated, and a length that disagrees with itself
            let e = parse_op2(&b[..b.len() - 3], Path::new("a.op2"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("truncated"), "{e}");
            let mut bad = b.clone();
            let n = bad.len();
            bad[n - 1] ^= 0x01;
            bad[n - 4] ^= 0x01;
            let e = parse_op2(&bad, Path::new("a.op2")).unwrap_err().to_string();
            assert!(e.contains("at its start and"), "{e}");
        }
        let e = parse_op2(
            &[8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 8, 0, 0, 0],
            Path::new("d.op2"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("8-byte words"), "{e}");
        let e = parse_op2(b"%PDF-1.4", Path::new("x.op2"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not an OP2 file"), "{e}");
    }
}
