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
use std::path::Path;

fn content(path: &Path, reason: String) -> IoError {
    IoError::Content {
        path: path.to_path_buf(),
        reason,
    }
}

/// A Fortran record: its byte offset and its bytes.
type Record<'a> = (usize, &'a [u8]);

/// The Fortran records of `bytes`, and whether the file is little-endian.
fn records<'a>(bytes: &'a [u8], path: &Path) -> Result<(Vec<Record<'a>>, bool), IoError> {
    let first = bytes
        .get(..4)
        .ok_or_else(|| content(path, "shorter than one record".into()))?;
    let little = match (
        i32::from_le_bytes(first.try_into().expect("4 bytes")),
        i32::from_be_bytes(first.try_into().expect("4 bytes")),
    ) {
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
    let word = |b: &[u8]| {
        let b: [u8; 4] = b.try_into().expect("4 bytes");
        if little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        }
    };
    let mut out = Vec::new();
    let mut pos = 0;
    while pos < bytes.len() {
        let truncated = || {
            content(
                path,
                format!("truncated: the record at byte {pos} runs past the end of the file"),
            )
        };
        let n = word(bytes.get(pos..pos + 4).ok_or_else(truncated)?);
        let n = usize::try_from(n).map_err(|_| {
            content(
                path,
                format!("the record at byte {pos} has a negative length {n}"),
            )
        })?;
        let data = bytes.get(pos + 4..pos + 4 + n).ok_or_else(truncated)?;
        let end = word(bytes.get(pos + 4 + n..pos + 8 + n).ok_or_else(truncated)?);
        if end as usize != n {
            return Err(content(
                path,
                format!(
                    "the record at byte {pos} says {n} bytes at its start and {end} at its end"
                ),
            ));
        }
        out.push((pos, data));
        pos += 8 + n;
    }
    Ok((out, little))
}

/// Reads the real modes of an OP2 file's `OUGV1` table.
///
/// # Errors
/// [`IoError::Io`] if unreadable; [`IoError::Content`] naming the byte offset for a truncated or
/// inconsistent record, 8-byte words, a table whose markers are not where the format puts them,
/// complex or SORT2 eigenvectors, scalar points, a second subcase; no `OUGV1` table of real
/// eigenvectors.
pub fn read_op2(path: impl AsRef<Path>) -> Result<F06, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    parse_op2(&bytes, path)
}

/// Parses OP2 bytes (`path` names them in messages).
///
/// # Errors
/// As [`read_op2`].
pub fn parse_op2(bytes: &[u8], path: &Path) -> Result<F06, IoError> {
    let (recs, little) = records(bytes, path)?;
    let int = |r: &[u8]| -> Option<i32> {
        let b: [u8; 4] = r.try_into().ok()?;
        Some(if little {
            i32::from_le_bytes(b)
        } else {
            i32::from_be_bytes(b)
        })
    };
    let words = |r: &[u8]| -> Vec<[u8; 4]> {
        r.chunks_exact(4)
            .map(|c| c.try_into().expect("4 bytes"))
            .collect()
    };
    let to_i = |w: [u8; 4]| {
        if little {
            i32::from_le_bytes(w)
        } else {
            i32::from_be_bytes(w)
        }
    };
    let to_f = |w: [u8; 4]| {
        f64::from(if little {
            f32::from_le_bytes(w)
        } else {
            f32::from_be_bytes(w)
        })
    };
    let at = |k: usize| recs.get(k).map_or(bytes.len(), |r| r.0);
    let mut modes: Vec<F06Mode> = Vec::new();
    let mut subcase: Option<i32> = None;
    let mut k = 0;
    // the header (date, tape code, label) ends at the first table: `2`, its name, `-1`, `7`
    let table_at = |k: usize| {
        recs.get(k).and_then(|r| int(r.1)) == Some(2)
            && recs.get(k + 1).is_some_and(|r| r.1.len() == 8)
            && recs.get(k + 2).and_then(|r| int(r.1)) == Some(-1)
            && recs.get(k + 3).and_then(|r| int(r.1)) == Some(7)
    };
    while k < recs.len() && !table_at(k) {
        k += 1;
    }
    while k + 1 < recs.len() {
        if int(recs[k].1) != Some(2) || recs[k + 1].1.len() != 8 {
            // the file's last records (a table count of 0) end it
            if int(recs[k].1) == Some(0) {
                k += 1;
                continue;
            }
            return Err(content(
                path,
                format!("byte {}: a table's name was expected here", at(k)),
            ));
        }
        let name = String::from_utf8_lossy(recs[k + 1].1).trim().to_string();
        // -1, 7, trailer, -2, 1, 0, n, header
        let layout = [Some(-1), Some(7), None, Some(-2), Some(1), Some(0)];
        for (j, want) in layout.iter().enumerate() {
            let r = recs
                .get(k + 2 + j)
                .ok_or_else(|| content(path, format!("table {name} ends inside its header")))?;
            if let Some(w) = want
                && int(r.1) != Some(*w)
            {
                return Err(content(
                    path,
                    format!(
                        "byte {}: table {name}'s header has no marker {w} where the format puts it",
                        r.0
                    ),
                ));
            }
        }
        k += 2 + layout.len() + 2; // past the header's length and the header
        let mut data: Vec<&[u8]> = Vec::new();
        loop {
            // -m, 1, 0, n (0 ends the table), data
            let marker = |j: usize| recs.get(k + j).and_then(|r| int(r.1));
            match (marker(0), marker(1), marker(2), marker(3)) {
                (Some(m), Some(1), Some(0), Some(0)) if m < 0 => {
                    k += 4;
                    break;
                }
                (Some(m), Some(1), Some(0), Some(n)) if m < 0 && n > 0 => {
                    let r = recs.get(k + 4).ok_or_else(|| {
                        content(path, format!("table {name} ends before its data record"))
                    })?;
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
                    data.push(r.1);
                    k += 5;
                }
                _ => {
                    return Err(content(
                        path,
                        format!(
                            "byte {}: table {name} has no record marker where the format puts one",
                            at(k)
                        ),
                    ));
                }
            }
        }
        if name != "OUGV1" && name != "BOUGV1" {
            continue;
        }
        for pair in data.chunks(2) {
            let [ident, points] = pair else {
                return Err(content(
                    path,
                    format!("table {name} ends with an identification record without its data"),
                ));
            };
            let w = words(ident);
            if w.len() < 10 {
                return Err(content(
                    path,
                    format!(
                        "table {name}: an identification record of {} words, not 146",
                        w.len()
                    ),
                ));
            }
            let (approach, table, case, number) =
                (to_i(w[0]) / 10, to_i(w[1]), to_i(w[3]), to_i(w[4]));
            let (format, width) = (to_i(w[8]), to_i(w[9]));
            if approach != 2 || table != 7 {
                // displacements of another analysis: not modes
                continue;
            }
            if format != 1 || width != 8 {
                return Err(content(
                    path,
                    format!(
                        "table {name}, mode {number}: format {format} with {width} words a point; femu reads real SORT1 eigenvectors (format 1, 8 words)"
                    ),
                ));
            }
            match subcase {
                Some(s) if s != case => {
                    return Err(content(
                        path,
                        format!(
                            "table {name}: eigenvectors of subcase {case} after those of subcase {s}: femu reads the modes of one subcase"
                        ),
                    ));
                }
                _ => subcase = Some(case),
            }
            let eigenvalue = to_f(w[5]);
            let mut pts = Vec::new();
            for p in words(points).chunks(8) {
                if p.len() != 8 {
                    return Err(content(
                        path,
                        format!("table {name}, mode {number}: a point of fewer than 8 words"),
                    ));
                }
                let id = to_i(p[0]) / 10;
                match to_i(p[1]) {
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
                let v: [f64; 6] = std::array::from_fn(|c| to_f(p[2 + c]));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Records written by hand, both byte orders: the header, a table to skip, and OUGV1 with one
    /// mode of two grids.
    #[test]
    fn tables_by_hand() {
        for little in [true, false] {
            let mut b = Vec::new();
            let word = |v: i32| {
                if little {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                }
            };
            let float = |v: f32| {
                if little {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                }
            };
            let mut record = |data: &[u8]| {
                b.extend(word(data.len() as i32));
                b.extend_from_slice(data);
                b.extend(word(data.len() as i32));
            };
            let int = |v: i32| word(v).to_vec();
            record(&int(3));
            record(&[0; 12]);
            record(&int(7));
            record(b"NASTRAN FORT TAPE ID CODE - ");
            record(&int(2));
            record(b"XXXXXXXX");
            record(&int(-1));
            record(&int(0));
            for name in [b"GEOM1   ", b"OUGV1   "] {
                record(&int(2));
                record(name);
                record(&int(-1));
                record(&int(7));
                record(&[0; 28]);
                record(&int(-2));
                record(&int(1));
                record(&int(0));
                record(&int(2));
                record(name);
                let mut ident = Vec::new();
                for v in [23, 7, 0, 1, 1] {
                    ident.extend(word(v));
                }
                ident.extend(float(1.5e5));
                ident.extend(word(0));
                ident.extend(word(0));
                ident.extend(word(1));
                ident.extend(word(8));
                ident.resize(584, 0);
                let mut points = Vec::new();
                for (id, t1) in [(7, 0.25f32), (9, -1.0)] {
                    points.extend(word(10 * id + 3));
                    points.extend(word(1));
                    points.extend(float(t1));
                    for _ in 0..5 {
                        points.extend(float(0.5));
                    }
                }
                for (m, rec) in [(-3, &ident), (-4, &points)] {
                    record(&int(m));
                    record(&int(1));
                    record(&int(0));
                    record(&int((rec.len() / 4) as i32));
                    record(rec);
                }
                record(&int(-5));
                record(&int(1));
                record(&int(0));
                record(&int(0));
            }
            record(&int(0));
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
