//! Abaqus/CalculiX decks: a hand-made fixture, round trips through the writer, malformed input.

use femu_fem::element::Formulation;
use femu_fem::prelude::*;
use femu_io::IoError;
use femu_io::inp::{FrequencyStep, inp_string, parse_inp, read_inp};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/inp")
        .join(name)
}

#[test]
fn hand_made_fixture_is_read_exactly() {
    let deck = read_inp(fixture("two_hex.inp")).unwrap();
    let mesh = &deck.mesh;
    assert_eq!((mesh.node_count(), mesh.element_count()), (12, 2));
    assert_eq!(mesh.coords()[mesh.node_index(12).unwrap()], [0.2, 0.1, 0.1]);
    // the continued element line and the lower-case keyword
    let e1 = mesh.element(mesh.element_index(1).unwrap());
    let ids: Vec<u64> = e1.nodes.iter().map(|n| mesh.node_id(*n)).collect();
    assert_eq!(ids, vec![1, 2, 5, 4, 7, 8, 11, 10]);
    assert_eq!(e1.kind, ElementKind::Hex8);
    // sets: GENERATE, by names, from keyword parameters
    let ids_of = |name: &str| -> Vec<u64> {
        let mut v: Vec<u64> = mesh
            .node_set(name)
            .unwrap()
            .iter()
            .map(|n| mesh.node_id(*n))
            .collect();
        v.sort();
        v
    };
    assert_eq!(ids_of("ROOT"), vec![1, 4, 7, 10]);
    assert_eq!(ids_of("ENDS"), vec![1, 3, 4, 6, 7, 9, 10, 12]);
    assert_eq!(ids_of("NALL").len(), 12);
    assert_eq!(mesh.element_set("ALLE").unwrap().len(), 2);
    // material with a D exponent, upper-cased names
    let steel = &deck.materials["STEEL"];
    assert_eq!(steel.density, 7850.0);
    assert!(
        matches!(steel.elasticity, femu_fem::material::Elasticity::Isotropic { e, nu } if e == 2.1e11 && nu == 0.3)
    );
    assert_eq!(
        deck.frequency,
        Some(FrequencyStep {
            count: 4,
            shift_cycles2: None
        })
    );
    // warnings: C3D8R read as C3D8 (line 6), *AMPLITUDE and *NODE FILE ignored; with lines
    let w: Vec<String> = deck.warnings.iter().map(|w| w.to_string()).collect();
    assert!(
        w.iter()
            .any(|m| m.contains("two_hex.inp:5:") && m.contains("C3D8R")),
        "{w:?}"
    );
    assert!(w.iter().any(|m| m.contains("*AMPLITUDE")), "{w:?}");
    // the model: clamped root (4 nodes x 3 DOFs), mass = rho V
    let model = deck.to_model().unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    assert_eq!(sys.dofs.free_count(), 36 - 12);
    let mass = model.total_mass().unwrap();
    assert!((mass / (7850.0 * 0.2 * 0.1 * 0.1) - 1.0).abs() < 1e-12);
}

/// Writer -> reader round trip on the mixed hex/wedge/tet plate (linear and quadratic): same
/// nodes, elements, sets, and K and M equal entry by entry.
#[test]
fn round_trip_reproduces_k_and_m() {
    for quadratic in [false, true] {
        let spec = PlateSpec {
            lengths: [0.06, 0.04, 0.01],
            divisions: [6, 4, 1],
            tet_block: [2, 2],
            quadratic,
        };
        let mut model = Model::new(mixed_plate(&spec).unwrap()).unwrap();
        model.set_material(None, Material::steel()).unwrap();
        model
            .set_material(
                Some("tet"),
                Material::isotropic("alu", 70e9, 0.33, 2700.0).unwrap(),
            )
            .unwrap();
        model.fix_set("xmin", &[0, 1, 2]).unwrap();
        model.fix_set("ymin", &[1]).unwrap();
        // every other linear brick with incompatible modes: written as C3D8I and read back as
        // such (K would differ otherwise)
        let bricks: Vec<usize> = model
            .mesh()
            .elements()
            .filter(|e| e.kind == ElementKind::Hex8)
            .map(|e| e.index)
            .step_by(2)
            .collect();
        assert_eq!(bricks.is_empty(), quadratic);
        for e in bricks {
            model
                .set_formulation(e, Formulation::IncompatibleModes)
                .unwrap();
        }
        let text = inp_string(
            &model,
            Some(&FrequencyStep {
                count: 10,
                shift_cycles2: None,
            }),
        )
        .unwrap();
        let deck = parse_inp(&text, "roundtrip.inp").unwrap();
        assert!(
            deck.warnings
                .iter()
                .all(|w| w.message.contains("*NODE FILE")),
            "{:?}",
            deck.warnings
        );
        assert_eq!(deck.frequency.unwrap().count, 10);
        let back = deck.to_model().unwrap();
        assert_eq!(back.mesh().node_count(), model.mesh().node_count());
        assert_eq!(back.mesh().element_count(), model.mesh().element_count());
        assert_eq!(
            back.mesh().node_set("XMIN").unwrap().len(),
            model.mesh().node_set("xmin").unwrap().len()
        );
        let (a, b) = (
            model.assemble(MassKind::Consistent).unwrap(),
            back.assemble(MassKind::Consistent).unwrap(),
        );
        assert_eq!(a.dofs.free_count(), b.dofs.free_count());
        for (x, y) in [(&a.k, &b.k), (&a.m, &b.m)] {
            assert_eq!(x.nnz(), y.nnz());
            let scale = x.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (v, (r, c)) in x.iter() {
                let w = y.get(r, c).copied().unwrap_or(f64::NAN);
                assert!(
                    (v - w).abs() <= 1e-14 * scale,
                    "q={quadratic} ({r},{c}): {v} vs {w}"
                );
            }
        }
        // writing again gives the same text: the writer is a fixed point after one round trip
        let again = inp_string(
            &back,
            Some(&FrequencyStep {
                count: 10,
                shift_cycles2: None,
            }),
        )
        .unwrap();
        let (a, b) = (again.to_ascii_uppercase(), text.to_ascii_uppercase());
        if let Some((k, (x, y))) = a
            .lines()
            .zip(b.lines())
            .enumerate()
            .find(|(_, (x, y))| x != y)
        {
            panic!("q={quadratic}: line {} differs: {x:?} vs {y:?}", k + 1);
        }
        assert_eq!(a.lines().count(), b.lines().count());
    }
}

/// A corpus of malformed decks: each is an error naming the file and the line.
#[test]
fn malformed_decks_name_the_line() {
    let nodes = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n";
    let cases: Vec<(String, usize, &str)> = vec![
        ("*NODE\n1, 0, abc, 0\n".into(), 2, "coordinate"),
        ("*NODE\n1, 0, nan, 0\n".into(), 2, "coordinate"),
        ("*NODE\nx, 0, 0, 0\n".into(), 2, "node id"),
        ("*NODE\n1, 0\n".into(), 2, "a node needs"),
        (
            format!("{nodes}*ELEMENT\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"),
            10,
            "TYPE",
        ),
        (
            format!("{nodes}*ELEMENT, TYPE=S9R5\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"),
            10,
            "S9R5 is not read",
        ),
        (
            format!("{nodes}*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4, 5, 6, 7, 8, 9\n"),
            11,
            "needs 8 nodes",
        ),
        (
            format!("{nodes}*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4,\n*NSET, NSET=A\n1\n"),
            11,
            "cut short",
        ),
        (
            format!("{nodes}*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4, 5, 6, 7, 99\n"),
            11,
            "missing node 99",
        ),
        (
            format!("{nodes}*NSET, NSET=A\nNOPE\n"),
            10,
            "NOPE, which is neither",
        ),
        (
            format!("{nodes}*NSET, NSET=A, GENERATE\n5, 1, 1\n"),
            10,
            "GENERATE",
        ),
        // a range longer than the model: an error, not 10^15 ids in memory
        (
            format!("{nodes}*NSET, NSET=A, GENERATE\n1, 1000000000000000, 1\n"),
            10,
            "the model has 8 nodes",
        ),
        ("*ELASTIC\n1, 0.3\n".into(), 1, "outside a *MATERIAL"),
        (
            "*MATERIAL, NAME=A\n*ELASTIC\n1e9, 0.3\n".into(),
            1,
            "no *DENSITY",
        ),
        (
            "*MATERIAL, NAME=A\n*ELASTIC, TYPE=TRACTION\n".into(),
            2,
            "TYPE=TRACTION is not read",
        ),
        (
            "*MATERIAL, NAME=A\n*ELASTIC, TYPE=ANISO\n1e9, 2e8\n*DENSITY\n1\n".into(),
            2,
            "TYPE=ANISOTROPIC takes 21 constants, got 2",
        ),
        (
            "*MATERIAL, NAME=A\n*ELASTIC, TYPE=ORTHOTROPIC\n1e9, 2e8, x\n".into(),
            3,
            "constant 3 = \"x\" is not a number",
        ),
        (
            "*MATERIAL, NAME=A\n*ELASTIC\n1e9, 0.7\n*DENSITY\n1\n".into(),
            1,
            "material",
        ),
        ("*BOUNDARY\n1, x\n".into(), 2, "DOF"),
        ("*STEP\n*FREQUENCY\n-3\n".into(), 3, "positive number"),
        ("*INCLUDE\n".into(), 1, "INPUT"),
    ];
    for (text, line, needle) in cases {
        let err = parse_inp(&text, "bad.inp").unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.starts_with(&format!("bad.inp:{line}:")),
            "{text:?}: {msg}"
        );
        assert!(msg.contains(needle), "{text:?}: {msg}");
    }
    // model errors found after parsing still name the line of the offender
    let inverted = format!(
        "{nodes}*ELEMENT, TYPE=C3D8, ELSET=E\n7, 5, 6, 7, 8, 1, 2, 3, 4\n*MATERIAL, NAME=M\n*ELASTIC\n1e9, 0.3\n*DENSITY\n1000\n*SOLID SECTION, ELSET=E, MATERIAL=M\n"
    );
    let err = parse_inp(&inverted, "inv.inp")
        .unwrap()
        .to_model()
        .unwrap_err();
    assert!(
        err.to_string().starts_with("inv.inp:11:") && err.to_string().contains("inverted"),
        "{err}"
    );
    let no_section = format!("{nodes}*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4, 5, 6, 7, 8\n");
    let err = parse_inp(&no_section, "ns.inp")
        .unwrap()
        .to_model()
        .unwrap_err();
    assert!(err.to_string().starts_with("ns.inp:11:"), "{err}");
    let unknown_material = format!(
        "{nodes}*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n*SOLID SECTION, ELSET=E, MATERIAL=GOLD\n"
    );
    let err = parse_inp(&unknown_material, "um.inp")
        .unwrap()
        .to_model()
        .unwrap_err();
    assert!(
        err.to_string().contains("um.inp:12:") && err.to_string().contains("GOLD"),
        "{err}"
    );
    // a missing include names the including line and the missing file
    let err = parse_inp("*INCLUDE, INPUT=nowhere.inp\n", "inc.inp").unwrap_err();
    assert!(
        matches!(&err, IoError::Parse { path, line: 1, reason } if path.ends_with("inc.inp") && reason.contains("cannot read nowhere.inp")),
        "{err}"
    );
    // a missing file
    assert!(matches!(
        read_inp("/nonexistent/deck.inp"),
        Err(IoError::Io { .. })
    ));
}

/// CSV test modes: parsed exactly (signed and oblique directions, damping), written and read
/// back identically, malformed files named by line.
#[test]
fn csv_test_modes() {
    use femu_io::csv::{parse_test_csv, test_csv_string};
    let text = "# two modes at two sensors\nmode,frequency_hz,node,direction,value,damping\n1,100.5,7,z,0.5,0.01\n1,100.5,9,0.6 0.8 0,-1.5,\n2,230,9,0.6 0.8 0,2.0,0.02\n2,230,7,-z,0.25,\n";
    let d = parse_test_csv(text, "t.csv").unwrap();
    assert_eq!(d.sensors.len(), 2);
    assert_eq!(
        (d.sensors[0].node, d.sensors[0].direction),
        (7, [0.0, 0.0, 1.0])
    );
    assert_eq!(d.modes.frequencies_hz, vec![100.5, 230.0]);
    // each mode gives its damping on one of its rows
    assert_eq!(d.modes.damping_ratios, Some(vec![0.01, 0.02]));
    let m = &d.modes.shapes;
    // -z flips the sign of the reading on the +z sensor
    assert_eq!(
        (m[(0, 0)], m[(1, 0)], m[(0, 1)], m[(1, 1)]),
        (0.5, -1.5, -0.25, 2.0)
    );
    let again = parse_test_csv(&test_csv_string(&d.sensors, &d.modes), "t2.csv").unwrap();
    assert_eq!(again.modes.shapes, d.modes.shapes);
    assert_eq!(again.sensors, d.sensors);
    for (text, line, needle) in [
        ("mode,freq\n", 1, "header"),
        (
            "mode,frequency_hz,node,direction,value\n1,abc,7,z,1\n",
            2,
            "frequency",
        ),
        (
            "mode,frequency_hz,node,direction,value\n1,100,7,w,1\n",
            2,
            "direction",
        ),
        (
            "mode,frequency_hz,node,direction,value\n1,100,7,z,nan\n",
            2,
            "value",
        ),
        (
            "mode,frequency_hz,node,direction,value\n1,100,7,z,1\n1,101,8,z,1\n",
            3,
            "frequency 101",
        ),
        (
            "mode,frequency_hz,node,direction,value\n1,100,7,z,1\n1,100,7,z,2\n",
            3,
            "second value",
        ),
        (
            "mode,frequency_hz,node,direction,value\n1,100,7,z,1\n2,200,8,z,1\n",
            2,
            "no value for sensor 2",
        ),
        (
            "mode,frequency_hz,node,direction,value\n",
            1,
            "no test modes",
        ),
    ] {
        let e = parse_test_csv(text, "bad.csv").unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("bad.csv:{line}:")) && e.contains(needle),
            "{text:?}: {e}"
        );
    }
}

/// Numbers whose exact form is longer than CalculiX's 20-character fields are written with 14
/// significant digits; everything else exactly.
#[test]
fn long_numbers_fit_calculix_fields() {
    let mut mesh = Mesh::new();
    let odd = [-0.049999999999999996, 1.2345678901234567e-5, -1.0 / 3.0];
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    for (i, c) in corners.iter().enumerate() {
        mesh.add_node(i as u64 + 1, *c).unwrap();
        mesh.add_node(i as u64 + 5, [c[0], c[1], 1.0]).unwrap();
    }
    mesh.add_node(9, odd).unwrap();
    mesh.add_element(1, ElementKind::Hex8, &[1, 2, 3, 4, 5, 6, 7, 8])
        .unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    let text = inp_string(&model, None).unwrap();
    for line in text.lines().filter(|l| l.starts_with("9,")) {
        assert!(line.split(',').all(|f| f.trim().len() <= 20), "{line}");
    }
    let back = parse_inp(&text, "long.inp").unwrap();
    let x = back.mesh.coords()[back.mesh.node_index(9).unwrap()];
    for (a, b) in x.iter().zip(odd) {
        assert!((a - b).abs() <= 5e-14 * b.abs(), "{a} vs {b}");
    }
    // the exact (short) ones are unchanged
    assert_eq!(x[2], -1.0 / 3.0);
}

/// JSON test modes equal the CSV fixture they transcribe; malformed JSON names line or row.
#[test]
fn json_test_modes() {
    let csv = femu_io::csv::read_test_csv(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/csv/two_modes.csv"),
    )
    .unwrap();
    let json = r#"{"rows": [
        {"mode": 1, "frequency_hz": 1520.5, "node": 1, "direction": "y", "value": 0.012, "damping": 0.002},
        {"mode": 1, "frequency_hz": 1520.5, "node": 1, "direction": "z", "value": -0.98, "damping": 0.002},
        {"mode": 1, "frequency_hz": 1520.5, "node": 7, "direction": [-1, 0, 0], "value": 0.25, "damping": 0.002},
        {"mode": 2, "frequency_hz": 2210.25, "node": 1, "direction": "y", "value": 0.5, "damping": 0.003},
        {"mode": 2, "frequency_hz": 2210.25, "node": 1, "direction": "z", "value": 0.1, "damping": 0.003},
        {"mode": 2, "frequency_hz": 2210.25, "node": 7, "direction": "-x", "value": -0.75, "damping": 0.003}
    ]}"#;
    let j = femu_io::json::parse_test_json(json, "t.json").unwrap();
    assert_eq!(j.sensors, csv.sensors);
    assert_eq!(j.modes.frequencies_hz, csv.modes.frequencies_hz);
    assert_eq!(j.modes.damping_ratios, csv.modes.damping_ratios);
    assert_eq!(j.modes.shapes, csv.modes.shapes);
    // syntax: the JSON line
    match femu_io::json::parse_test_json("[\n{\"mode\": 1,\n \"frequency_hz\": x}]", "bad.json") {
        Err(femu_io::IoError::Parse { line, .. }) => assert_eq!(line, 3),
        other => panic!("{other:?}"),
    }
    // content: the row
    let bad = json.replace("\"value\": 0.5,", "\"value\": 0.5, \"extra\": 1,");
    assert!(femu_io::json::parse_test_json(&bad, "bad.json").is_err());
    let bad = json.replace(
        "2210.25, \"node\": 1, \"direction\": \"z\"",
        "2211.0, \"node\": 1, \"direction\": \"z\"",
    );
    let e = femu_io::json::parse_test_json(&bad, "bad.json")
        .unwrap_err()
        .to_string();
    assert!(e.contains("row 5"), "{e}");
}

/// Test node coordinates in CSV (`x,y,z` after `value` or `damping`) and JSON (`"x"`, `"y"`,
/// `"z"`): read per node; a node placed at two positions, a missing coordinate and a misplaced
/// column are errors naming the line.
#[test]
fn test_coordinates_in_csv_and_json() {
    use femu_io::csv::parse_test_csv;
    let text = "mode,frequency_hz,node,direction,value,damping,x,y,z\n\
                1,100,7,x,0.5,0.01,10,20,30\n\
                1,100,7,y,0.25,0.01,10,20,30\n\
                1,100,8,z,1.0,0.01,-5,0,2.5\n";
    let d = parse_test_csv(text, "c.csv").unwrap();
    assert_eq!(d.coordinates.len(), 2);
    assert_eq!(d.coordinates[&7], [10.0, 20.0, 30.0]);
    assert_eq!(d.coordinates[&8], [-5.0, 0.0, 2.5]);
    let moved = text.replacen(
        "1,100,7,y,0.25,0.01,10,20,30",
        "1,100,7,y,0.25,0.01,10,21,30",
        1,
    );
    let e = parse_test_csv(&moved, "c.csv").unwrap_err().to_string();
    assert_eq!(
        e,
        "c.csv:3: node 7 is at [10.0, 21.0, 30.0] here and at [10.0, 20.0, 30.0] on line 2"
    );
    let missing = text.replacen("-5,0,2.5", "-5,,2.5", 1);
    let e = parse_test_csv(&missing, "c.csv").unwrap_err().to_string();
    assert_eq!(
        e,
        "c.csv:4: coordinate y \"\" of node 8 is not a finite number"
    );
    let misplaced = "mode,frequency_hz,node,direction,value,x,y,z,damping\n1,100,7,x,1,0,0,0,0\n";
    let e = parse_test_csv(misplaced, "c.csv").unwrap_err().to_string();
    assert!(
        e.starts_with("c.csv:1: unknown or misplaced column \"x\""),
        "{e}"
    );
    let json = r#"[{"mode": 1, "frequency_hz": 100, "node": 7, "direction": "x", "value": 0.5, "x": 1, "y": 2, "z": 3},
                   {"mode": 1, "frequency_hz": 100, "node": 8, "direction": "z", "value": 1.0, "x": 4, "y": 5, "z": 6}]"#;
    let j = femu_io::json::parse_test_json(json, "c.json").unwrap();
    assert_eq!(j.coordinates[&8], [4.0, 5.0, 6.0]);
    let half = json.replacen(r#", "x": 4, "y": 5, "z": 6"#, r#", "x": 4"#, 1);
    let e = femu_io::json::parse_test_json(&half, "c.json")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "c.json: row 2: coordinate y \"\" of node 8 is not a finite number"
    );
}

/// Point masses in a deck: `*ELEMENT, TYPE=MASS` with its `*MASS`, read onto the model; each
/// mistake an error naming the line.
#[test]
fn point_masses_in_decks() {
    let base = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n9, 5, 5, 5\n*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n*MATERIAL, NAME=S\n*ELASTIC\n2e11, 0.3\n*DENSITY\n7800\n*SOLID SECTION, ELSET=E, MATERIAL=S\n";
    let good =
        format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 7\n102, 6\n*MASS, ELSET=PM\n2.5\n");
    let model = parse_inp(&good, "m.inp").unwrap().to_model().unwrap();
    let masses: Vec<(u64, f64)> = model
        .point_masses()
        .iter()
        .map(|p| (model.mesh().node_id(p.node), p.mass[0][0]))
        .collect();
    assert_eq!(masses, vec![(7, 2.5), (6, 2.5)]);
    assert!((model.total_mass().unwrap() - (7800.0 + 5.0)).abs() < 1e-9);
    // the *MASS's element set is a mass set of both masses, for updating
    use femu_fem::model::MassRef;
    assert_eq!(
        model.mass_set("PM"),
        Some(&[MassRef::Point(0), MassRef::Point(1)][..])
    );
    let cases: Vec<(String, &str)> = vec![
        (
            format!("{base}*ELEMENT, TYPE=MASS\n101, 7\n"),
            "m.inp:19: *ELEMENT, TYPE=MASS needs ELSET= (the set its *MASS names)",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 7\n*MASS, ELSET=PM\n"),
            "m.inp:21: *MASS without its data line (the mass)",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 7\n*MASS, ELSET=PM\n-1\n"),
            "m.inp:22: *MASS needs a positive mass, got \"-1\"",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 77\n*MASS, ELSET=PM\n1\n"),
            "m.inp:20: MASS element 101 is on node 77, which the deck does not define",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 7\n*MASS, ELSET=PN\n1\n"),
            "m.inp:21: *MASS names element set PN, which no *ELEMENT, TYPE=MASS defines (did you mean PM?)",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 7, 8\n*MASS, ELSET=PM\n1\n"),
            "m.inp:20: a MASS element line is an id and a node, got \"101, 7, 8\"",
        ),
        (
            format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n1, 7\n*MASS, ELSET=PM\n1\n"),
            "m.inp:20: MASS element 1 has the id of a solid element",
        ),
    ];
    for (text, want) in cases {
        let e = parse_inp(&text, "m.inp")
            .and_then(|d| d.to_model())
            .unwrap_err()
            .to_string();
        assert_eq!(e, want);
    }
    // a mass on a node no solid connects: no stiffness under it
    let loose = format!("{base}*ELEMENT, TYPE=MASS, ELSET=PM\n101, 9\n*MASS, ELSET=PM\n1\n");
    let e = parse_inp(&loose, "m.inp")
        .unwrap()
        .to_model()
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("m.inp:21: *MASS on node 9, which no solid element or constraint connects"),
        "{e}"
    );
}

/// Couplings and equations in a deck: a `*KINEMATIC COUPLING` of two top nodes to a reference
/// above them (its rotation about z fixed by `*BOUNDARY` 6), a `*COUPLING` with `*DISTRIBUTING`
/// on a weighted node surface, and an `*EQUATION` (scaled: only the ratios matter), with masses on
/// the references; the deck gives the K and M of the same constraints made through femu's API.
/// Bad constraints are errors naming the line.
#[test]
fn couplings_and_equations_in_decks() {
    let base = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n9, 0.5, 0.5, 3\n10, 0.2, 0.3, 1.5\n*ELEMENT, TYPE=C3D8, ELSET=E\n1, 1, 2, 3, 4, 5, 6, 7, 8\n*MATERIAL, NAME=S\n*ELASTIC\n2e11, 0.3\n*DENSITY\n7800\n*SOLID SECTION, ELSET=E, MATERIAL=S\n*NSET, NSET=TOP\n5, 6\n*BOUNDARY\n1, 1, 3\n2, 1, 3\n3, 1, 3\n4, 1, 3\n";
    let links = "*KINEMATIC COUPLING, REF NODE=9\nTOP, 1, 3\n*BOUNDARY\n9, 6, 6\n*SURFACE, TYPE=NODE, NAME=S1\n5, 2.\n6\n7, 3.\n*COUPLING, REF NODE=10, SURFACE=S1\n*DISTRIBUTING\n1, 3\n*EQUATION\n2\n7, 3, -2., 8, 3, 1.\n*ELEMENT, TYPE=MASS, ELSET=PM\n101, 9\n102, 10\n*MASS, ELSET=PM\n1.5\n";
    let text = format!("{base}{links}");
    let sys = parse_inp(&text, "c.inp")
        .unwrap()
        .to_model()
        .unwrap()
        .assemble(MassKind::Consistent)
        .unwrap();
    let mut api = parse_inp(base, "c.inp").unwrap().to_model().unwrap();
    api.add_rigid_link(9, &[5, 6], &[0, 1, 2], "k").unwrap();
    api.fix_node_dofs(9, &[5]).unwrap();
    api.add_weighted_average(10, &[0, 1, 2], &[(5, 2.0), (6, 1.0), (7, 3.0)], "d")
        .unwrap();
    api.add_constraint((7, 2), &[((8, 2), 0.5)], "e").unwrap();
    api.add_point_mass(9, 1.5).unwrap();
    api.add_point_mass(10, 1.5).unwrap();
    let want = api.assemble(MassKind::Consistent).unwrap();
    assert_eq!(sys.dofs, want.dofs);
    let diff = |a: &femu_sparse::SparseMatrix, b: &femu_sparse::SparseMatrix| {
        let (a, b) = (femu_sparse::csc::to_dense(a), femu_sparse::csc::to_dense(b));
        (&a - &b).norm_max() / b.norm_max()
    };
    assert!(diff(&sys.k, &want.k) < 1e-15 && diff(&sys.m, &want.m) < 1e-15);
    let cases: Vec<(String, &str)> = vec![
        (
            text.replace("7, 3, -2., 8, 3, 1.", "7, 3, -2."),
            "c.inp:39: *EQUATION announces 2 terms and gives 1 before the next keyword",
        ),
        (
            text.replace("7, 3, -2., 8, 3, 1.", "7, 3, 0., 8, 3, 1."),
            "c.inp:39: *EQUATION: the first coefficient (of the dependent DOF) is zero",
        ),
        (
            text.replace("7, 3, -2., 8, 3, 1.", "5, 3, -2., 8, 3, 1."),
            "constraint *EQUATION (c.inp line 39): its dependent DOF, node 5 z, is already dependent in kinematic coupling to node 9 (c.inp line 28)",
        ),
        (
            text.replace("7, 3, -2., 8, 3, 1.", "7, 3, -2., 8, 7, 1."),
            "c.inp:40: *EQUATION: DOF \"7\" is not 1-6",
        ),
        (
            text.replace("*SURFACE, TYPE=NODE, NAME=S1", "*SURFACE, NAME=S1"),
            "c.inp:36: *DISTRIBUTING: surface S1 is element-based; a coupling takes a node-based surface (*SURFACE, TYPE=NODE)",
        ),
        (
            text.replace("SURFACE=S1", "SURFACE=S2"),
            "c.inp:36: *DISTRIBUTING: surface S2 is not defined (femu reads *SURFACE, TYPE=NODE) (did you mean S1?)",
        ),
        (
            text.replace("*COUPLING, REF NODE=10, SURFACE=S1\n", ""),
            "c.inp:35: *DISTRIBUTING without a *COUPLING before it",
        ),
        (
            text.replace("*KINEMATIC COUPLING, REF NODE=9", "*KINEMATIC COUPLING"),
            "c.inp:27: *KINEMATIC COUPLING needs REF NODE=<node id or node set>",
        ),
        (
            text.replace(
                "*KINEMATIC COUPLING, REF NODE=9",
                "*KINEMATIC COUPLING, REF NODE=TOP",
            ),
            "c.inp:28: REF NODE=TOP: the set holds 2 nodes",
        ),
        (
            text.replace(
                "*KINEMATIC COUPLING, REF NODE=9",
                "*KINEMATIC COUPLING, REF NODE=TOPP",
            ),
            "c.inp:28: REF NODE=TOPP: no node set has that name",
        ),
        (
            text.replace("TOP, 1, 3", "TOQ, 1, 3"),
            "c.inp:28: *KINEMATIC COUPLING names TOQ, which is neither a node id nor a node set of the deck (did you mean TOP?)",
        ),
        (
            text.replace("*BOUNDARY\n9, 6, 6", "*BOUNDARY\n9, 6, 6\n5, 3, 3"),
            "its dependent DOF, node 5 z, is also fixed",
        ),
    ];
    for (t, want) in cases {
        let e = parse_inp(&t, "c.inp")
            .and_then(|d| d.to_model())
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "want {want:?}\n got {e}");
    }
}

/// `*NODE, SYSTEM=C`: cylindrical coordinates `r, theta (degrees), z` are the rectangular `r cos
/// theta, r sin theta, z` (by hand, 1e-15), in a deck and in a part placed by an instance (a
/// translation after the conversion); `SYSTEM=S` is refused with its line.
#[test]
fn cylindrical_node_coordinates() {
    let deck = "*NODE, SYSTEM=C\n1, 2., 30., 0.5\n2, 1., 90., 0.\n3, 3., 180., -1.\n*NODE\n4, 0., 0., 0.\n\
                *ELEMENT, TYPE=C3D4, ELSET=E\n1, 1, 2, 3, 4\n\
                *MATERIAL, NAME=S\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n7850.\n*SOLID SECTION, ELSET=E, MATERIAL=S\n";
    let d = parse_inp(deck, "cyl.inp").unwrap();
    let x = |id: u64| d.mesh.coords()[d.mesh.node_index(id).unwrap()];
    let (s, c) = 30f64.to_radians().sin_cos();
    let want = [
        (1, [2.0 * c, 2.0 * s, 0.5]),
        (2, [0.0, 1.0, 0.0]),
        (3, [-3.0, 0.0, -1.0]),
        (4, [0.0, 0.0, 0.0]),
    ];
    for (id, w) in want {
        for k in 0..3 {
            assert!(
                (x(id)[k] - w[k]).abs() < 1e-15,
                "node {id}: {:?} {w:?}",
                x(id)
            );
        }
    }
    // in a part: converted, then moved by the instance's translation
    let part = format!(
        "*PART, NAME=P\n{}*END PART\n*ASSEMBLY, NAME=A\n*INSTANCE, NAME=I, PART=P\n1., 0., 0.\n*END INSTANCE\n*END ASSEMBLY\n*MATERIAL, NAME=S\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n7850.\n",
        deck.replace(
            "*MATERIAL, NAME=S\n*ELASTIC\n2.e11, 0.3\n*DENSITY\n7850.\n",
            ""
        )
    );
    let p = parse_inp(&part, "part.inp").unwrap();
    let y = p.mesh.coords()[p.mesh.node_index(2).unwrap()];
    assert!(
        (y[0] - 1.0).abs() < 1e-15 && (y[1] - 1.0).abs() < 1e-15,
        "{y:?}"
    );
    let e = parse_inp(&deck.replace("SYSTEM=C", "SYSTEM=S"), "bad.inp")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.inp:1:") && e.contains("SYSTEM=S"), "{e}");
}
