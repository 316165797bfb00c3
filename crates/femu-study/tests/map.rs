//! A test with its own node numbering, in millimetres, mapped onto the model's nodes: the readings
//! land on the same model DOFs as a test given with the model's node ids; a node too far, two
//! test nodes on one model node, and a file without coordinates are errors that say so.

use femu_io::uff::{UffMode, UffNode, UffUnits, Universal, write_uff};
use femu_study::load::{ModelOptions, TestOptions, load_model, load_test, load_test_with};
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
    let mapped = load_test_with(
        &own,
        &model,
        &TestOptions {
            map_nearest: Some(1e-3),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(mapped.mapping.len(), 4);
    for m in &mapped.mapping {
        assert_eq!(m.model + 1000, m.test);
        // 0.2 mm in x and in z
        assert!((m.distance - 0.2e-3 * 2f64.sqrt()).abs() < 1e-12, "{m:?}");
    }
    assert_eq!(mapped.data.sensors, direct.data.sensors);
    assert_eq!(mapped.data.modes.shapes, direct.data.modes.shapes);
    // too far: 0.28 mm against a 0.1 mm tolerance
    let e = load_test_with(
        &own,
        &model,
        &TestOptions {
            map_nearest: Some(1e-4),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("test node 1003 at (0.200200, 0.000000, -0.000200) m is 2.828e-4 m from the nearest model node (3), beyond the tolerance 1e-4 m"),
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
    let e = load_test_with(
        &crowded,
        &model,
        &TestOptions {
            map_nearest: Some(1e-3),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("test nodes 1003 and 1006 both map to model node 3"),
        "{e}"
    );
    // a CSV has no coordinates to map
    let e = load_test_with(
        &fixture("malformed", "tip_modes.csv"),
        &model,
        &TestOptions {
            map_nearest: Some(1e-3),
            ..Default::default()
        },
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
        map_nearest: Some(1e-3),
        test_units: Some(femu_study::load::length_unit("mm").unwrap()),
    };
    let mapped = load_test_with(&path, &model, &mm).unwrap();
    assert!(
        mapped
            .mapping
            .iter()
            .all(|m| m.distance < 1e-12 && m.model + 1000 == m.test)
    );
    // read as metres, the nodes are 200 m away
    let metres = TestOptions {
        map_nearest: Some(1e-3),
        test_units: None,
    };
    assert!(load_test_with(&path, &model, &metres).is_err());
    assert!(femu_study::load::length_unit("furlong").is_err());
}
