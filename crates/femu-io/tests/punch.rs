//! Nastran punch output (`.pch`) as another solver's modes: a punch file of real eigenvectors in
//! the layout Nastran writes (80-column records, sequence numbers in columns 73-80, `-CONT-`
//! records for the rotations) read back exactly, pyNastran's punch files of complex modes and of
//! static results refused or described, and malformed records refused with their line.

use femu_io::punch::{looks_like_results, parse_punch_modes, read_punch_modes};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran")
        .join(name)
}

/// A punch record: `text` padded to 72 columns and the sequence number in 73-80.
fn rec(out: &mut String, text: &str) {
    let n = out.lines().count() + 1;
    out.push_str(&format!("{text:<72}{n:>8}\n"));
}

/// The header records of a block.
fn header(out: &mut String, kind: &str, output: &str, subcase: u64) {
    rec(out, "$TITLE   = PLATE MODES");
    rec(out, "$SUBTITLE=");
    rec(out, "$LABEL   =");
    rec(out, &format!("${kind}"));
    rec(out, &format!("${output}"));
    rec(out, &format!("$SUBCASE ID = {subcase:>11}"));
}

/// A value as Nastran punches it: `1.500000E-02` (six decimals, a signed two-digit exponent),
/// right-aligned in 18 columns; eigenvalues have seven decimals.
fn e(v: f64) -> String {
    e_with(v, 6)
}

fn e_with(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$E}");
    let (mantissa, exp) = s.split_once('E').unwrap();
    let exp: i32 = exp.parse().unwrap();
    let sign = if exp < 0 { '-' } else { '+' };
    format!("{:>18}", format!("{mantissa}E{sign}{:02}", exp.abs()))
}

/// A grid's two records, as Nastran punches them.
fn grid(out: &mut String, id: u64, v: [f64; 6]) {
    rec(
        out,
        &format!("{id:>10}       G{}{}{}", e(v[0]), e(v[1]), e(v[2])),
    );
    rec(
        out,
        &format!("{:<18}{}{}{}", "-CONT-", e(v[3]), e(v[4]), e(v[5])),
    );
}

/// Modes as `(eigenvalue, [(grid, six components)])`.
type Modes = Vec<(f64, Vec<(u64, [f64; 6])>)>;

/// Two modes of three grids, after a block of static displacements that is not read.
fn two_modes() -> (String, Modes) {
    let modes: Modes = vec![
        (
            1.2345678e3,
            vec![
                (11, [0.0, 1.5e-2, -2.25e-1, 3.0e-3, 0.0, -7.5e-4]),
                (12, [1.0, -2.0e-5, 4.0e-1, 0.0, 6.0e-2, 1.0e-6]),
                (20, [-3.5e-1, 0.0, 0.0, 0.0, 0.0, 2.5e-2]),
            ],
        ),
        (
            9.8765432e4,
            vec![
                (11, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
                (
                    12,
                    [-5.0e-1, 2.5e-1, -1.25e-1, 6.25e-2, -3.125e-2, 1.5625e-2],
                ),
                (20, [0.0, -1.0, 0.0, 1.0e-10, 0.0, 0.0]),
            ],
        ),
    ];
    let mut s = String::new();
    header(&mut s, "DISPLACEMENTS", "REAL OUTPUT", 1);
    grid(&mut s, 11, [1.0; 6]);
    for (k, (value, points)) in modes.iter().enumerate() {
        header(&mut s, "EIGENVECTOR", "REAL OUTPUT", 1);
        rec(
            &mut s,
            &format!(
                "$EIGENVALUE = {}  MODE = {:>5}",
                e_with(*value, 7).trim(),
                k + 1
            ),
        );
        for (id, v) in points {
            grid(&mut s, *id, *v);
        }
    }
    (s, modes)
}

/// Real eigenvectors read back to the digits punched (E13.6: a relative 5e-7), the eigenvalues
/// from their `$EIGENVALUE` records, the displacement block before them passed over; the file is
/// told apart from a DMIG punch by its head.
#[test]
fn real_eigenvectors_are_read_as_punched() {
    let (text, want) = two_modes();
    assert!(looks_like_results(&text));
    assert!(!looks_like_results(
        "DMIG    KAAX           0       6       2       0                       \n"
    ));
    let got = parse_punch_modes(&text, Path::new("plate.pch")).unwrap();
    assert_eq!(got.modes.len(), 2);
    for (k, (m, (value, points))) in got.modes.iter().zip(&want).enumerate() {
        assert_eq!(m.number, k + 1);
        assert!(
            (m.eigenvalue / value - 1.0).abs() < 1e-7,
            "{}",
            m.eigenvalue
        );
        assert_eq!(m.points.len(), points.len());
        for ((id, v), (wid, w)) in m.points.iter().zip(points) {
            assert_eq!(id, wid);
            for c in 0..6 {
                assert!(
                    (v[c] - w[c]).abs() <= 5e-7 * w[c].abs(),
                    "mode {} grid {id} component {c}: {} against {}",
                    k + 1,
                    v[c],
                    w[c]
                );
            }
        }
    }
    // the records' columns are those of Nastran's own punch file (pyNastran's cbush.pch): the
    // point type, the exponents and the sequence number in the same places
    let columns = |l: &str| -> Vec<usize> {
        l.char_indices()
            .filter(|(_, c)| matches!(c, 'G' | 'E'))
            .map(|(i, _)| i)
            .collect()
    };
    let nastran = std::fs::read_to_string(fixture("cbush.pch")).unwrap();
    let theirs: Vec<&str> = nastran.lines().skip(6).take(2).collect();
    let ours: Vec<&str> = text.lines().skip(6).take(2).collect();
    for (a, b) in ours.iter().zip(&theirs) {
        assert_eq!(a.len(), b.len(), "{a:?} {b:?}");
        assert_eq!(columns(a), columns(b), "{a:?} {b:?}");
    }
}

/// pyNastran's `fsi.pch`: complex eigenvectors (`$REAL-IMAGINARY OUTPUT`) refused at the mode's
/// first `$EIGENVALUE` record, line 7; its `cbush.pch` of static results: no eigenvectors, and the
/// blocks it holds named.
#[test]
fn pynastran_punch_files_are_refused_with_what_they_hold() {
    let e = read_punch_modes(fixture("fsi.pch"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("fsi.pch:7") && e.contains("REAL-IMAGINARY OUTPUT") && e.contains("complex"),
        "{e}"
    );
    let e = read_punch_modes(fixture("cbush.pch"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no real eigenvectors")
            && e.contains("$DISPLACEMENTS, $SPCF, $ELEMENT STRAINS, $ELEMENT STRESSES"),
        "{e}"
    );
    for name in ["fsi.pch", "cbush.pch"] {
        let head = std::fs::read_to_string(fixture(name)).unwrap();
        assert!(looks_like_results(&head), "{name}");
        assert_eq!(
            femu_io::Format::from_path(&fixture(name)),
            Some(femu_io::Format::Results),
            "{name}"
        );
    }
}

/// Malformed or unsupported records refused with their line: a scalar point, a second subcase,
/// a grid without its `-CONT-`, a `-CONT-` without its grid, a number that is not one, a mode
/// punched twice, a block without its `$EIGENVALUE`.
#[test]
fn bad_records_are_refused_with_their_line() {
    let (text, _) = two_modes();
    let lines: Vec<&str> = text.lines().collect();
    // the first grid record of mode 1 and its line
    let first = lines
        .iter()
        .position(|l| l.starts_with("$EIGENVALUE"))
        .unwrap()
        + 1;
    let edit = |at: usize, with: Option<&str>| -> String {
        let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        match with {
            Some(w) => out[at] = w.to_string(),
            None => {
                out.remove(at);
            }
        }
        out.join("\n")
    };
    let scalar = lines[first].replacen("       G", "       S", 1);
    // the second mode's block in subcase 2
    let at = text.rfind("$SUBCASE ID =           1").unwrap();
    let second = format!(
        "{}$SUBCASE ID =           2{}",
        &text[..at],
        &text[at + "$SUBCASE ID =           1".len()..]
    );
    let twice = text.replace("MODE =     2", "MODE =     1");
    let no_value: String = text
        .lines()
        .filter(|l| !l.contains("MODE =     2"))
        .map(|l| format!("{l}\n"))
        .collect();
    let cases: Vec<(String, usize, &str)> = vec![
        (edit(first, Some(&scalar)), first + 1, "scalar point 11"),
        (second, 0, "after those of subcase 1"),
        (
            edit(first + 1, None),
            first + 1,
            "-CONT- record) are missing",
        ),
        (edit(first, None), first + 1, "without the grid record"),
        (
            edit(first, Some(&lines[first].replacen("E-02", "X-02", 1))),
            first + 1,
            "three numbers",
        ),
        (twice, 0, "punched twice"),
        (no_value, 0, "without its $EIGENVALUE"),
    ];
    for (text, line, what) in cases {
        let e = parse_punch_modes(&text, Path::new("bad.pch"))
            .map(|_| ())
            .expect_err(what)
            .to_string();
        assert!(e.contains(what), "{what}: {e}");
        if line > 0 {
            assert!(e.contains(&format!("bad.pch:{line}")), "{what}: {e}");
        }
    }
}
