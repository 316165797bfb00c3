//! Files written by vendors' systems (from pyuff's test data, `fixtures/uff/pyuff/`, MIT): each is
//! read, or refused with the exact reason and line. The expected values are read off the files
//! by hand (see the comments).

use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/uff/pyuff")
        .join(name)
}

/// LMS TestLab geometry: coordinate systems (18), 36 nodes (dataset 15) and three trace lines
/// (82) whose announced label
/// counts (9, 32, 11) differ from the records as written: TestLab pads with zeros, which are not
/// labels; "Stator" announces all 32 it writes.
#[test]
fn testlab_trace_lines_with_padded_records() {
    let u = femu_io::uff::read_uff(fixture("testlab_161_164_18_15_82.uff")).unwrap();
    assert_eq!(u.nodes.len(), 36);
    // dataset 151: record 1 "AME_Test", record 6 the program
    let h = u.header.as_ref().unwrap();
    assert_eq!(
        (h.model.as_str(), h.program.as_str()),
        ("AME_Test", "LMS Test.Lab Rev project-15A")
    );
    // 36 coordinate systems (18), 30 of them turned; every node measures in its own system.
    // SYS1 by its points: origin (-2.4, -0.95, 0), x towards (-3.4, -0.95, -8.7e-8), xz plane
    // through (-3.4, -0.95, -1): local x = -X, y = +Y, z = -Z (to the file's 8.7e-8)
    assert_eq!(u.coordinate_systems.len(), 36);
    assert_eq!(
        u.coordinate_systems
            .values()
            .filter(|c| !c.is_global_orientation())
            .count(),
        30
    );
    assert_eq!(u.displacement_systems.len(), 36);
    let sys1 = &u.coordinate_systems[&1];
    assert_eq!(sys1.name, "SYS1");
    let want = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (sys1.axes[i][j] - want[i][j]).abs() < 1e-6,
                "{:?}",
                sys1.axes
            );
        }
    }
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

/// Coordinate systems (dataset 18) as test systems use them: a system 5 at origin (1, 2, 3)
/// turned 90 degrees about z (local x = global -y, local y = global x), by its three points.
/// Node 1 is measured along its three local axes in system 5: read as global components
/// `(b, -a, c)` of the local `(a, b, c)`; node 2 only along its local x: one sensor along global
/// -y with its reading as written; node 3 in the global system; node 4's coordinates (1, 0, 0)
/// in system 5 are (1, 1, 3) globally. A system named but not defined is an error naming the
/// node.
#[test]
fn displacement_and_definition_systems_of_dataset_18() {
    use femu_io::uff::{UffMode, UffNode, Universal, parse_uff, uff_string};
    let u = Universal {
        nodes: (1..=4)
            .map(|id| UffNode {
                id,
                x: [id as f64, 0.0, 0.0],
            })
            .collect(),
        modes: vec![UffMode {
            number: 1,
            frequency_hz: 100.0,
            damping: 0.0,
            modal_mass: 0.0,
            values: vec![
                (1, [0.5, -0.25, 0.125]),
                (2, [0.75, 0.0, 0.0]),
                (3, [0.0, 1.0, 0.0]),
                (4, [0.0, 0.0, 0.5]),
            ],
            complex: false,
            complexity: None,
            imaginary: None,
        }],
        ..Default::default()
    };
    let text = uff_string(&u);
    let system = "    -1\n    18\n         5         0         0         8         1\nTURNED\n  1.00000e+00  2.00000e+00  3.00000e+00  1.00000e+00  1.00000e+00  3.00000e+00\n  1.00000e+00  2.00000e+00  4.00000e+00\n    -1\n";
    // nodes 1 and 2 measure in system 5; node 4 is defined in it
    let mut patched = String::new();
    for line in text.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        let line = if t.len() == 7 && (t[0] == "1" || t[0] == "2") && t[3] == "11" {
            line.replacen("         0        11", "         5        11", 1)
        } else if t.len() == 7 && t[0] == "4" && t[3] == "11" {
            "         4         5         0        11  1.00000E+00  0.00000E+00  0.00000E+00"
                .to_string()
        } else {
            line.to_string()
        };
        patched.push_str(&line);
        patched.push('\n');
    }
    let at = patched.find("    -1\n    15\n").unwrap();
    patched.insert_str(at, system);
    let read = parse_uff(&patched, std::path::Path::new("cs.uff")).unwrap();
    let n4 = read.nodes.iter().find(|n| n.id == 4).unwrap();
    for (got, want) in n4.x.iter().zip([1.0, 1.0, 3.0]) {
        assert!((got - want).abs() < 1e-12, "{:?}", n4.x);
    }
    let data = read.test_data(std::path::Path::new("cs.uff")).unwrap();
    let got: Vec<(u64, [f64; 3], f64)> = data
        .sensors
        .iter()
        .enumerate()
        .map(|(r, s)| (s.node, s.direction, data.modes.shapes[(r, 0)]))
        .collect();
    let want: Vec<(u64, [f64; 3], f64)> = vec![
        (1, [1.0, 0.0, 0.0], -0.25),
        (1, [0.0, 1.0, 0.0], -0.5),
        (1, [0.0, 0.0, 1.0], 0.125),
        (2, [0.0, -1.0, 0.0], 0.75),
        (3, [0.0, 1.0, 0.0], 1.0),
        (4, [0.0, 0.0, 1.0], 0.5),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for ((n, d, v), (wn, wd, wv)) in got.iter().zip(&want) {
        assert_eq!(n, wn);
        for c in 0..3 {
            assert!((d[c] - wd[c]).abs() < 1e-12, "node {n}: {d:?} vs {wd:?}");
        }
        assert!((v - wv).abs() < 1e-12, "node {n}: {v} vs {wv}");
    }
    // a system named but not defined
    let undefined = patched.replacen("    18\n         5", "    18\n         6", 1);
    let e = parse_uff(&undefined, std::path::Path::new("cs.uff"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "node 4 is defined in coordinate system 5, which no dataset 18 or 2420 before it defines"
        ),
        "{e}"
    );
}

/// The TestLab geometry written by femu and read back: the same coordinate systems (to the six
/// digits of the format), the same nodes and displacement systems.
#[test]
fn coordinate_systems_survive_a_round_trip() {
    let u = femu_io::uff::read_uff(fixture("testlab_161_164_18_15_82.uff")).unwrap();
    let text = femu_io::uff::uff_string(&u);
    let back = femu_io::uff::parse_uff(&text, std::path::Path::new("back.uff")).unwrap();
    assert_eq!(back.displacement_systems, u.displacement_systems);
    assert_eq!(back.nodes.len(), u.nodes.len());
    for (a, b) in u.nodes.iter().zip(&back.nodes) {
        assert_eq!(a.id, b.id);
        for c in 0..3 {
            assert!((a.x[c] - b.x[c]).abs() <= 1e-5 * a.x[c].abs().max(1.0));
        }
    }
    assert_eq!(back.coordinate_systems.len(), u.coordinate_systems.len());
    for (k, a) in &u.coordinate_systems {
        let b = &back.coordinate_systems[k];
        assert_eq!((&a.name, a.kind), (&b.name, b.kind));
        for i in 0..3 {
            assert!((a.origin[i] - b.origin[i]).abs() < 1e-5);
            for j in 0..3 {
                assert!((a.axes[i][j] - b.axes[i][j]).abs() < 1e-5, "system {k}");
            }
        }
    }
}

/// A mesh in millimetres (dataset 164, length factor 1000, as I-DEAS writes a mm system): the
/// model's coordinates are metres, and the conversion is said.
#[test]
fn millimetre_meshes_become_metres() {
    use femu_io::uff::{UffElement, UffNode, UffUnits, Universal, parse_uff, uff_string};
    let corners = [
        [0.0, 0.0, 0.0],
        [100.0, 0.0, 0.0],
        [100.0, 50.0, 0.0],
        [0.0, 50.0, 0.0],
        [0.0, 0.0, 20.0],
        [100.0, 0.0, 20.0],
        [100.0, 50.0, 20.0],
        [0.0, 50.0, 20.0],
    ];
    let u = Universal {
        units: Some(UffUnits {
            code: 5,
            description: "mm (milli newton)".into(),
            factors: [1000.0, 1.0, 1.0],
        }),
        nodes: corners
            .iter()
            .enumerate()
            .map(|(i, x)| UffNode {
                id: i as u64 + 1,
                x: *x,
            })
            .collect(),
        nodes_2411: true,
        elements: vec![UffElement {
            id: 1,
            descriptor: 115,
            nodes: (1..=8).collect(),
        }],
        ..Default::default()
    };
    let path = std::path::Path::new("mm.unv");
    let back = parse_uff(&uff_string(&u), path).unwrap();
    let (mesh, warnings) = back.to_mesh(path).unwrap();
    assert_eq!(mesh.coords()[6], [0.1, 0.05, 0.02]);
    // 0.1 x 0.05 x 0.02 m
    assert!((mesh.volume().unwrap() - 1e-4).abs() < 1e-18);
    assert!(
        warnings.iter().any(|w| w
            .message
            .starts_with("coordinates converted to metres: divided by the length factor 1000")),
        "{warnings:?}"
    );
}

/// NX export: coordinate systems of dataset 2420 (rows 1-3 of the matrix are the local axes in
/// global components, row 4 the origin), each node defined and measured in its own system, and
/// 176 complex normal modes of dataset 2414. Expected values computed by hand with numpy from
/// the file's records: node 3992 is given as (20.9409, 13.0694, 39.6833) in CS1; `x_local R`
/// puts it at (-13.00982232, 39.70284674, -20.94090139) mm; its first mode (record 10 mode 1,
/// 2.33832E+04 Hz) reads (0.0195655, 13.0354, -1.92335e-7) in CS1, globally
/// (-13.03538532, 0.01956535, -0.0195655). The 18 nodes lie in one plane z = -20.9409 (as the
/// curved beam they are) only with this reading of the matrix: the transposed reading scatters
/// them by 0.04 mm off any plane.
#[test]
fn nx_coordinate_systems_of_2420_and_modes_of_2414() {
    let path = fixture("nx_2420_2414_beam.uff");
    let u = femu_io::uff::read_uff(&path).unwrap();
    assert_eq!(u.coordinate_systems.len(), 18);
    assert_eq!(u.header.as_ref().unwrap().program, "NX: Correlation");
    assert!(
        u.warnings
            .iter()
            .all(|w| !w.to_string().contains("dataset 151"))
    );
    assert_eq!(u.modes.len(), 176);
    assert_eq!(u.modes_from_2414, 176);
    assert!(u.modes.iter().all(|m| m.complex));
    let n = u.nodes.iter().find(|n| n.id == 3992).unwrap();
    let want = [-13.00982232, 39.70284674, -20.94090139];
    for i in 0..3 {
        assert!((n.x[i] - want[i]).abs() < 1e-7, "{:?}", n.x);
    }
    let z: Vec<f64> = u.nodes.iter().map(|n| n.x[2]).collect();
    assert!(z.iter().all(|v| (v + 20.9409).abs() < 1e-4), "{z:?}");
    assert_eq!(u.modes[0].number, 1);
    assert!((u.modes[0].frequency_hz - 2.33832e4).abs() < 1e-6);
    let data = u.test_data(&path).unwrap();
    assert_eq!(data.modes.frequencies_hz[0], 2.33832e4);
    let row = |c: usize| {
        data.sensors
            .iter()
            .position(|s| s.node == 3992 && s.direction[c] == 1.0)
            .unwrap()
    };
    let want = [-13.03538532, 0.01956535, -0.0195655];
    for (c, w) in want.iter().enumerate() {
        let got = data.modes.shapes[(row(c), 0)];
        assert!((got - w).abs() < 1e-7, "component {c}: {got} vs {w}");
    }
}

/// A temperature result in dataset 2414 is not a mode: skipped with a warning naming it.
#[test]
fn dataset_2414_static_result_is_skipped() {
    let u = femu_io::uff::read_uff(fixture("heat_engine_2414_static.uff")).unwrap();
    assert!(u.modes.is_empty());
    let w: Vec<String> = u.warnings.iter().map(ToString::to_string).collect();
    assert!(
        w.iter().any(|m| m.ends_with(
            "heat_engine_2414_static.uff:61: dataset 2414 1 (Temperature) is a static result, not a mode: skipped"
        )),
        "{w:?}"
    );
}

/// Cylindrical and spherical systems of dataset 2420, by hand: both share the frame origin
/// (1, 2, 3), local x = global Y, local y = global Z, local z = global X.
/// Node 9 at cylindrical (r 2, theta 90 deg, z 0.5): local (0, 2, 0.5), global (1.5, 2, 5); its
/// reading (u_r, u_theta, u_z) = (0.3, -0.2, 0.7) along e_r = Z, e_theta = -Y, e_z = X is
/// globally (0.7, 0.2, 0.3). Node 10 at spherical (r 1, theta 90, phi 90): local (0, 1, 0),
/// global (1, 2, 4); e_r = Z, e_theta = -X, e_phi = -Y, so (0.1, 0.2, 0.4) is (-0.2, -0.4, 0.1).
#[test]
fn cylindrical_and_spherical_systems_of_2420() {
    use femu_io::uff::{UffMode, UffNode, Universal, parse_uff, uff_string};
    let u = Universal {
        nodes: vec![
            UffNode {
                id: 9,
                x: [2.0, 90.0, 0.5],
            },
            UffNode {
                id: 10,
                x: [1.0, 90.0, 90.0],
            },
        ],
        modes: vec![UffMode {
            number: 1,
            frequency_hz: 50.0,
            damping: 0.0,
            modal_mass: 0.0,
            values: vec![(9, [0.3, -0.2, 0.7]), (10, [0.1, 0.2, 0.4])],
            complex: false,
            complexity: None,
            imaginary: None,
        }],
        ..Default::default()
    };
    let text = uff_string(&u);
    let frame = "  0.0  1.0  0.0\n  0.0  0.0  1.0\n  1.0  0.0  0.0\n  1.0  2.0  3.0\n";
    let systems = format!(
        "    -1\n  2420\n         1\nPart\n         7         1         8\nCYL\n{frame}         8         2         8\nSPH\n{frame}    -1\n"
    );
    let mut patched = String::new();
    for line in text.lines() {
        let t: Vec<&str> = line.split_whitespace().collect();
        let line = match (t.len(), t.first()) {
            (7, Some(&"9")) => line.replacen(
                "         0         0        11",
                "         7         7        11",
                1,
            ),
            (7, Some(&"10")) => line.replacen(
                "         0         0        11",
                "         8         8        11",
                1,
            ),
            _ => line.to_string(),
        };
        patched.push_str(&line);
        patched.push('\n');
    }
    let at = patched.find("    -1\n    15\n").unwrap();
    patched.insert_str(at, &systems);
    let path = std::path::Path::new("curvilinear.uff");
    let read = parse_uff(&patched, path).unwrap();
    assert_eq!(read.coordinate_systems[&7].kind, 1);
    assert_eq!(read.coordinate_systems[&8].kind, 2);
    let at = |id: u64| read.nodes.iter().find(|n| n.id == id).unwrap().x;
    for (id, want) in [(9, [1.5, 2.0, 5.0]), (10, [1.0, 2.0, 4.0])] {
        let x = at(id);
        assert!(
            (0..3).all(|i| (x[i] - want[i]).abs() < 1e-5),
            "node {id}: {x:?}"
        );
    }
    let data = read.test_data(path).unwrap();
    for (id, want) in [(9, [0.7, 0.2, 0.3]), (10, [-0.2, -0.4, 0.1])] {
        for (c, w) in want.iter().enumerate() {
            let r = data
                .sensors
                .iter()
                .position(|s| s.node == id && s.direction[c] == 1.0)
                .unwrap();
            let got = data.modes.shapes[(r, 0)];
            assert!((got - w).abs() < 1e-5, "node {id} component {c}: {got}");
        }
    }
    // a matrix whose rows are not orthonormal axes
    let skewed = patched.replacen("  0.0  1.0  0.0\n", "  0.0  1.0  0.5\n", 1);
    let e = parse_uff(&skewed, path).unwrap_err().to_string();
    assert!(
        e.contains("coordinate system 7: rows 1-3 of its matrix are not orthonormal axes"),
        "{e}"
    );
}
