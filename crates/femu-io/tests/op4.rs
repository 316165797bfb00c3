//! Nastran's OUTPUT4 matrices read as Nastran writes them.
//!
//! - Files MSC Nastran wrote (`fixtures/nastran/pynastran/op4/`, from pyNastran's tests, BSD):
//!   the same nine MATGEN matrices (identity, a pattern, random real and complex ones in single
//!   and double precision, a null one, strings) as text and binary, dense, sparse and `BIGMAT`,
//!   each equal to what pyNastran 1.4.1 reads from the binary sparse file
//!   (`op4_reference.json`, written by `reference_op4.py` beside them): the binary files to the
//!   bit, the text to its printed digits; and a plate's `KGG` (726 rows), text and binary, against
//!   pyNastran's count, diagonal, norm, sum and sampled entries, the two files against each other
//!   entry by entry to their ten printed digits.
//! - Files the test writes from known matrices (`femu_testkit::op4`, written from the format's
//!   description): every layout, both byte orders, back to the bit.
//! - Malformed files: each refused with its line or byte.

use femu_io::op4::{Op4Matrix, read_op4};
use femu_testkit::op4::{Op4Layout, Op4Out, columns_of, op4_binary, op4_text};
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/nastran/pynastran/op4")
}

fn reference() -> serde_json::Value {
    let text = std::fs::read_to_string(fixtures().join("op4_reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn dense(m: &Op4Matrix) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mut re = vec![vec![0.0; m.cols]; m.rows];
    let mut im = vec![vec![0.0; m.cols]; m.rows];
    for c in 0..m.cols {
        for k in m.col_start[c]..m.col_start[c + 1] {
            re[m.row_index[k]][c] = m.re[k];
            if let Some(i) = &m.im {
                im[m.row_index[k]][c] = i[k];
            }
        }
    }
    (re, im)
}

fn table(v: &serde_json::Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn nastran_s_matgen_matrices_equal_pynastran_s_reading_in_every_layout() {
    let reference = reference();
    let small = reference["small"].as_object().unwrap();
    for file in [
        "mat_b_dn.op4",
        "mat_b_s1.op4",
        "mat_b_s2.op4",
        "mat_t_dn.op4",
        "mat_t_s1.op4",
        "mat_t_s2.op4",
    ] {
        let text = file.starts_with("mat_t");
        let matrices = read_op4(fixtures().join(file)).unwrap();
        assert_eq!(matrices.len(), small.len(), "{file}");
        for m in &matrices {
            let r = &small[&m.name];
            assert_eq!(m.form, r["form"].as_i64().unwrap(), "{file} {}", m.name);
            let shape: Vec<usize> = r["shape"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as usize)
                .collect();
            assert_eq!((m.rows, m.cols), (shape[0], shape[1]), "{file} {}", m.name);
            assert_eq!(m.is_complex(), [3, 4].contains(&m.kind));
            let (re, im) = dense(m);
            let (rre, rim) = (table(&r["re"]), table(&r["im"]));
            for i in 0..m.rows {
                for j in 0..m.cols {
                    for (a, b) in [(re[i][j], rre[i][j]), (im[i][j], rim[i][j])] {
                        // the binary files to the bit; the text ones print 16 or 17 digits;
                        // single precision (types 1 and 3) to the bit of its f32 values
                        let single = [1, 3].contains(&m.kind);
                        // (femu-io's serde_json parses decimal text correctly rounded, its
                        // `float_roundtrip` feature: the reference's text is pyNastran's bits)
                        let tol = if text { 1e-15 * b.abs() } else { 0.0 };
                        assert!(
                            if single {
                                a as f32 == b as f32
                            } else {
                                (a - b).abs() <= tol
                            },
                            "{file} {} ({i}, {j}): {a} vs {b}",
                            m.name
                        );
                    }
                }
            }
        }
        let eye = matrices.iter().find(|m| m.name == "EYE10").unwrap();
        assert_eq!(eye.re, vec![1.0; 10]);
        assert_eq!(eye.row_index, (0..10).collect::<Vec<_>>());
        let null = matrices.iter().find(|m| m.name == "NULL").unwrap();
        assert!(null.re.is_empty() && null.col_start == vec![0; 4]);
    }
}

#[test]
fn a_plate_s_kgg_equals_pynastran_s_reading_as_text_and_binary() {
    let r = &reference()["kgg"];
    let binary = read_op4(fixtures().join("testplate_kgg.op4")).unwrap();
    let text = read_op4(fixtures().join("testplate_kgg_ascii.op4")).unwrap();
    let (b, t) = (&binary[0], &text[0]);
    assert_eq!(
        (b.name.as_str(), b.rows, b.cols, b.form, b.kind),
        ("KGG", 726, 726, 6, 2)
    );
    assert_eq!(b.re.len(), r["stored"].as_u64().unwrap() as usize);
    let mut diagonal = vec![0.0; 726];
    let (mut sum, mut squares) = (0.0, 0.0);
    let entries: Vec<(usize, usize, f64)> = b.entries().collect();
    for &(i, j, v) in &entries {
        if i == j {
            diagonal[i] = v;
        }
        sum += v;
        squares += v * v;
    }
    let rd: Vec<f64> = r["diagonal"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(diagonal, rd);
    let norm = r["frobenius"].as_f64().unwrap();
    // checksums summed in another order than numpy's pairwise sums: 12,196 terms round to
    // n eps ~ 1e-12 of the sum of magnitudes (the entries themselves are compared exactly)
    assert!(
        (squares.sqrt() / norm - 1.0).abs() < 1e-12,
        "{} vs {norm}",
        squares.sqrt()
    );
    assert!((sum - r["sum"].as_f64().unwrap()).abs() < 1e-10 * norm);
    for (k, s) in r["sample"].as_array().unwrap().iter().enumerate() {
        let s = s.as_array().unwrap();
        let e = entries[97 * k];
        let want = s[2].as_f64().unwrap();
        assert_eq!(
            (e.0, e.1),
            (
                s[0].as_u64().unwrap() as usize,
                s[1].as_u64().unwrap() as usize
            )
        );
        assert_eq!(e.2, want);
    }
    // the text file: the same entries to its ten printed digits (1P,5E16.9)
    assert_eq!(
        (t.col_start.clone(), t.row_index.clone()),
        (b.col_start.clone(), b.row_index.clone())
    );
    for (x, y) in t.re.iter().zip(&b.re) {
        assert!((x - y).abs() <= 5e-10 * y.abs(), "{x} vs {y}");
    }
    // and the stiffness is symmetric, as form 6 says: both triangles are in the file
    let at = |i: usize, j: usize| {
        (b.col_start[j]..b.col_start[j + 1])
            .find(|&k| b.row_index[k] == i)
            .map_or(0.0, |k| b.re[k])
    };
    for &(i, j, v) in &entries {
        assert_eq!(at(j, i), v, "({i}, {j})");
    }
}

/// A known symmetric matrix with null columns, single entries, long strings and gaps.
fn known(n: usize, seed: u64) -> Vec<Vec<(usize, f64)>> {
    let mut rng = femu_testkit::Rng(seed);
    let mut entries = Vec::new();
    for i in 0..n {
        if i % 7 == 3 {
            continue; // a null row and column
        }
        entries.push((i, i, 1.0 + rng.next_f64() * 1e6));
        for d in [1, 2, 5, 11] {
            let j = i + d;
            if j < n && j % 7 != 3 {
                let v = (rng.next_f64() - 0.5) * 10f64.powi((rng.next_f64() * 30.0) as i32 - 15);
                entries.push((i, j, v));
                entries.push((j, i, v));
            }
        }
    }
    columns_of(n, entries.into_iter())
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn matrices_written_from_the_format_s_description_read_back_to_the_bit() {
    let dir = tempfile_dir("op4_back");
    let k = known(40, 7);
    let rect: Vec<Vec<(usize, f64)>> = (0..5)
        .map(|c| {
            if c == 2 {
                vec![]
            } else {
                vec![(c, 2.5), (c + 3, -1e-300)]
            }
        })
        .collect();
    let mats = [
        Op4Out {
            name: "KAA",
            rows: 40,
            form: 6,
            columns: k.clone(),
        },
        Op4Out {
            name: "R",
            rows: 9,
            form: 2,
            columns: rect.clone(),
        },
    ];
    for layout in [Op4Layout::Dense, Op4Layout::Sparse, Op4Layout::BigMat] {
        let mut files = vec![write(
            &dir,
            &format!("{layout:?}.op4"),
            op4_text(&mats, layout).as_bytes(),
        )];
        for little in [true, false] {
            files.push(write(
                &dir,
                &format!("{layout:?}_{little}.op4"),
                &op4_binary(&mats, layout, little),
            ));
        }
        for f in files {
            let got = read_op4(&f).unwrap();
            assert_eq!(got.len(), 2);
            for (m, want) in got.iter().zip([&k, &rect]) {
                let mut cols = vec![Vec::new(); m.cols];
                for (r, c, v) in m.entries() {
                    cols[c].push((r, v));
                }
                // a dense column holds the zeros between its first and last rows
                if layout == Op4Layout::Dense {
                    for c in &mut cols {
                        c.retain(|e| e.1 != 0.0);
                    }
                }
                assert_eq!(&cols, want, "{} in {}", m.name, f.display());
            }
        }
    }
    // more than 65,535 rows: the strings are BIGMAT's even when the row count is positive
    let big = Op4Out {
        name: "BIG",
        rows: 70_000,
        form: 2,
        columns: vec![vec![(69_998, 3.0), (69_999, 4.0)]],
    };
    let mut bytes = op4_binary(std::slice::from_ref(&big), Op4Layout::BigMat, true);
    bytes[8..12].copy_from_slice(&70_000i32.to_le_bytes());
    let got = read_op4(write(&dir, "big.op4", &bytes)).unwrap();
    assert_eq!(
        got[0].entries().collect::<Vec<_>>(),
        vec![(69_998, 0, 3.0), (69_999, 0, 4.0)]
    );
}

fn tempfile_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("femu_op4_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn refused(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let e = read_op4(write(dir, name, bytes)).unwrap_err().to_string();
    assert!(e.contains(name), "{e}");
    e
}

#[test]
fn malformed_op4_files_are_refused_with_their_line_or_byte() {
    let dir = tempfile_dir("bad");
    let m = [Op4Out {
        name: "KAA",
        rows: 4,
        form: 6,
        columns: columns_of(
            4,
            [
                (0, 0, 2.0),
                (1, 1, 3.0),
                (2, 2, 4.0),
                (3, 3, 5.0),
                (0, 3, 1.0),
                (3, 0, 1.0),
            ]
            .into_iter(),
        ),
    }];
    let text = op4_text(&m, Op4Layout::Sparse);
    let bin = op4_binary(&m, Op4Layout::Sparse, true);

    // text: truncated, a column out of order, a row outside, a non-number, a wrong count
    let cut: String = text.lines().take(5).map(|l| format!("{l}\n")).collect();
    assert!(refused(&dir, "cut.op4", cut.as_bytes()).contains("ends inside matrix KAA"));
    let swapped = text.replacen("       2       0", "       9       0", 1);
    assert!(refused(&dir, "col.op4", swapped.as_bytes()).contains("column 9 is outside 1..4"));
    let nan = text.replacen("3.0000000000000000E+00", "3.00000000000000NaN+00", 1);
    let line = 1 + nan.lines().position(|l| l.contains("NaN")).unwrap();
    let e = refused(&dir, "nan.op4", nan.as_bytes());
    assert!(
        e.contains(&format!(":{line}: matrix KAA: not a line of numbers")),
        "{e}"
    );
    let header = text.replacen("       6       2KAA", "       6      x2KAA", 1);
    assert!(refused(&dir, "head.op4", header.as_bytes()).contains(":1: not an OP4 matrix header"));
    assert!(refused(&dir, "empty.op4", b"\n\n").contains("no matrix in the file"));
    let dense = op4_text(&m, Op4Layout::Dense).replacen(
        "       1       1       4",
        "       1       3       4",
        1,
    );
    assert!(refused(&dir, "rows.op4", dense.as_bytes()).contains("rows 3..6 outside 1..4"));

    // binary: truncated, the two lengths differ, NW against the record, 8-byte integers
    assert!(refused(&dir, "short.op4", &bin[..bin.len() - 6]).contains("truncated"));
    let mut lengths = bin.clone();
    lengths[28] ^= 1; // the first header record's closing length
    assert!(
        refused(&dir, "len.op4", &lengths)
            .contains("byte 0: the record says 24 bytes at its start and 25 at its end")
    );
    let mut nw = bin.clone();
    nw[44..48].copy_from_slice(&99i32.to_le_bytes()); // marker 32, ICOL 36, IROW 40, NW 44
    assert!(refused(&dir, "nw.op4", &nw).contains("byte 32: matrix KAA, column 1: NW = 99"));
    let mut wide = bin.clone();
    wide[0..4].copy_from_slice(&48i32.to_le_bytes());
    assert!(refused(&dir, "wide.op4", &wide).contains("8-byte integers"));
    let mut string = bin.clone();
    // the first string's header says 8 words where the record has 6 after it
    string[48..52].copy_from_slice(&(1 + 65_536 * 9i32).to_le_bytes());
    let e = refused(&dir, "string.op4", &string);
    assert!(e.contains("a string of 8 words does not fit"), "{e}");
}
