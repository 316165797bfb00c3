//! Fuzzing of the Nastran, Universal File, CalculiX result, Nastran printed-output and OP2
//! readers on the stable toolchain, in CI: decks and files of the corpus (`fixtures/`, the seed
//! corpus of `fuzz/run.sh`, files up to 16 KiB) mutated by proptest (bytes replaced by the
//! characters their formats are made of, lines deleted, duplicated, swapped and cut, fields
//! inserted) must give a model or an error, never a panic;
//! a model that reads must also give its DOF map. `FEMU_FUZZ_CASES` sets the cases per reader
//! (default 192, a few seconds); `fuzz/run.sh` runs libFuzzer for longer on the nightly toolchain.

use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn corpus(dirs: &[&str], exts: &[&str]) -> Vec<(PathBuf, Vec<u8>)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    let mut out = Vec::new();
    for d in dirs {
        let Ok(entries) = std::fs::read_dir(root.join(d)) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for p in paths {
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if exts.contains(&ext) {
                let bytes = std::fs::read(&p).unwrap();
                if bytes.len() <= 16 * 1024 {
                    out.push((p, bytes));
                }
            }
        }
    }
    assert!(!out.is_empty(), "no corpus in {dirs:?}");
    out
}

/// One edit of a file: where (a fraction of its length or of its lines) and what.
#[derive(Debug, Clone)]
enum Edit {
    Byte(f64, u8),
    DeleteLine(f64),
    DuplicateLine(f64),
    SwapLines(f64, f64),
    Truncate(f64),
    InsertField(f64, String),
}

fn edit() -> impl Strategy<Value = Edit> {
    // the characters the formats are made of: digits, signs, exponents, separators, markers
    let alphabet: Vec<u8> = b"0123456789.+-*,$ EeDd\n\r\t-1GRIDTHRU".to_vec();
    let field = prop::sample::select(vec![
        "",
        "0",
        "-1",
        "1.+30",
        "1.-300",
        "NaN",
        "inf",
        "THRU",
        "999999999999",
        "+",
        "*",
        ",",
        "-0.",
        "1e308",
        "123456",
        "ALL",
        "=",
    ]);
    prop_oneof![
        (0.0..1.0f64, prop::sample::select(alphabet)).prop_map(|(p, b)| Edit::Byte(p, b)),
        (0.0..1.0f64).prop_map(Edit::DeleteLine),
        (0.0..1.0f64).prop_map(Edit::DuplicateLine),
        (0.0..1.0f64, 0.0..1.0f64).prop_map(|(a, b)| Edit::SwapLines(a, b)),
        (0.0..1.0f64).prop_map(Edit::Truncate),
        (0.0..1.0f64, field).prop_map(|(p, f)| Edit::InsertField(p, f.to_string())),
    ]
}

fn apply(bytes: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for e in edits {
        let at = |f: f64, n: usize| ((f * n as f64) as usize).min(n.saturating_sub(1));
        match e {
            Edit::Byte(f, c) if !b.is_empty() => {
                let i = at(*f, b.len());
                b[i] = *c;
            }
            Edit::Truncate(f) => b.truncate(at(*f, b.len() + 1)),
            Edit::InsertField(f, s) => {
                let i = at(*f, b.len() + 1).min(b.len());
                let text = format!(",{s}");
                b.splice(i..i, text.bytes());
            }
            _ => {
                let mut lines: Vec<Vec<u8>> =
                    b.split(|c| *c == b'\n').map(<[u8]>::to_vec).collect();
                let n = lines.len();
                match e {
                    Edit::DeleteLine(f) if n > 1 => {
                        lines.remove(at(*f, n));
                    }
                    Edit::DuplicateLine(f) if n > 0 => {
                        let i = at(*f, n);
                        let l = lines[i].clone();
                        lines.insert(i, l);
                    }
                    Edit::SwapLines(x, y) if n > 1 => lines.swap(at(*x, n), at(*y, n)),
                    _ => {}
                }
                b = lines.join(&b'\n');
            }
        }
    }
    b
}

fn cases() -> u32 {
    std::env::var("FEMU_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(192)
}

/// Every reader's run: [`cases`] cases, no failure file.
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// The Nastran reader, strict and lenient, on mutated decks (`INCLUDE`s are left out: they name
/// files).
#[test]
fn nastran_reader_never_panics() {
    let mut decks = corpus(
        &["nastran/femu", "nastran/pynastran", "malformed/model"],
        &["bdf"],
    );
    // decks with a case control, subcases, labels and the cards the reader reads
    decks.push((
        PathBuf::from("cases.bdf"),
        b"SOL 103\nCEND\nSPC = 1 $ c\nMETHOD = 2\nSUBCASE 1\n  SPC = 1\nBEGIN BULK\nGRDSET,,,,,,,3\n\
GRID,1,,0.,0.,0.,,123\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nCTETRA,1,1,1,2,3,4\n\
PSOLID,1,1,3,2,,FULL\nCORD2R,3,0,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nMAT1,1,2.1+11,8.+10,,7850.\n\
SPC1,1,123,2,,,,,,+S\n+S,3\nEIGRL,2,,,3\nPARAM,COUPMASS,1\nCONM2,5,4,,1.,.1\nENDDATA\n"
            .to_vec(),
    ));
    // bars, beams, rods, springs and bushings with their properties (assembled when read)
    decks.push((
        PathBuf::from("structural.bdf"),
        b"SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.,7\nGRID,3,,2.,0.,0.\n\
GRID,4,,2.,1.,0.\nCORD2R,7,,0.,0.,0.,0.,0.,1.,+C\n+C,1.,1.,0.\nMAT1,1,2.1+11,,0.3,7850.\n\
CBAR,1,1,1,2,0.,1.,0.,,+B\n+B,,,0.,0.,0.1\nPBAR,1,1,1.e-4,1.e-8,2.e-8,3.e-8,0.5,,+P\n+P,,,,,,,,,+Q\n+Q,0.8,0.8\n\
CBEAM,2,2,2,3,4\nPBEAML,2,1,,I\n,0.2,0.1,0.1,0.01,0.01,0.01\nCROD,3,3,1,3\nPROD,3,1,1.e-4,1.e-8\n\
CONROD,4,1,2,1,2.e-4\nCELAS1,5,6,2,4,3,4\nPELAS,6,1.e3,0.01\nCELAS2,7,2.e3,3,2\n\
CBUSH,8,9,3,4,,,,7\nPBUSH,9,K,1.e4,1.e4,1.e4,1.e2,1.e2,1.e2\n,B,1.\nBAROR,,1,,,0.,0.,1.\n\
CONM2,10,3,,1.,,,,,+M\n+M,0.1,,0.1,,,0.1\nGRID,5,,0.,1.,0.\nGRID,6,,1.,1.,0.\n\
CQUAD4,11,12,1,2,6,5\nPSHELL,12,1,0.01,1,,1\nSPC1,1,123456,1\nENDDATA\n"
            .to_vec(),
    ));
    let n = decks.len();
    let config = config();
    proptest!(config, |(k in 0..n, edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(&decks[k].1, &edits);
        let text = String::from_utf8_lossy(&bytes);
        if !text.to_ascii_uppercase().contains("INCLUDE") {
            for lenient in [false, true] {
                let options = femu_io::nastran::BdfOptions { lenient };
                if let Ok(deck) = femu_io::nastran::parse_bdf(&text, &decks[k].0, &options) {
                    let _ = deck.model.dof_map();
                    if !deck.model.structural().is_empty() {
                        let _ = deck.model.assemble(deck.mass);
                    }
                }
            }
        }
    });
}

/// The Universal File reader (text and binary datasets) on mutated files, and its test data.
#[test]
fn universal_file_reader_never_panics() {
    let files = corpus(&["uff", "uff/pyuff", "malformed/test"], &["unv", "uff"]);
    let n = files.len();
    let config = config();
    proptest!(config, |(k in 0..n, edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(&files[k].1, &edits);
        let path: &Path = &files[k].0;
        if let Ok(u) = femu_io::uff::parse_uff_bytes(&bytes, path) {
            let _ = u.test_data(path);
            let _ = u.to_mesh(path);
        }
    });
}

/// CalculiX's result file reader on mutated `.frd` files (fixed columns: a byte moved shifts a
/// field).
#[test]
fn frd_reader_never_panics() {
    let files = corpus(&["frd"], &["frd"]);
    let n = files.len();
    let config = config();
    proptest!(config, |(k in 0..n, edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(&files[k].1, &edits);
        let _ = femu_io::frd::parse_frd(&String::from_utf8_lossy(&bytes), &files[k].0);
    });
}

/// CalculiX's printed-output reader on mutated `.dat` files (the eigenvalue table and four modes'
/// displacements CalculiX printed for `fixtures/calculix/cantilever_modes.inp`).
#[test]
fn calculix_dat_reader_never_panics() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/calculix/cantilever_modes.dat");
    let bytes = std::fs::read(&path).unwrap();
    let read =
        femu_io::ccx_dat::parse_calculix_dat(&String::from_utf8_lossy(&bytes), &path).unwrap();
    assert_eq!(read.modes.len(), 4);
    let config = config();
    proptest!(config, |(edits in prop::collection::vec(edit(), 1..6))| {
        let mutated = apply(&bytes, &edits);
        let _ = femu_io::ccx_dat::parse_calculix_dat(&String::from_utf8_lossy(&mutated), &path);
    });
}

/// Nastran's `.f06` reader on mutated pages of a real run's printed modes (the eigenvalue table
/// and the eigenvector blocks of `fixtures/nastran/pynastran/mode_solid_shell_bar.f06`, lines
/// 280-460, about 16 KiB).
#[test]
fn f06_reader_never_panics() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran/mode_solid_shell_bar.f06");
    let text = std::fs::read_to_string(&path).unwrap();
    let pages: String = text
        .lines()
        .skip(279)
        .take(180)
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(femu_io::f06::parse_f06(&pages, &path).is_ok());
    let config = config();
    proptest!(config, |(edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(pages.as_bytes(), &edits);
        let _ = femu_io::f06::parse_f06(&String::from_utf8_lossy(&bytes), &path);
    });
}

/// Nastran's punch reader on mutated records of pyNastran's punch files: the first mode of
/// `fsi.pch` made real (its output form `$REAL OUTPUT`, its eigenvalue a number, each grid's two
/// imaginary records and the scalar points left out), which reads as 9 grids, and `cbush.pch`
/// (static results).
#[test]
fn punch_reader_never_panics() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/nastran/pynastran");
    let fsi = std::fs::read_to_string(dir.join("fsi.pch")).unwrap();
    let mut real = String::new();
    let mut after_point = 0;
    for l in fsi.lines() {
        if l.contains("     S    ") {
            break;
        }
        if l.starts_with("-CONT-") {
            after_point += 1;
            if after_point > 1 {
                continue;
            }
        } else {
            after_point = 0;
        }
        real.push_str(
            &l.replace("$REAL-IMAGINARY OUTPUT", "$REAL OUTPUT          ")
                .replace(
                    "(  0.0000000E+00,  0.0000000E+00)",
                    "  1.0000000E+00                  ",
                ),
        );
        real.push('\n');
    }
    let path = dir.join("fsi.pch");
    let modes = femu_io::punch::parse_punch_modes(&real, &path).unwrap();
    assert_eq!(modes.modes.len(), 1);
    assert_eq!(modes.modes[0].points.len(), 9);
    let cbush = std::fs::read_to_string(dir.join("cbush.pch")).unwrap();
    let corpus = [real, cbush];
    let config = config();
    proptest!(config, |(k in 0..2usize, edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(corpus[k].as_bytes(), &edits);
        let _ = femu_io::punch::parse_punch_modes(&String::from_utf8_lossy(&bytes), &path);
    });
}

/// Nastran's OP2 reader on mutated bytes of a real run's OP2
/// (`fixtures/nastran/pynastran/mode_solid_shell_bar.op2`): record lengths, markers and values
/// changed, records cut, must give modes or an error.
#[test]
fn op2_reader_never_panics() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran/mode_solid_shell_bar.op2");
    let bytes = std::fs::read(&path).unwrap();
    assert!(femu_io::op2::parse_op2(&bytes, &path).is_ok());
    let config = config();
    proptest!(config, |(edits in prop::collection::vec(edit(), 1..6))| {
        let _ = femu_io::op2::parse_op2(&apply(&bytes, &edits), &path);
    });
}

/// Nastran's OUTPUT4 reader on mutated bytes of files Nastran wrote
/// (`fixtures/nastran/pynastran/op4/`: binary and text, dense, sparse and `BIGMAT` strings):
/// record lengths, headers, string words and values changed, records cut, must give matrices or
/// an error.
#[test]
fn op4_reader_never_panics() {
    let dir =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/nastran/pynastran/op4");
    let files: Vec<(PathBuf, Vec<u8>)> = [
        "mat_b_dn", "mat_b_s1", "mat_b_s2", "mat_t_dn", "mat_t_s1", "mat_t_s2",
    ]
    .iter()
    .map(|f| {
        let p = dir.join(format!("{f}.op4"));
        let b = std::fs::read(&p).unwrap();
        (p, b)
    })
    .collect();
    for (p, b) in &files {
        assert!(femu_io::op4::parse_op4(b.as_slice(), p).is_ok());
    }
    let n = files.len();
    let config = config();
    proptest!(config, |(k in 0..n, edits in prop::collection::vec(edit(), 1..6))| {
        let bytes = apply(&files[k].1, &edits);
        let _ = femu_io::op4::parse_op4(bytes.as_slice(), &files[k].0);
    });
}
