//! Files written by vendors' systems (from pyuff's test data, `fixtures/uff/pyuff/`, MIT): each is
//! read, or refused with the exact reason and line. The expected values are read off the files
//! by hand (see the comments).

use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/uff/pyuff")
        .join(name)
}

/// LMS TestLab geometry: 36 nodes (dataset 15) and three trace lines (82) whose announced label
/// counts (9, 32, 11) differ from the records as written: TestLab pads with zeros, which are not
/// labels; "Stator" announces all 32 it writes.
#[test]
fn testlab_trace_lines_with_padded_records() {
    let u = femu_io::uff::read_uff(fixture("testlab_161_164_18_15_82.uff")).unwrap();
    assert_eq!(u.nodes.len(), 36);
    // node 36: "36 0 36 8 1.20000e+00 8.40000e+00 0.00000e+00"
    let n36 = u.nodes.iter().find(|n| n.id == 36).unwrap();
    assert_eq!(n36.x, [1.2, 8.4, 0.0]);
    let lines: Vec<(&str, Vec<u64>)> = u
        .trace_lines
        .iter()
        .map(|t| (t.id.as_str(), t.nodes.clone()))
        .collect();
    assert_eq!(
        lines,
        [
            ("Massif", vec![2, 5, 6, 3, 4, 1, 2, 3, 0]),
            (
                "Stator",
                vec![
                    7, 8, 11, 14, 17, 18, 0, 30, 29, 26, 23, 20, 19, 0, 30, 18, 0, 29, 17, 0, 26,
                    14, 0, 11, 23, 0, 8, 20, 0, 7, 19, 0
                ]
            ),
            ("Dalle", vec![34, 33, 36, 35, 32, 31, 34, 0, 33, 32, 0]),
        ]
    );
}

/// Dataset 55 whose fields touch ("4.111111E+03-3.111111E+03"): a complex mode (analysis type 3,
/// data type 5) with eigenvalue -0.1111111 + 41.11111 i rad/s and three complex translations at
/// nodes 111111 and 60101, read as real shapes rotated to the phase of the largest component.
#[test]
fn dataset_55_with_touching_fields() {
    let u = femu_io::uff::read_uff(fixture("uff55_touching_fields.uff")).unwrap();
    assert_eq!(u.modes.len(), 1);
    let m = &u.modes[0];
    let f = (0.1111111f64.hypot(41.11111)) / (2.0 * std::f64::consts::PI);
    assert!(
        (m.frequency_hz / f - 1.0).abs() < 1e-12,
        "{}",
        m.frequency_hz
    );
    // the largest component, 0.1111111 + 0.09111111 i at node 111111 in y, sets the phase
    let phase = 0.09111111f64.atan2(0.1111111);
    let real = |re: f64, im: f64| re * phase.cos() + im * phase.sin();
    let expected = [
        (
            111111,
            [
                0.0,
                real(0.1111111, 0.09111111),
                real(0.007111111, 0.004111111),
            ],
        ),
        (60101, [0.0, 0.0, real(-0.04111111, -0.01111111)]),
    ];
    for ((node, v), (en, ev)) in m.values.iter().zip(expected) {
        assert_eq!(*node, en);
        for c in 0..3 {
            assert!((v[c] - ev[c]).abs() < 1e-12, "node {node}: {v:?} vs {ev:?}");
        }
    }
}

/// Dataset 58 with vendor text in its header and a reference "NONE" on node -1 (both read), whose
/// header announces 2,508,876 points while the file holds 42 values: refused, saying so.
#[test]
fn dataset_58_truncated_is_refused_with_the_reason() {
    let e = femu_io::uff::read_uff(fixture("dataset58_truncated.uff")).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.ends_with("dataset58_truncated.uff:2: dataset 58: record 7 announces 2508876 points (2508876 values), 42 values found"),
        "{msg}"
    );
}

/// Dataset 2412 with beams and shells only: read, and as a model refused with what it holds.
#[test]
fn dataset_2412_without_solids() {
    let path = fixture("mesh_2412_mixed.uff");
    let u = femu_io::uff::read_uff(&path).unwrap();
    assert_eq!((u.nodes.len(), u.elements.len()), (5, 5));
    let e = u.to_mesh(&path).unwrap_err().to_string();
    assert!(
        e.ends_with("no solid element in the file (5 nodes, 5 elements of other kinds): a model needs solid elements (dataset 2412, descriptors 111-118)"),
        "{e}"
    );
}
