//! Universal File Format: round trips, Fortran and Windows spellings, complex modes, malformed
//! files (each error names its line).

use femu_io::IoError;
use femu_io::uff::{UffElement, UffMode, UffNode, UffUnits, Universal, parse_uff, uff_string};
use std::path::Path;

fn sample() -> Universal {
    Universal {
        units: Some(UffUnits {
            code: 1,
            description: "SI".into(),
            factors: [1.0, 1.0, 1.0],
        }),
        nodes: vec![
            UffNode {
                id: 1,
                x: [0.0, 0.0, 0.01],
            },
            UffNode {
                id: 7,
                x: [0.123456789, -0.07, 0.01],
            },
        ],
        modes: vec![UffMode {
            number: 1,
            frequency_hz: 1538.8612345,
            damping: 0.002,
            modal_mass: 1.0,
            values: vec![(1, [0.0, 1.25e-3, -0.987654321]), (7, [0.0, -2.5e-12, 0.5])],
            complex: false,
            complexity: None,
            imaginary: None,
        }],
        ..Default::default()
    }
}

#[test]
fn round_trip_is_exact_on_the_text_and_to_six_digits_on_values() {
    let u = sample();
    let text = uff_string(&u);
    let back = parse_uff(&text, Path::new("t.unv")).unwrap();
    assert_eq!(uff_string(&back), text);
    assert_eq!(back.nodes.len(), 2);
    assert_eq!(back.units.as_ref().unwrap().code, 1);
    let rel = |a: f64, b: f64| (a - b).abs() <= 5e-6 * b.abs();
    assert!(rel(back.modes[0].frequency_hz, 1538.8612345));
    assert!(rel(back.nodes[1].x[0], 0.123456789));
    assert!(rel(back.modes[0].values[0].1[2], -0.987654321));
    assert!(rel(back.modes[0].values[1].1[1], -2.5e-12));
    // sensors: only the directions with a non-zero value (x is all zeros here)
    let td = back.test_data(Path::new("t.unv")).unwrap();
    assert_eq!(td.sensors.len(), 4);
    assert_eq!(td.modes.frequencies_hz.len(), 1);
}

#[test]
fn fortran_exponents_crlf_complex_modes_and_unknown_datasets() {
    let text = "    -1\r\n    55\r\nid1\r\nid2\r\nid3\r\nid4\r\nid5\r\n         1         3         2         8         5         3\r\n         2         6         1         4\r\n -3.5D+00  6.28318D+03  0.0D+00  0.0D+00  0.0D+00  0.0D+00\r\n         3\r\n  0.0D+00  0.0D+00  1.0D+00  1.0D+00  0.0D+00  0.0D+00\r\n    -1\r\n    -1\r\n  2400\r\nsomething\r\n    -1\r\n";
    let u = parse_uff(text, Path::new("c.unv")).unwrap();
    let m = &u.modes[0];
    assert!(m.complex && m.number == 4);
    // lambda = -2 pi + 2 pi 1000 i: f = |lambda| / 2 pi, zeta = -Re / |lambda|
    let w = 3.5f64.hypot(6283.18);
    assert!((m.frequency_hz - w / (2.0 * std::f64::consts::PI)).abs() < 1e-9);
    assert!((m.damping - 3.5 / w).abs() < 1e-12);
    // (1 + i, 0) rotated by its phase: sqrt(2) real
    assert!((m.values[0].1[1] - 2f64.sqrt()).abs() < 1e-12 && m.values[0].1[0] == 0.0);
    assert_eq!(u.warnings.len(), 1);
    assert!(
        u.warnings[0].message.contains("dataset 2400") && u.warnings[0].line == 15,
        "{:?}",
        u.warnings
    );
}

#[test]
fn malformed_files_name_the_line() {
    let good = uff_string(&sample());
    let cases: Vec<(String, usize)> = vec![
        (good.replacen("   164", "   abc", 1), 2),
        (good.replace("1.53886E+03", "1.5388xE+03"), 21),
        (good.trim_end().trim_end_matches("-1").to_string(), 12),
        (good.replacen("    -1\n", "  junk\n", 1), 1),
        (
            good.replace(
                "         1         2         2         8         2         3",
                "         1         2         7         8         2         3",
            ),
            19,
        ),
        (good.replace("         7\n", "        -7\n"), 24),
        (good.replace("1.53886E+03", "-1.53886E+03"), 21),
    ];
    for (k, (text, line)) in cases.iter().enumerate() {
        match parse_uff(text, Path::new("bad.unv")) {
            Err(IoError::Parse {
                line: l, reason, ..
            }) => assert_eq!(l, *line, "case {k}: {reason}"),
            other => panic!("case {k}: {other:?}"),
        }
    }
}

/// Found by the fuzzer: a value with a three-digit exponent ran into its neighbour on writing.
#[test]
fn three_digit_exponents_stay_separate() {
    let mut u = sample();
    u.modes[0].values[0].1 = [-9.06449e-3, -1.16504e101, 2.5e-120];
    let text = uff_string(&u);
    let back = parse_uff(&text, Path::new("e.unv")).unwrap();
    assert_eq!(
        back.modes[0].values[0].1,
        [-9.06449e-3, -1.16504e101, 2.5e-120]
    );
    assert_eq!(uff_string(&back), text);
    // a NaN written by a careless caller is refused on reading, with its line
    u.modes[0].values[0].1[0] = f64::NAN;
    assert!(matches!(
        parse_uff(&uff_string(&u), Path::new("n.unv")),
        Err(IoError::Parse { line: 23, .. })
    ));
}

/// Found by the fuzzer too: dataset 164's D25.17 fields and the integer fields of datasets 15 and
/// 55 had the same problem (a negative three-digit exponent, a ten-digit mode number).
#[test]
fn wide_fields_stay_separate() {
    let mut u = sample();
    u.units.as_mut().unwrap().factors = [0.0, -1.99475e-201, 0.232075];
    u.units.as_mut().unwrap().description = "a very long unit description, é".into();
    u.modes[0].number = -9_000_000_000;
    let text = uff_string(&u);
    let back = parse_uff(&text, Path::new("w.unv")).unwrap();
    assert_eq!(
        back.units.as_ref().unwrap().factors,
        [0.0, -1.99475e-201, 0.232075]
    );
    assert_eq!(back.modes[0].number, -9_000_000_000);
    assert_eq!(uff_string(&back), text);
}

/// Datasets 2411 and 2412: a hex8 and a wedge with a shell and a beam element; double-precision
/// coordinates come back bit for bit, the text on rewrite; the mesh has the exact volume; a
/// quadratic brick is refused with its label.
#[test]
fn nodes_and_elements_2411_2412() {
    let x = |i: u64| {
        let c = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
            [2.0, 0.0, 0.0],
            [2.0, 0.0, 1.0],
        ];
        let p = c[(i - 1) as usize];
        [
            p[0] * 0.1 + 1e-17,
            p[1] * std::f64::consts::PI / 30.0,
            p[2] * 0.01,
        ]
    };
    let u = Universal {
        nodes: (1..=10).map(|i| UffNode { id: i, x: x(i) }).collect(),
        nodes_2411: true,
        elements: vec![
            UffElement {
                id: 1,
                descriptor: 115,
                nodes: (1..=8).collect(),
            },
            UffElement {
                id: 2,
                descriptor: 112,
                nodes: vec![2, 9, 3, 6, 10, 7],
            },
            UffElement {
                id: 3,
                descriptor: 94,
                nodes: vec![1, 2, 3, 4],
            },
            UffElement {
                id: 4,
                descriptor: 21,
                nodes: vec![1, 5],
            },
        ],
        ..Default::default()
    };
    let text = uff_string(&u);
    let back = parse_uff(&text, Path::new("m.unv")).unwrap();
    assert_eq!(back.nodes, u.nodes);
    assert_eq!(back.elements, u.elements);
    assert_eq!(uff_string(&back), text);
    let (mesh, warnings) = back.to_mesh(Path::new("m.unv")).unwrap();
    assert_eq!(mesh.element_count(), 2);
    assert_eq!(warnings.len(), 1);
    let (lx, ly, lz) = (0.1, std::f64::consts::PI / 30.0, 0.01);
    assert!((mesh.volume().unwrap() - 1.5 * lx * ly * lz).abs() < 1e-15);
    let mut quad = back.clone();
    quad.elements[0].descriptor = 116;
    let e = quad.to_mesh(Path::new("q.unv")).unwrap_err().to_string();
    assert!(e.contains("element 1") && e.contains("116"), "{e}");
    // a truncated element record names its line
    let cut = text.replace(
        "         1         2         3         4         5         6         7         8\n",
        "         1         2         3\n",
    );
    assert!(matches!(
        parse_uff(&cut, Path::new("c.unv")),
        Err(IoError::Parse { .. })
    ));
}

/// Dataset 55 with an absurd count of values per node is an error naming record 6, not an
/// allocation of that size.
#[test]
fn absurd_values_per_node() {
    let good = uff_string(&sample());
    let bad = good.replace(
        "         1         2         2         8         2         3",
        "         1         2         2         8         2 900000000000000",
    );
    match parse_uff(&bad, Path::new("v.unv")) {
        Err(IoError::Parse { line, reason, .. }) => {
            assert_eq!(line, 19, "{reason}");
            assert!(reason.contains("values per node"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

/// A complex mode's indicators read from the file (`docs/MATH.md`, "Complex modes"): node 3's y
/// is `1`, node 5's y is `e^(i 30 deg)` (equal magnitudes): by hand `MPC = cos^2 30 = 0.75` and
/// `MPD = 15` degrees. A real mode has none.
#[test]
fn complex_mode_indicators() {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let text = format!(
        "    -1\n    55\nid1\nid2\nid3\nid4\nid5\n         1         3         2         8         5         3\n         2         6         1         4\n -3.5D+00  6.28318D+03  0.0D+00  0.0D+00  0.0D+00  0.0D+00\n         3\n  0.0D+00  0.0D+00  1.0D+00  0.0D+00  0.0D+00  0.0D+00\n         5\n  0.0D+00  0.0D+00  {c:.15E}  {s:.15E}  0.0D+00  0.0D+00\n    -1\n"
    );
    let u = parse_uff(&text, Path::new("c.unv")).unwrap();
    let k = u.modes[0]
        .complexity
        .expect("a complex mode has indicators");
    assert!((k.mpc - 0.75).abs() < 1e-12, "{k:?}");
    assert!((k.mpd_degrees - 15.0).abs() < 1e-9, "{k:?}");
    assert!(sample().modes.iter().all(|m| m.complexity.is_none()));
    let real = parse_uff(&uff_string(&sample()), Path::new("r.unv")).unwrap();
    assert!(real.modes.iter().all(|m| m.complexity.is_none()));
}

/// A complex mode keeps its imaginary parts, turned with the real ones by the phase of the largest
/// component (node 3's y, `2 e^(i 90 deg)`: turned to 2), and is written back complex: node 5's y
/// `e^(i 120 deg)` becomes `e^(i 30 deg)` (`0.866 + 0.5 i`), and a second reading gives the same
/// values, frequency, damping and indicators to the written digits (six).
#[test]
fn complex_modes_keep_and_write_their_imaginary_parts() {
    let (c, s) = (120f64.to_radians().cos(), 120f64.to_radians().sin());
    let text = format!(
        "    -1\n    55\nid1\nid2\nid3\nid4\nid5\n         1         3         2         8         5         3\n         2         6         1         4\n -3.5D+00  6.28318D+03  0.0D+00  0.0D+00  0.0D+00  0.0D+00\n         3\n  0.0D+00  0.0D+00  0.0D+00  2.0D+00  0.0D+00  0.0D+00\n         5\n  0.0D+00  0.0D+00  {c:.15E}  {s:.15E}  0.0D+00  0.0D+00\n    -1\n"
    );
    let u = parse_uff(&text, Path::new("c.unv")).unwrap();
    let m = &u.modes[0];
    let im = m.imaginary.as_ref().expect("imaginary parts kept");
    assert!((m.values[0].1[1] - 2.0).abs() < 1e-12 && im[0][1].abs() < 1e-12);
    let (c30, s30) = (30f64.to_radians().cos(), 0.5);
    assert!((m.values[1].1[1] - c30).abs() < 1e-12, "{:?}", m.values);
    assert!((im[1][1] - s30).abs() < 1e-12, "{im:?}");
    let again = parse_uff(&uff_string(&u), Path::new("again.unv")).unwrap();
    let b = &again.modes[0];
    assert!(b.complex);
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-5 * y.abs().max(1.0);
    assert!(close(b.frequency_hz, m.frequency_hz) && close(b.damping, m.damping));
    let bi = b.imaginary.as_ref().unwrap();
    for k in 0..2 {
        for c in 0..3 {
            assert!(close(b.values[k].1[c], m.values[k].1[c]) && close(bi[k][c], im[k][c]));
        }
    }
    let (ka, kb) = (m.complexity.unwrap(), b.complexity.unwrap());
    assert!(close(ka.mpc, kb.mpc) && close(ka.mpd_degrees, kb.mpd_degrees));
    // a real file stays real
    let real = parse_uff(&uff_string(&sample()), Path::new("r.unv")).unwrap();
    assert!(
        real.modes
            .iter()
            .all(|m| !m.complex && m.imaginary.is_none())
    );
}
