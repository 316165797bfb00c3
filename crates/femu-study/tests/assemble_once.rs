//! `femu run` reads and assembles the model once for correlation, estimation, expansion with the
//! sensor-removal study, and updating (the quadratic reference of the discretisation estimate is
//! another model, assembled by its own assembler). The count is the loaded model's assembler's
//! own (shared with its clones), so other tests may assemble beside this one.

use femu_correlate::{Sensor, SensorLayout, TestModes};
use femu_fem::prelude::*;
use femu_update::{Corrections, UpdateModel, model_modes};

#[test]
fn a_study_file_assembles_the_model_once() {
    let dir = std::env::temp_dir().join(format!("femu-study-once-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // a clamped steel bar in four slabs; the "real" one has slab g1 20 % softer
    let mut mesh = box_mesh(&BoxSpec::new(
        [0.4, 0.03, 0.02],
        [12, 2, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    add_slab_sets(&mut mesh, 0, 4, "g").unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    femu_io::inp::write_inp(&model, None, dir.join("bar.inp")).unwrap();
    let sets = ["g0", "g1", "g2", "g3"];
    let mut real =
        UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent, Corrections::Stiffness)
            .unwrap();
    real.set_theta(&[0.0, -0.2, 0.0, 0.0]).unwrap();
    let modes = model_modes(&mut real, 6, &Default::default()).unwrap();
    let nodes = femu_correlate::placement::grid_nodes(model.mesh(), "zmax", [6, 2]).unwrap();
    let sensors: Vec<Sensor> = nodes
        .iter()
        .flat_map(|n| [Sensor::axis(*n, 1), Sensor::axis(*n, 2)])
        .collect();
    let layout = SensorLayout::new(model.mesh(), &real.matrices().dofs, sensors.clone()).unwrap();
    let y = layout.measure_all(modes.shapes.as_ref()).unwrap();
    let test = TestModes::new(modes.frequencies_hz(), None, y).unwrap();
    std::fs::write(
        dir.join("test.csv"),
        femu_io::csv::test_csv_string(&sensors, &test),
    )
    .unwrap();
    std::fs::write(
        dir.join("study.toml"),
        "model = \"bar.inp\"\ntest = \"test.csv\"\n[expansion]\nmethod = \"dynamic\"\nstudy = true\n[update]\nsets = [\"g0\", \"g1\", \"g2\", \"g3\"]\ntuned = 4\n",
    )
    .unwrap();
    let run =
        femu_study::study_file::run_study_file(&dir.join("study.toml"), &dir.join("out"), |_| {})
            .unwrap();
    // the model once, by its loader; the updating reuses that assembly, and the discretisation
    // estimate's reference (the same mesh with quadratic elements) is a different model
    assert_eq!(run.model_assemblies, 1);
    // every step ran and wrote its file
    let update = run.update.as_ref().unwrap();
    assert_eq!(update.result.names.len(), update.updated_sets.len());
    assert!(run.expansion.as_ref().unwrap().study.is_some());
    for f in &run.files {
        assert!(f.exists(), "{}", f.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
