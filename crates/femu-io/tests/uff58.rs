//! Universal-file datasets 58 and 58b (functions at nodal DOFs) and 82 (trace lines) from files
//! written by pyuff (`fixtures/uff/generate_frf.py`), checked against the formulas that made
//! their values; round trips; malformed functions; and quadratic solids of dataset 2412 from
//! files written by Gmsh, against the same meshes read from Gmsh's `.msh`.

use femu_fem::element::ElementKind;
use femu_fem::mesh::Mesh;
use femu_io::IoError;
use femu_io::uff::{
    Abscissa, Ordinate, Universal, parse_uff, parse_uff_bytes, read_uff, uff_bytes, uff_string,
};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn fixture(dir: &str, name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(dir)
        .join(name)
}

/// The FRF of the fixture: `1 / (k - w^2 m + i w c)` at 0, 50, ..., 500 Hz.
fn frf(f: f64) -> (f64, f64) {
    let (w0, w) = (2.0 * PI * 100.0, 2.0 * PI * f);
    let (re, im) = (w0 * w0 - w * w, w * 2.0 * 0.02 * w0);
    let d = re * re + im * im;
    (re / d, -im / d)
}

const T_UNEVEN: [f64; 5] = [0.0, 0.1, 0.25, 0.45, 0.7];

fn check_frf_and_sine(u: &Universal, tol: f64) {
    let f = &u.functions[0];
    assert_eq!(f.function_type, 4);
    assert_eq!((f.response.node, f.response.direction), (3, 2));
    assert_eq!((f.reference.node, f.reference.direction), (1, 3));
    assert_eq!(f.response.entity, "struct");
    assert_eq!(f.ids[0], "FRF 3Y/1Z");
    assert!(f.double);
    assert_eq!(
        f.abscissa,
        Abscissa::Even {
            min: 0.0,
            step: 50.0
        }
    );
    assert_eq!(
        (
            f.axes[0].data_type,
            f.axes[0].label.as_str(),
            f.axes[0].units.as_str()
        ),
        (18, "Frequency", "Hz")
    );
    assert_eq!((f.axes[1].data_type, f.axes[2].data_type), (12, 13));
    let Ordinate::Complex(h) = &f.ordinate else {
        panic!("complex FRF expected")
    };
    assert_eq!(h.len(), 11);
    let peak = (0..11)
        .map(|k| frf(50.0 * k as f64).0.hypot(frf(50.0 * k as f64).1))
        .fold(0.0, f64::max);
    for (k, (re, im)) in h.iter().enumerate() {
        let (r, i) = frf(50.0 * k as f64);
        assert!(
            (re - r).abs() <= tol * peak && (im - i).abs() <= tol * peak,
            "point {k}"
        );
    }
    let s = &u.functions[1];
    assert_eq!(
        (s.function_type, s.response.node, s.response.direction),
        (1, 5, -1)
    );
    assert_eq!(s.abscissa, Abscissa::Uneven(T_UNEVEN.to_vec()));
    let Ordinate::Real(y) = &s.ordinate else {
        panic!("real values expected")
    };
    for (t, v) in T_UNEVEN.iter().zip(y) {
        assert!((v - (7.0 * t).sin()).abs() <= tol, "t = {t}");
    }
}

#[test]
fn pyuff_functions_against_their_formulas() {
    // text: pyuff writes doubles with 12 significant digits, singles with 6
    let a = read_uff(fixture("uff", "frf_ascii.uff")).unwrap();
    assert_eq!((a.functions.len(), a.trace_lines.len()), (3, 1));
    assert!(a.functions.iter().all(|f| !f.binary));
    check_frf_and_sine(&a, 1e-11);
    let c = &a.functions[2];
    assert!(!c.double);
    assert_eq!(c.abscissa_values().len(), 8);
    let Ordinate::Real(y) = &c.ordinate else {
        panic!()
    };
    for (k, v) in y.iter().enumerate() {
        let t = 0.1 * k as f64;
        assert!((c.abscissa_values()[k] - t).abs() < 1e-15);
        assert!((v - (3.0 * t).cos()).abs() <= 5e-6, "{k}");
    }
    let t = &a.trace_lines[0];
    assert_eq!((t.number, t.color, t.id.as_str()), (1, 8, "outline"));
    assert_eq!(t.nodes, vec![1, 2, 3, 0, 2, 4]);
    // binary: the doubles themselves (to the last bit of Python's arithmetic)
    let b = read_uff(fixture("uff", "frf_binary.uff")).unwrap();
    assert_eq!(b.functions.len(), 2);
    assert!(b.functions.iter().all(|f| f.binary));
    check_frf_and_sine(&b, 1e-15);
    // pyuff's header counts num_pts * 8 bytes; the records need 176 and 80: said, not fatal
    assert_eq!(b.warnings.len(), 2, "{:?}", b.warnings);
    assert!(b.warnings[0].message.contains("88 bytes") && b.warnings[0].message.contains("176"));
}

#[test]
fn round_trips_are_exact() {
    // text: the same text again
    let a = read_uff(fixture("uff", "frf_ascii.uff")).unwrap();
    let text = uff_string(&a);
    let back = parse_uff(&text, Path::new("a.uff")).unwrap();
    assert_eq!(uff_string(&back), text);
    assert_eq!(back.functions, a.functions);
    assert_eq!(back.trace_lines, a.trace_lines);
    // binary: the same bytes and the same values, bit for bit, also in single precision
    let mut b = read_uff(fixture("uff", "frf_binary.uff")).unwrap();
    let mut single = b.functions[1].clone();
    single.double = false;
    if let Ordinate::Real(y) = &mut single.ordinate {
        y.iter_mut().for_each(|v| *v = *v as f32 as f64);
    }
    if let Abscissa::Uneven(x) = &mut single.abscissa {
        x.iter_mut().for_each(|v| *v = *v as f32 as f64);
    }
    b.functions.push(single);
    b.warnings.clear();
    let bytes = uff_bytes(&b);
    let back = parse_uff_bytes(&bytes, Path::new("b.uff")).unwrap();
    assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    assert_eq!(back.functions, b.functions);
    assert_eq!(uff_bytes(&back), bytes);
    // the text form of binary functions reads back to 13 significant digits
    let as_text = parse_uff(&uff_string(&b), Path::new("t.uff")).unwrap();
    assert!(as_text.functions.iter().all(|f| !f.binary));
    check_frf_and_sine(&as_text, 1e-12);
}

/// A big-endian 58b (the header's byte order 2) reads the same values.
#[test]
fn big_endian_binary() {
    let mut u = read_uff(fixture("uff", "frf_binary.uff")).unwrap();
    u.functions.truncate(1);
    let little = uff_bytes(&u);
    // the values are the last 176 bytes before the closing "    -1\n"
    let end = little.len() - "    -1\n".len();
    let start = end - 176;
    let mut big = little.clone();
    for k in (start..end).step_by(8) {
        big[k..k + 8].reverse();
    }
    let header = String::from_utf8_lossy(&little[..60]).to_string();
    let at = header.find("58b").unwrap() + 3;
    assert_eq!(&big[at..at + 6], b"     1");
    big[at + 5] = b'2';
    let back = parse_uff_bytes(&big, Path::new("big.uff")).unwrap();
    assert_eq!(back.functions[0].ordinate, u.functions[0].ordinate);
}

#[test]
fn malformed_functions_name_the_line() {
    let text = std::fs::read_to_string(fixture("uff", "frf_ascii.uff")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let join = |l: &[&str]| l.join("\n") + "\n";
    let cases: Vec<(String, usize, &str)> = vec![
        // a value line of the FRF removed: fewer values than record 7 announces
        (
            join(&[&lines[..17], &lines[18..]].concat()),
            2,
            "announces 11 points",
        ),
        // ordinate data type 3
        (
            text.replacen("         6        11", "         3        11", 1),
            9,
            "data type 3",
        ),
        // a bad number
        (
            text.replacen("2.53302959106e-06", "2.53302959x06e-06", 1),
            14,
            "not a finite",
        ),
    ];
    // a trace line announcing 7 labels and writing 6: writers disagree on the count (TestLab),
    // so the labels written are kept and the difference is a warning at its line
    let u = parse_uff(
        &text.replace(
            "         1         6         8",
            "         1         7         8",
        ),
        Path::new("bad.uff"),
    )
    .unwrap();
    assert_eq!(u.trace_lines[0].nodes, [1, 2, 3, 0, 2, 4]);
    assert_eq!(
        u.warnings.last().map(|w| (w.line, w.message.as_str())),
        Some((
            56,
            "trace line 1: 7 node labels announced, 6 found: all 6 kept"
        ))
    );
    for (k, (t, line, needle)) in cases.iter().enumerate() {
        match parse_uff(t, Path::new("bad.uff")) {
            Err(e @ IoError::Parse { .. }) => {
                let IoError::Parse { line: l, .. } = &e else {
                    unreachable!()
                };
                assert_eq!(*l, *line, "case {k}: {e}");
                assert!(e.to_string().contains(needle), "case {k}: {e}");
            }
            other => panic!("case {k}: {other:?}"),
        }
    }
    let bin = std::fs::read(fixture("uff", "frf_binary.uff")).unwrap();
    let second = bin.windows(3).rposition(|w| w == b"58b").unwrap();
    // half of the last function's values and the delimiter cut off
    let cut = &bin[..bin.len() - 7 - 40];
    let e = parse_uff_bytes(cut, Path::new("cut.uff"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bytes of values expected") && e.contains("byte offset"),
        "{e}"
    );
    let mut order = bin.clone();
    order[second + 8] = b'3';
    let e = parse_uff_bytes(&order, Path::new("o.uff"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("byte order 3") && e.contains(":17:"), "{e}");
    let mut nan = bin.clone();
    // the first function's last value: before its closing "-1" and the second's opening one
    let data = second - 4 - 7 - 7 - 8;
    nan[data..data + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let e = parse_uff_bytes(&nan, Path::new("n.uff"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("NaN") && e.contains("byte offset"), "{e}");
}

/// (kind, node ids) of every element, sorted: element labels differ between Gmsh's two writers.
fn elements(mesh: &Mesh) -> Vec<(ElementKind, Vec<u64>)> {
    let mut v: Vec<(ElementKind, Vec<u64>)> = (0..mesh.element_count())
        .map(|e| {
            let el = mesh.element(e);
            (el.kind, el.nodes.iter().map(|n| mesh.node_id(*n)).collect())
        })
        .collect();
    v.sort();
    v
}

/// Element and node sets by name, as sorted ids.
fn sets(mesh: &Mesh) -> Vec<(String, bool, Vec<u64>)> {
    let mut v = Vec::new();
    for (name, ids) in mesh.element_sets() {
        let mut ids: Vec<u64> = ids.iter().map(|e| mesh.element(*e).id).collect();
        ids.sort_unstable();
        v.push((name.clone(), false, ids));
    }
    for (name, ids) in mesh.node_sets() {
        let mut ids: Vec<u64> = ids.iter().map(|n| mesh.node_id(*n)).collect();
        ids.sort_unstable();
        v.push((name.clone(), true, ids));
    }
    v
}

/// Dataset 2412's parabolic solids (118, 113, 116) and linear ones (111, 112, 115), as Gmsh
/// writes them, give the same femu elements (node for node) as Gmsh's `.msh` of the same mesh,
/// whose orderings are checked by geometry in `gmsh.rs`; the groups of dataset 2477 give the same
/// element and node sets as the `.msh`'s physical groups.
#[test]
fn quadratic_solids_from_gmsh_unv_equal_the_msh() {
    for (unv, msh, volume) in [
        ("box_mixed2.unv", "box_mixed2_ascii.msh", 2.0),
        ("box_tet10.unv", "box_tet10_ascii.msh", 1.0),
        ("box_mixed1.unv", "box_mixed1.msh", 2.0),
    ] {
        let path = fixture("msh", unv);
        let u = read_uff(&path).unwrap();
        let (from_unv, warnings) = u.to_mesh(&path).unwrap();
        assert!(
            warnings.iter().any(|w| w.message.contains("skipped")),
            "{unv}"
        );
        let from_msh = femu_io::gmsh::read_msh(fixture("msh", msh)).unwrap().mesh;
        let (a, b) = (elements(&from_unv), elements(&from_msh));
        assert_eq!(a.len(), b.len(), "{unv}");
        assert_eq!(a, b, "{unv}");
        // the groups of dataset 2477 are Gmsh's physical groups: the same sets, by ids
        assert_eq!(sets(&from_unv), sets(&from_msh), "{unv}");
        assert!(!sets(&from_unv).is_empty());
        assert!((from_unv.volume().unwrap() - volume).abs() < 1e-12, "{unv}");
        for e in 0..from_unv.element_count() {
            let el = from_unv.element(e);
            for (k, n) in el.nodes.iter().enumerate() {
                let m = from_msh.node_index(from_unv.node_id(*n)).unwrap();
                for c in 0..3 {
                    let (x, y) = (from_unv.coords()[*n][c], from_msh.coords()[m][c]);
                    assert!((x - y).abs() <= 1e-15 * x.abs().max(1.0), "{unv}: node {k}");
                }
            }
        }
    }
    // a parabolic brick with 19 nodes is an error naming the element
    let path = fixture("msh", "box_mixed2.unv");
    let mut u = read_uff(&path).unwrap();
    let e = u.elements.iter_mut().find(|e| e.descriptor == 116).unwrap();
    e.nodes.pop();
    let id = e.id;
    let err = u.to_mesh(&path).unwrap_err().to_string();
    assert!(
        err.contains(&format!("element {id}")) && err.contains("needs 20"),
        "{err}"
    );
}

/// Dataset 2477 groups round-trip (text identical); a group announcing more entities than it
/// lists, or naming an element that does not exist, is an error naming it.
#[test]
fn groups_round_trip_and_malformed_groups() {
    let path = fixture("msh", "box_mixed2.unv");
    let u = read_uff(&path).unwrap();
    assert_eq!(
        u.groups.iter().map(|g| g.name.as_str()).collect::<Vec<_>>(),
        ["xmin", "quads", "wedges"]
    );
    let text = uff_string(&u);
    let back = parse_uff(&text, Path::new("g.unv")).unwrap();
    assert_eq!(back.groups, u.groups);
    assert_eq!(uff_string(&back), text);
    let good = std::fs::read_to_string(&path).unwrap();
    let short = good.replacen(
        "         1         0         0         0         0         0         0         8\nquads",
        "         1         0         0         0         0         0         0         9\nquads",
        1,
    );
    assert_ne!(short, good);
    let e = parse_uff(&short, Path::new("s.unv"))
        .unwrap_err()
        .to_string();
    // the next group's header is read as entities: its zeros are not tags
    assert!(e.contains(":533:") && e.contains("entity tag 0"), "{e}");
    let mut missing = u.clone();
    missing.groups[1].elements.push(999_999);
    let e = missing.to_mesh(&path).unwrap_err().to_string();
    assert!(e.contains("quads") && e.contains("999999"), "{e}");
}

/// Found by the fuzzer: a text field that reads "-1" once written (here after its non-ASCII
/// characters are dropped) would end its dataset; it is written as "(-1)".
#[test]
fn a_text_field_never_writes_the_delimiter() {
    let mut u = read_uff(fixture("uff", "frf_ascii.uff")).unwrap();
    u.trace_lines[0].id = "\u{fffd}-1\u{fffd}".into();
    u.functions[0].ids[1] = " -1 ".into();
    let back = parse_uff(&uff_string(&u), Path::new("d.uff")).unwrap();
    assert_eq!(back.trace_lines[0].id, "(-1)");
    assert_eq!(back.functions[0].ids[1], "(-1)");
    assert_eq!(back.trace_lines[0].nodes, u.trace_lines[0].nodes);
}
