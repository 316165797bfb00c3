//! Models given as another solver's `K` and `M` (docs/VERIFICATION.md, "Models solved
//! elsewhere"): CalculiX's stored matrices give CalculiX's eigenvalues and equal femu's assembly of
//! the same deck; a spring-mass chain written by hand has its analytic eigenvalues and mode
//! shapes; femu's own export, rotations included, reads back as the model it came from; and what
//! cannot be used is refused with the file, row and node.

use femu_correlate::{ModeSet, PairingOptions, correlate};
use femu_fem::prelude::*;
use femu_io::inp::{FrequencyStep, inp_string};
use femu_sparse::eigen::{EigenOptions, Which};
use femu_study::load::{ModelOptions, load_model, load_test};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("femu-external-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn lowest(path: &Path, count: usize) -> (Vec<f64>, femu_study::load::LoadedModel) {
    let loaded = load_model(path, &ModelOptions::default()).unwrap();
    let modes = loaded
        .sys
        .modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap();
    assert!(modes.sturm.verified(), "{:?}", modes.sturm);
    (modes.values, loaded)
}

/// Another solver's modes correlated with the test at `test` placed on their nodes.
fn correlate_on(
    results: &femu_study::external::ResultModes,
    test: &Path,
) -> femu_correlate::CorrelationReport {
    let test = femu_study::load::load_test_on(
        test,
        results.model.mesh(),
        &results.dofs,
        &Default::default(),
    )
    .unwrap();
    correlate(
        &results.modes,
        &test.data.modes,
        &test.layout,
        &PairingOptions::default(),
    )
    .unwrap()
}

/// The largest entry of `a - b` over the largest of `b`.
fn relative_difference(a: &femu_sparse::SparseMatrix, b: &femu_sparse::SparseMatrix) -> f64 {
    let (da, db) = (femu_sparse::csc::to_dense(a), femu_sparse::csc::to_dense(b));
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for i in 0..db.nrows() {
        for j in 0..db.ncols() {
            worst = worst.max((da[(i, j)] - db[(i, j)]).abs());
            scale = scale.max(db[(i, j)].abs());
        }
    }
    worst / scale
}

/// A steel cantilever of hex8 bricks with a point mass at the tip and an `*EQUATION` tying two
/// tip nodes' x motions: CalculiX stores its `K` and `M` (`*FREQUENCY, SOLVER=MATRIXSTORAGE`,
/// 14 digits) on the free DOFs after the boundary conditions and the equation. Read by femu
/// (nodes from the deck beside them) they give
/// - CalculiX's own eigenvalues of the deck (its `.dat`, 7 digits) to 1e-6,
/// - femu's assembly of the same deck entry by entry to 1e-12 of the largest (the files' 14
///   digits: 1.3e-14 measured), hence its eigenvalues to 1e-9.
#[test]
fn calculix_stored_matrices_are_the_deck() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let spec = BoxSpec::new([0.4, 0.1, 0.05], [8, 2, 2], BoxCells::Hex, false);
    let mesh = box_mesh(&spec).unwrap();
    let tip: Vec<u64> = mesh
        .node_set("xmax")
        .unwrap()
        .iter()
        .map(|&n| mesh.node_id(n))
        .collect();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    model.add_point_mass(tip[0], 0.5).unwrap();
    model
        .add_constraint((tip[1], 0), &[((tip[2], 0), 1.0)], "tie")
        .unwrap();
    let d = dir("ccx");
    let text = inp_string(
        &model,
        Some(&FrequencyStep {
            count: 6,
            shift_cycles2: None,
        }),
    )
    .unwrap();
    assert!(text.contains("*FREQUENCY\n"));
    std::fs::write(d.join("reference.inp"), &text).unwrap();
    std::fs::write(
        d.join("job.inp"),
        text.replace("*FREQUENCY\n", "*FREQUENCY, SOLVER=MATRIXSTORAGE\n"),
    )
    .unwrap();
    femu_testkit::ccx::run(&d, "reference");
    femu_testkit::ccx::run(&d, "job");
    let ccx =
        femu_testkit::ccx::eigenvalues(&std::fs::read_to_string(d.join("reference.dat")).unwrap());
    let (external, loaded) = lowest(&d.join("job.sti"), 6);
    let (own, deck) = lowest(&d.join("reference.inp"), 6);
    assert_eq!(loaded.sys.dofs.free_count(), deck.sys.dofs.free_count());
    for j in 0..6 {
        let to_ccx = (external[j] / ccx[j] - 1.0).abs();
        assert!(
            to_ccx < 1e-6,
            "mode {}: {} vs ccx {}",
            j + 1,
            external[j],
            ccx[j]
        );
        // the files' 14 digits perturb K by 1e-14 of its largest entry, which moves the lowest
        // eigenvalue by up to that times lambda_max / lambda_1 (here about 1e5): 2.6e-10 measured
        let to_femu = (external[j] / own[j] - 1.0).abs();
        assert!(to_femu < 1e-9, "mode {}: {to_femu:.1e}", j + 1);
    }
    let dk = relative_difference(&loaded.sys.k, &deck.sys.k);
    let dm = relative_difference(&loaded.sys.m, &deck.sys.m);
    assert!(dk < 1e-12 && dm < 1e-12, "K {dk:.1e}, M {dm:.1e}");
    let origin = loaded.matrices.as_ref().unwrap();
    assert_eq!(origin.nodes, d.join("job.inp"));
    let _ = std::fs::remove_dir_all(&d);
}

/// Five masses `m` in a line joined by springs `k`, the first spring to the ground, written by
/// hand as MatrixMarket with a DOF table (x of nodes 1-5) and a node table: the eigenvalues are
/// `4 (k / m) sin^2((2j - 1) pi / (2 (2n + 1)))` and the shapes `sin((2j - 1) i pi / (2n + 1))`
/// at mass `i`. A test made of those shapes at three masses correlates with MAC 1 and no
/// frequency error, and its residues (expanded dynamically, the estimators' bounds proven by
/// inertia) vanish.
#[test]
fn a_spring_mass_chain_by_hand() {
    let (n, k, m) = (5usize, 4.0e5, 2.0);
    let d = dir("chain");
    let mut entries = Vec::new();
    for i in 0..n {
        entries.push((i, i, if i + 1 < n { 2.0 * k } else { k }));
        if i + 1 < n {
            entries.push((i + 1, i, -k));
        }
    }
    let mut kt = format!(
        "%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {}\n",
        entries.len()
    );
    for (i, j, v) in &entries {
        kt.push_str(&format!("{} {} {v}\n", i + 1, j + 1));
    }
    std::fs::write(d.join("chain_K.mtx"), kt).unwrap();
    let mut mt = format!("%%MatrixMarket matrix coordinate real general\n{n} {n} {n}\n");
    let mut dofs = String::from("row,node,component\n");
    let mut nodes = String::from("node,x,y,z\n");
    for i in 0..n {
        mt.push_str(&format!("{} {} {m}\n", i + 1, i + 1));
        dofs.push_str(&format!("{},{},x\n", i + 1, i + 1));
        nodes.push_str(&format!("{},{},0,0\n", i + 1, 0.1 * (i + 1) as f64));
    }
    std::fs::write(d.join("chain_M.mtx"), mt).unwrap();
    std::fs::write(d.join("chain_dofs.csv"), dofs).unwrap();
    std::fs::write(d.join("chain_nodes.csv"), nodes).unwrap();
    let (values, loaded) = lowest(&d.join("chain_K.mtx"), n);
    let pi = std::f64::consts::PI;
    let exact: Vec<f64> = (1..=n)
        .map(|j| {
            let s = ((2 * j - 1) as f64 * pi / (2.0 * (2 * n + 1) as f64)).sin();
            4.0 * k / m * s * s
        })
        .collect();
    for j in 0..n {
        assert!(
            (values[j] / exact[j] - 1.0).abs() < 1e-12,
            "{} vs {}",
            values[j],
            exact[j]
        );
    }
    assert_eq!(loaded.sys.mass_kind, MassKind::Lumped);
    // the analytic shapes at masses 2, 4 and 5 as a CSV test
    let mut test = String::from("mode,frequency_hz,node,direction,value\n");
    for j in 1..=3 {
        let f = exact[j - 1].sqrt() / (2.0 * pi);
        for i in [2, 4, 5] {
            let v = ((2 * j - 1) as f64 * i as f64 * pi / (2 * n + 1) as f64).sin();
            test.push_str(&format!("{j},{f:.12},{i},x,{v:.12}\n"));
        }
    }
    std::fs::write(d.join("test.csv"), test).unwrap();
    let t = load_test(&d.join("test.csv"), &loaded).unwrap();
    let modes =
        femu_study::modes::lowest_for_test(&loaded, None, 3, &EigenOptions::default()).unwrap();
    let report = correlate(
        &ModeSet::from_modes(&modes),
        &t.data.modes,
        &t.layout,
        &PairingOptions::default(),
    )
    .unwrap();
    assert_eq!(report.pairing.pairs.len(), 3);
    for p in &report.pairing.pairs {
        assert_eq!(p.test, p.model);
        assert!((p.mac.unwrap() - 1.0).abs() < 1e-12, "{p:?}");
        assert!(p.frequency_error.abs() < 1e-11, "{p:?}");
    }
    // the estimators, with lambda_max and mu_min proven by inertia (no elements to bound them):
    // the test modes are exact eigenpairs, so every residue vanishes to round-off
    let run = femu_study::estimate::estimate_loaded(
        &loaded,
        &t,
        &femu_study::estimate::EstimateOptions::default(),
        |_| {},
    )
    .unwrap();
    for row in &run.result.rows {
        assert!(row.t2_rigorous_holds, "{row:?}");
        assert!(row.rho_m < 1e-6 * exact[row.test - 1], "{row:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A clamped hex8 cantilever whose tip is a rigid link to a reference node (9999) with rotations
/// and a point mass.
fn linked_cantilever() -> Model {
    let spec = BoxSpec::new([0.3, 0.05, 0.05], [6, 1, 1], BoxCells::Hex, false);
    let mut mesh = box_mesh(&spec).unwrap();
    let tip: Vec<u64> = mesh
        .node_set("xmax")
        .unwrap()
        .iter()
        .map(|&n| mesh.node_id(n))
        .collect();
    mesh.add_node(9999, [0.35, 0.025, 0.025]).unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    model.add_rotations(9999).unwrap();
    model
        .add_rigid_link(9999, &tip, &[0, 1, 2], "tip link")
        .unwrap();
    model.add_point_mass(9999, 0.3).unwrap();
    model
}

/// `femu matrices`' set (K, M, DOF table with rotations, node table) of a cantilever whose tip is
/// a rigid link to a reference node with rotations and a point mass: read back as a model, it has
/// the same free DOFs, rotations included, and the eigenvalues of the model it was written from.
#[test]
fn femu_export_reads_back_with_rotations() {
    let model = linked_cantilever();
    let d = dir("export");
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let own = sys
        .modes(Which::Lowest(8), &EigenOptions::default())
        .unwrap()
        .values;
    let rotations = (0..sys.dofs.free_count())
        .filter(|&f| sys.dofs.point_node(sys.dofs.free_dof(f).0).1)
        .count();
    assert_eq!(rotations, 3);
    let written =
        femu_study::external::write_matrices(&model, &sys, &d.join("cantilever")).unwrap();
    let dofs = std::fs::read_to_string(&written.files[2]).unwrap();
    assert_eq!(dofs.matches(",9999,r").count(), 3, "{dofs}");
    let (back, loaded) = lowest(&written.files[0], 8);
    assert_eq!(loaded.sys.dofs.free_count(), sys.dofs.free_count());
    for j in 0..8 {
        assert!(
            (back[j] / own[j] - 1.0).abs() < 1e-12,
            "mode {}: {} vs {}",
            j + 1,
            back[j],
            own[j]
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// What cannot be a model is refused, naming the file and what is wrong: a DOF of a node the
/// coordinates lack, no coordinates at all, a negative mass on the diagonal; and updating such a
/// model over a set given without its matrices (`NAME=FILE`).
#[test]
fn refusals() {
    let d = dir("bad");
    let sym = |diag: f64| {
        format!("%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 {diag}\n2 2 1\n")
    };
    std::fs::write(d.join("a_K.mtx"), sym(1.0)).unwrap();
    std::fs::write(d.join("a_M.mtx"), sym(1.0)).unwrap();
    std::fs::write(d.join("a_dofs.csv"), "row,node,component\n1,1,x\n2,7,y\n").unwrap();
    let load = || load_model(&d.join("a_K.mtx"), &ModelOptions::default());
    let e = load().unwrap_err().to_string();
    assert!(e.contains("a_nodes.csv") && e.contains("--nodes"), "{e}");
    std::fs::write(d.join("a_nodes.csv"), "node,x,y,z\n1,0,0,0\n").unwrap();
    let e = load().unwrap_err().to_string();
    assert!(
        e.contains("a_dofs.csv") && e.contains("row 2 is node 7 y"),
        "{e}"
    );
    std::fs::write(d.join("a_nodes.csv"), "node,x,y,z\n1,0,0,0\n7,1,0,0\n").unwrap();
    std::fs::write(d.join("a_M.mtx"), sym(-1.0)).unwrap();
    let e = load().unwrap_err().to_string();
    assert!(
        e.contains("a_M.mtx") && e.contains("negative diagonal entry at row 1 (node 1 x)"),
        "{e}"
    );
    std::fs::write(d.join("a_M.mtx"), sym(1.0)).unwrap();
    let loaded = load().unwrap();
    std::fs::write(
        d.join("t.csv"),
        "mode,frequency_hz,node,direction,value\n1,0.2,1,x,1\n1,0.2,7,y,0.5\n2,0.3,1,x,-0.5\n2,0.3,7,y,1\n",
    )
    .unwrap();
    let test = load_test(&d.join("t.csv"), &loaded).unwrap();
    let request: femu_study::updating::UpdateRequest = toml::from_str("sets = [\"r0\"]").unwrap();
    let e = femu_study::updating::update_loaded(
        &loaded,
        &test,
        &request,
        &EigenOptions::default(),
        None,
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("a_K.mtx") && e.contains("NAME=FILE"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// CalculiX stores the matrices of a shell model on the solids it expands the shells into: their
/// DOF labels repeat (`2.1` twice) and name nodes the deck does not have. femu refuses the set,
/// naming the `.dof` file's line, instead of reading a model it cannot place.
#[test]
fn calculix_shell_matrices_are_refused() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let d = dir("shell");
    std::fs::write(
        d.join("shell.inp"),
        "*NODE\n1,0,0,0\n2,1,0,0\n3,2,0,0\n4,0,1,0\n5,1,1,0\n6,2,1,0\n\
         *ELEMENT, TYPE=S4, ELSET=E\n1,1,2,5,4\n2,2,3,6,5\n\
         *MATERIAL, NAME=S\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *SHELL SECTION, ELSET=E, MATERIAL=S\n0.01\n\
         *BOUNDARY\n1,1,6\n4,1,6\n\
         *STEP\n*FREQUENCY, SOLVER=MATRIXSTORAGE\n4\n*END STEP\n",
    )
    .unwrap();
    femu_testkit::ccx::run(&d, "shell");
    let e = load_model(&d.join("shell.sti"), &ModelOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("shell.dof:") && e.contains("is listed again") && e.contains("expands shells"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A steel hex8 cantilever (8 x 2 x 2 bricks, clamped at `x = 0`) written as `job.inp` in `d`
/// with a six-mode `*FREQUENCY` step asking for `outputs`, and solved by CalculiX there.
fn solved_cantilever(d: &Path, outputs: &str) {
    let spec = BoxSpec::new([0.4, 0.1, 0.05], [8, 2, 2], BoxCells::Hex, false);
    let mut model = Model::new(box_mesh(&spec).unwrap()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let text = inp_string(
        &model,
        Some(&FrequencyStep {
            count: 6,
            shift_cycles2: None,
        }),
    )
    .unwrap();
    assert!(text.contains("*END STEP"));
    std::fs::write(
        d.join("job.inp"),
        text.replace("*END STEP", &format!("{outputs}*END STEP")),
    )
    .unwrap();
    femu_testkit::ccx::run(d, "job");
}

/// `test.csv` in `d`: femu's own six lowest modes of `job.inp` at its free end (`XMAX`) in y and
/// z, the "test" another solver's modes of the same deck are correlated with.
fn femu_test_at_the_tip(d: &Path) {
    let (values, loaded) = lowest(&d.join("job.inp"), 6);
    let modes = loaded
        .sys
        .modes(Which::Lowest(6), &EigenOptions::default())
        .unwrap();
    let mesh = loaded.model.mesh();
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    for j in 0..6 {
        let f = values[j].sqrt() / (2.0 * std::f64::consts::PI);
        for &n in mesh.node_set("XMAX").unwrap() {
            for (c, name) in [(1, "y"), (2, "z")] {
                let r = loaded.sys.dofs.free_index(n, c).unwrap();
                csv.push_str(&format!(
                    "{},{f:.12},{},{name},{:.15e}\n",
                    j + 1,
                    mesh.node_id(n),
                    modes.vectors[(r, j)]
                ));
            }
        }
    }
    std::fs::write(d.join("test.csv"), csv).unwrap();
}

/// CalculiX's modes as the model side: a hex8 cantilever solved by CalculiX (`*NODE FILE, U`
/// in its `*FREQUENCY` step: a `.frd` of 6 significant digits per value, 10 per frequency) and a
/// "test" of femu's own modes of the same deck at the tip's nodes in y and z. The two codes'
/// modes pair one to one with MAC above 1 - 1e-10 (1 - 4.6e-12 measured) and frequencies within
/// 1e-9 (1.3e-10 measured: the `.frd`'s 10 digits); a study file of the `.frd` gives the same
/// correlation; asked for K and M, the `.frd` is refused with what to give instead.
#[test]
fn calculix_modes_are_the_model_side() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let d = dir("frd");
    solved_cantilever(&d, "*NODE FILE\nU\n");
    femu_test_at_the_tip(&d);
    let results = femu_study::external::load_result_modes(&d.join("job.frd"), None).unwrap();
    assert_eq!(results.modes.len(), 6);
    let report = correlate_on(&results, &d.join("test.csv"));
    assert_eq!(report.pairing.pairs.len(), 6);
    for p in &report.pairing.pairs {
        assert_eq!(p.test, p.model);
        assert!(p.mac.unwrap() > 1.0 - 1e-10, "{p:?}");
        assert!(p.frequency_error.abs() < 1e-9, "{p:?}");
    }
    let e = load_model(&d.join("job.frd"), &ModelOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("femu correlate") && e.contains("SOLVER=MATRIXSTORAGE"),
        "{e}"
    );
    // a study file of the .frd correlates, and the same report; a step that needs K and M refused
    std::fs::write(
        d.join("study.toml"),
        "model = \"job.frd\"\ntest = \"test.csv\"\n",
    )
    .unwrap();
    let run = femu_study::study_file::run_study_file(&d.join("study.toml"), &d.join("out"), |_| {})
        .unwrap();
    assert_eq!(run.correlation, report);
    assert!(run.estimate.is_none());
    let written: femu_correlate::CorrelationReport =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/correlation.json")).unwrap())
            .unwrap();
    assert_eq!(written.pairing.pairs.len(), 6);
    std::fs::write(
        d.join("study.toml"),
        "model = \"job.frd\"\ntest = \"test.csv\"\n[update]\nsets = [\"a\"]\n",
    )
    .unwrap();
    let e = femu_study::study_file::run_study_file(&d.join("study.toml"), &d.join("out"), |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("study.toml") && e.contains("[update]") && e.contains("need K and M"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// MSC Nastran's modes (the `.f06` and the `.op2` of a run from pyNastran's models, their grids
/// from the run's deck, which holds shells, bars, beams and rods) as the model side, against a
/// test written from pyNastran's reading of the same run's OP2 (an independent reader): the
/// translations of grids 1-13 in x, y and z. Each pairs one to one with MAC 1 to 1e-9 and the
/// same frequencies to 1e-6. The same modes punched (`.pch`, written here in Nastran's punch
/// layout from pyNastran's reading, the deck beside it) pair the same way.
#[test]
fn nastran_modes_are_the_model_side() {
    let fixtures =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/nastran/pynastran");
    let reference: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixtures.join("mode_solid_shell_bar.modes.json")).unwrap(),
    )
    .unwrap();
    let d = dir("f06");
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    for j in 0..3 {
        let f = reference["eigenvalues"][j].as_f64().unwrap().sqrt() / (2.0 * std::f64::consts::PI);
        for (k, node) in reference["nodes"].as_array().unwrap().iter().enumerate() {
            let node = node.as_u64().unwrap();
            if node > 13 {
                continue;
            }
            for (c, name) in ["x", "y", "z"].iter().enumerate() {
                let v = reference["vectors"][j][k][c].as_f64().unwrap();
                csv.push_str(&format!("{},{f:.9},{node},{name},{v:e}\n", j + 1));
            }
        }
    }
    std::fs::write(d.join("test.csv"), csv).unwrap();
    // the same modes as a punch file (VECTOR(PUNCH)), written here from pyNastran's reading in
    // Nastran's punch layout, beside a copy of the run's deck
    let mut pch = String::new();
    let mut rec = |text: String| {
        let n = pch.lines().count() + 1;
        pch.push_str(&format!("{text:<72}{n:>8}\n"));
    };
    let e = |v: f64| {
        let s = format!("{v:.6E}");
        let (m, x) = s.split_once('E').unwrap();
        let x: i32 = x.parse().unwrap();
        format!(
            "{:>18}",
            format!("{m}E{}{:02}", if x < 0 { '-' } else { '+' }, x.abs())
        )
    };
    for j in 0..3 {
        for h in [
            "$TITLE   =",
            "$SUBTITLE=",
            "$LABEL   =",
            "$EIGENVECTOR",
            "$REAL OUTPUT",
        ] {
            rec(h.to_string());
        }
        rec("$SUBCASE ID =           1".to_string());
        let value = reference["eigenvalues"][j].as_f64().unwrap();
        rec(format!("$EIGENVALUE = {:.7E}  MODE = {:>5}", value, j + 1));
        for (k, node) in reference["nodes"].as_array().unwrap().iter().enumerate() {
            let v: Vec<f64> = (0..6)
                .map(|c| reference["vectors"][j][k][c].as_f64().unwrap())
                .collect();
            rec(format!(
                "{:>10}       G{}{}{}",
                node.as_u64().unwrap(),
                e(v[0]),
                e(v[1]),
                e(v[2])
            ));
            rec(format!("{:<18}{}{}{}", "-CONT-", e(v[3]), e(v[4]), e(v[5])));
        }
    }
    std::fs::write(d.join("mode_solid_shell_bar.pch"), pch).unwrap();
    for deck in ["mode_solid_shell_bar.bdf", "geom.inc"] {
        std::fs::copy(fixtures.join(deck), d.join(deck)).unwrap();
    }
    assert_eq!(
        femu_io::Format::from_path(&d.join("mode_solid_shell_bar.pch")),
        Some(femu_io::Format::Results)
    );
    for path in [
        fixtures.join("mode_solid_shell_bar.f06"),
        fixtures.join("mode_solid_shell_bar.op2"),
        d.join("mode_solid_shell_bar.pch"),
    ] {
        let file = path.file_name().unwrap().to_string_lossy().into_owned();
        let results = femu_study::external::load_result_modes(&path, None).unwrap();
        assert_eq!(results.model.mesh().node_count(), 25);
        let report = correlate_on(&results, &d.join("test.csv"));
        assert_eq!(report.pairing.pairs.len(), 3);
        for p in &report.pairing.pairs {
            assert_eq!(p.test, p.model);
            assert!(p.mac.unwrap() > 1.0 - 1e-9, "{file}: {p:?}");
            assert!(p.frequency_error.abs() < 1e-6, "{file}: {p:?}");
        }
    }
    // without the deck beside it, the .f06 says what it needs
    std::fs::copy(
        fixtures.join("mode_solid_shell_bar.f06"),
        d.join("alone.f06"),
    )
    .unwrap();
    let e = femu_study::external::load_result_modes(&d.join("alone.f06"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--nodes") && e.contains(".bdf"), "{e}");
    // femu info describes the modes alone and says what it needs for the grids
    let info = femu_study::info::describe(&d.join("alone.f06")).unwrap();
    assert!(
        info.contains("modes: 3 at 25 grids") && info.contains("--nodes DECK"),
        "{info}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A clamped steel bar of hex8 bricks in four slabs `G0`-`G3` along x, with `scaled`'s set's
/// Young's modulus and density multiplied by its factors.
fn bar(scaled: Option<(&str, f64, f64)>) -> Model {
    let spec = BoxSpec::new([0.4, 0.06, 0.03], [8, 3, 2], BoxCells::Hex, false);
    let mut mesh = box_mesh(&spec).unwrap();
    add_slab_sets(&mut mesh, 0, 4, "G").unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    if let Some((set, e, rho)) = scaled {
        let steel = Material::steel();
        let (young, poisson) = match steel.elasticity {
            femu_fem::material::Elasticity::Isotropic { e, nu } => (e, nu),
            _ => unreachable!("steel is isotropic"),
        };
        let m = Material::isotropic("scaled", e * young, poisson, rho * steel.density).unwrap();
        model.set_material(Some(set), m).unwrap();
    }
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    model
}

/// The update of `model` (a file) over `sets` from the test `test`, with every default.
fn update(model: &Path, test: &Path, sets: &[String]) -> femu_study::updating::UpdateStudy {
    let loaded = load_model(model, &ModelOptions::default()).unwrap();
    let test = load_test(test, &loaded).unwrap();
    let request: femu_study::updating::UpdateRequest =
        toml::from_str(&format!("sets = {sets:?}")).unwrap();
    femu_study::updating::update_loaded(
        &loaded,
        &test,
        &request,
        &EigenOptions::default(),
        None,
        |_| {},
    )
    .unwrap()
}

/// A steel bar in four slabs `G0`-`G3`; the "real" bar has `G1` 20 % softer. Updating the
/// bar's exported matrices over matrix groups (each the same export with the group's modulus and
/// density doubled: `K_g = K_2 - K_0`, no element involved) recovers the change, and agrees with
/// the element route on the deck: the same selection and the same parameters. A group given
/// without its file, or by another model's matrices, is refused.
#[test]
fn updating_over_matrix_groups_recovers_a_known_change() {
    let d = dir("groups");
    // the test: the real bar's modes at the top face in y and z
    let real = bar(Some(("G1", 0.8, 1.0)));
    let sys = real.assemble(MassKind::Consistent).unwrap();
    let modes = sys
        .modes(Which::Lowest(6), &EigenOptions::default())
        .unwrap();
    let mesh = real.mesh();
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    for j in 0..6 {
        let f = modes.values[j].sqrt() / (2.0 * std::f64::consts::PI);
        for n in 0..mesh.node_count() {
            let x = mesh.coords()[n];
            if (x[2] - 0.03).abs() > 1e-12 || x[0] == 0.0 {
                continue;
            }
            for (c, name) in [(1, "y"), (2, "z")] {
                let r = sys.dofs.free_index(n, c).unwrap();
                csv.push_str(&format!(
                    "{},{f:.15e},{},{name},{:.15e}\n",
                    j + 1,
                    mesh.node_id(n),
                    modes.vectors[(r, j)]
                ));
            }
        }
    }
    std::fs::write(d.join("test.csv"), csv).unwrap();
    // the nominal bar as a deck and as matrices, and each group doubled as matrices
    let nominal = bar(None);
    std::fs::write(d.join("bar.inp"), inp_string(&nominal, None).unwrap()).unwrap();
    let sys = nominal.assemble(MassKind::Consistent).unwrap();
    femu_study::external::write_matrices(&nominal, &sys, &d.join("bar")).unwrap();
    let mut sets = Vec::new();
    for g in 0..4 {
        let name = format!("G{g}");
        let doubled = bar(Some((&name, 2.0, 2.0)));
        let s = doubled.assemble(MassKind::Consistent).unwrap();
        femu_study::external::write_matrices(&doubled, &s, &d.join(format!("bar_{name}"))).unwrap();
        sets.push(format!("{name}=bar_{name}_K.mtx"));
    }
    let on_matrices = update(&d.join("bar_K.mtx"), &d.join("test.csv"), &sets);
    let on_elements = update(
        &d.join("bar.inp"),
        &d.join("test.csv"),
        &(0..4).map(|g| format!("G{g}")).collect::<Vec<_>>(),
    );
    assert_eq!(on_matrices.result.names, on_elements.result.names);
    let g1 = on_matrices
        .result
        .names
        .iter()
        .position(|n| n.contains("G1"))
        .unwrap();
    // -0.19999999998 measured
    assert!((on_matrices.result.theta[g1] + 0.2).abs() < 1e-8);
    for (a, b) in on_matrices
        .result
        .theta
        .iter()
        .zip(&on_elements.result.theta)
    {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
    // a group without its file, and a group file of another model, refused
    let loaded = load_model(&d.join("bar_K.mtx"), &ModelOptions::default()).unwrap();
    let test = load_test(&d.join("test.csv"), &loaded).unwrap();
    let refused = |sets: &str| {
        let request: femu_study::updating::UpdateRequest =
            toml::from_str(&format!("sets = {sets}")).unwrap();
        femu_study::updating::update_loaded(
            &loaded,
            &test,
            &request,
            &EigenOptions::default(),
            None,
            |_| {},
        )
        .unwrap_err()
        .to_string()
    };
    let e = refused("[\"G0\"]");
    assert!(e.contains("NAME=FILE"), "{e}");
    let mut other_mesh_model = Model::new(
        box_mesh(&BoxSpec::new(
            [0.4, 0.06, 0.03],
            [4, 3, 2],
            BoxCells::Hex,
            false,
        ))
        .unwrap(),
    )
    .unwrap();
    other_mesh_model
        .set_material(None, Material::steel())
        .unwrap();
    let s = other_mesh_model.assemble(MassKind::Consistent).unwrap();
    femu_study::external::write_matrices(&other_mesh_model, &s, &d.join("other")).unwrap();
    let e = refused("[\"G0=other_K.mtx\"]");
    assert!(
        e.contains("other_K.mtx") && e.contains("rows are not the model's"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The same update on CalculiX's matrices, against a test CalculiX solved: CalculiX stores the
/// nominal bar's `K` and `M` and each group's doubled ones (`*FREQUENCY, SOLVER=MATRIXSTORAGE`),
/// and solves the real bar (`G1` 20 % softer) for the test (its `.frd`, 6 digits per value, read
/// at the top face in y and z). No femu element is involved in the update or the test; the
/// selection keeps `G1` alone and finds -0.2 to 1e-6 (3.7e-10 measured).
#[test]
fn updating_calculix_matrices_recovers_a_calculix_change() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let d = dir("ccx-groups");
    let step = |model: &Model, job: &str, step: &str| {
        let text = inp_string(
            model,
            Some(&FrequencyStep {
                count: 6,
                shift_cycles2: None,
            }),
        )
        .unwrap();
        std::fs::write(
            d.join(format!("{job}.inp")),
            text.replace("*FREQUENCY\n", step).replace(
                "*END STEP",
                if step.contains("MATRIX") {
                    "*END STEP"
                } else {
                    "*NODE FILE\nU\n*END STEP"
                },
            ),
        )
        .unwrap();
        femu_testkit::ccx::run(&d, job);
    };
    step(&bar(None), "job", "*FREQUENCY, SOLVER=MATRIXSTORAGE\n");
    let mut sets = Vec::new();
    for g in 0..4 {
        let name = format!("G{g}");
        step(
            &bar(Some((&name, 2.0, 2.0))),
            &format!("job_{name}"),
            "*FREQUENCY, SOLVER=MATRIXSTORAGE\n",
        );
        sets.push(format!("{name}=job_{name}.sti"));
    }
    step(&bar(Some(("G1", 0.8, 1.0))), "real", "*FREQUENCY\n");
    let frd = femu_io::frd::read_frd(d.join("real.frd")).unwrap();
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    for m in &frd.modes {
        for (n, (id, x)) in frd.nodes.iter().enumerate() {
            if (x[2] - 0.03).abs() > 1e-9 || x[0] == 0.0 {
                continue;
            }
            for (c, name) in [(1, "y"), (2, "z")] {
                csv.push_str(&format!(
                    "{},{},{id},{name},{:e}\n",
                    m.number, m.frequency_hz, m.shape[n][c]
                ));
            }
        }
    }
    std::fs::write(d.join("test.csv"), csv).unwrap();
    let study = update(&d.join("job.sti"), &d.join("test.csv"), &sets);
    assert_eq!(study.result.names, ["k:G1"]);
    // -0.20000000037 measured
    assert!(
        (study.result.theta[0] + 0.2).abs() < 1e-6,
        "{:?}",
        study.result.theta
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Abaqus's generated matrices (`*MATRIX OUTPUT, FORMAT=MATRIX INPUT`: `node, DOF, node, DOF,
/// value` lines) written here from femu's own assembly of a cantilever with a rigid link and a
/// rotating tip node: the stiffness by its lower triangle with the clamped DOFs as Abaqus writes
/// them (a unit diagonal, no mass), the mass by both triangles, a `**` comment. They read back
/// entry by entry, by node and component (to 1e-15 of the largest entry: femu's assembly is
/// symmetric to round-off, not bit for bit), their eigenvalues are the model's to 1e-12
/// with the Sturm proof, and the node coordinates come from `job.inp` beside them. A file that is
/// not symmetric, an internal node, a DOF beyond 6 and the label-less coordinate format are
/// refused with file and line.
#[test]
fn abaqus_generated_matrices_are_the_model() {
    let model = linked_cantilever();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let own = sys
        .modes(Which::Lowest(8), &EigenOptions::default())
        .unwrap()
        .values;
    let mesh = model.mesh();
    let labels: Vec<(u64, usize)> = (0..sys.dofs.free_count())
        .map(|f| {
            let (p, c) = sys.dofs.free_dof(f);
            let (n, rotation) = sys.dofs.point_node(p);
            (mesh.node_id(n), c + 1 + if rotation { 3 } else { 0 })
        })
        .collect();
    let d = dir("abaqus");
    let mut stif = String::from("** the lower triangle, as Abaqus writes it\n");
    for (i, j, v) in femu_sparse::csc::entries(&sys.k).filter(|(i, j, _)| i >= j) {
        let (a, b) = (labels[i], labels[j]);
        stif.push_str(&format!("{}, {}, {}, {}, {v:e}\n", a.0, a.1, b.0, b.1));
    }
    for (n, c) in model.fixed_dofs() {
        stif.push_str(&format!(
            "{0}, {1}, {0}, {1}, 1.0\n",
            mesh.node_id(n),
            c + 1
        ));
    }
    let mut mass = String::new();
    for (i, j, v) in femu_sparse::csc::entries(&sys.m) {
        let (a, b) = (labels[i], labels[j]);
        mass.push_str(&format!("{},{},{},{},{v:e}\n", a.0, a.1, b.0, b.1));
    }
    std::fs::write(d.join("job_STIF2.mtx"), &stif).unwrap();
    std::fs::write(d.join("job_MASS2.mtx"), &mass).unwrap();
    let mut nodes = String::from("*NODE\n");
    for i in 0..mesh.node_count() {
        let x = mesh.coords()[i];
        nodes.push_str(&format!(
            "{}, {}, {}, {}\n",
            mesh.node_id(i),
            x[0],
            x[1],
            x[2]
        ));
    }
    std::fs::write(d.join("job.inp"), nodes).unwrap();
    // exact read-back, entry by entry through the labels
    let ext = femu_io::matrices::read_matrices(&d.join("job_STIF2.mtx")).unwrap();
    assert_eq!(ext.source, femu_io::matrices::MatrixSource::Abaqus);
    assert_eq!(ext.dofs.len(), labels.len());
    let row: std::collections::HashMap<(u64, usize), usize> = ext
        .dofs
        .iter()
        .enumerate()
        .map(|(r, l)| ((l.node, l.component + 1), r))
        .collect();
    // to the round-off by which femu's own assembly is not symmetric (1e-15 of the largest
    // entry): the stiffness's upper triangle is its lower one's mirror, the mass's the mean
    for (ours, theirs, tol) in [(&sys.k, &ext.k, 1e-15), (&sys.m, &ext.m, 1e-15)] {
        assert_eq!(ours.nnz(), theirs.nnz());
        let scale = ours.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, j, v) in femu_sparse::csc::entries(ours) {
            let (r, c) = (row[&labels[i]], row[&labels[j]]);
            let got = theirs.get(r, c).copied().unwrap();
            assert!((got - v).abs() <= tol * scale, "{got} {v}");
        }
    }
    let (back, loaded) = lowest(&d.join("job_STIF2.mtx"), 8);
    assert_eq!(loaded.sys.dofs.free_count(), sys.dofs.free_count());
    for j in 0..8 {
        assert!((back[j] / own[j] - 1.0).abs() < 1e-12, "{back:?} {own:?}");
    }
    // refusals, with file and line
    let cases = [
        (
            "1, 1, 1, 1, 2.0\n2, 1, 1, 1, 0.5\n1, 1, 2, 1, 0.6\n2, 1, 2, 1, 2.0\n",
            3,
            "not symmetric",
        ),
        ("1, 1, 1, 1, 2.0\n-3, 1, 1, 1, 0.5\n", 2, "internal node"),
        ("1, 1, 1, 1, 2.0\n1, 8, 1, 8, 2.0\n", 2, "not 1 to 6"),
        ("1 1 2.0\n", 1, "FORMAT=COORDINATE"),
    ];
    for (text, line, what) in cases {
        std::fs::write(d.join("bad_STIF1.mtx"), text).unwrap();
        std::fs::write(d.join("bad_MASS1.mtx"), "1, 1, 1, 1, 1.0\n").unwrap();
        let e = femu_io::matrices::read_matrices(&d.join("bad_STIF1.mtx"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("bad_STIF1.mtx:{line}")) && e.contains(what),
            "{text}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Nastran's DMIG matrices in a punch file (`job.pch`, as `PARAM,EXTOUT,DMIGPCH` writes them),
/// written here from femu's assembly of a Nastran deck of a clamped CQUAD4 plate (grids with
/// rotations): `KAAX` symmetric (`IFO` 6) by its lower triangle in large-field cards with `D`
/// exponents (ten digits, as a punch prints them), `MAAX` square (`IFO` 1) in free-field cards at
/// full precision; the grids from `job.bdf` beside it. The entries read back (the stiffness to
/// its ten digits, 8e-11 of its largest entry; the mass exactly), and the eigenvalues are the
/// deck's to 1e-5 with the Sturm proof (2e-6 measured: the punch's ten digits moved by the thin
/// plate's `lambda_max / lambda_1`). A complex matrix, a scalar point, and grids in a turned displacement frame are
/// refused with file and line or grid.
/// A plate of `n x n` CQUAD4 (0.1 x 0.08 each, 4 mm aluminium, coupled mass) clamped along its
/// first column of grids by SPC1 123456, as a Nastran deck.
fn clamped_plate_deck(n: usize) -> String {
    let mut deck = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    let g = |i: usize, j: usize| 1 + i + (n + 1) * j;
    for j in 0..=n {
        for i in 0..=n {
            deck.push_str(&format!(
                "GRID,{},,{},{},0.\n",
                g(i, j),
                0.1 * i as f64,
                0.08 * j as f64
            ));
        }
        deck.push_str(&format!("SPC1,1,123456,{}\n", g(0, j)));
    }
    for j in 0..n {
        for i in 0..n {
            deck.push_str(&format!(
                "CQUAD4,{},1,{},{},{},{}\n",
                1 + i + n * j,
                g(i, j),
                g(i + 1, j),
                g(i + 1, j + 1),
                g(i, j + 1)
            ));
        }
    }
    deck.push_str("PSHELL,1,1,0.004,1,,1\nMAT1,1,7.+10,,0.33,2700.\nENDDATA\n");
    deck
}

/// The clamped plate of [`clamped_plate_deck`] (3 x 3) with a grid no element touches (999): its
/// deck and femu's stiffness, mass and DOF labels (node, 0-based component) of its free DOFs,
/// from the deck without grid 999.
fn clamped_plate(d: &Path) -> (String, femu_study::load::LoadedModel, Vec<(u64, usize)>) {
    let deck = clamped_plate_deck(3);
    std::fs::write(d.join("own.bdf"), &deck).unwrap();
    let loaded = load_model(&d.join("own.bdf"), &ModelOptions::default()).unwrap();
    let mesh = loaded.model.mesh();
    let labels = (0..loaded.sys.dofs.free_count())
        .map(|f| {
            let (p, c) = loaded.sys.dofs.free_dof(f);
            let (node, rotation) = loaded.sys.dofs.point_node(p);
            (mesh.node_id(node), c + if rotation { 3 } else { 0 })
        })
        .collect();
    let deck = deck.replace("ENDDATA", "GRID,999,,5.,5.,5.\nENDDATA");
    (deck, loaded, labels)
}

#[test]
fn nastran_op4_matrices_are_the_model() {
    use femu_testkit::op4::{Op4Layout, Op4Out, columns_of, op4_binary, op4_text};
    let d = dir("op4");
    let (deck, own, labels) = clamped_plate(&d);
    let want = own
        .sys
        .modes(Which::Lowest(6), &EigenOptions::default())
        .unwrap()
        .values;
    // the g-set: 17 grids x 6 in the order of their ids; the clamped grids' rows hold stiffness
    // and mass that couple them to the free ones (Nastran's KGG before SPCs), which the reader
    // must drop; grid 999's rows are null (Nastran's AUTOSPC fixes them)
    let mut grids: Vec<u64> = labels.iter().map(|l| l.0).collect();
    grids.extend([1, 5, 9, 13, 999]);
    grids.sort_unstable();
    grids.dedup();
    let row = |node: u64, c: usize| 6 * grids.iter().position(|&g| g == node).unwrap() + c;
    let ng = 6 * grids.len();
    let gset = |a: &femu_sparse::SparseMatrix, clamp: f64| {
        let mut e: Vec<(usize, usize, f64)> = femu_sparse::csc::entries(a)
            .map(|(i, j, v)| {
                (
                    row(labels[i].0, labels[i].1),
                    row(labels[j].0, labels[j].1),
                    v,
                )
            })
            .collect();
        for g in [1u64, 5, 9, 13] {
            for c in 0..6 {
                let r = row(g, c);
                e.push((r, r, clamp));
                let f = row(g + 1, c); // the free grid beside
                e.push((r, f, -0.3 * clamp));
                e.push((f, r, -0.3 * clamp));
            }
        }
        columns_of(ng, e.into_iter())
    };
    let scale_k = own.sys.k.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale_m = own.sys.m.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let kgg = Op4Out {
        name: "KGG",
        rows: ng,
        form: 6,
        columns: gset(&own.sys.k, scale_k),
    };
    let mgg = Op4Out {
        name: "MGG",
        rows: ng,
        form: 6,
        columns: gset(&own.sys.m, scale_m),
    };
    let pair = [kgg, mgg];
    std::fs::write(
        d.join("bin.op4"),
        op4_binary(&pair, Op4Layout::Sparse, false),
    )
    .unwrap();
    std::fs::write(d.join("bin.bdf"), &deck).unwrap();
    std::fs::write(d.join("text.op4"), op4_text(&pair, Op4Layout::BigMat)).unwrap();
    std::fs::write(d.join("text.bdf"), &deck).unwrap();
    for file in ["bin.op4", "text.op4"] {
        // the free rows' entries to the bit (binary doubles; text of 17 digits), the clamped and
        // null rows gone
        let ext = femu_io::matrices::read_matrices(&d.join(file)).unwrap();
        let at: std::collections::HashMap<(u64, usize), usize> = ext
            .dofs
            .iter()
            .enumerate()
            .map(|(r, l)| ((l.node, l.component), r))
            .collect();
        assert_eq!(ext.dofs.len(), labels.len(), "{file}");
        for (ours, theirs) in [(&own.sys.k, &ext.k), (&own.sys.m, &ext.m)] {
            assert_eq!(ours.nnz(), theirs.nnz(), "{file}");
            for (i, j, v) in femu_sparse::csc::entries(ours) {
                assert_eq!(
                    theirs.get(at[&labels[i]], at[&labels[j]]),
                    Some(&v),
                    "{file}"
                );
            }
        }
        // the eigenvalues to the solver's convergence (the rows are in another order)
        let (got, _) = lowest(&d.join(file), 6);
        for (a, b) in got.iter().zip(&want) {
            assert!((a / b - 1.0).abs() < 1e-10, "{file}: {got:?} vs {want:?}");
        }
    }
    // femu info lists the file's matrices, then the model it makes
    let info = femu_study::info::describe(&d.join("bin.op4")).unwrap();
    assert!(
        info.contains(&format!(
            "matrix KGG: {ng} x {ng}, symmetric, RD (real, double precision)"
        )) && info.contains("(byte 0)")
            && info.contains(&format!(
                "use it as a model with {} free DOFs",
                labels.len()
            )),
        "{info}"
    );
    let info = femu_study::info::describe(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/nastran/pynastran/op4/mat_t_s2.op4"),
    )
    .unwrap();
    assert!(
        info.contains("matrix STRINGS: 30 x 20, rectangular, RS (real, single precision), 240 stored values (line 162)")
            && info.contains("not use it as a model"),
        "{info}"
    );
    // the a-set with its DOF table: the free rows as they are
    let aset = |name, a: &femu_sparse::SparseMatrix| Op4Out {
        name,
        rows: labels.len(),
        form: 6,
        columns: columns_of(labels.len(), femu_sparse::csc::entries(a)),
    };
    std::fs::write(
        d.join("aset.op4"),
        op4_binary(
            &[aset("KAA", &own.sys.k), aset("MAA", &own.sys.m)],
            Op4Layout::Dense,
            true,
        ),
    )
    .unwrap();
    let mut table = String::from("row,node,component\n");
    for (r, (node, c)) in labels.iter().enumerate() {
        table.push_str(&format!("{},{node},{}\n", r + 1, c + 1));
    }
    std::fs::write(d.join("aset_dofs.csv"), &table).unwrap();
    std::fs::write(d.join("aset.bdf"), &deck).unwrap();
    let (got, _) = lowest(&d.join("aset.op4"), 6);
    for (a, b) in got.iter().zip(&want) {
        assert!((a / b - 1.0).abs() < 1e-10, "aset: {got:?} vs {want:?}");
    }
    // refusals: an a-set without its table, a rigid element or a scalar point in the deck, a
    // complex matrix, no pair of names
    let bad = |name: &str, op4: &[u8], bdf: &str| {
        let _ = std::fs::remove_file(d.join(format!("{name}_dofs.csv")));
        std::fs::write(d.join(format!("{name}.op4")), op4).unwrap();
        std::fs::write(d.join(format!("{name}.bdf")), bdf).unwrap();
        load_model(&d.join(format!("{name}.op4")), &ModelOptions::default())
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let aset_bytes = std::fs::read(d.join("aset.op4")).unwrap();
    let e = bad("notable", &aset_bytes, &deck);
    assert!(
        e.contains("the g-set of the deck") && e.contains("notable_dofs.csv"),
        "{e}"
    );
    let gbytes = std::fs::read(d.join("bin.op4")).unwrap();
    let e = bad(
        "rbe",
        &gbytes,
        &deck.replace("ENDDATA", "RBE2,50,999,123456,16\nENDDATA"),
    );
    assert!(
        e.contains("rbe.bdf") && e.contains("RBE2: a multipoint constraint"),
        "{e}"
    );
    let e = bad(
        "spoint",
        &gbytes,
        &deck.replace("ENDDATA", "SPOINT,5000\nENDDATA"),
    );
    assert!(e.contains("scalar points"), "{e}");
    let e = bad(
        "names",
        &op4_binary(
            &[aset("A", &own.sys.k), aset("B", &own.sys.m)],
            Op4Layout::Sparse,
            true,
        ),
        &deck,
    );
    assert!(
        e.contains("no stiffness and mass pair") && e.contains("[\"A\", \"B\"]"),
        "{e}"
    );
    let complex = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/nastran/pynastran/op4/mat_b_s1.op4"),
    )
    .unwrap();
    let e = bad("complex", &complex, &deck);
    assert!(e.contains("no stiffness and mass pair"), "{e}");
    // the same file with its complex matrices named as a stiffness and a mass
    let renamed = String::from_utf8_lossy(&complex)
        .contains("RND1CD")
        .then(|| {
            let mut b = complex.clone();
            for (from, to) in [
                (&b"RND1CD  "[..], &b"KAA     "[..]),
                (b"RND1CS  ", b"MAA     "),
            ] {
                let at = b.windows(8).position(|w| w == from).unwrap();
                b[at..at + 8].copy_from_slice(to);
            }
            b
        })
        .unwrap();
    let e = bad("complex", &renamed, &deck);
    assert!(
        e.contains("matrix KAA (CD (complex, double precision)) is complex"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn nastran_dmig_punch_is_the_model() {
    let deck = clamped_plate_deck(4);
    let d = dir("dmig");
    std::fs::write(d.join("job.bdf"), &deck).unwrap();
    let (own, loaded) = lowest(&d.join("job.bdf"), 6);
    let sys = &loaded.sys;
    let mesh = loaded.model.mesh();
    let labels: Vec<(u64, usize)> = (0..sys.dofs.free_count())
        .map(|f| {
            let (p, c) = sys.dofs.free_dof(f);
            let (node, rotation) = sys.dofs.point_node(p);
            (mesh.node_id(node), c + 1 + if rotation { 3 } else { 0 })
        })
        .collect();
    let large = |fields: &[String]| -> String {
        // field 1 of 8 characters, then four of 16 per line, continued by `*`
        let mut s = String::new();
        for (k, chunk) in fields[1..].chunks(4).enumerate() {
            s.push_str(if k == 0 { &fields[0] } else { "*" });
            s.push_str(&" ".repeat(8 - if k == 0 { fields[0].len() } else { 1 }));
            for f in chunk {
                s.push_str(&format!("{f:>16}"));
            }
            s.push('\n');
        }
        s
    };
    let mut pch = large(&[
        "DMIG*".into(),
        "KAAX".into(),
        "0".into(),
        "6".into(),
        "2".into(),
    ]);
    let n_free = labels.len();
    for j in 0..n_free {
        let mut fields = vec![
            "DMIG*".to_string(),
            "KAAX".into(),
            labels[j].0.to_string(),
            labels[j].1.to_string(),
            String::new(),
        ];
        for (i, jj, v) in femu_sparse::csc::entries(&sys.k) {
            if jj == j && i >= j {
                fields.push(labels[i].0.to_string());
                fields.push(labels[i].1.to_string());
                fields.push(format!("{v:.9E}").replace('E', "D"));
                fields.push(String::new());
            }
        }
        pch.push_str(&large(&fields));
    }
    pch.push_str("DMIG,MAAX,0,1,2\n");
    for j in 0..n_free {
        // free-field cards: the first line's quad after `NAME GJ CJ -`, then two quads a line,
        // each line continued by `+` in field 10
        let quads: Vec<String> = femu_sparse::csc::entries(&sys.m)
            .filter(|e| e.1 == j)
            .map(|(i, _, v)| format!("{},{},{v:e},,", labels[i].0, labels[i].1))
            .collect();
        pch.push_str(&format!(
            "DMIG,MAAX,{},{},,{}+\n",
            labels[j].0, labels[j].1, quads[0]
        ));
        for pair in quads[1..].chunks(2) {
            pch.push_str(&format!(
                "+,{}{}+\n",
                pair[0],
                pair.get(1).map_or(",,,,", |q| q.as_str())
            ));
        }
    }
    std::fs::write(d.join("job.pch"), &pch).unwrap();
    // the entries as written: the stiffness to its ten digits, the mass exactly
    let ext = femu_io::matrices::read_matrices(&d.join("job.pch")).unwrap();
    let row: std::collections::HashMap<(u64, usize), usize> = ext
        .dofs
        .iter()
        .enumerate()
        .map(|(r, l)| ((l.node, l.component + 1), r))
        .collect();
    for (ours, theirs, tol) in [(&sys.k, &ext.k, 1e-10), (&sys.m, &ext.m, 0.0)] {
        assert_eq!(ours.nnz(), theirs.nnz());
        let scale = ours.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, j, v) in femu_sparse::csc::entries(ours) {
            let got = theirs
                .get(row[&labels[i]], row[&labels[j]])
                .copied()
                .unwrap();
            assert!((got - v).abs() <= tol * scale, "{got} {v}");
        }
    }
    let (back, from_pch) = lowest(&d.join("job.pch"), 6);
    assert_eq!(from_pch.sys.dofs.free_count(), n_free);
    for (b, o) in back.iter().zip(&own) {
        assert!((b / o - 1.0).abs() < 1e-5, "{back:?} {own:?}");
    }
    // refusals
    let bad = |text: &str| {
        std::fs::write(d.join("bad.pch"), text).unwrap();
        std::fs::write(d.join("bad.bdf"), &deck).unwrap();
        femu_study::load::load_model(&d.join("bad.pch"), &ModelOptions::default())
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let e = bad("DMIG,KAAX,0,6,3\n");
    assert!(e.contains("bad.pch:1") && e.contains("TIN = 3"), "{e}");
    let e = bad("DMIG,KAAX,0,6,2\nDMIG,KAAX,5,0,,5,0,1.0\n");
    assert!(e.contains("bad.pch:2") && e.contains("scalar point"), "{e}");
    std::fs::write(d.join("turned.pch"), &pch).unwrap();
    std::fs::write(
        d.join("turned.bdf"),
        deck.replace(
            "GRID,1,,",
            "CORD2R,3,,0.,0.,0.,0.,0.,1.,+C\n+C,0.,1.,0.\nGRID,1,,",
        )
        .replace(",0.32,0.\n", ",0.32,0.,3\n"),
    )
    .unwrap();
    let e = femu_study::load::load_model(&d.join("turned.pch"), &ModelOptions::default())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("turned.bdf") && e.contains("CD = 3"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A clamped square Kirchhoff plate built here by an FE of its own, independent of femu's
/// elements: non-conforming 12-DOF rectangles (Adini-Clough-Melosh: `w` a complete cubic plus
/// `x^3 y` and `x y^3`; `w`, `theta_x = dw/dy`, `theta_y = -dw/dx` at the corners), stiffness
/// `int B^T D B` and consistent mass `int rho t N^T N` by Gauss quadrature, written as
/// MatrixMarket with a DOF table (`z`, `rx`, `ry`). The plate's three lowest frequencies are
/// Leissa's for a square cantilever plate (`omega a^2 sqrt(rho t / D)` = 3.492, 8.525, 21.43,
/// nu = 0.3) within 2 %, so the FE is a plate. In four strips `R0`-`R3` along x, the "real" plate
/// has `R1`'s modulus 20 % lower; its six lowest modes at every free node's `w` are the test.
/// Updating the nominal plate's matrices over matrix groups (each the nominal export with its
/// strip's modulus doubled) recovers `R1` at -0.2 within 1e-6 and leaves the other strips
/// unchanged: femu updates a model of elements it does not have.
#[test]
fn updating_a_plate_of_another_fe_recovers_a_known_change() {
    use femu_sparse::faer::Mat;
    use femu_sparse::faer::linalg::solvers::DenseSolveCore;
    let d = dir("acm-plate");
    let (a, t, young, nu, rho) = (0.4, 0.004, 2.1e11, 0.3, 7850.0);
    let ne = 8;
    let h = a / ne as f64;
    // the polynomial basis and its derivatives at (x, y) in the element (origin at its corner)
    let basis = |x: f64, y: f64| -> [[f64; 12]; 6] {
        // rows: P, P_x, P_y, P_xx, P_yy, P_xy
        [
            [
                1.0,
                x,
                y,
                x * x,
                x * y,
                y * y,
                x * x * x,
                x * x * y,
                x * y * y,
                y * y * y,
                x * x * x * y,
                x * y * y * y,
            ],
            [
                0.0,
                1.0,
                0.0,
                2.0 * x,
                y,
                0.0,
                3.0 * x * x,
                2.0 * x * y,
                y * y,
                0.0,
                3.0 * x * x * y,
                y * y * y,
            ],
            [
                0.0,
                0.0,
                1.0,
                0.0,
                x,
                2.0 * y,
                0.0,
                x * x,
                2.0 * x * y,
                3.0 * y * y,
                x * x * x,
                3.0 * x * y * y,
            ],
            [
                0.0,
                0.0,
                0.0,
                2.0,
                0.0,
                0.0,
                6.0 * x,
                2.0 * y,
                0.0,
                0.0,
                6.0 * x * y,
                0.0,
            ],
            [
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                2.0,
                0.0,
                0.0,
                2.0 * x,
                6.0 * y,
                0.0,
                6.0 * x * y,
            ],
            [
                0.0,
                0.0,
                0.0,
                0.0,
                1.0,
                0.0,
                0.0,
                2.0 * x,
                2.0 * y,
                0.0,
                3.0 * x * x,
                3.0 * y * y,
            ],
        ]
    };
    let corners = [(0.0, 0.0), (h, 0.0), (h, h), (0.0, h)];
    // the coefficients of the shape functions: C^-1, C's rows the corner DOFs of each monomial
    let c = Mat::from_fn(12, 12, |r, j| {
        let (x, y) = corners[r / 3];
        let b = basis(x, y);
        match r % 3 {
            0 => b[0][j],
            1 => b[2][j],
            _ => -b[1][j],
        }
    });
    let c_inv = c.partial_piv_lu().inverse();
    // 4-point Gauss on [0, h]
    let g = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    ];
    let element = |e_mod: f64| -> (Mat<f64>, Mat<f64>) {
        let dd = e_mod * t * t * t / (12.0 * (1.0 - nu * nu));
        let dm = [
            [dd, nu * dd, 0.0],
            [nu * dd, dd, 0.0],
            [0.0, 0.0, 0.5 * (1.0 - nu) * dd],
        ];
        let (mut k, mut m) = (Mat::<f64>::zeros(12, 12), Mat::<f64>::zeros(12, 12));
        for (gx, wx) in g {
            for (gy, wy) in g {
                let (x, y) = (0.5 * h * (gx + 1.0), 0.5 * h * (gy + 1.0));
                let w = wx * wy * 0.25 * h * h;
                let b = basis(x, y);
                let row = |r: usize, s: f64| {
                    Mat::from_fn(1, 12, |_, j| {
                        s * (0..12).map(|i| b[r][i] * c_inv[(i, j)]).sum::<f64>()
                    })
                };
                let n = row(0, 1.0);
                // curvatures (-w_xx, -w_yy, -2 w_xy)
                let bm = [row(3, -1.0), row(4, -1.0), row(5, -2.0)];
                for p in 0..3 {
                    for q in 0..3 {
                        k += (w * dm[p][q]) * (bm[p].transpose() * &bm[q]);
                    }
                }
                m += (w * rho * t) * (n.transpose() * &n);
            }
        }
        (k, m)
    };
    let node = |i: usize, j: usize| 1 + i + (ne + 1) * j;
    // free DOFs: nodes with i > 0 (the edge x = 0 clamped), three each
    let row = |i: usize, j: usize, c: usize| -> Option<usize> {
        (i > 0).then(|| 3 * ((i - 1) + ne * j) + c)
    };
    let n = 3 * ne * (ne + 1);
    let assemble = |soft: Option<(usize, f64)>| -> (Mat<f64>, Mat<f64>) {
        let (mut kg, mut mg) = (Mat::<f64>::zeros(n, n), Mat::<f64>::zeros(n, n));
        for ej in 0..ne {
            for ei in 0..ne {
                let strip = ei / 2;
                let factor = soft.filter(|s| s.0 == strip).map_or(1.0, |s| s.1);
                let (ke, me) = element(young * factor);
                let at = [(ei, ej), (ei + 1, ej), (ei + 1, ej + 1), (ei, ej + 1)];
                let dofs: Vec<Option<usize>> = (0..12)
                    .map(|r| row(at[r / 3].0, at[r / 3].1, r % 3))
                    .collect();
                for p in 0..12 {
                    for q in 0..12 {
                        if let (Some(a), Some(b)) = (dofs[p], dofs[q]) {
                            kg[(a, b)] += ke[(p, q)];
                            mg[(a, b)] += me[(p, q)];
                        }
                    }
                }
            }
        }
        (kg, mg)
    };
    let write = |stem: &str, k: &Mat<f64>, m: &Mat<f64>| {
        for (name, a) in [("K", k), ("M", m)] {
            let mut entries = Vec::new();
            for j in 0..n {
                for i in j..n {
                    if a[(i, j)] != 0.0 {
                        entries.push(format!("{} {} {:.17e}", i + 1, j + 1, a[(i, j)]));
                    }
                }
            }
            std::fs::write(
                d.join(format!("{stem}_{name}.mtx")),
                format!(
                    "%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {}\n{}\n",
                    entries.len(),
                    entries.join("\n")
                ),
            )
            .unwrap();
        }
        let mut dofs = String::from("row,node,component\n");
        let mut nodes = String::from("node,x,y,z\n");
        for j in 0..=ne {
            for i in 0..=ne {
                nodes.push_str(&format!(
                    "{},{},{},0\n",
                    node(i, j),
                    h * i as f64,
                    h * j as f64
                ));
                for (c, name) in ["z", "rx", "ry"].iter().enumerate() {
                    if let Some(r) = row(i, j, c) {
                        dofs.push_str(&format!("{},{},{name}\n", r + 1, node(i, j)));
                    }
                }
            }
        }
        std::fs::write(d.join(format!("{stem}_dofs.csv")), dofs).unwrap();
        std::fs::write(d.join(format!("{stem}_nodes.csv")), nodes).unwrap();
    };
    // the FE is a plate: Leissa's square cantilever
    let (k0, m0) = assemble(None);
    let nominal =
        femu_sparse::dense::generalized_symmetric_eigen(k0.as_ref(), m0.as_ref()).unwrap();
    let scale = a * a * (rho * t * 12.0 * (1.0 - nu * nu) / (young * t * t * t)).sqrt();
    for (r, leissa) in [3.492, 8.525, 21.43].iter().enumerate() {
        let lambda = nominal.values[r].sqrt() * scale;
        // measured on 8 x 8 elements: 3.471, 8.510, 21.36 (0.6 %, 0.2 %, 0.3 % below)
        assert!(
            (lambda / leissa - 1.0).abs() < 0.02,
            "mode {}: {lambda} vs {leissa}",
            r + 1
        );
    }
    // the test: the real plate (R1 20 % softer) at every free node's w
    let (kr, mr) = assemble(Some((1, 0.8)));
    let real = femu_sparse::dense::generalized_symmetric_eigen(kr.as_ref(), mr.as_ref()).unwrap();
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    for mode in 0..6 {
        let f = real.values[mode].sqrt() / (2.0 * std::f64::consts::PI);
        for j in 0..=ne {
            for i in 1..=ne {
                let v = real.vectors[(row(i, j, 0).unwrap(), mode)];
                csv.push_str(&format!(
                    "{},{f:.15e},{},z,{v:.15e}\n",
                    mode + 1,
                    node(i, j)
                ));
            }
        }
    }
    std::fs::write(d.join("test.csv"), csv).unwrap();
    // the nominal plate and each strip's modulus doubled, as matrices
    write("plate", &k0, &m0);
    let mut sets = Vec::new();
    for s in 0..4 {
        let (ks, _) = assemble(Some((s, 2.0)));
        write(&format!("plate_R{s}"), &ks, &m0);
        sets.push(format!("R{s}=plate_R{s}_K.mtx"));
    }
    let run = update(&d.join("plate_K.mtx"), &d.join("test.csv"), &sets);
    let theta = |name: &str| {
        run.result
            .names
            .iter()
            .position(|n| n.contains(name))
            .map(|i| run.result.theta[i])
    };
    let r1 = theta("R1").expect("R1 selected");
    // measured: R1 alone selected, -0.19999999998
    assert!(
        (r1 + 0.2).abs() < 1e-6,
        "R1: {r1} ({:?} {:?})",
        run.result.names,
        run.result.theta
    );
    for s in ["R0", "R2", "R3"] {
        if let Some(v) = theta(s) {
            assert!(v.abs() < 1e-6, "{s}: {v}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// CalculiX's printed modes (`*NODE PRINT` with `U` in the `*FREQUENCY` step: its `.dat`, seven
/// digits per value) as the model side, with the nodes of the deck beside it: the same run's
/// `.frd` (another file, another reader) gives the same frequencies to 1e-6 and shapes with MAC
/// above 1 - 1e-9, and femu's own modes of the deck, as the test, pair one to one with MAC above
/// 1 - 1e-9 and frequencies within 1e-6. A Nastran deck named `.dat` is still bulk data; a study
/// file of the `.dat` correlates the same.
#[test]
fn calculix_printed_modes_are_the_model_side() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let d = dir("dat");
    solved_cantilever(&d, "*NODE PRINT, NSET=NALL\nU\n*NODE FILE\nU\n");
    assert_eq!(
        femu_io::Format::from_path(&d.join("job.dat")),
        Some(femu_io::Format::Results)
    );
    let dat = femu_study::external::load_result_modes(&d.join("job.dat"), None).unwrap();
    let frd = femu_study::external::load_result_modes(&d.join("job.frd"), None).unwrap();
    assert_eq!(dat.modes.len(), 6);
    let (fd, ff) = (dat.modes.frequencies_hz(), frd.modes.frequencies_hz());
    let ids = |r: &femu_study::external::ResultModes| -> Vec<u64> {
        let m = r.model.mesh();
        (0..m.node_count()).map(|i| m.node_id(i)).collect()
    };
    let (dat_ids, frd_ids) = (ids(&dat), ids(&frd));
    for j in 0..6 {
        assert!((fd[j] / ff[j] - 1.0).abs() < 1e-6, "{fd:?} {ff:?}");
        // the .frd's shape at the .dat's nodes
        let a: Vec<f64> = (0..3 * dat_ids.len())
            .map(|r| dat.modes.shapes[(r, j)])
            .collect();
        let b: Vec<f64> = dat_ids
            .iter()
            .flat_map(|id| {
                let k = frd_ids.iter().position(|x| x == id).unwrap();
                (0..3).map(move |c| (k, c))
            })
            .map(|(k, c)| frd.modes.shapes[(3 * k + c, j)])
            .collect();
        let mac = femu_correlate::correlation::mac(&a, &b).unwrap();
        // measured: frequencies within 2.1e-7 (the .dat's seven digits), MAC 1 - 1.3e-12 at worst
        assert!(mac > 1.0 - 1e-9, "mode {}: {mac}", j + 1);
    }
    // femu's own modes of the deck as the test, at the free end in y and z
    femu_test_at_the_tip(&d);
    let report = correlate_on(&dat, &d.join("test.csv"));
    assert_eq!(report.pairing.pairs.len(), 6);
    for p in &report.pairing.pairs {
        assert_eq!(p.test, p.model);
        assert!(p.mac.unwrap() > 1.0 - 1e-9, "{p:?}");
        assert!(p.frequency_error.abs() < 1e-6, "{p:?}");
    }
    std::fs::write(
        d.join("study.toml"),
        "model = \"job.dat\"\ntest = \"test.csv\"\n",
    )
    .unwrap();
    let run = femu_study::study_file::run_study_file(&d.join("study.toml"), &d.join("out"), |_| {})
        .unwrap();
    assert_eq!(run.correlation, report);
    // a Nastran deck named .dat stays bulk data
    std::fs::write(d.join("deck.dat"), "SOL 103\nCEND\nBEGIN BULK\nENDDATA\n").unwrap();
    assert_eq!(
        femu_io::Format::from_path(&d.join("deck.dat")),
        Some(femu_io::Format::Nastran)
    );
    let _ = std::fs::remove_dir_all(&d);
}
