//! A test with its own node numbering, in millimetres, mapped onto the model's nodes: the readings
//! land on the same model DOFs as a test given with the model's node ids; a node too far, two
//! test nodes on one model node, and a file without coordinates are errors that say so.

use femu_io::uff::{UffMode, UffNode, UffUnits, Universal, write_uff};
use femu_study::load::{ModelOptions, TestOptions, load_model, load_test, load_test_with};
use femu_study::mapping::{Align, MapMethod, MapOptions, Target};

/// Nearest-node mapping within `tolerance` m, without alignment.
fn nearest(tolerance: f64) -> TestOptions {
    TestOptions {
        map: Some(MapOptions {
            method: MapMethod::Nearest,
            tolerance: Some(tolerance),
            align: Align::None,
            scale: false,
        }),
        test_units: None,
    }
}

/// The model node a mapped test node landed on.
fn model_node(t: &Target) -> u64 {
    match t {
        Target::Node { model } => *model,
        other => panic!("not on a node: {other:?}"),
    }
}
use std::path::PathBuf;

fn fixture(dir: &str, name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(dir)
        .join(name)
}

/// The two-hex deck's free tip nodes 3, 6, 9, 12 at (0.2, 0, 0), (0.2, 0.1, 0), (0.2, 0, 0.1),
/// (0.2, 0.1, 0.1) m; a test on them, labelled `label(id)`, at `offset` mm from them, in mm.
fn test_file(name: &str, label: impl Fn(u64) -> u64, offset: f64) -> PathBuf {
    let at = [
        (3, [200.0, 0.0, 0.0]),
        (6, [200.0, 100.0, 0.0]),
        (9, [200.0, 0.0, 100.0]),
        (12, [200.0, 100.0, 100.0]),
    ];
    let u = Universal {
        units: Some(UffUnits {
            code: 5,
            description: "mm".into(),
            factors: [1000.0, 1.0, 1.0],
        }),
        nodes: at
            .iter()
            .map(|(id, x)| UffNode {
                id: label(*id),
                x: [x[0] + offset, x[1], x[2] - offset],
            })
            .collect(),
        modes: vec![UffMode {
            number: 1,
            frequency_hz: 2200.0,
            damping: 0.0,
            modal_mass: 0.0,
            values: at
                .iter()
                .enumerate()
                .map(|(k, (id, _))| (label(*id), [0.1 * k as f64, 1.0, -0.5 + 0.25 * k as f64]))
                .collect(),
            complex: false,
            complexity: None,
            imaginary: None,
        }],
        ..Default::default()
    };
    let path = std::env::temp_dir().join(format!("femu-map-{}-{name}.unv", std::process::id()));
    write_uff(&path, &u).unwrap();
    path
}

#[test]
fn a_test_on_its_own_wireframe_maps_onto_the_model() {
    let model = load_model(&fixture("inp", "two_hex.inp"), &ModelOptions::default()).unwrap();
    let direct = load_test(&test_file("direct", |id| id, 0.0), &model).unwrap();
    // labels 1000 + id, 0.2 mm off in x and z
    let own = test_file("own", |id| 1000 + id, 0.2);
    let mapped = load_test_with(&own, &model, &nearest(1e-3)).unwrap();
    let mapping = mapped.mapping.as_ref().unwrap();
    assert_eq!(mapping.nodes.len(), 4);
    for m in &mapping.nodes {
        assert_eq!(model_node(&m.target) + 1000, m.test);
        // 0.2 mm in x and in z
        assert!((m.distance - 0.2e-3 * 2f64.sqrt()).abs() < 1e-12, "{m:?}");
    }
    assert_eq!(mapped.data.sensors, direct.data.sensors);
    assert_eq!(mapped.data.modes.shapes, direct.data.modes.shapes);
    // too far: 0.28 mm against a 0.1 mm tolerance
    let e = load_test_with(&own, &model, &nearest(1e-4))
        .unwrap_err()
        .to_string();
    // every test node beyond it counted, the farthest named (the first of equals)
    assert!(
        e.contains("test node 1003 at (0.200200, 0.000000, -0.000200) m in the model's frame is 2.828e-4 m from the nearest model node (3), beyond the tolerance 1.000e-4 m; the farthest of 4 test nodes beyond it (1006 at 2.828e-4 m, 1009 at 2.000e-4 m, 1012 at 2.000e-4 m) (is the test in another frame? see --align)"),
        "{e}"
    );
    // a tolerance that takes two test nodes to one model node: move node 1006 onto node 3
    let crowded = test_file("crowded", |id| 1000 + id, 0.0);
    let text = std::fs::read_to_string(&crowded).unwrap().replacen(
        "  2.00000E+02  1.00000E+02  0.00000E+00",
        "  2.00000E+02  1.00000E-01  0.00000E+00",
        1,
    );
    std::fs::write(&crowded, text).unwrap();
    let e = load_test_with(&crowded, &model, &nearest(1e-3))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test nodes 1003 and 1006 both map to model node 3"),
        "{e}"
    );
    // a mode on a node the geometry lacks: drop node 1012's coordinates (dataset 15)
    let lacking = test_file("lacking", |id| 1000 + id, 0.0);
    let text = std::fs::read_to_string(&lacking).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !(l.split_whitespace().count() == 7 && l.trim_start().starts_with("1012 ")))
        .collect();
    std::fs::write(&lacking, kept.join("\n") + "\n").unwrap();
    let e = load_test_with(&lacking, &model, &nearest(1e-3))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test node 1012 has modes but no coordinates"),
        "{e}"
    );
    // a CSV has no coordinates to map
    let e = load_test_with(
        &fixture("malformed", "tip_modes.csv"),
        &model,
        &nearest(1e-3),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("needs the test nodes' coordinates"), "{e}");
}

/// A test file in millimetres that does not say so (no dataset 164): with the unit given, it maps.
#[test]
fn test_units_where_the_file_says_nothing() {
    let model = load_model(&fixture("inp", "two_hex.inp"), &ModelOptions::default()).unwrap();
    let path = test_file("silent", |id| 1000 + id, 0.0);
    // drop dataset 164
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("    -1\n   164\n").expect("dataset 164");
    let end = start + text[start + 7..].find("    -1\n").unwrap() + 7 + 7;
    let text = format!("{}{}", &text[..start], &text[end..]);
    assert!(!text.contains("   164\n"));
    std::fs::write(&path, text).unwrap();
    let mm = TestOptions {
        test_units: Some(femu_study::load::length_unit("mm").unwrap()),
        ..nearest(1e-3)
    };
    let mapped = load_test_with(&path, &model, &mm).unwrap();
    assert!(
        mapped
            .mapping
            .unwrap()
            .nodes
            .iter()
            .all(|m| m.distance < 1e-12 && model_node(&m.target) + 1000 == m.test)
    );
    // read as metres, the wireframe is 1000 times the model: the refusal says so and names the
    // unit (it spoke of frames and --align), before any node is searched for
    let metres = nearest(1e-3);
    let e = load_test_with(&path, &model, &metres)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("times the model's") && e.contains("its coordinates are in other units"),
        "{e}"
    );
    assert!(e.contains("--test-units mm"), "{e}");
    assert!(femu_study::load::length_unit("furlong").is_err());
}

/// Rotation by `angle` (rad) about `axis` (Rodrigues), written here independently of femu.
fn rodrigues(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|v| v / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

fn mul(a: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn mul_t(a: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| a[k][i] * v[k]).sum())
}

/// The evidence of mapping, on a case built here without femu's mapping code: a clamped steel
/// plate 0.4 x 0.3 x 0.02 m of 8 x 6 hex8 cells (h = 0.05 m); a test wireframe with its own
/// labels, 12 nodes on FE nodes of the top face and 10 accelerometers inside top-face cells,
/// written in millimetres in a frame turned 30 degrees about (1, 2, 3) and offset by
/// (0.1, -0.05, 0.2) m, six of its nodes measuring in a local system turned 90 degrees. The
/// readings are the model's own modes, interpolated here by the bilinear formula of a
/// rectangular face (exactly the hex8 field on its top face): so after alignment and mapping the
/// sensors must be the sensors given on the model directly, the MACs equal, and the test modes
/// must be the model's modes (MAC 1, `rho_M = 0`), to round-off: the frame's rotation recovered
/// from three pairs to 1e-12, coordinates in double precision (dataset 2411). Nearest-node mapping
/// of the same file moves the 10 accelerometers by up to 0.035 m and costs MAC: that is the
/// interpolation error interpolation removes.
#[test]
fn a_turned_millimetre_wireframe_between_nodes_maps_onto_the_model() {
    use femu_correlate::prelude::mac_matrix;
    use femu_correlate::{Estimator, Sensor, SensorLayout};
    use femu_fem::prelude::*;
    use femu_io::uff::CoordinateSystem;

    let dir = std::env::temp_dir().join(format!("femu-map-evidence-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = box_mesh(&BoxSpec::new(
        [0.4, 0.3, 0.02],
        [8, 6, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let mut plate = Model::new(mesh).unwrap();
    plate.set_material(None, Material::steel()).unwrap();
    plate.fix_set("xmin", &[0, 1, 2]).unwrap();
    let deck = dir.join("plate.inp");
    femu_io::inp::write_inp(&plate, None, &deck).unwrap();
    let model = load_model(&deck, &ModelOptions::default()).unwrap();
    let modes =
        femu_study::modes::lowest_for_test(&model, Some(6), 0, &Default::default()).unwrap();
    let mesh = model.model.mesh();
    let dofs = &model.sys.dofs;
    let h = 0.05;
    let node_at = |x: f64, y: f64| -> u64 {
        let i = (0..mesh.node_count())
            .find(|&i| {
                let c = mesh.coords()[i];
                (c[0] - x).abs() < 1e-9 && (c[1] - y).abs() < 1e-9 && (c[2] - 0.02).abs() < 1e-9
            })
            .unwrap();
        mesh.node_id(i)
    };
    // model displacement of mode j at a node (zero on fixed DOFs)
    let u_node = |id: u64, j: usize| -> [f64; 3] {
        let d = dofs.node_dofs(mesh.node_index(id).unwrap());
        std::array::from_fn(|c| d[c].map_or(0.0, |f| modes.vectors[(f, j)]))
    };
    // a top-face point: its cell's corner nodes and bilinear weights
    let bilinear = |x: f64, y: f64| -> Vec<(u64, f64)> {
        let (i, j) = ((x / h).floor(), (y / h).floor());
        let (xi, eta) = (x / h - i, y / h - j);
        let (x0, y0) = (i * h, j * h);
        vec![
            (node_at(x0, y0), (1.0 - xi) * (1.0 - eta)),
            (node_at(x0 + h, y0), xi * (1.0 - eta)),
            (node_at(x0 + h, y0 + h), xi * eta),
            (node_at(x0, y0 + h), (1.0 - xi) * eta),
        ]
    };
    let on_nodes: Vec<(u64, [f64; 2])> = (0..12)
        .map(|k| {
            let (i, j) = (1 + (k % 4) * 2, 1 + (k / 4) * 2);
            (501 + k as u64, [i as f64 * h, j as f64 * h])
        })
        .collect();
    let between: Vec<(u64, [f64; 2])> = [
        [0.0731, 0.0213],
        [0.1187, 0.2662],
        [0.1819, 0.1044],
        [0.2231, 0.0377],
        [0.2668, 0.2213],
        [0.3117, 0.1152],
        [0.3272, 0.2831],
        [0.3821, 0.0468],
        [0.0288, 0.1761],
        [0.2043, 0.1869],
    ]
    .iter()
    .enumerate()
    .map(|(k, p)| (601 + k as u64, *p))
    .collect();
    let rot = rodrigues([1.0, 2.0, 3.0], 30f64.to_radians());
    let offset = [0.1, -0.05, 0.2];
    let local = rodrigues([0.0, 0.0, 1.0], 90f64.to_radians());
    let mut nodes = Vec::new();
    let mut reads: Vec<(u64, Vec<(u64, f64)>)> = Vec::new();
    let mut displacement_systems = std::collections::BTreeMap::new();
    for (label, [x, y]) in on_nodes.iter().chain(&between) {
        let p = [*x, *y, 0.02];
        let d: [f64; 3] = std::array::from_fn(|i| p[i] - offset[i]);
        let test_m = mul_t(&rot, d);
        nodes.push(UffNode {
            id: *label,
            x: test_m.map(|v| v * 1000.0),
        });
        let at = if *label < 600 {
            vec![(node_at(*x, *y), 1.0)]
        } else {
            bilinear(*x, *y)
        };
        if label % 2 == 0 && *label < 600 {
            displacement_systems.insert(*label, 7);
        }
        reads.push((*label, at));
    }
    let values = |j: usize| -> Vec<(u64, [f64; 3])> {
        reads
            .iter()
            .map(|(label, at)| {
                let mut u = [0.0; 3];
                for (id, w) in at {
                    let un = u_node(*id, j);
                    for c in 0..3 {
                        u[c] += w * un[c];
                    }
                }
                let v = mul_t(&rot, u);
                let v = if displacement_systems.contains_key(label) {
                    mul_t(&local, v)
                } else {
                    v
                };
                (*label, v)
            })
            .collect()
    };
    let u = Universal {
        units: Some(UffUnits {
            code: 5,
            description: "mm".into(),
            factors: [1000.0, 1.0, 1.0],
        }),
        nodes,
        nodes_2411: true,
        coordinate_systems: [(
            7,
            CoordinateSystem {
                name: "turned".into(),
                kind: 0,
                origin: [0.0; 3],
                axes: local,
            },
        )]
        .into_iter()
        .collect(),
        displacement_systems: displacement_systems.clone(),
        modes: (0..6)
            .map(|j| UffMode {
                number: j as i64 + 1,
                frequency_hz: modes.values[j].sqrt() / (2.0 * std::f64::consts::PI),
                damping: 0.0,
                modal_mass: 1.0,
                values: values(j),
                complex: false,
                complexity: None,
                imaginary: None,
            })
            .collect(),
        ..Default::default()
    };
    let file = dir.join("wireframe.unv");
    write_uff(&file, &u).unwrap();
    let pairs = Align::Pairs(vec![
        (501, node_at(0.05, 0.05)),
        (504, node_at(0.35, 0.05)),
        (512, node_at(0.35, 0.25)),
    ]);
    let options = |method, align| TestOptions {
        map: Some(MapOptions {
            method,
            tolerance: Some(if method == MapMethod::Nearest {
                0.04
            } else {
                1e-6
            }),
            align,
            scale: false,
        }),
        test_units: None,
    };
    let mapped = load_test_with(
        &file,
        &model,
        &options(MapMethod::Interpolate, pairs.clone()),
    )
    .unwrap();
    let mapping = mapped.mapping.as_ref().unwrap();
    let a = mapping.alignment.as_ref().unwrap();
    for i in 0..3 {
        for k in 0..3 {
            assert!((a.transform.rotation[i][k] - rot[i][k]).abs() < 1e-12);
        }
        assert!((a.transform.translation[i] - offset[i]).abs() < 1e-12);
    }
    assert!(a.rms() < 1e-12);
    // the sensors given on the model directly: the test's directions turned by the frame's
    // rotation, on the FE node or with the bilinear weights
    let raw = femu_io::uff::read_uff(&file)
        .unwrap()
        .test_data(&file)
        .unwrap();
    let direct: Vec<Sensor> = raw
        .sensors
        .iter()
        .map(|s| {
            let at = &reads.iter().find(|r| r.0 == s.node).unwrap().1;
            let d = mul(&rot, s.direction);
            if at.len() == 1 {
                Sensor::new(at[0].0, d)
            } else {
                Sensor::between(s.node, d, at.clone())
            }
        })
        .collect();
    let direct = SensorLayout::new(mesh, dofs, direct).unwrap();
    let (cm, cd) = (
        mapped.layout.measure_all(modes.vectors.as_ref()).unwrap(),
        direct.measure_all(modes.vectors.as_ref()).unwrap(),
    );
    let scale = cd.norm_max();
    assert!(
        (&cm - &cd).norm_max() < 1e-12 * scale,
        "{}",
        (&cm - &cd).norm_max()
    );
    let shapes = mapped.data.modes.shapes.as_ref();
    let (mac_m, mac_d) = (
        mac_matrix(shapes, cm.as_ref()).unwrap(),
        mac_matrix(shapes, cd.as_ref()).unwrap(),
    );
    assert!((&mac_m - &mac_d).norm_max() < 1e-12);
    for j in 0..6 {
        // the test modes are the model's: the file's 6 printed digits bound the agreement
        assert!(mac_m[(j, j)] > 1.0 - 1e-9, "MAC {j}: {}", mac_m[(j, j)]);
    }
    // the estimators: dynamic expansion from the mapped and the direct sensors
    let lambdas = mapped.data.modes.eigenvalues();
    let estimator = Estimator::new(&model.sys.k, &model.sys.m).unwrap();
    let norms = |layout: &SensorLayout| {
        let x = femu_study::expand::expand_shapes(
            &model.sys,
            layout,
            &lambdas,
            shapes,
            femu_correlate::Method::Dynamic,
            None,
        )
        .unwrap();
        estimator.residual_norms(&lambdas, x.as_ref()).unwrap().0
    };
    let (nm, nd) = (norms(&mapped.layout), norms(&direct));
    for j in 0..6 {
        // C agrees to 1e-12; dynamic expansion of the file's rounded readings amplifies that
        // by about lambda_max / lambda (measured: at most 1.4e-9)
        assert!(
            (nm[j].rho_m - nd[j].rho_m).abs() <= 1e-8 * nd[j].rho_m,
            "mode {j}"
        );
    }
    // exact modal readings at the exact eigenvalue expand to the mode itself (rho_M = 0): the
    // file's 6 printed digits are not exact, and dynamic expansion amplifies their rounding by
    // about lambda_max / lambda, so this identity uses the readings of the mapped sensors
    let exact = femu_study::expand::expand_shapes(
        &model.sys,
        &mapped.layout,
        &modes.values[..6],
        cm.as_ref(),
        femu_correlate::Method::Dynamic,
        None,
    )
    .unwrap();
    let (en, _) = estimator
        .residual_norms(&modes.values[..6], exact.as_ref())
        .unwrap();
    for j in 0..6 {
        assert!(
            en[j].rho_m < 1e-8 * modes.values[j],
            "mode {j}: {}",
            en[j].rho_m / modes.values[j]
        );
    }
    // nearest-node mapping of the same file: the accelerometers move to FE nodes
    let near = load_test_with(&file, &model, &options(MapMethod::Nearest, pairs.clone()));
    let near = match near {
        Ok(t) => t,
        Err(e) => panic!("{e}"),
    };
    let moved = near
        .mapping
        .as_ref()
        .unwrap()
        .nodes
        .iter()
        .map(|n| n.distance)
        .fold(0.0, f64::max);
    assert!(moved > 0.01 && moved < 0.0355, "{moved}");
    let cn = near.layout.measure_all(modes.vectors.as_ref()).unwrap();
    let mac_n = mac_matrix(near.data.modes.shapes.as_ref(), cn.as_ref()).unwrap();
    let worst = (0..6).map(|j| mac_n[(j, j)]).fold(1.0, f64::min);
    // measured: 0.932 for the worst of the 6 modes
    assert!(worst < 0.95, "nearest-node MAC {worst}");
    // bad alignment input, each named
    let err = |align: Align| {
        load_test_with(&file, &model, &options(MapMethod::Interpolate, align))
            .unwrap_err()
            .to_string()
    };
    let e = err(Align::Pairs(vec![
        (501, node_at(0.05, 0.05)),
        (504, node_at(0.35, 0.05)),
    ]));
    assert!(
        e.contains("2 point pair(s) given: a rotation needs at least three"),
        "{e}"
    );
    let e = err(Align::Pairs(vec![
        (501, node_at(0.05, 0.05)),
        (502, node_at(0.15, 0.05)),
        (503, node_at(0.25, 0.05)),
    ]));
    assert!(e.contains("lie on one line"), "{e}");
    let e = err(Align::Pairs(vec![(501, 99999), (504, 1), (512, 2)]));
    assert!(
        e.contains("alignment pair 501:99999: the model has no node 99999"),
        "{e}"
    );
    let e = err(Align::Pairs(vec![(777, 1), (504, 1), (512, 2)]));
    assert!(
        e.contains("the test file has no node 777 with coordinates"),
        "{e}"
    );
    // without alignment the wireframe is far from the model: the message says where and why
    let e = load_test_with(&file, &model, &options(MapMethod::Interpolate, Align::None))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("test node 609 at (0.075566, 0.197255, -0.209692) m in the model's frame lies outside the model, 2.097e-1 m from element 26, beyond the tolerance 1.000e-6 m; the farthest of 22 test nodes beyond it (501 at 1.938e-1 m,"),
        "{e}"
    );
    assert!(
        e.ends_with(") (is the test in another frame? see --align)"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Without --map a test's labels are the model's node ids; a file whose coordinates put those
/// nodes elsewhere (here 20 mm off in x and z, the model 0.2 m long) is refused with a pointer to
/// --map, naming the farthest node and both positions (it was read by its labels alone, and its
/// sensors read nodes other than those measured). Within 1 % of the model's size it is read.
#[test]
fn coordinates_that_disagree_with_the_labels_are_refused() {
    let model = load_model(&fixture("inp", "two_hex.inp"), &ModelOptions::default()).unwrap();
    let off = test_file("labels-off", |id| id, 20.0);
    let e = load_test(&off, &model).unwrap_err().to_string();
    assert!(
        e.contains("4 of its 4 nodes are not where the model's nodes of the same ids are"),
        "{e}"
    );
    assert!(e.contains("--map nearest or --map interpolate"), "{e}");
    assert!(e.contains("2.828e-2 m apart"), "{e}");
    let close = test_file("labels-close", |id| id, 0.5);
    assert!(load_test(&close, &model).is_ok());
    std::fs::remove_file(&off).ok();
    std::fs::remove_file(&close).ok();
}
