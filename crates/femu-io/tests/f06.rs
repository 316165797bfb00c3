//! MSC Nastran's printed modes read as Nastran prints them, checked against an independent reader
//! of another file of the same run: `fixtures/nastran/pynastran/mode_solid_shell_bar.f06` (a SOL
//! 103 run of solids, shells, bars, beams and rods, from pyNastran's models, BSD) against what
//! pyNastran 1.4.1 reads from the run's OP2 (`mode_solid_shell_bar.modes.json`, written by
//! `reference_modes.py` beside it): the three eigenvalues to 1e-6 and every grid's six components
//! to 1e-6 of the mode's largest (the `.f06` prints 7 digits, the OP2 holds single precision).
//! The grids come from the run's deck, whatever its elements (`read_grids`). femu's reading of the
//! OP2 itself equals pyNastran's to the last bit (both widen the file's single precision; the
//! reference's decimal text is parsed to within an ulp).

use std::path::PathBuf;

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/nastran/pynastran")
}

#[test]
fn nastran_f06_modes_equal_pynastran_s_op2_reading() {
    let f06 = femu_io::f06::read_f06(fixtures().join("mode_solid_shell_bar.f06")).unwrap();
    let text = std::fs::read_to_string(fixtures().join("mode_solid_shell_bar.modes.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let values: Vec<f64> = reference["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let nodes: Vec<u64> = reference["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(f06.modes.len(), values.len());
    assert_eq!(f06.without_vectors, 0);
    for (j, mode) in f06.modes.iter().enumerate() {
        assert_eq!(mode.number, j + 1);
        assert!(
            (mode.eigenvalue / values[j] - 1.0).abs() < 1e-6,
            "mode {}: {} vs {}",
            j + 1,
            mode.eigenvalue,
            values[j]
        );
        let vectors = &reference["vectors"][j];
        let scale = mode
            .points
            .iter()
            .flat_map(|(_, v)| v.iter())
            .fold(0.0_f64, |a, b| a.max(b.abs()));
        assert_eq!(mode.points.len(), nodes.len());
        for (id, v) in &mode.points {
            let k = nodes.iter().position(|n| n == id).unwrap();
            for c in 0..6 {
                let r = vectors[k][c].as_f64().unwrap();
                assert!(
                    (v[c] - r).abs() <= 1e-6 * scale,
                    "mode {}, grid {id}, component {c}: {} vs {r}",
                    j + 1,
                    v[c]
                );
            }
        }
    }
    // the deck's grids, its shells, beams and rods left alone (its INCLUDE holds the elements)
    let grids = femu_io::nastran::read_grids(fixtures().join("mode_solid_shell_bar.bdf")).unwrap();
    assert_eq!(grids.len(), 25);
    let g13 = grids.iter().find(|g| g.id == 13).unwrap();
    assert_eq!(g13.position, [0.5, 0.5, 3.0]);
    let g25 = grids.iter().find(|g| g.id == 25).unwrap();
    assert_eq!((g25.position, g25.cd), ([1.0, 0.0, -3.0], 0));
}

/// A displacement frame turns the printed components into basic ones: a grid whose CD is a
/// cylindrical frame about z at (0, 1, 0) has its axes radial, tangential and axial there.
#[test]
fn displacement_frames_of_grids() {
    let dir = std::env::temp_dir().join(format!("femu-grids-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = dir.join("cd.bdf");
    std::fs::write(
        &deck,
        "BEGIN BULK\nCORD2C,5,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\nGRID,1,,0.,1.,0.,5\nGRID,2,,2.,0.,0.\nCQUAD4,1,1,1,2,2,1\nENDDATA\n",
    )
    .unwrap();
    let grids = femu_io::nastran::read_grids(&deck).unwrap();
    let g1 = &grids[0];
    assert_eq!(g1.cd, 5);
    // at (0, 1, 0): radial = y, tangential = -x, axial = z (columns)
    let want = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    for i in 0..3 {
        for j in 0..3 {
            assert!((g1.axes[i][j] - want[i][j]).abs() < 1e-12, "{:?}", g1.axes);
        }
    }
    assert_eq!(
        grids[1].axes,
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nastran_op2_modes_equal_pynastran_s_reading() {
    let op2 = femu_io::op2::read_op2(fixtures().join("mode_solid_shell_bar.op2")).unwrap();
    let text = std::fs::read_to_string(fixtures().join("mode_solid_shell_bar.modes.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(op2.modes.len(), 3);
    for (j, mode) in op2.modes.iter().enumerate() {
        assert_eq!(mode.number, j + 1);
        let r = reference["eigenvalues"][j].as_f64().unwrap();
        assert!((mode.eigenvalue - r).abs() <= 2.0 * f64::EPSILON * r);
        assert_eq!(mode.points.len(), 25);
        for (k, (id, v)) in mode.points.iter().enumerate() {
            assert_eq!(*id, reference["nodes"][k].as_u64().unwrap());
            for c in 0..6 {
                // the same single-precision value; serde_json's decimal parsing may miss by an ulp
                let r = reference["vectors"][j][k][c].as_f64().unwrap();
                assert!(
                    (v[c] - r).abs() <= 2.0 * f64::EPSILON * r.abs(),
                    "{} vs {r}",
                    v[c]
                );
            }
        }
    }
    // the same run's .f06 prints the same modes to its 7 digits
    let f06 = femu_io::f06::read_f06(fixtures().join("mode_solid_shell_bar.f06")).unwrap();
    for (a, b) in op2.modes.iter().zip(&f06.modes) {
        assert!((a.eigenvalue / b.eigenvalue - 1.0).abs() < 1e-6);
    }
}
