//! The `femu` command end to end: happy paths against the library's dense reference, bad input.

use assert_cmd::Command;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/inp")
        .join(name)
}

fn femu() -> Command {
    Command::cargo_bin("femu").unwrap()
}

/// The two-hex fixture's model and its assembled matrices (consistent mass).
fn two_hex_system() -> (femu_fem::model::Model, femu_fem::assembly::SystemMatrices) {
    let model = femu_io::inp::read_inp(fixture("two_hex.inp"))
        .unwrap()
        .to_model()
        .unwrap();
    let sys = model
        .assemble(femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    (model, sys)
}

/// The two-hex fixture's lowest `count` modes and triaxial sensors on its free nodes 3, 6, 9, 12.
fn two_hex_case(
    count: usize,
) -> (
    femu_sparse::eigen::Modes,
    Vec<femu_correlate::Sensor>,
    femu_correlate::SensorLayout,
) {
    use femu_correlate::{Sensor, SensorLayout};
    let (model, sys) = two_hex_system();
    let modes = femu_sparse::eigen::eigs(
        &sys.k,
        &sys.m,
        femu_sparse::eigen::Which::Lowest(count),
        &Default::default(),
    )
    .unwrap();
    let sensors: Vec<Sensor> = [3u64, 6, 9, 12]
        .iter()
        .flat_map(|n| (0..3).map(move |c| Sensor::axis(*n, c)))
        .collect();
    let layout = SensorLayout::new(model.mesh(), &sys.dofs, sensors.clone()).unwrap();
    (modes, sensors, layout)
}

/// `femu modes` on the hand-made deck: the JSON frequencies equal a dense solution of the same
/// model, the Sturm check passes, the table lists the modes.
#[test]
fn modes_json_matches_dense_reference() {
    let dir = std::env::temp_dir().join(format!("femu-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("modes.json");
    let vtu = dir.join("modes.vtu");
    let deck = fixture("two_hex.inp");
    let stdout = stdout_of_success(&[
        "modes",
        deck.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--vtu",
        vtu.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("| 4 |") && stdout.contains("verified"),
        "{stdout}"
    );
    let v = json_of(&json);
    assert_eq!(v["dofs"], 24);
    // the load's phases: each a duration (their values are the machine's, not checked here)
    for phase in [
        "read_seconds",
        "checks_seconds",
        "pattern_seconds",
        "assembly_seconds",
    ] {
        let t = v["load"][phase].as_f64().unwrap();
        assert!(t.is_finite() && t >= 0.0, "{phase}: {t}");
    }
    assert!(stdout.contains("Model: read "), "{stdout}");
    let vtu_text = std::fs::read_to_string(&vtu).unwrap();
    assert_eq!(vtu_text.matches("Name=\"model mode ").count(), 4);
    assert!(vtu_text.contains("NumberOfPoints=\"12\" NumberOfCells=\"2\""));
    assert_eq!(v["sturm_verified"], true);
    let f: Vec<f64> = v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(f.len(), 4); // the deck's *FREQUENCY count
    // dense reference through the libraries
    let (_, sys) = two_hex_system();
    let eig = femu_sparse::dense::generalized_symmetric_eigen(
        femu_sparse::csc::to_dense(&sys.k).as_ref(),
        femu_sparse::csc::to_dense(&sys.m).as_ref(),
    )
    .unwrap();
    for (j, fj) in f.iter().enumerate() {
        let reference = eig.values[j].sqrt() / (2.0 * std::f64::consts::PI);
        assert!(
            (fj / reference - 1.0).abs() < 1e-10,
            "mode {j}: {fj} vs {reference}"
        );
    }
    for key in ["eigenvalues", "residuals"] {
        assert_eq!(v[key].as_array().unwrap().len(), 4);
    }
    // where the eigensolve's time went: two factorizations (the run's and the Sturm count's),
    // the vectors solved, phases that add up to the whole
    let e = &v["eigensolver"];
    assert_eq!(e["block_size"], 4);
    assert_eq!(e["factorizations"], 2, "{e}");
    assert!(e["solved_vectors"].as_u64().unwrap() >= 4, "{e}");
    let secs = |k: &str| e[k].as_f64().unwrap();
    let phases: f64 = [
        "check_seconds",
        "symbolic_seconds",
        "factor_seconds",
        "solve_seconds",
        "orthogonalization_seconds",
        "ritz_seconds",
        "other_seconds",
    ]
    .iter()
    .map(|k| secs(k))
    .sum();
    assert!((phases - secs("total_seconds")).abs() < 1e-9, "{e}");
    // no two phases' clocks overlap
    assert!(secs("other_seconds") >= 0.0, "{e}");
    assert!(stdout.contains("Eigensolver: 2 factorizations"), "{stdout}");
    // other block sizes, the narrowest and the widest (wider than the 24-DOF model's basis):
    // the same modes, to the dense reference
    for block in ["1", "64"] {
        let stdout = stdout_of_success(&[
            "modes",
            deck.to_str().unwrap(),
            "--block-size",
            block,
            "--json",
            json.to_str().unwrap(),
        ]);
        assert!(
            stdout.contains(&format!("in blocks of {block} ")),
            "{stdout}"
        );
        let v = json_of(&json);
        assert_eq!(v["eigensolver"]["block_size"].to_string(), block);
        for (j, fj) in v["frequencies_hz"].as_array().unwrap().iter().enumerate() {
            let reference = eig.values[j].sqrt() / (2.0 * std::f64::consts::PI);
            let fj = fj.as_f64().unwrap();
            assert!(
                (fj / reference - 1.0).abs() < 1e-10,
                "block {block}, mode {j}: {fj} vs {reference}"
            );
        }
    }
    // a band from just above the first mode to just above the fourth, quiet: nothing on stdout;
    // the count of modes in it comes from the dense reference
    let lo = f[0] * 1.001;
    let hi = f[3] * 1.001;
    let hz: Vec<f64> = eig
        .values
        .iter()
        .map(|l| l.sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let expected = hz.iter().filter(|x| **x >= lo && **x <= hi).count();
    assert!(expected >= 2);
    let stdout = stdout_of_success(&[
        "--quiet",
        "modes",
        deck.to_str().unwrap(),
        "--band",
        &lo.to_string(),
        &hi.to_string(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(stdout.is_empty(), "{stdout}");
    let v = json_of(&json);
    assert_eq!(v["frequencies_hz"].as_array().unwrap().len(), expected);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_fails_with_a_message() {
    // missing file: names it
    let err = stderr_of_failure(&["modes", "/nonexistent/model.inp"]);
    assert!(err.contains("/nonexistent/model.inp"), "{err}");
    // a malformed deck: names the line
    let dir = std::env::temp_dir().join(format!("femu-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.inp");
    std::fs::write(&bad, "*NODE\n1, 0, zero, 0\n").unwrap();
    let err = stderr_of_failure(&["modes", bad.to_str().unwrap()]);
    assert!(
        err.contains("bad.inp:2:") && err.starts_with("error:"),
        "{err}"
    );
    // bad options
    let deck = fixture("two_hex.inp");
    femu()
        .args(["modes", deck.to_str().unwrap(), "--count", "0"])
        .assert()
        .failure();
    femu()
        .args(["modes", deck.to_str().unwrap(), "--band", "300", "100"])
        .assert()
        .failure();
    femu()
        .args(["modes", deck.to_str().unwrap(), "--shift", "-5"])
        .assert()
        .failure();
    for (block, says) in [("0", "block size 0"), ("65", "between 1 and 64")] {
        let err = stderr_of_failure(&["modes", deck.to_str().unwrap(), "--block-size", block]);
        assert!(err.contains(says), "{block}: {err}");
    }
    femu()
        .args(["modes", deck.to_str().unwrap(), "--block-size", "-1"])
        .assert()
        .failure()
        .code(2);
    femu()
        .args([
            "modes",
            deck.to_str().unwrap(),
            "--shift",
            "5",
            "--band",
            "1",
            "2",
        ])
        .assert()
        .failure()
        .code(2);
    femu().args(["frobnicate"]).assert().failure().code(2);
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `femu args`, expects exit code 1, returns stderr.
fn stderr_of_failure(args: &[&str]) -> String {
    let out = femu().args(args).assert().failure().code(1);
    String::from_utf8_lossy(&out.get_output().stderr).into_owned()
}

/// What `femu args` printed on stdout, asserting that it succeeded.
fn stdout_of_success(args: &[&str]) -> String {
    let out = femu().args(args).assert().success();
    String::from_utf8(out.get_output().stdout.clone()).unwrap()
}

/// A JSON file a command wrote.
/// Asserts that a command succeeded, showing its standard error when it did not.
fn succeeded(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn json_of(path: impl AsRef<std::path::Path>) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `femu correlate`: a CSV "test" made of the model's own modes 1-3 (listed 2, 1, 3, frequencies
/// 1 % low) measured at the free end pairs back onto them with MAC 1 and the error +1/0.99 - 1
/// (the test's frequency is 1 % below the model's), the repeated pair 1-2 included.
#[test]
fn correlate_pairs_the_model_with_itself() {
    use femu_correlate::TestModes;
    let deck = fixture("two_hex.inp");
    let (modes, sensors, layout) = two_hex_case(4);
    let at = layout.measure_all(modes.vectors.as_ref()).unwrap();
    let order = [1usize, 0, 2];
    let f = modes.frequencies_hz();
    let shapes = femu_sparse::faer::Mat::from_fn(at.nrows(), 3, |i, j| at[(i, order[j])]);
    let test = TestModes::new(order.iter().map(|j| 0.99 * f[*j]).collect(), None, shapes).unwrap();
    let dir = std::env::temp_dir().join(format!("femu-cli-corr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("test.csv");
    std::fs::write(&csv, femu_io::csv::test_csv_string(&sensors, &test)).unwrap();
    let json = dir.join("corr.json");
    let stdout = stdout_of_success(&[
        "correlate",
        deck.to_str().unwrap(),
        csv.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(stdout.contains("| test | f test (Hz)"), "{stdout}");
    let v = json_of(&json);
    let pairs = v["pairing"]["pairs"].as_array().unwrap();
    // modes 1 and 2 are a repeated pair (square section): the model's basis of the pair's plane
    // is the eigensolver's, decided by round-off; correlation turns it towards the test
    // (align_repeated), so each test mode pairs back with MAC 1 whatever that basis was
    assert_eq!(pairs.len(), 3, "{stdout}");
    for p in pairs {
        let (t, m) = (p["test"].as_u64().unwrap(), p["model"].as_u64().unwrap());
        assert!(if t < 2 { m < 2 } else { m == 2 }, "{p}");
        assert!((p["mac"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{p}");
        let e = p["frequency_error"].as_f64().unwrap();
        assert!((e - (1.0 / 0.99 - 1.0)).abs() < 1e-9, "{p}");
    }
    // estimate: every theorem-labelled bound holds, each interval holds a model frequency
    let json = dir.join("est.json");
    femu()
        .args([
            "estimate",
            deck.to_str().unwrap(),
            csv.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ])
        .assert()
        .success();
    let v = json_of(&json);
    let list = v.as_array().unwrap();
    assert_eq!(list.len(), 3);
    for a in list {
        let lo = a["frequency_interval_hz"][0].as_f64().unwrap();
        let hi = a["frequency_interval_hz"][1].as_f64().unwrap();
        assert!(f.iter().any(|x| *x >= lo && *x <= hi), "{a}");
        for b in a["bounds"].as_array().unwrap() {
            if b["theorem"] == true && !b["quantity"].is_null() {
                let (q, bd) = (
                    b["quantity"].as_f64().unwrap(),
                    b["bound"].as_f64().unwrap(),
                );
                let ok = if b["relation"] == "AtMost" {
                    q <= bd * (1.0 + 1e-9) + 1e-12
                } else {
                    q >= bd * (1.0 - 1e-9) - 1e-12
                };
                assert!(ok, "{b}");
            }
        }
    }
    // an unknown method is a usage error of the argument parser (exit 2, as for every other
    // invalid option value), listing the methods
    let out = femu()
        .args([
            "estimate",
            deck.to_str().unwrap(),
            csv.to_str().unwrap(),
            "--expansion",
            "guess",
        ])
        .assert()
        .failure()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
    assert!(err.contains("guess"), "{err}");
    // a sensor on a missing node is an error naming the file and the node
    std::fs::write(
        &csv,
        "mode,frequency_hz,node,direction,value\n1,100,999,z,1\n",
    )
    .unwrap();
    let err = stderr_of_failure(&["correlate", deck.to_str().unwrap(), csv.to_str().unwrap()]);
    assert!(err.contains("test.csv") && err.contains("999"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `femu demo --quick` writes the report, and `femu update` on the files it wrote (the plate as
/// `.inp`, the test as `.unv`) selects region r3 and recovers its +30 % from noise-free data.
#[test]
fn demo_then_update_from_its_files() {
    let dir = std::env::temp_dir().join(format!("femu-cli-demo-{}", std::process::id()));
    let stdout = stdout_of_success(&[
        "demo",
        "--quick",
        "--shape-noise",
        "0",
        "--frequency-noise",
        "0",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("Does the updated model tell the truth? yes"),
        "{stdout}"
    );
    for f in [
        "report.md",
        "report.json",
        "figure1.svg",
        "error_map.svg",
        "plate.vtu",
        "plate.inp",
        "test.unv",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let json = dir.join("update.json");
    femu()
        .args([
            "update",
            dir.join("plate.inp").to_str().unwrap(),
            dir.join("test.unv").to_str().unwrap(),
            "--sets",
            "r0,r1,r2,r3,r4,r5,r6,r7,r8,r9",
            "--tuned",
            "4",
            "--json",
            json.to_str().unwrap(),
            "--quiet",
        ])
        .assert()
        .success();
    let v = json_of(&json);
    assert_eq!(v["result"]["names"][0], "k:R3");
    let p = v["result"]["theta"][0].as_f64().unwrap();
    // the default (inverse eigensensitivity on frequencies and shapes) fits the UFF's
    // frequencies, stored to six digits (1631.76 Hz): a 3e-6 relative rounding of an eigenvalue
    // whose sensitivity to k:R3 is about 0.07 moves the minimum by up to 1e-4 (measured 2.6e-5)
    assert!((p - 0.3).abs() < 1e-4, "{p}");
    // bad input: an unknown set, an unknown method, noise out of range
    let bad = femu()
        .args([
            "update",
            dir.join("plate.inp").to_str().unwrap(),
            dir.join("test.unv").to_str().unwrap(),
            "--sets",
            "nope",
        ])
        .assert()
        .failure();
    let stderr = String::from_utf8(bad.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("no element set nope"), "{stderr}");
    femu()
        .args([
            "update",
            dir.join("plate.inp").to_str().unwrap(),
            dir.join("test.unv").to_str().unwrap(),
            "--sets",
            "r1",
            "--method",
            "magic",
        ])
        .assert()
        .failure();
    femu()
        .args(["demo", "--shape-noise", "2", "--out", dir.to_str().unwrap()])
        .assert()
        .failure();
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu modes MESH` with steel from the command line, `extra` arguments and `--json`: the JSON.
fn steel_modes(
    mesh: &std::path::Path,
    extra: &[&str],
    json: &std::path::Path,
) -> serde_json::Value {
    let mut args = vec![
        "modes",
        mesh.to_str().unwrap(),
        "--young",
        "2.1e11",
        "--poisson",
        "0.3",
        "--density",
        "7850",
    ];
    args.extend(extra);
    args.extend(["--json", json.to_str().unwrap(), "--quiet"]);
    femu().args(&args).assert().success();
    json_of(json)
}

/// `femu modes` on a Gmsh mesh with the material and clamp from the command line: the JSON
/// frequencies equal a dense solution of the same model built through the library; the mesh
/// material's `--structural-damping` damps every element, and needs the material.
#[test]
fn modes_of_a_gmsh_mesh() {
    let msh =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/msh/hex20_cube_v41.msh");
    let dir = std::env::temp_dir().join(format!("femu-cli-msh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("modes.json");
    let v = steel_modes(&msh, &["--fix", "bottom", "--count", "3"], &json);
    let g = femu_io::gmsh::read_msh(&msh).unwrap();
    let mut model = femu_fem::model::Model::new(g.mesh).unwrap();
    model
        .set_material(
            None,
            femu_fem::material::Material::isotropic("s", 2.1e11, 0.3, 7850.0).unwrap(),
        )
        .unwrap();
    model.fix_set("bottom", &[0, 1, 2]).unwrap();
    let sys = model
        .assemble(femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    let k = femu_sparse::csc::to_dense(&sys.k);
    let m = femu_sparse::csc::to_dense(&sys.m);
    let dense = femu_sparse::dense::generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap();
    let f = v["frequencies_hz"].as_array().unwrap();
    assert!(f.len() >= 3);
    for (j, fj) in f.iter().take(3).enumerate() {
        let fd = dense.values[j].sqrt() / (2.0 * std::f64::consts::PI);
        assert!((fj.as_f64().unwrap() / fd - 1.0).abs() < 1e-9, "mode {j}");
    }
    let out = femu()
        .args(["modes", msh.to_str().unwrap()])
        .assert()
        .failure();
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("--young"), "{stderr}");
    // the mesh material's structural damping reaches every element (the command line's options
    // are the library's), and needs the material
    steel_modes(
        &msh,
        &["--fix", "bottom", "--structural-damping", "0.03"],
        &json,
    );
    let loaded = femu::study::load::load_model(
        &msh,
        &femu::study::load::ModelOptions {
            material: Some(femu::study::load::MaterialOptions {
                young: 2.1e11,
                poisson: 0.3,
                density: 7850.0,
                structural_damping: 0.03,
            }),
            fix: vec!["bottom".into()],
            ..Default::default()
        },
    )
    .unwrap();
    let damped = loaded.model.element_damping();
    assert_eq!(damped.len(), model.mesh().element_count());
    assert!(damped.values().all(|g| *g == 0.03));
    let out = femu()
        .args([
            "modes",
            msh.to_str().unwrap(),
            "--structural-damping",
            "0.03",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--young, --poisson and --density"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu expand`: an exact model mode, measured at the free nodes of the fixture and expanded at its
/// own frequency, comes back exact (rho_M = 0 to round-off); the study and VTK files are written.
#[test]
fn expand_recovers_a_model_mode() {
    use femu_correlate::TestModes;
    let deck = fixture("two_hex.inp");
    let (modes, sensors, layout) = two_hex_case(3);
    let at = layout
        .measure_all(modes.vectors.as_ref().subcols(2, 1))
        .unwrap();
    let test = TestModes::new(vec![modes.frequencies_hz()[2]], None, at).unwrap();
    let dir = std::env::temp_dir().join(format!("femu-cli-expand-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("test.csv");
    std::fs::write(&csv, femu_io::csv::test_csv_string(&sensors, &test)).unwrap();
    let (json, vtu, study) = (dir.join("e.json"), dir.join("e.vtu"), dir.join("study"));
    femu()
        .args([
            "expand",
            deck.to_str().unwrap(),
            csv.to_str().unwrap(),
            "--method",
            "dynamic",
            "--json",
            json.to_str().unwrap(),
            "--vtu",
            vtu.to_str().unwrap(),
            "--study",
            study.to_str().unwrap(),
            "--quiet",
        ])
        .assert()
        .success();
    let v = json_of(&json);
    let rho = v["rho_m"][0].as_f64().unwrap();
    assert!(rho < 1e-6 * modes.values[2], "{rho}");
    assert!(vtu.exists() && study.join("study.csv").exists() && study.join("study.svg").exists());
    let png = std::fs::read(study.join("study.png")).unwrap();
    assert_eq!(&png[..4], b"\x89PNG");
    assert!(!v["study"].as_array().unwrap().is_empty());
    // SEREP on the lowest three modes, which hold the measured one: exact too (serep:M was
    // refused by the command line, and a study file's serep:M failed for want of a basis)
    femu()
        .args([
            "expand",
            deck.to_str().unwrap(),
            csv.to_str().unwrap(),
            "--method",
            "serep:3",
            "--json",
            json.to_str().unwrap(),
            "--quiet",
        ])
        .assert()
        .success();
    let rho = json_of(&json)["rho_m"][0].as_f64().unwrap();
    assert!(rho < 1e-6 * modes.values[2], "serep: {rho}");
    // a usage error (exit 2) that lists the methods
    let out = femu()
        .args([
            "expand",
            deck.to_str().unwrap(),
            csv.to_str().unwrap(),
            "--method",
            "guess",
        ])
        .assert()
        .failure()
        .code(2);
    let e = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
    assert!(
        e.contains("expected static, dynamic, serep:M (M >= 1 model modes), min-residual or mdre"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu run`: a study file with correlation, estimation and expansion (with the sensor-removal
/// study) writes every result; an unknown key is an error naming its line.
#[test]
fn run_a_study_file() {
    use femu_correlate::TestModes;
    let deck = fixture("two_hex.inp");
    let (modes, sensors, layout) = two_hex_case(3);
    let at = layout
        .measure_all(modes.vectors.as_ref().subcols(2, 1))
        .unwrap();
    let test = TestModes::new(vec![1.01 * modes.frequencies_hz()[2]], None, at).unwrap();
    let dir = std::env::temp_dir().join(format!("femu-cli-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("test.csv"),
        femu_io::csv::test_csv_string(&sensors, &test),
    )
    .unwrap();
    std::fs::copy(&deck, dir.join("model.inp")).unwrap();
    std::fs::copy(fixture("two_hex_nodes.inp"), dir.join("two_hex_nodes.inp")).unwrap();
    let toml = "model = \"model.inp\"\ntest = \"test.csv\"\n[pairing]\nmac_threshold = 0.7\n[expansion]\nmethod = \"static\"\nstudy = true\n";
    std::fs::write(dir.join("study.toml"), toml).unwrap();
    let out = dir.join("out");
    femu()
        .args([
            "run",
            dir.join("study.toml").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .assert()
        .success();
    for f in [
        "correlation.json",
        "estimate.json",
        "expansion.json",
        "expanded.vtu",
        "figure1/study.svg",
        "report.md",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let v = json_of(out.join("correlation.json"));
    assert_eq!(v["pairing"]["pairs"].as_array().unwrap().len(), 1);
    // one report of every step
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for section in ["# correlation", "# estimators", "# expansion (static)"] {
        assert!(report.contains(section), "{section}\n{report}");
    }
    std::fs::write(
        dir.join("bad.toml"),
        "model = \"model.inp\"\ntest = \"test.csv\"\nmodell = 1\n",
    )
    .unwrap();
    let bad = femu()
        .args(["run", dir.join("bad.toml").to_str().unwrap()])
        .assert()
        .failure();
    let stderr = String::from_utf8(bad.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("bad.toml:3"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu matrices`: the MatrixMarket files read back (by femu-sparse's reader) equal the assembled
/// matrices entry by entry, and the DOF map names every free DOF.
#[test]
fn matrices_export_round_trips() {
    let deck = fixture("two_hex.inp");
    let dir = std::env::temp_dir().join(format!("femu-cli-mtx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prefix = dir.join("m");
    femu()
        .args([
            "matrices",
            deck.to_str().unwrap(),
            "--out",
            prefix.to_str().unwrap(),
            "--quiet",
        ])
        .assert()
        .success();
    let (_, sys) = two_hex_system();
    let k = femu_sparse::mtx::read_matrix_market(dir.join("m_K.mtx")).unwrap();
    let m = femu_sparse::mtx::read_matrix_market(dir.join("m_M.mtx")).unwrap();
    let (kd, ke) = (
        femu_sparse::csc::to_dense(&k),
        femu_sparse::csc::to_dense(&sys.k),
    );
    let (md, me) = (
        femu_sparse::csc::to_dense(&m),
        femu_sparse::csc::to_dense(&sys.m),
    );
    for i in 0..ke.nrows() {
        for j in 0..ke.ncols() {
            assert!(
                (kd[(i, j)] - ke[(i, j)]).abs() <= 1e-15 * ke[(i, i)].abs().max(ke[(j, j)].abs())
            );
            assert!(
                (md[(i, j)] - me[(i, j)]).abs() <= 1e-15 * me[(i, i)].abs().max(me[(j, j)].abs())
            );
        }
    }
    let dofs = std::fs::read_to_string(dir.join("m_dofs.csv")).unwrap();
    assert_eq!(dofs.lines().count(), sys.dofs.free_count() + 1);
    // the set is a model: the same modes from the files as from the deck
    let lines = |model: &std::path::Path| {
        let out = femu()
            .args(["modes", model.to_str().unwrap(), "--count", "4"])
            .output()
            .unwrap();
        succeeded(&out);
        String::from_utf8(out.stdout).unwrap()
    };
    let (from_files, from_deck) = (lines(&dir.join("m_K.mtx")), lines(&deck));
    assert!(
        from_files.contains("Matrices: MatrixMarket matrices with a DOF table"),
        "{from_files}"
    );
    let table = |s: &str| -> Vec<String> {
        s.lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| mode"))
            .map(|l| l.split('|').nth(2).unwrap().trim().to_string())
            .collect()
    };
    assert_eq!(table(&from_files), table(&from_deck));
    assert_eq!(table(&from_files).len(), 4);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu modes` on the same second-order mesh as a binary `.msh` and as a universal file
/// (datasets 2411/2412 with parabolic solids, 2477 groups), both written by Gmsh and clamped on
/// the group "xmin" of each: the same frequencies; an unknown set is an error naming it.
#[test]
fn modes_of_binary_msh_and_unv_agree() {
    let fixtures = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/msh");
    let dir = std::env::temp_dir().join(format!("femu-cli-unv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut freqs = Vec::new();
    for name in ["box_mixed2_binary.msh", "box_mixed2.unv"] {
        let json = dir.join(format!("{name}.json"));
        let v = steel_modes(
            &fixtures.join(name),
            &["--fix", "xmin", "--count", "6"],
            &json,
        );
        assert_eq!(v["sturm_verified"], serde_json::Value::Bool(true));
        let f: Vec<f64> = v["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        freqs.push(f);
    }
    assert_eq!(freqs[0].len(), freqs[1].len());
    let top = freqs[0].iter().copied().fold(0.0, f64::max);
    // clamped at x = 0 (the group "xmin" of both files): no rigid-body mode
    assert!(freqs[0][0] > 100.0, "{:?}", freqs[0]);
    for (a, b) in freqs[0].iter().zip(&freqs[1]) {
        assert!((a - b).abs() <= 1e-9 * top, "{a} {b}");
    }
    let out = femu()
        .args([
            "modes",
            fixtures.join("box_mixed2.unv").to_str().unwrap(),
            "--young",
            "2.1e11",
            "--poisson",
            "0.3",
            "--density",
            "7850",
            "--fix",
            "nope",
        ])
        .assert()
        .failure();
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("nope"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A flag a command cannot use is refused by name, before anything runs: the model, test and
/// eigensolver arguments belong to the commands that read a model, a test or solve (a study file
/// has its own model, material and engine; `info` solves nothing; `matrices` reads no test).
#[test]
fn flags_a_command_cannot_use_are_refused_by_name() {
    let deck = fixture("two_hex.inp");
    let deck = deck.to_str().unwrap();
    for (args, flag) in [
        (vec!["run", "study.toml", "--young", "1"], "--young"),
        (vec!["run", "study.toml", "--engine", "slepc"], "--engine"),
        (vec!["run", "study.toml", "--map", "nearest"], "--map"),
        (vec!["demo", "--quick", "--fix", "bottom"], "--fix"),
        (vec!["info", deck, "--lenient"], "--lenient"),
        (vec!["info", deck, "--np", "2"], "--np"),
        (
            vec!["matrices", deck, "--out", "k", "--map", "nearest"],
            "--map",
        ),
        (vec!["modes", deck, "--test-units", "mm"], "--test-units"),
    ] {
        // clap's usage error: exit 2, the flag named, nothing run
        let out = femu().args(&args).assert().failure().code(2);
        let stderr = String::from_utf8_lossy(&out.get_output().stderr);
        assert!(
            stderr.contains(&format!("unexpected argument '{flag}'")),
            "{args:?}: {stderr}"
        );
    }
    // typed values: an unknown engine, mapping or unit names the accepted ones
    for (args, accepted) in [
        (
            vec!["modes", deck, "--engine", "arpack"],
            "[possible values: femu, slepc]",
        ),
        (
            vec!["correlate", deck, "t.csv", "--map", "closest"],
            "[possible values: nearest, interpolate]",
        ),
        (
            vec!["estimate", deck, "t.csv", "--test-units", "yd"],
            "[possible values: m, cm, mm, in, ft]",
        ),
    ] {
        let out = femu().args(&args).assert().failure().code(2);
        let stderr = String::from_utf8_lossy(&out.get_output().stderr);
        assert!(stderr.contains(accepted), "{args:?}: {stderr}");
    }
    // the engine's settings that femu's own engine would ignore
    let stderr = stderr_of_failure(&["modes", deck, "--np", "2"]);
    assert!(
        stderr.contains("--np and --hostfile apply with --engine slepc"),
        "{stderr}"
    );
}

/// A Nastran deck's own request: `femu modes` solves the EIGRL the case control's METHOD selects
/// (ND lowest modes, or every mode in V1-V2) unless --count, --shift or --band say otherwise, with
/// the deck's mass formulation (lumped: no PARAM,COUPMASS), and `femu info` says so. The band's
/// modes are the lowest-count solve's modes inside it (the same solver's two requests must agree,
/// and the band's Sturm count proves none is missing).
#[test]
fn a_nastran_deck_s_eigrl_and_mass_are_honoured() {
    let dir = std::env::temp_dir().join(format!("femu-cli-eigrl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut deck = String::from("SOL 103\nCEND\nSPC = 1\nMETHOD = 20 $ three modes\nBEGIN BULK\n");
    let nx = 6;
    let id = |i: usize, j: usize, k: usize| 1 + i + (nx + 1) * (j + 2 * k);
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..=nx {
                deck.push_str(&format!(
                    "GRID,{},,{:?},{:?},{:?}\n",
                    id(i, j, k),
                    0.05 * i as f64,
                    0.02 * j as f64,
                    0.01 * k as f64
                ));
            }
        }
    }
    for i in 0..nx {
        deck.push_str(&format!(
            "CHEXA,{},1,{},{},{},{},{},{}\n,{},{}\n",
            i + 1,
            id(i, 0, 0),
            id(i + 1, 0, 0),
            id(i + 1, 1, 0),
            id(i, 1, 0),
            id(i, 0, 1),
            id(i + 1, 0, 1),
            id(i + 1, 1, 1),
            id(i, 1, 1)
        ));
    }
    deck.push_str("PSOLID,1,1,,2,,FULL\nMAT1,1,2.1+11,,.3,7850.\nEIGRL,10,,,8\nEIGRL,20,,,3\n");
    deck.push_str(&format!(
        "SPC1,1,123,{},{},{},{}\n",
        id(0, 0, 0),
        id(0, 1, 0),
        id(0, 0, 1),
        id(0, 1, 1)
    ));
    let path = dir.join("bar.bdf");
    std::fs::write(&path, &deck).unwrap();
    let p = path.to_str().unwrap();
    let json = dir.join("m.json");
    let j = json.to_str().unwrap();
    stdout_of_success(&["modes", p, "--json", j]);
    let v = json_of(&json);
    assert_eq!(v["frequencies_hz"].as_array().unwrap().len(), 3);
    assert_eq!(v["mass"], "lumped");
    assert!(
        v["notes"][0]
            .as_str()
            .unwrap()
            .starts_with("the deck's EIGRL: the lowest 3 modes"),
        "{}",
        v["notes"]
    );
    stdout_of_success(&["modes", p, "--count", "5", "--json", j]);
    let five = json_of(&json);
    let f5: Vec<f64> = five["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect();
    assert_eq!(f5.len(), 5);
    // V1-V2: the modes between the 2nd and the 4th of the five, each to the solver's tolerance
    let (lo, hi) = (0.5 * (f5[0] + f5[1]), 0.5 * (f5[3] + f5[4]));
    std::fs::write(
        &path,
        deck.replace("EIGRL,20,,,3", &format!("EIGRL,20,{lo:?},{hi:?}")),
    )
    .unwrap();
    stdout_of_success(&["modes", p, "--json", j]);
    let band = json_of(&json);
    let fb: Vec<f64> = band["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect();
    assert_eq!(fb.len(), 3, "{fb:?}");
    for (a, b) in fb.iter().zip(&f5[1..4]) {
        assert!((a / b - 1.0).abs() < 1e-8, "{a} {b}");
    }
    assert!(band["sturm_verified"].as_bool().unwrap());
    let info = stdout_of_success(&["info", p]);
    assert!(
        info.contains("mass: lumped (no PARAM,COUPMASS: MSC Nastran's default)"),
        "{info}"
    );
    assert!(info.contains("SPC set 1"), "{info}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A deck whose EIGRL asks for more modes than the model has (pyNastran's two-mode flutter model:
/// ND = 20, two free DOFs) gets all it has, as Nastran returns them, with a note; a `--count`
/// above them is still refused.
#[test]
fn a_deck_asking_for_more_modes_than_exist_gets_them_all() {
    let deck = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/nastran/pynastran/two_mode_flutter/0012_flutter.bdf");
    let dir = std::env::temp_dir().join(format!("femu-cli-nd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("m.json");
    let (p, j) = (deck.to_str().unwrap(), json.to_str().unwrap());
    stdout_of_success(&["modes", p, "--json", j]);
    let v = json_of(&json);
    assert_eq!(v["frequencies_hz"].as_array().unwrap().len(), 2);
    assert!(
        v["notes"].as_array().unwrap().iter().any(|n| n
            .as_str()
            .unwrap()
            .contains("asks for 20 modes and the model has 2 free degrees of freedom: all 2")),
        "{}",
        v["notes"]
    );
    let err = stderr_of_failure(&["modes", p, "--count", "3"]);
    assert!(err.contains("3 modes requested"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A test with one reading for three modes: every MAC is 1, so the pairs rest on the
/// frequencies; correlate says so (it paired without a word), and the pairs are the nearest
/// frequencies (test modes 1.5 % above the model's first three, read at one sensor).
#[test]
fn one_sensor_pairs_by_frequency_and_says_so() {
    use femu_correlate::TestModes;
    let deck = fixture("two_hex.inp");
    let (modes, sensors, layout) = two_hex_case(6);
    let at = layout.measure_all(modes.vectors.as_ref()).unwrap();
    let f = modes.frequencies_hz();
    // the first sensor alone, modes 1-3 (mode 3 is not in the repeated pair 1-2)
    let shapes = femu_sparse::faer::Mat::from_fn(1, 3, |_, j| at[(0, j)]);
    let test = TestModes::new((0..3).map(|j| 1.015 * f[j]).collect(), None, shapes).unwrap();
    let dir = std::env::temp_dir().join(format!("femu-cli-one-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("test.csv");
    std::fs::write(&csv, femu_io::csv::test_csv_string(&sensors[..1], &test)).unwrap();
    let json = dir.join("corr.json");
    let stdout = stdout_of_success(&[
        "correlate",
        deck.to_str().unwrap(),
        csv.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    let v = json_of(&json);
    let w = v["pairing"]["warnings"][0].as_str().unwrap_or_default();
    assert!(
        w.starts_with("1 reading for 3 test modes: MAC cannot tell any shapes apart at the sensors (every MAC is 1)"),
        "{w}\n{stdout}"
    );
    assert!(stdout.contains("1 reading for 3 test modes"), "{stdout}");
    // the nearest frequencies: test modes 1 and 2 with the repeated pair 1-2, test mode 3 with 3
    let pairs = v["pairing"]["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 3, "{stdout}");
    for p in pairs {
        let (t, m) = (p["test"].as_u64().unwrap(), p["model"].as_u64().unwrap());
        assert!(if t < 2 { m < 2 } else { m == 2 }, "{p}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A test of frequencies alone, as CSV (`mode,frequency_hz` and blank readings) and as a Universal
/// File whose datasets 55 have no node records: `correlate` pairs it by frequency and says what
/// shapes would add; `estimate` and `expand` refuse it by naming the missing shapes; `update`
/// fits the frequencies and refuses SB-EBE by name.
#[test]
fn a_test_of_frequencies_alone_is_read_and_paired_by_frequency() {
    let deck = fixture("two_hex.inp");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    for test in [
        root.join("csv/frequencies_only.csv"),
        root.join("csv/frequencies_blank_shapes.csv"),
        root.join("uff/frequencies_only.unv"),
    ] {
        let t = test.to_str().unwrap();
        let out = stdout_of_success(&["correlate", deck.to_str().unwrap(), t]);
        assert!(out.contains("at 0 sensors"), "{out}");
        assert!(
            out.contains("warning: the test gives frequencies without mode shapes"),
            "{out}"
        );
        assert!(
            out.contains("pairs by optimal assignment on the frequencies"),
            "{out}"
        );
        // the pairs are by frequency: the first test mode, 1311.2 or 1442.8 Hz, with model
        // mode 1, and no MAC column value
        assert!(
            out.contains("| 1 | 13") || out.contains("| 1 | 14"),
            "{out}"
        );
        assert!(out.contains("| - | - |"), "{out}");
        for cmd in ["estimate", "expand"] {
            let err = stderr_of_failure(&[cmd, deck.to_str().unwrap(), t]);
            assert!(
                err.contains("frequencies without mode shapes"),
                "{cmd}: {err}"
            );
        }
        let err = stderr_of_failure(&[
            "update",
            deck.to_str().unwrap(),
            t,
            "--sets",
            "LEFT,RIGHT",
            "--method",
            "sbebe",
        ]);
        assert!(err.contains("frequencies alone"), "{err}");
    }
    let out = stdout_of_success(&[
        "update",
        deck.to_str().unwrap(),
        root.join("uff/frequencies_only.unv").to_str().unwrap(),
        "--sets",
        "LEFT,RIGHT",
        "--tuned",
        "2",
    ]);
    assert!(out.contains("the test gives frequencies alone"), "{out}");
    assert!(
        out.contains("Does the updated model tell the truth?"),
        "{out}"
    );
}

/// A cantilever of `nx` hex8 bricks along x, one through the width and the thickness, node ids
/// `1 + i + (nx + 1) (j + 2 k)`, clamped at `x = 0` (the `root` face).
struct Cantilever {
    nx: usize,
    coords: Vec<(usize, [f64; 3])>,
    hexes: Vec<[usize; 8]>,
    root: [usize; 4],
}

impl Cantilever {
    fn new(nx: usize, [l, b, h]: [f64; 3]) -> Self {
        let id = |i: usize, j: usize, k: usize| 1 + i + (nx + 1) * (j + 2 * k);
        let mut coords = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..=nx {
                    coords.push((
                        id(i, j, k),
                        [l * i as f64 / nx as f64, b * j as f64, h * k as f64],
                    ));
                }
            }
        }
        let hexes = (0..nx)
            .map(|i| {
                [
                    id(i, 0, 0),
                    id(i + 1, 0, 0),
                    id(i + 1, 1, 0),
                    id(i, 1, 0),
                    id(i, 0, 1),
                    id(i + 1, 0, 1),
                    id(i + 1, 1, 1),
                    id(i, 1, 1),
                ]
            })
            .collect();
        let root = [id(0, 0, 0), id(0, 1, 0), id(0, 1, 1), id(0, 0, 1)];
        Self {
            nx,
            coords,
            hexes,
            root,
        }
    }

    fn id(&self, i: usize, j: usize, k: usize) -> usize {
        1 + i + (self.nx + 1) * (j + 2 * k)
    }

    /// A CalculiX deck of the cantilever: elements `ty`, steel with Young's modulus `young`.
    fn deck(&self, ty: &str, young: f64) -> String {
        let mut s = String::from("*NODE\n");
        for (n, x) in &self.coords {
            s.push_str(&format!("{n}, {:e}, {:e}, {:e}\n", x[0], x[1], x[2]));
        }
        s.push_str(&format!("*ELEMENT, TYPE={ty}, ELSET=EALL\n"));
        for (e, c) in self.hexes.iter().enumerate() {
            let c: Vec<String> = c.iter().map(|v| v.to_string()).collect();
            s.push_str(&format!("{}, {}\n", e + 2, c.join(", ")));
        }
        let r = self.root;
        s.push_str(&format!(
            "*NSET, NSET=ROOT\n{}, {}, {}, {}\n*BOUNDARY\nROOT, 1, 3\n",
            r[0], r[1], r[2], r[3]
        ));
        s.push_str(&format!(
            "*MATERIAL, NAME=STEEL\n*ELASTIC\n{young:e}, 0.3\n*DENSITY\n7850.\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
        ));
        s
    }
}

/// `--bricks incompatible-modes` on a Gmsh mesh builds the brick that a deck asks for with C3D8I
/// (checked against CalculiX in `crates/femu-io/tests/calculix.rs`): the same cantilever as a
/// `.msh` with the flag and as an `.inp` of C3D8I elements gives the same frequencies to 1e-9, and
/// without the flag those of C3D8; on this mesh (one brick through the thickness) the fully
/// integrated brick is more than 20 % stiffer. A deck with the flag says the flag is not used.
#[test]
fn bricks_with_incompatible_modes_from_the_command_line() {
    let beam = Cantilever::new(8, [0.4, 0.04, 0.02]);
    let (coords, hexes, root) = (&beam.coords, &beam.hexes, beam.root);
    let join = |v: &[usize]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    // Gmsh 2.2: the root face as a physical surface "root", the bricks as a physical volume
    let mut msh = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 \"root\"\n3 2 \"solid\"\n$EndPhysicalNames\n",
    );
    msh.push_str(&format!("$Nodes\n{}\n", coords.len()));
    for (n, x) in coords {
        msh.push_str(&format!("{n} {:e} {:e} {:e}\n", x[0], x[1], x[2]));
    }
    msh.push_str(&format!("$EndNodes\n$Elements\n{}\n", 1 + hexes.len()));
    msh.push_str(&format!("1 3 2 1 1 {}\n", join(&root)));
    for (e, c) in hexes.iter().enumerate() {
        msh.push_str(&format!("{} 5 2 2 2 {}\n", e + 2, join(c)));
    }
    msh.push_str("$EndElements\n");
    let deck = |ty: &str| beam.deck(ty, 2.1e11);
    let dir = std::env::temp_dir().join(format!("femu-cli-bricks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name);
    std::fs::write(path("beam.msh"), &msh).unwrap();
    std::fs::write(path("c3d8i.inp"), deck("C3D8I")).unwrap();
    std::fs::write(path("c3d8.inp"), deck("C3D8")).unwrap();
    let freqs = |v: serde_json::Value| -> Vec<f64> {
        v["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_f64().unwrap())
            .collect()
    };
    let fix = ["--fix", "root", "--count", "3"];
    let bricks = [&fix[..], &["--bricks", "incompatible-modes"]].concat();
    let with = freqs(steel_modes(&path("beam.msh"), &bricks, &path("a.json")));
    let without = freqs(steel_modes(&path("beam.msh"), &fix, &path("b.json")));
    let deck_modes = |name: &str, json: &str| {
        femu()
            .args([
                "modes",
                path(name).to_str().unwrap(),
                "--count",
                "3",
                "--json",
            ])
            .arg(path(json))
            .arg("--quiet")
            .assert()
            .success();
        freqs(json_of(path(json)))
    };
    let (c3d8i, c3d8) = (
        deck_modes("c3d8i.inp", "c.json"),
        deck_modes("c3d8.inp", "d.json"),
    );
    for j in 0..3 {
        assert!(
            (with[j] / c3d8i[j] - 1.0).abs() < 1e-9,
            "{with:?} {c3d8i:?}"
        );
        assert!(
            (without[j] / c3d8[j] - 1.0).abs() < 1e-9,
            "{without:?} {c3d8:?}"
        );
    }
    assert!(without[0] > 1.2 * with[0], "{without:?} {with:?}");
    let stderr = String::from_utf8(
        femu()
            .args(["modes", path("c3d8.inp").to_str().unwrap(), "--count", "1"])
            .args(["--bricks", "incompatible-modes"])
            .assert()
            .success()
            .get_output()
            .stderr
            .clone(),
    )
    .unwrap();
    assert!(
        stderr.contains("the deck states its bricks' formulation (C3D8 or C3D8I)"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A deck read and assembled (consistent mass), with `K` and `M` dense.
fn dense_deck(
    path: &std::path::Path,
) -> (
    femu_fem::model::Model,
    femu_fem::assembly::SystemMatrices,
    faer::Mat<f64>,
    faer::Mat<f64>,
) {
    let model = femu_io::inp::read_inp(path).unwrap().to_model().unwrap();
    let sys = model
        .assemble(femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    let (k, m) = (
        femu_sparse::csc::to_dense(&sys.k),
        femu_sparse::csc::to_dense(&sys.m),
    );
    (model, sys, k, m)
}

/// Receptances of the dense pencil at `outputs` (free DOFs) for a unit force at `force`, on
/// `count` lines from `min` by `step` Hz, by a dense complex solve of
/// `(K - w^2 M + i D(w)) x = f` per line, `D(w)` the damping's imaginary part (`eta K` for a loss
/// factor, `w C` for viscous damping): the "measurement", independent of the modal superposition.
#[allow(clippy::too_many_arguments)]
fn direct_frfs(
    k: &faer::Mat<f64>,
    m: &faer::Mat<f64>,
    outputs: &[usize],
    force: usize,
    min: f64,
    step: f64,
    count: usize,
    damping: impl Fn(f64) -> faer::Mat<f64>,
) -> Vec<Vec<(f64, f64)>> {
    use faer::c64;
    use faer::linalg::solvers::Solve;
    let n = k.nrows();
    let mut values = vec![Vec::new(); outputs.len()];
    for q in 0..count {
        let w = 2.0 * std::f64::consts::PI * (min + step * q as f64);
        let d = damping(w);
        let a = faer::Mat::<c64>::from_fn(n, n, |i, j| {
            c64::new(k[(i, j)] - w * w * m[(i, j)], d[(i, j)])
        });
        let mut f = faer::Mat::<c64>::zeros(n, 1);
        f[(force, 0)] = c64::new(1.0, 0.0);
        let x = a.as_ref().partial_piv_lu().solve(&f);
        for (o, r) in outputs.iter().enumerate() {
            values[o].push((x[(*r, 0)].re, x[(*r, 0)].im));
        }
    }
    values
}

/// Receptances of the deck `measured` by [`direct_frfs`] with a loss factor of 0.02 at `outputs`
/// (node, direction 1-3) for a unit force along z at `tip`, on `count` lines from `min` by `step`
/// Hz.
fn measured_receptances(
    measured: &std::path::Path,
    outputs: &[(u64, i64)],
    tip: u64,
    (min, step, count): (f64, f64, usize),
) -> Vec<Vec<(f64, f64)>> {
    let (model, sys, k, m) = dense_deck(measured);
    let free = |node: u64, c: usize| {
        sys.dofs
            .free_index(model.mesh().node_index(node).unwrap(), c)
            .unwrap()
    };
    let out_free: Vec<usize> = outputs
        .iter()
        .map(|(node, d)| free(*node, (*d - 1) as usize))
        .collect();
    direct_frfs(&k, &m, &out_free, free(tip, 2), min, step, count, |_| {
        faer::Mat::from_fn(k.nrows(), k.ncols(), |i, j| 0.02 * k[(i, j)])
    })
}

/// The receptance `1 / A(w)` of a single DOF whose dynamic stiffness is `A(w) = re + i im`
/// (`dynamic(w)`, w in rad/s) at the lines `min + step l` Hz, as `(re, im)` pairs.
fn oscillator(
    (min, step, count): (f64, f64, usize),
    dynamic: impl Fn(f64) -> (f64, f64),
) -> Vec<(f64, f64)> {
    (0..count)
        .map(|l| {
            let (re, im) = dynamic(2.0 * std::f64::consts::PI * (min + step * l as f64));
            let d = re * re + im * im;
            (re / d, -im / d)
        })
        .collect()
}

/// The receptance of a one-DOF oscillator (grid 2 along z, force there) whose dynamic stiffness
/// is `dynamic(w)` ([`oscillator`]), at 80 lines from 1 Hz by 0.25 Hz (the resonance of 3e4 N/m
/// under 10 kg at 8.72 Hz among them), written to `dir/frf.uff` as the measurement; returned.
fn measured_oscillator(
    dir: &std::path::Path,
    dynamic: impl Fn(f64) -> (f64, f64),
) -> Vec<(f64, f64)> {
    let (min, step, count) = (1.0, 0.25, 80usize);
    let h = oscillator((min, step, count), dynamic);
    write_frf_uff(
        &dir.join("frf.uff"),
        &[(2, 3)],
        2,
        min,
        step,
        std::slice::from_ref(&h),
    );
    h
}

/// The one-DOF oscillator of [`measured_oscillator`] (3e4 N/m under 10 kg along z at node 2) as an
/// Abaqus deck whose frequency step holds `modal_damping`.
fn abaqus_oscillator(modal_damping: &str) -> String {
    format!(
        "*NODE\n2, 0., 0., 0.\n*ELEMENT, TYPE=SPRING1, ELSET=S\n7, 2\n*SPRING, ELSET=S\n3\n3.e4\n\
         *ELEMENT, TYPE=MASS, ELSET=M\n9, 2\n*MASS, ELSET=M\n10.\n*BOUNDARY\n2, 1, 2\n\
         *STEP\n*FREQUENCY\n1\n{modal_damping}*END STEP\n"
    )
}

/// `femu frf` of the deck `name` in `dir` against the measured oscillator `h` (`dir/frf.uff`):
/// the written FRF's deviation from it ([`file_deviation`]) and the run's notes.
fn oscillator_frf(dir: &std::path::Path, name: &str, h: &[(f64, f64)]) -> ((f64, f64), String) {
    let out = femu()
        .args(["frf", dir.join(name).to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--uff"])
        .arg(dir.join("model.uff"))
        .arg("--json")
        .arg(dir.join("frf.json"))
        .output()
        .unwrap();
    succeeded(&out);
    let notes = json_of(dir.join("frf.json"))["notes"].to_string();
    (file_deviation(&dir.join("model.uff"), h), notes)
}

/// [`deviation`] of the first function of the universal file `path` written by femu.
fn file_deviation(path: &std::path::Path, measured: &[(f64, f64)]) -> (f64, f64) {
    let back = femu_io::uff::read_uff(path).unwrap();
    deviation(&back.functions[0].ordinate, measured)
}

/// A complex FRF written by femu against the `measured` one at the same lines: the measured peak
/// magnitude and the largest distance between the two in the complex plane.
fn deviation(model: &femu_io::uff::Ordinate, measured: &[(f64, f64)]) -> (f64, f64) {
    let femu_io::uff::Ordinate::Complex(m) = model else {
        panic!("complex FRF expected")
    };
    let peak = measured
        .iter()
        .map(|(a, b)| a.hypot(*b))
        .fold(0.0, f64::max);
    let err = m
        .iter()
        .zip(measured)
        .map(|((a, b), (c, d))| (a - c).hypot(b - d))
        .fold(0.0, f64::max);
    (peak, err)
}

/// Writes receptances (`values[o]` at `outputs[o]`, force at `tip` in z) as dataset 58.
fn write_frf_uff(
    path: &std::path::Path,
    outputs: &[(u64, i64)],
    tip: u64,
    min: f64,
    step: f64,
    values: &[Vec<(f64, f64)>],
) {
    use femu_io::uff::{Abscissa, Ordinate, UffAxis, UffDof, UffFunction, Universal};
    let axis = |data_type: i64, exponents: [i64; 3], label: &str, units: &str| UffAxis {
        data_type,
        exponents,
        label: label.into(),
        units: units.into(),
    };
    let functions = outputs
        .iter()
        .enumerate()
        .map(|(o, (node, d))| UffFunction {
            ids: [
                format!("H {node}/{tip}"),
                "direct solve".into(),
                "NONE".into(),
                "NONE".into(),
                "NONE".into(),
            ],
            function_type: 4,
            numbers: [o as i64 + 1, 0, 0],
            response: UffDof {
                entity: "bar".into(),
                node: *node,
                direction: *d,
            },
            reference: UffDof {
                entity: "bar".into(),
                node: tip,
                direction: 3,
            },
            double: true,
            abscissa: Abscissa::Even { min, step },
            z_value: 0.0,
            axes: [
                axis(18, [0, 0, 0], "Frequency", "Hz"),
                axis(8, [1, 0, 0], "Displacement", "m"),
                axis(13, [0, 1, 0], "Force", "N"),
                axis(0, [0, 0, 0], "NONE", "NONE"),
            ],
            ordinate: Ordinate::Complex(values[o].clone()),
            binary: false,
        })
        .collect();
    let u = Universal {
        functions,
        ..Default::default()
    };
    femu_io::uff::write_uff(path, &u).unwrap();
}

/// `femu frf --damping-from`: FRFs "measured" by a dense direct solve with viscous damping
/// `C = M Phi diag(2 zeta_j omega_j) Phi^T M` of other ratios on each of the first four modes (the
/// dense eigenvectors, written here), and a test of those four modes (frequencies, ratios and
/// shapes at the tip) with the ratios in its damping column. Each model mode takes its paired test
/// mode's ratio (the JSON's damping, checked against the ratios written here); the FRFs then
/// match to FRAC 0.9999 (0.99997 at worst, measured), and with the default 1 % on every mode two
/// of the four fall to 0.838.
#[test]
fn frf_damping_from_the_test() {
    let nx = 10;
    let beam = Cantilever::new(nx, [0.4, 0.04, 0.02]);
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-zeta-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), beam.deck("C3D8", 2.1e11)).unwrap();
    let (model, sys, k, m) = dense_deck(&dir.join("bar.inp"));
    let eig = femu_sparse::dense::generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap();
    let zeta = [0.004, 0.03, 0.012, 0.02];
    let n = k.nrows();
    // C = (M Phi) diag(2 zeta_j omega_j) (M Phi)^T over the four modes with M-normalised Phi
    let mphi = &m * eig.vectors.as_ref().subcols(0, 4);
    let c = faer::Mat::from_fn(n, n, |i, j| {
        (0..4)
            .map(|r| 2.0 * zeta[r] * eig.values[r].sqrt() * mphi[(i, r)] * mphi[(j, r)])
            .sum::<f64>()
    });
    let free = |node: u64, comp: usize| {
        sys.dofs
            .free_index(model.mesh().node_index(node).unwrap(), comp)
            .unwrap()
    };
    let tip = beam.id(nx, 0, 1) as u64;
    let outputs = [
        (tip, 3i64),
        (beam.id(nx, 1, 0) as u64, 2),
        (beam.id(nx / 2, 0, 1) as u64, 3),
        (beam.id(nx / 2, 1, 1) as u64, 2),
    ];
    let out_free: Vec<usize> = outputs
        .iter()
        .map(|(node, d)| free(*node, (*d - 1) as usize))
        .collect();
    let (min, step, count) = (5.0, 2.5, 360usize);
    let values = direct_frfs(&k, &m, &out_free, free(tip, 2), min, step, count, |w| {
        faer::Mat::from_fn(n, n, |i, j| w * c[(i, j)])
    });
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    // the test: the four modes at the tip's nodes in y and z, with their ratios
    let mut csv = String::from("mode,frequency_hz,node,direction,value,damping\n");
    for (r, z) in zeta.iter().enumerate() {
        let f = eig.values[r].sqrt() / (2.0 * std::f64::consts::PI);
        for j in 0..2 {
            for kk in 0..2 {
                let node = beam.id(nx, j, kk) as u64;
                for (comp, name) in [(1, "y"), (2, "z")] {
                    let v = eig.vectors[(free(node, comp), r)];
                    csv.push_str(&format!("{},{f:.12},{node},{name},{v:.15e},{z}\n", r + 1));
                }
            }
        }
    }
    std::fs::write(dir.join("test.csv"), csv).unwrap();
    let run = |extra: &[&str], json: &str| {
        femu()
            .args(["frf", dir.join("bar.inp").to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(extra)
            .args(["--quiet", "--json"])
            .arg(dir.join(json))
            .assert()
            .success();
        json_of(dir.join(json))
    };
    let from_test = run(
        &["--damping-from", dir.join("test.csv").to_str().unwrap()],
        "test.json",
    );
    let ratios: Vec<f64> = from_test["damping"]["ratios"]
        .as_array()
        .unwrap_or_else(|| panic!("{}", from_test["damping"]))
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(&ratios[..4], &zeta);
    assert!(ratios[4..].iter().all(|z| *z == 0.01), "{ratios:?}");
    let fracs = |v: &serde_json::Value| -> Vec<f64> {
        v["functions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["frac"].as_f64().unwrap())
            .collect()
    };
    let constant = run(&[], "constant.json");
    let (good, bad) = (fracs(&from_test), fracs(&constant));
    assert!(good.iter().all(|f| *f > 0.9999), "{good:?}");
    assert!(bad.iter().any(|f| *f < 0.99), "{bad:?}");
    // a test without damping is refused, naming it
    std::fs::write(
        dir.join("bare.csv"),
        format!("mode,frequency_hz,node,direction,value\n1,10,{tip},z,1\n"),
    )
    .unwrap();
    let out = femu()
        .args(["frf", dir.join("bar.inp").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .arg("--damping-from")
        .arg(dir.join("bare.csv"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("bare.csv") && stderr.contains("no damping"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu frf`: FRFs "measured" on a clamped bar by a dense direct solve of `(K (1 + i eta) - w^2
/// M) x = f` (written here, independent of the modal superposition), written as a universal file
/// (dataset 58, receptance) and correlated with the same model: FRAC and CSAC above 0.999 with the
/// modes to twice the highest line and the residual flexibility of those above; against a model 10
/// % stiffer, the resonances miss and the lowest FRAC falls below 0.9. The CSV has one row per line
/// and function.
#[test]
fn frf_correlation_against_a_direct_solve() {
    use femu_io::uff::{Abscissa, Ordinate};
    let nx = 10;
    let beam = Cantilever::new(nx, [0.4, 0.04, 0.02]);
    let id = |i: usize, j: usize, k: usize| beam.id(i, j, k);
    let deck = |young: f64| beam.deck("C3D8", young);
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), deck(2.1e11)).unwrap();
    std::fs::write(dir.join("stiffer.inp"), deck(2.31e11)).unwrap();
    // the "measurement": a dense complex solve with a loss factor of 0.02
    let (model, sys, k, m) = dense_deck(&dir.join("bar.inp"));
    let eta = 0.02;
    let free = |node: u64, c: usize| {
        sys.dofs
            .free_index(model.mesh().node_index(node).unwrap(), c)
            .unwrap()
    };
    let tip = id(nx, 0, 1) as u64;
    let outputs = [
        (tip, 3i64),
        (id(nx, 1, 0) as u64, 2),
        (id(nx / 2, 0, 1) as u64, 3),
        (id(nx / 2, 1, 1) as u64, 2),
    ];
    let (min, step, count) = (5.0, 2.5, 360usize); // 5 to 902.5 Hz: the first four modes
    let out_free: Vec<usize> = outputs
        .iter()
        .map(|(node, d)| free(*node, (*d - 1) as usize))
        .collect();
    let values = direct_frfs(&k, &m, &out_free, free(tip, 2), min, step, count, |_| {
        faer::Mat::from_fn(k.nrows(), k.ncols(), |i, j| eta * k[(i, j)])
    });
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    let run = |deck: &str, json: &str| {
        femu()
            .args(["frf", dir.join(deck).to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(["--loss-factor", "0.02", "--quiet", "--json"])
            .arg(dir.join(json))
            .arg("--csv")
            .arg(dir.join(format!("{json}.csv")))
            .assert()
            .success();
        json_of(dir.join(json))
    };
    let same = run("bar.inp", "same.json");
    let fracs = |v: &serde_json::Value| -> Vec<f64> {
        v["functions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["frac"].as_f64().unwrap())
            .collect()
    };
    assert_eq!(fracs(&same).len(), 4);
    assert!(
        fracs(&same).iter().all(|f| *f > 0.999),
        "{:?}",
        fracs(&same)
    );
    assert_eq!(same["residual_flexibility"], true);
    let lines = same["lines"].as_array().unwrap();
    assert_eq!(lines.len(), count);
    let mean_csac = lines
        .iter()
        .map(|l| l["csac"].as_f64().unwrap())
        .sum::<f64>()
        / count as f64;
    assert!(mean_csac > 0.999, "{mean_csac}");
    let csv = std::fs::read_to_string(dir.join("same.json.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + count * 4);
    // the model's FRFs as a universal file: the direct solve's values to 1e-4 of each curve's peak
    // along the force and 1e-2 across it (modes to twice the highest line and the residual
    // flexibility of those above); and a chart per function, magnitude and phase of both curves
    femu()
        .args(["frf", dir.join("bar.inp").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--loss-factor", "0.02", "--quiet", "--uff"])
        .arg(dir.join("model.uff"))
        .arg("--charts")
        .arg(dir.join("charts"))
        .assert()
        .success();
    let back = femu_io::uff::read_uff(dir.join("model.uff")).unwrap();
    assert_eq!(back.functions.len(), 4);
    for (o, f) in back.functions.iter().enumerate() {
        let (peak, err) = deviation(&f.ordinate, &values[o]);
        // measured: 1.0e-5 and 2.1e-6 of the peak for the responses along the force (z); 4.0e-3 and
        // 1.7e-3 for the small y responses it couples to, where the left-out modes' dynamics
        // (beyond their static part) weigh more
        let tol = if outputs[o].1 == 3 { 1e-4 } else { 1e-2 };
        assert!(
            err < tol * peak,
            "function {o}: {err:e} against peak {peak:e}"
        );
        assert_eq!(f.abscissa, Abscissa::Even { min, step });
        assert_eq!(f.axes[1].data_type, 8);
    }
    for k in 1..=4 {
        let svg = std::fs::read_to_string(dir.join(format!("charts/frf_{k}.svg"))).unwrap();
        assert_eq!(svg.matches("<polyline").count(), 4, "chart {k}");
        assert!(dir.join(format!("charts/frf_{k}.png")).is_file());
    }
    let stiffer = run("stiffer.inp", "stiffer.json");
    let low = fracs(&stiffer).into_iter().fold(1.0, f64::min);
    assert!(low < 0.9, "{:?}", fracs(&stiffer));
    // the alignment: a modulus 1.1 times the measured bar's scales every frequency by sqrt(1.1)
    // and the receptance by 1 / 1.1 (FRAC does not see it), so the model at sqrt(1.1) f is the
    // test at f; the measured bar itself aligns at 1
    let factor = |v: &serde_json::Value| v["alignment"]["factor"].as_f64().unwrap();
    assert!((factor(&same) - 1.0).abs() < 1e-6, "{}", same["alignment"]);
    assert!(
        (factor(&stiffer) - 1.1f64.sqrt()).abs() < 1e-6,
        "{}",
        stiffer["alignment"]
    );
    assert!(stiffer["alignment"]["mean_frac"].as_f64().unwrap() > 0.999);
    // the direct route solves the same dynamic stiffness as the measurement: every value to 1e-9
    // of the largest response, no mode left out (the small y responses the force couples to are
    // met to about 1e-17 absolute, 5e-9 of their own peak: both solves carry the conditioning of
    // the dynamic stiffness, which near a resonance is 1 / eta times that of K)
    femu()
        .args(["frf", dir.join("bar.inp").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--direct", "--loss-factor", "0.02", "--quiet", "--uff"])
        .arg(dir.join("direct.uff"))
        .arg("--json")
        .arg(dir.join("direct.json"))
        .assert()
        .success();
    let back = femu_io::uff::read_uff(dir.join("direct.uff")).unwrap();
    let peak = values
        .iter()
        .flatten()
        .map(|(a, b)| a.hypot(*b))
        .fold(0.0, f64::max);
    for (o, f) in back.functions.iter().enumerate() {
        let Ordinate::Complex(v) = &f.ordinate else {
            panic!("complex FRF expected")
        };
        let err = v
            .iter()
            .zip(&values[o])
            .map(|((a, b), (c, d))| (a - c).hypot(b - d))
            .fold(0.0, f64::max);
        assert!(err < 1e-9 * peak, "function {o}: {err:e} against {peak:e}");
    }
    let direct = json_of(dir.join("direct.json"));
    assert_eq!(direct["direct"], true);
    assert!(direct["backward_error"].as_f64().unwrap() < 1e-13);
    assert!(fracs(&direct).iter().all(|f| *f > 1.0 - 1e-12));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu frf` on a free-free bar: the "measurement" a dense direct solve of `(K (1 + i eta) - w^2
/// M) x = f` (nonsingular at every line above 0 Hz), the model's modes from 0 Hz (six rigid-body
/// modes among them) to twice the highest line, and the residual flexibility of the elastic modes
/// above under loads balanced by the rigid-body inertia (inertia relief): the responses along the
/// force to 1e-4 of their peak, as on the clamped bar, and a note that says how it was formed.
#[test]
fn frf_of_a_free_structure_with_inertia_relief() {
    let nx = 10;
    let beam = Cantilever::new(nx, [0.4, 0.04, 0.02]);
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-free-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let clamped = beam.deck("C3D8", 2.1e11);
    let free = clamped.replace("*BOUNDARY\nROOT, 1, 3\n", "");
    assert_ne!(free, clamped);
    std::fs::write(dir.join("free.inp"), free).unwrap();
    let tip = beam.id(nx, 0, 1) as u64;
    let outputs = [(tip, 3i64), (beam.id(nx / 2, 0, 1) as u64, 3)];
    let (min, step, count) = (5.0, 5.0, 180usize); // 5 to 900 Hz: rigid motion and the first bending
    let values = measured_receptances(&dir.join("free.inp"), &outputs, tip, (min, step, count));
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    femu()
        .args(["frf", dir.join("free.inp").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--loss-factor", "0.02", "--quiet", "--uff"])
        .arg(dir.join("model.uff"))
        .arg("--json")
        .arg(dir.join("free.json"))
        .assert()
        .success();
    let v = json_of(dir.join("free.json"));
    assert_eq!(v["residual_flexibility"], true);
    let notes = v["notes"].to_string();
    assert!(notes.contains("inertia relief"), "{notes}");
    let back = femu_io::uff::read_uff(dir.join("model.uff")).unwrap();
    for (o, f) in back.functions.iter().enumerate() {
        let (peak, err) = deviation(&f.ordinate, &values[o]);
        // measured: 3.3e-7 of the peak at the tip, 6.1e-9 at mid-length
        assert!(
            err < 1e-4 * peak,
            "function {o}: {err:e} against peak {peak:e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu frf --direct` on a Nastran deck whose damping is its own: a CONM2 of 10 kg on a
/// grounded CBUSH with PBUSH stiffnesses, viscous `B` and structural `GE`. Along z the receptance
/// is the single-DOF oscillator's `1 / (K3 (1 + i GE) - w^2 m + i w B3)`, written here by hand as
/// the "measurement": the direct route reproduces it to 1e-9 of the peak (FRAC 1); so does modal
/// superposition, which projects the deck's dampers on the six modes and says so. The
/// same damping in a second CBUSH of its own (PBUSH with `B` alone: a pure damper, which Nastran
/// reads) gives the same receptance to 1e-9.
#[test]
fn frf_direct_with_the_decks_own_dampers() {
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-bush-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = "\
SOL 103
CEND
SPC = 1
BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,0.,0.,0.
CBUSH,7,8,1,2,,,,0
PBUSH,8,K,1.+4,2.+4,3.+4,500.,700.,900.
,B,1.,2.,30.,4.,5.,6.
,GE,0.04
CONM2,9,2,,10.,,,,,+C
+C,0.5,,0.7,,,0.9
SPC1,1,123456,1
ENDDATA
";
    std::fs::write(dir.join("bush.bdf"), deck).unwrap();
    let (k3, b3, ge, m) = (3e4, 30.0, 0.04, 10.0);
    let h = measured_oscillator(&dir, |w| (k3 - w * w * m, k3 * ge + w * b3));
    femu()
        .args(["frf", dir.join("bush.bdf").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--direct", "--quiet", "--uff"])
        .arg(dir.join("model.uff"))
        .arg("--json")
        .arg(dir.join("direct.json"))
        .assert()
        .success();
    let (peak, err) = file_deviation(&dir.join("model.uff"), &h);
    assert!(err < 1e-9 * peak, "{err:e} against {peak:e}");
    let direct = json_of(dir.join("direct.json"));
    assert!(direct["functions"][0]["frac"].as_f64().unwrap() > 1.0 - 1e-12);
    let notes = direct["notes"].to_string();
    assert!(notes.contains("own dampers alone"), "{notes}");
    // modal superposition projects the dampers on the modes (all six of the bushing's are in the
    // band) and solves the modal equations together: with no damping of its own added, the same
    // receptance
    let out = femu()
        .args(["frf", dir.join("bush.bdf").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--damping-ratio", "0", "--uff"])
        .arg(dir.join("modal.uff"))
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(stderr.contains("projected on the 6 modes"), "{stderr}");
    let (_, err) = file_deviation(&dir.join("modal.uff"), &h);
    assert!(err < 1e-9 * peak, "modal: {err:e} against {peak:e}");
    // updating from FRFs does not parameterise a bushing's own damping: refused, naming it
    let out = femu()
        .args(["frf", dir.join("bush.bdf").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--update", "PID8"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("element 7 is a spring or bushing"),
        "{stderr}"
    );
    // the damping in a bushing of its own (a pure damper: PBUSH B alone, which Nastran reads)
    // beside the stiff one: the same receptance
    let split = deck.replace(
        ",B,1.,2.,30.,4.,5.,6.\n,GE,0.04\n",
        ",GE,0.04\nCBUSH,17,18,1,2,,,,0\nPBUSH,18,B,1.,2.,30.,4.,5.,6.\n",
    );
    assert_ne!(split, deck);
    std::fs::write(dir.join("damper.bdf"), split).unwrap();
    femu()
        .args(["frf", dir.join("damper.bdf").to_str().unwrap()])
        .arg(dir.join("frf.uff"))
        .args(["--direct", "--quiet", "--uff"])
        .arg(dir.join("damper.uff"))
        .assert()
        .success();
    let (_, err) = file_deviation(&dir.join("damper.uff"), &h);
    assert!(err < 1e-9 * peak, "{err:e} against {peak:e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nastran's `PARAM,G` is the model's structural loss factor (`K (1 + i G)`, QRG PARAM G) when
/// `femu frf` is given no damping: a CELAS2 spring to ground under a CONM2 with `G = 0.05`
/// measured as the single-DOF receptance `1 / (k (1 + i G) - w^2 m)` written by hand is
/// reproduced to 1e-9 of its peak by the direct route and by modal superposition (its one mode
/// holds the whole response), and both say the damping is the deck's; `--loss-factor` given
/// overrides it, and the peak then moves away from the measured one.
#[test]
fn frf_takes_the_decks_param_g() {
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-g-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = "\
SOL 103
CEND
SPC = 1
BEGIN BULK
PARAM,G,0.05
GRID,2,,0.,0.,0.
CELAS2,7,3.+4,2,3
CONM2,9,2,,10.
SPC1,1,12,2
ENDDATA
";
    std::fs::write(dir.join("spring.bdf"), deck).unwrap();
    let (k, g, m) = (3e4, 0.05, 10.0);
    let h = measured_oscillator(&dir, |w| (k - w * w * m, k * g));
    let run = |extra: &[&str], name: &str| {
        femu()
            .args(["frf", dir.join("spring.bdf").to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(["--quiet", "--uff"])
            .arg(dir.join(format!("{name}.uff")))
            .arg("--json")
            .arg(dir.join(format!("{name}.json")))
            .args(extra)
            .assert()
            .success();
        let (peak, err) = file_deviation(&dir.join(format!("{name}.uff")), &h);
        (
            err / peak,
            json_of(dir.join(format!("{name}.json")))["notes"].to_string(),
        )
    };
    for (extra, name) in [(&["--direct"][..], "direct"), (&[][..], "modal")] {
        let (err, notes) = run(extra, name);
        assert!(err < 1e-9, "{name}: {err:e} of the peak");
        assert!(
            notes.contains("the deck's own (a loss factor of 0.05"),
            "{notes}"
        );
    }
    let (err, notes) = run(&["--direct", "--loss-factor", "0.02"], "given");
    assert!(err > 0.5, "{err:e}");
    assert!(!notes.contains("the deck's own"), "{notes}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nastran's `SDAMPING` selecting a `TABDMP1` (CRIT, 0.03 at every frequency) is the modes'
/// damping when `femu frf` is given none: the CELAS2 under a CONM2 measured as
/// `1 / (k - w^2 m + i 2 zeta w_n w m)` written by hand is reproduced to 1e-9 of its peak by modal
/// superposition, which says the damping is the deck's table; the direct route says the table
/// does not act there; `PARAM,G` beside the table is refused (Nastran adds the two, femu takes
/// one).
#[test]
fn frf_takes_the_decks_modal_damping_table() {
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-sdamping-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = "\
SOL 111
CEND
SPC = 1
SDAMPING = 4
BEGIN BULK
GRID,2,,0.,0.,0.
CELAS2,7,3.+4,2,3
CONM2,9,2,,10.
SPC1,1,12,2
TABDMP1,4,CRIT
,0.,0.03,100.,0.03,ENDT
ENDDATA
";
    std::fs::write(dir.join("spring.bdf"), deck).unwrap();
    let (k, zeta, m): (f64, f64, f64) = (3e4, 0.03, 10.0);
    let wn = (k / m).sqrt();
    let h = measured_oscillator(&dir, |w| (k - w * w * m, 2.0 * zeta * wn * w * m));
    let run = |deck: &str, extra: &[&str]| {
        femu()
            .args(["frf", dir.join(deck).to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(["--uff"])
            .arg(dir.join("model.uff"))
            .arg("--json")
            .arg(dir.join("frf.json"))
            .args(extra)
            .output()
            .unwrap()
    };
    let out = run("spring.bdf", &[]);
    succeeded(&out);
    let (peak, err) = file_deviation(&dir.join("model.uff"), &h);
    assert!(err < 1e-9 * peak, "{err:e} against {peak:e}");
    let notes = json_of(dir.join("frf.json"))["notes"].to_string();
    assert!(notes.contains("modal damping table"), "{notes}");
    let out = run("spring.bdf", &["--direct"]);
    succeeded(&out);
    let notes = json_of(dir.join("frf.json"))["notes"].to_string();
    assert!(notes.contains("not in the direct route"), "{notes}");
    std::fs::write(
        dir.join("both.bdf"),
        deck.replace("BEGIN BULK\n", "BEGIN BULK\nPARAM,G,0.02\n"),
    )
    .unwrap();
    let out = run("both.bdf", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("both a damping of the whole model (PARAM,G"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Modal damping as each mode's complex stiffness: Nastran's `PARAM,KDAMP,-1` with a `TABDMP1`
/// (CRIT, 0.01 at 0 Hz rising to 0.05 at 20 Hz) and Abaqus' `*MODAL DAMPING, STRUCTURAL` on a
/// spring under a mass. Measured as `1 / (k (1 + i g) - w^2 m)` written by hand, `g` twice the
/// table's ratio at the natural frequency (QRG PARAM,KDAMP: the viscous damping `g w_i m_i` goes
/// into the stiffness as `g`), or Abaqus' structural factor: femu frf reproduces it to 1e-9 of the
/// peak, where the same table as viscous damping (no KDAMP) is off by more than 1e-4 of it away
/// from resonance; femu modes --damped gives the mode the root `i w_n sqrt(1 + i g)` (damping
/// `-2 Re p / Im p`, to 1e-9); femu info says how each deck's modal damping acts.
#[test]
fn modal_damping_as_complex_stiffness() {
    let dir = std::env::temp_dir().join(format!("femu-cli-kdamp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (k, m): (f64, f64) = (3e4, 10.0);
    let wn = (k / m).sqrt();
    let fn_hz = wn / (2.0 * std::f64::consts::PI);
    // the table's ratio at the natural frequency, twice it the loss factor
    let g = 2.0 * (0.01 + (0.05 - 0.01) * fn_hz / 20.0);
    let nastran = |kdamp: &str| {
        format!(
            "SOL 111\nCEND\nSPC = 1\nSDAMPING = 4\nBEGIN BULK\n{kdamp}GRID,2,,0.,0.,0.\n\
             CELAS2,7,3.+4,2,3\nCONM2,9,2,,10.\nSPC1,1,12,2\nTABDMP1,4,CRIT\n,0.,0.01,20.,0.05,ENDT\nENDDATA\n"
        )
    };
    std::fs::write(dir.join("kdamp.bdf"), nastran("PARAM,KDAMP,-1\n")).unwrap();
    std::fs::write(dir.join("viscous.bdf"), nastran("")).unwrap();
    std::fs::write(
        dir.join("structural.inp"),
        abaqus_oscillator(&format!("*MODAL DAMPING, STRUCTURAL\n1, 1, {g}\n")),
    )
    .unwrap();
    let h = measured_oscillator(&dir, |w| (k - w * w * m, g * k));
    let frf = |deck: &str| oscillator_frf(&dir, deck, &h);
    for deck in ["kdamp.bdf", "structural.inp"] {
        let ((peak, err), notes) = frf(deck);
        assert!(err < 1e-9 * peak, "{deck}: {err:e} against {peak:e}");
        assert!(notes.contains("complex stiffness"), "{deck}: {notes}");
    }
    for (deck, says) in [
        ("kdamp.bdf", "as each mode's complex stiffness (KDAMP = -1)"),
        (
            "structural.inp",
            "structural damping factors: each mode's complex stiffness",
        ),
    ] {
        let out = femu()
            .args(["info", dir.join(deck).to_str().unwrap()])
            .output()
            .unwrap();
        succeeded(&out);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains(says), "{deck}: {stdout}");
    }
    let ((peak, err), notes) = frf("viscous.bdf");
    assert!(err > 1e-4 * peak, "{err:e} against {peak:e}");
    assert!(notes.contains("as viscous ratios"), "{notes}");
    // the damped mode: p = i w_n sqrt(1 + i g) = i w_n (a + i b)
    let a = ((1.0 + (1.0 + g * g).sqrt()) / 2.0).sqrt();
    let b = g / (2.0 * a);
    for deck in ["kdamp.bdf", "structural.inp"] {
        let json = dir.join("modes.json");
        let out = femu()
            .args(["modes", dir.join(deck).to_str().unwrap(), "--count", "1"])
            .args(["--damped", "--json", json.to_str().unwrap()])
            .output()
            .unwrap();
        succeeded(&out);
        let d = &json_of(&json)["damped"][0];
        let got = d["damping"].as_f64().unwrap();
        assert!((got - 2.0 * b / a).abs() < 1e-9, "{deck}: {d}");
        let f = d["frequency_hz"].as_f64().unwrap();
        assert!((f - fn_hz * a).abs() < 1e-9 * fn_hz, "{deck}: {d}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Abaqus' `*MODAL DAMPING, RAYLEIGH` by mode numbers: a spring under a mass whose one mode gets
/// `alpha M + beta K` (`1, 1, alpha, beta`), measured as `1 / (k - w^2 m + i w (alpha m + beta k))`
/// written by hand, is reproduced by femu frf to 1e-9 of the peak; the same line for mode 2 only
/// leaves the mode undamped, which the same measurement is then far from.
#[test]
fn modal_rayleigh_by_mode_numbers() {
    let dir = std::env::temp_dir().join(format!("femu-cli-rayleigh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (k, m, alpha, beta): (f64, f64, f64, f64) = (3e4, 10.0, 2.0, 1e-4);
    let deck = |range: &str| {
        abaqus_oscillator(&format!(
            "*MODAL DAMPING, RAYLEIGH\n{range}, {alpha}, {beta}\n"
        ))
    };
    std::fs::write(dir.join("first.inp"), deck("1, 1")).unwrap();
    std::fs::write(dir.join("second.inp"), deck("2, 2")).unwrap();
    let h = measured_oscillator(&dir, |w| (k - w * w * m, w * (alpha * m + beta * k)));
    let frf = |name: &str| oscillator_frf(&dir, name, &h);
    let ((peak, err), notes) = frf("first.inp");
    assert!(err < 1e-9 * peak, "{err:e} against {peak:e}");
    assert!(notes.contains("Rayleigh damping by mode number"), "{notes}");
    let ((peak, err), _) = frf("second.inp");
    assert!(err > 0.1 * peak, "{err:e} against {peak:e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 10-element C3D8 cantilever (`bar.inp`, element sets ROOT_HALF and TIP_HALF) and the same
/// with its root half 20 % softer (`softer.inp`, material SOFT), in a new folder named by `tag`;
/// `damping` (a `*DAMPING` line or nothing) is added to both halves' materials of the softer one,
/// 0.05 in the root half's when given. Returns the folder, the beam, its twelve response sensors
/// (ten z, two y) and the tip node (the force).
fn softer_halves(
    tag: &str,
    damping: &str,
) -> (std::path::PathBuf, Cantilever, Vec<(u64, i64)>, u64) {
    let nx = 10;
    let beam = Cantilever::new(nx, [0.4, 0.04, 0.02]);
    let sets = "*ELSET, ELSET=ROOT_HALF\n2, 3, 4, 5, 6\n*ELSET, ELSET=TIP_HALF\n7, 8, 9, 10, 11\n";
    let nominal = format!("{}{sets}", beam.deck("C3D8", 2.1e11));
    let soft_damping = if damping.is_empty() {
        ""
    } else {
        "*DAMPING, STRUCTURAL=0.05\n"
    };
    let softer = nominal.replace(
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n",
        &format!("{damping}*MATERIAL, NAME=SOFT\n*ELASTIC\n1.68e11, 0.3\n*DENSITY\n7850.\n{soft_damping}*SOLID SECTION, ELSET=ROOT_HALF, MATERIAL=SOFT\n*SOLID SECTION, ELSET=TIP_HALF, MATERIAL=STEEL\n"),
    );
    assert_ne!(softer, nominal);
    let dir = std::env::temp_dir().join(format!("femu-cli-frf-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), &nominal).unwrap();
    std::fs::write(dir.join("softer.inp"), &softer).unwrap();
    let tip = beam.id(nx, 0, 1) as u64;
    let mut outputs: Vec<(u64, i64)> = (1..=nx).map(|i| (beam.id(i, 0, 1) as u64, 3)).collect();
    outputs.push((beam.id(nx, 1, 0) as u64, 2));
    outputs.push((beam.id(nx / 2, 1, 1) as u64, 2));
    (dir, beam, outputs, tip)
}

/// `femu frf --update`: receptances "measured" by a dense direct solve on the cantilever whose
/// root half is 20 % softer (loss factor 0.02), at ten z and two y sensors under a force at the
/// tip, written as dataset 58; the nominal deck updated over its two halves from a loss factor of
/// 0.01 finds the root half (-0.2 to 1e-4), the tip half unchanged (1e-4), the loss factor 0.02
/// (1e-5), and the held-out lines' receptance error falls below 1e-4 of what it was; fitting
/// Rayleigh damping instead (`--rayleigh 1,1e-7`, which cannot equal a loss factor at every line)
/// still finds the root half within 0.01; the same measurement written as accelerance gives the
/// same update to 1e-6. Bad input: an unknown set (named), a response on a clamped DOF, damping
/// ratios with the update, one Rayleigh coefficient.
#[test]
fn frf_update_finds_the_softer_half() {
    let (dir, beam, outputs, tip) = softer_halves("update", "");
    let (min, step, count) = (5.0, 2.5, 360usize);
    let values = measured_receptances(&dir.join("softer.inp"), &outputs, tip, (min, step, count));
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    let frf = |extra: &[&str]| {
        femu()
            .args(["frf", dir.join("bar.inp").to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(extra)
            .output()
            .unwrap()
    };
    let json = dir.join("update.json");
    let out = frf(&[
        "--update",
        "ROOT_HALF,TIP_HALF",
        "--update-all",
        "--loss-factor",
        "0.01",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    succeeded(&out);
    assert!(
        stdout.contains("Updating from FRFs") && stdout.contains("better"),
        "{stdout}"
    );
    let v = json_of(&json);
    let u = &v["update"];
    let names: Vec<&str> = u["result"]["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let theta: Vec<f64> = u["result"]["theta"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_f64().unwrap())
        .collect();
    assert_eq!(names, ["k:ROOT_HALF", "k:TIP_HALF"]);
    assert!(
        (theta[0] + 0.2).abs() < 1e-4 && theta[1].abs() < 1e-4,
        "{theta:?}"
    );
    let eta = u["result"]["damping"]["loss_factor"].as_f64().unwrap();
    assert!((eta - 0.02).abs() < 1e-5, "{eta}");
    let held = u["held_out_error"].as_array().unwrap();
    let (before, after) = (held[0].as_f64().unwrap(), held[1].as_f64().unwrap());
    assert!(after < 1e-4 * before, "{before} -> {after}");
    // the ranking names the softer half first
    assert_eq!(u["ranking"][0]["name"], "ROOT_HALF", "{u}");
    // the same measurement as accelerance (-w^2 times each value, ordinate type 12): the same
    // update
    let mut acc = femu_io::uff::read_uff(dir.join("frf.uff")).unwrap();
    for f in &mut acc.functions {
        let x = f.abscissa_values();
        if let femu_io::uff::Ordinate::Complex(v) = &mut f.ordinate {
            for (value, hz) in v.iter_mut().zip(&x) {
                let w2 = (2.0 * std::f64::consts::PI * hz).powi(2);
                *value = (-w2 * value.0, -w2 * value.1);
            }
        }
        f.axes[1].data_type = 12;
    }
    femu_io::uff::write_uff(dir.join("accelerance.uff"), &acc).unwrap();
    let acc_json = dir.join("accelerance.json");
    let out = femu()
        .args(["frf", dir.join("bar.inp").to_str().unwrap()])
        .arg(dir.join("accelerance.uff"))
        .args([
            "--update",
            "ROOT_HALF,TIP_HALF",
            "--update-all",
            "--loss-factor",
            "0.01",
        ])
        .arg("--json")
        .arg(&acc_json)
        .output()
        .unwrap();
    succeeded(&out);
    let a = json_of(&acc_json);
    assert_eq!(a["kind"], "accelerance");
    for (k, t) in theta.iter().enumerate() {
        let ta = a["update"]["result"]["theta"][k].as_f64().unwrap();
        assert!((ta - t).abs() < 1e-6, "{ta} {t}");
    }
    // Rayleigh damping fitted instead (it cannot be the measured loss factor at every line):
    // reported as such, the softer half still found
    let rayleigh = dir.join("rayleigh.json");
    let out = frf(&[
        "--update",
        "ROOT_HALF,TIP_HALF",
        "--update-all",
        "--rayleigh",
        "1,1e-7",
        "--json",
        rayleigh.to_str().unwrap(),
    ]);
    succeeded(&out);
    let r = &json_of(&rayleigh)["update"]["result"];
    assert!(
        r["damping"]["rayleigh"]["alpha"].as_f64().unwrap() >= 0.0,
        "{r}"
    );
    let root = r["theta"][0].as_f64().unwrap();
    assert!((root + 0.2).abs() < 0.01, "{r}");
    // Rayleigh damping takes two coefficients
    let out = frf(&["--rayleigh", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("two coefficients"),
        "{stderr}"
    );
    // bad input
    let out = frf(&["--update", "ROOT_HALF,NOPE"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("NOPE"), "{stderr}");
    let out = frf(&["--update", "ROOT_HALF", "--damping-ratio", "0.01"]);
    assert!(!out.status.success());
    let mut clamped = outputs.clone();
    clamped.push((beam.id(0, 0, 0) as u64, 3));
    let mut with_root = values.clone();
    with_root.push(values[0].clone());
    write_frf_uff(&dir.join("root.uff"), &clamped, tip, min, step, &with_root);
    let out = femu()
        .args(["frf", dir.join("bar.inp").to_str().unwrap()])
        .arg(dir.join("root.uff"))
        .args(["--update", "ROOT_HALF"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("clamps") && stderr.contains("root.uff"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu frf --update ... --loss-factor-per-set`: the cantilever whose root half is 20 % softer
/// and whose materials damp differently (`*DAMPING, STRUCTURAL=0.05` in the root half's, 0.01 in
/// the tip half's), "measured" by a dense direct solve of `(K + i K_4 - w^2 M) u = f` with the
/// deck's `K_4 = sum_e GE_e K_e`; the nominal deck, without damping, updated over its two halves
/// from a loss factor of 0.02 for each finds the root half (-0.2 to 1e-4), the tip half unchanged
/// (1e-4) and each half's loss factor (1e-5), and the held-out lines' error falls below 1e-4 of
/// what it was. With one loss factor for the whole beam the fit cannot reproduce the lines.
/// Rayleigh coefficients with the flag are refused. The nominal deck with its material damped
/// (`*DAMPING, STRUCTURAL=0.02`), updated with no damping option, fits a loss factor per set from
/// the deck's values to the same result; `--loss-factor` beside the deck's damping is refused, and
/// so is a material's Rayleigh damping (`*DAMPING, ALPHA=`), which updating does not model.
#[test]
fn frf_update_fits_a_loss_factor_per_set() {
    let (dir, _, outputs, tip) = softer_halves("per-set", "*DAMPING, STRUCTURAL=0.01\n");
    let (min, step, count) = (5.0, 2.5, 360usize);
    let (model, sys, k, m) = dense_deck(&dir.join("softer.inp"));
    let asm = femu_fem::assembly::Assembler::new(&model).unwrap();
    let k4 = femu_sparse::csc::to_dense(
        &asm.dampers(&model, femu_fem::assembly::MassKind::Consistent)
            .unwrap()
            .structural
            .unwrap(),
    );
    let free = |node: u64, c: usize| {
        sys.dofs
            .free_index(model.mesh().node_index(node).unwrap(), c)
            .unwrap()
    };
    let out_free: Vec<usize> = outputs
        .iter()
        .map(|(node, d)| free(*node, (*d - 1) as usize))
        .collect();
    let values = direct_frfs(&k, &m, &out_free, free(tip, 2), min, step, count, |_| {
        k4.clone()
    });
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    let frf = |extra: &[&str], json: &std::path::Path| {
        let out = femu()
            .args(["frf", dir.join("bar.inp").to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(["--update", "ROOT_HALF,TIP_HALF", "--update-all"])
            .args(extra)
            .arg("--json")
            .arg(json)
            .output()
            .unwrap();
        (out, json.to_path_buf())
    };
    let (out, json) = frf(
        &["--loss-factor", "0.02", "--loss-factor-per-set"],
        &dir.join("per_set.json"),
    );
    succeeded(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("loss factor of ROOT_HALF"), "{stdout}");
    let u = &json_of(&json)["update"];
    let r = &u["result"];
    let theta: Vec<f64> = (0..2).map(|k| r["theta"][k].as_f64().unwrap()).collect();
    assert!(
        (theta[0] + 0.2).abs() < 1e-4 && theta[1].abs() < 1e-4,
        "{theta:?}"
    );
    let per = &r["damping"]["group_loss_factors"]["groups"];
    let etas: Vec<f64> = (0..2).map(|k| per[k].as_f64().unwrap()).collect();
    assert!(
        (etas[0] - 0.05).abs() < 1e-5 && (etas[1] - 0.01).abs() < 1e-5,
        "{r}"
    );
    let held = u["held_out_error"].as_array().unwrap();
    let (before, after) = (held[0].as_f64().unwrap(), held[1].as_f64().unwrap());
    assert!(after < 1e-4 * before, "{before} -> {after}");
    // one loss factor for the whole beam: the lines are not reproduced
    let (out, json) = frf(&["--loss-factor", "0.02"], &dir.join("one.json"));
    succeeded(&out);
    let one = json_of(&json)["update"]["held_out_error"][1]
        .as_f64()
        .unwrap();
    assert!(
        one > 100.0 * after,
        "one loss factor {one}, per set {after}"
    );
    // Rayleigh damping is not a loss factor per set
    let (out, _) = frf(
        &["--rayleigh", "1,1e-7", "--loss-factor-per-set"],
        &dir.join("bad.json"),
    );
    assert!(!out.status.success());
    // the engineer's deck damps its material (0.02): updated with no damping option, a loss
    // factor per set started from the deck's, the same result
    let damped = std::fs::read_to_string(dir.join("bar.inp"))
        .unwrap()
        .replace(
            "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n",
            "*DAMPING, STRUCTURAL=0.02\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n",
        );
    std::fs::write(dir.join("damped.inp"), damped).unwrap();
    let from_deck = |extra: &[&str]| {
        femu()
            .args(["frf", dir.join("damped.inp").to_str().unwrap()])
            .arg(dir.join("frf.uff"))
            .args(["--update", "ROOT_HALF,TIP_HALF", "--update-all"])
            .args(extra)
            .output()
            .unwrap()
    };
    let deck_json = dir.join("deck.json");
    let out = from_deck(&["--json", deck_json.to_str().unwrap()]);
    succeeded(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("started from the deck's"), "{stderr}");
    let r = &json_of(&deck_json)["update"]["result"];
    let per = &r["damping"]["group_loss_factors"]["groups"];
    assert!(
        (r["theta"][0].as_f64().unwrap() + 0.2).abs() < 1e-4
            && (per[0].as_f64().unwrap() - 0.05).abs() < 1e-5
            && (per[1].as_f64().unwrap() - 0.01).abs() < 1e-5,
        "{r}"
    );
    // a loss factor for the whole model would replace the deck's damping: refused
    let out = from_deck(&["--loss-factor", "0.02"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("materials damp their elements"),
        "{stderr}"
    );
    // a material's Rayleigh damping, which updating does not model: refused
    let rayleigh = std::fs::read_to_string(dir.join("damped.inp"))
        .unwrap()
        .replace("*DAMPING, STRUCTURAL=0.02\n", "*DAMPING, ALPHA=2.\n");
    std::fs::write(dir.join("damped.inp"), rayleigh).unwrap();
    let out = from_deck(&[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("Rayleigh damping (*DAMPING, ALPHA="),
        "{stderr}"
    );
    eprintln!("held-out error: per set {before:.3e} -> {after:.3e}, one loss factor {one:.3e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Coherence (dataset 58, function type 6) in the file: the clamped bar's receptances by a dense
/// solve, one function corrupted (its values turned by +90 and -90 degrees on alternate lines) over
/// the band of its 40 largest values (the first resonance), where its coherence is written as 0.3
/// (0.99 elsewhere).
/// With the default threshold (0.8) those lines are left out of its FRAC and the line's CSAC and
/// the FRAC is above 0.999, as for the clean functions; with `--min-coherence 0` the corrupted
/// lines count and it falls below 0.9. A coherence above 1, a threshold outside [0, 1], lines
/// out of order (naming the function and the line) and a NaN value (the file's line) are refused.
#[test]
fn frf_lines_of_low_coherence_are_left_out() {
    use femu_io::uff::Ordinate;
    let nx = 10;
    let beam = Cantilever::new(nx, [0.4, 0.04, 0.02]);
    let dir = std::env::temp_dir().join(format!("femu-cli-coherence-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), beam.deck("C3D8", 2.1e11)).unwrap();
    let tip = beam.id(nx, 0, 1) as u64;
    let outputs = [
        (tip, 3i64),
        (beam.id(nx / 2, 0, 1) as u64, 3),
        (beam.id(nx / 2, 1, 1) as u64, 3),
    ];
    let (min, step, count) = (5.0, 2.5, 200usize);
    let mut values = measured_receptances(&dir.join("bar.inp"), &outputs, tip, (min, step, count));
    // the band around the first resonance: its 40 lines of largest response
    let mut order: Vec<usize> = (0..count).collect();
    order.sort_by(|a, b| {
        let h = |l: usize| values[1][l].0.hypot(values[1][l].1);
        h(*b).total_cmp(&h(*a))
    });
    let band: Vec<usize> = order[..40].to_vec();
    for &l in &band {
        // turned by +-90 degrees on alternate lines: the band's contribution to the FRAC's
        // numerator cancels
        let (re, im) = values[1][l];
        let s = if l % 2 == 0 { 1.0 } else { -1.0 };
        values[1][l] = (-s * im, s * re);
    }
    write_frf_uff(&dir.join("frf.uff"), &outputs, tip, min, step, &values);
    let uff = femu_io::uff::read_uff(dir.join("frf.uff")).unwrap();
    let with_coherence = |bad: f64| {
        let mut u = uff.clone();
        let extra: Vec<_> = u
            .functions
            .iter()
            .enumerate()
            .map(|(o, f)| {
                let mut c = f.clone();
                c.function_type = 6;
                c.numbers[0] += 10;
                c.ids[0] = format!("coherence {o}");
                c.axes[1].data_type = 0;
                c.ordinate = Ordinate::Real(
                    (0..count)
                        .map(|l| {
                            if o == 1 && band.contains(&l) {
                                bad
                            } else {
                                0.99
                            }
                        })
                        .collect(),
                );
                c
            })
            .collect();
        u.functions.extend(extra);
        u
    };
    femu_io::uff::write_uff(dir.join("coherent.uff"), &with_coherence(0.3)).unwrap();
    let run = |file: &str, extra: &[&str]| {
        femu()
            .args(["frf", dir.join("bar.inp").to_str().unwrap()])
            .arg(dir.join(file))
            .args(["--loss-factor", "0.02", "--quiet"])
            .args(extra)
            .output()
            .unwrap()
    };
    let fracs = |extra: &[&str], json: &str| {
        let out = run(
            "coherent.uff",
            &[extra, &["--json", dir.join(json).to_str().unwrap()]].concat(),
        );
        succeeded(&out);
        let v = json_of(dir.join(json));
        v["functions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                (
                    f["frac"].as_f64().unwrap(),
                    f["low_coherence_lines"].as_u64().unwrap(),
                )
            })
            .collect::<Vec<_>>()
    };
    let kept = fracs(&[], "kept.json");
    assert!(kept.iter().all(|(f, _)| *f > 0.999), "{kept:?}");
    assert_eq!(kept.iter().map(|k| k.1).collect::<Vec<_>>(), [0, 40, 0]);
    let all = fracs(&["--min-coherence", "0"], "all.json");
    assert!(all[1].0 < 0.9 && all[1].1 == 0, "{all:?}");
    // bad input
    femu_io::uff::write_uff(dir.join("above.uff"), &with_coherence(1.5)).unwrap();
    let out = run("above.uff", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("between 0 and 1"),
        "{stderr}"
    );
    // lines out of order, and a value that is not a number
    let mut unsorted = uff.clone();
    for f in &mut unsorted.functions {
        let mut x = f.abscissa_values();
        x.swap(3, 4);
        f.abscissa = femu_io::uff::Abscissa::Uneven(x);
    }
    femu_io::uff::write_uff(dir.join("unsorted.uff"), &unsorted).unwrap();
    let out = run("unsorted.uff", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("line 5") && stderr.contains("increasing"),
        "{stderr}"
    );
    let mut nan = uff.clone();
    if let Ordinate::Complex(v) = &mut nan.functions[2].ordinate {
        v[7].1 = f64::NAN;
    }
    femu_io::uff::write_uff(dir.join("nan.uff"), &nan).unwrap();
    let out = run("nan.uff", &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("nan.uff:") && stderr.contains("not a finite"),
        "{stderr}"
    );
    let out = run("coherent.uff", &["--min-coherence", "2"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("between 0 and 1"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shells from a Gmsh mesh: NAFEMS FV16 (a 10 m square plate, 0.05 m thick, E = 200 GPa,
/// nu = 0.3, rho = 8000, one edge clamped) as 16 x 16 quadrangles in a physical surface "plate"
/// with the clamped edge a physical curve "edge", made shells by `--shell plate=0.05`: the six
/// frequencies equal those of the same plate as a Nastran deck of CQUAD4 (PSHELL with MID3,
/// coupled mass) to 1e-9, and NAFEMS' 0.421, 1.029, 2.582, 3.306, 3.753, 6.555 Hz to 1 %; the
/// same mesh cut into triangles to 1 % too (32 x 32 x 2), and as 8 x 8 8-node quadrangles (Gmsh
/// type 16) equal to the plate as a deck of CQUAD8 to 1e-8 and NAFEMS' frequencies to 1 %.
/// Refused: no `--shell` (the surface groups named), a group that is not a surface group, a
/// thickness of 0, a 9-node quadrangle.
#[test]
fn gmsh_surfaces_as_shells() {
    let dir = std::env::temp_dir().join(format!("femu-cli-gmsh-shells-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let node = |n: usize, i: usize, j: usize| 1 + i + (n + 1) * j;
    let msh = |n: usize, triangles: bool, quadratic_one: bool| {
        let mut s = String::from(
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 2 \"edge\"\n2 1 \"plate\"\n$EndPhysicalNames\n",
        );
        s.push_str(&format!("$Nodes\n{}\n", (n + 1) * (n + 1)));
        for j in 0..=n {
            for i in 0..=n {
                s.push_str(&format!(
                    "{} {:e} {:e} 0\n",
                    node(n, i, j),
                    10.0 * i as f64 / n as f64,
                    10.0 * j as f64 / n as f64
                ));
            }
        }
        let mut elements = Vec::new();
        for j in 0..n {
            elements.push(format!("1 2 2 2 {} {}", node(n, 0, j), node(n, 0, j + 1)));
        }
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (
                    node(n, i, j),
                    node(n, i + 1, j),
                    node(n, i + 1, j + 1),
                    node(n, i, j + 1),
                );
                if triangles {
                    elements.push(format!("2 2 1 1 {a} {b} {c}"));
                    elements.push(format!("2 2 1 1 {a} {c} {d}"));
                } else if quadratic_one && i == 0 && j == 0 {
                    // a 9-node quadrangle's type with its corners repeated: refused by type
                    elements.push(format!("10 2 1 1 {a} {b} {c} {d} {a} {b} {c} {d} {a}"));
                } else {
                    elements.push(format!("3 2 1 1 {a} {b} {c} {d}"));
                }
            }
        }
        s.push_str(&format!("$EndNodes\n$Elements\n{}\n", elements.len()));
        for (k, e) in elements.iter().enumerate() {
            s.push_str(&format!("{} {e}\n", k + 1));
        }
        s.push_str("$EndElements\n");
        s
    };
    std::fs::write(dir.join("quads.msh"), msh(16, false, false)).unwrap();
    std::fs::write(dir.join("triangles.msh"), msh(32, true, false)).unwrap();
    std::fs::write(dir.join("quadratic.msh"), msh(16, false, true)).unwrap();
    // the same plate as a Nastran deck (its element ids the .msh's: edges come first there)
    let n = 16;
    let mut bdf = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    for j in 0..=n {
        for i in 0..=n {
            bdf.push_str(&format!(
                "GRID,{},,{},{},0.\n",
                node(n, i, j),
                10.0 * i as f64 / n as f64,
                10.0 * j as f64 / n as f64
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            bdf.push_str(&format!(
                "CQUAD4,{},7,{},{},{},{}\n",
                n + 1 + i + n * j,
                node(n, i, j),
                node(n, i + 1, j),
                node(n, i + 1, j + 1),
                node(n, i, j + 1)
            ));
        }
    }
    bdf.push_str("PSHELL,7,3,0.05,3,,3\nMAT1,3,2.+11,,0.3,8000.\n");
    for j in 0..=n {
        bdf.push_str(&format!("SPC1,1,123456,{}\n", node(n, 0, j)));
    }
    bdf.push_str("ENDDATA\n");
    std::fs::write(dir.join("fv16.bdf"), bdf).unwrap();
    // femu info names the groups a section can make shells or beams of
    let info = femu()
        .args(["info", dir.join("quads.msh").to_str().unwrap()])
        .output()
        .unwrap();
    let info = String::from_utf8_lossy(&info.stdout);
    for line in [
        "surface group plate: 256 4-node quadrangles (type 3) (its nodes a set; shells with --shell plate=THICKNESS)",
        "line group edge: 16 2-node lines (type 1) (its nodes a set; beams with --beam edge=rect:A,B)",
    ] {
        assert!(info.contains(line), "{info}");
    }
    let material = ["--young", "2e11", "--poisson", "0.3", "--density", "8000"];
    let modes = |file: &str, extra: &[&str], json: &str| {
        let out = femu()
            .args(["modes", dir.join(file).to_str().unwrap(), "--count", "6"])
            .args(extra)
            .args(["--json", dir.join(json).to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        (out, dir.join(json))
    };
    let freqs = |json: &std::path::Path| -> Vec<f64> {
        json_of(json)["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_f64().unwrap())
            .collect()
    };
    let shell = [&material[..], &["--shell", "plate=0.05", "--fix", "edge"]].concat();
    let (out, json) = modes("quads.msh", &shell, "quads.json");
    succeeded(&out);
    let from_msh = freqs(&json);
    let (out, json) = modes("fv16.bdf", &[], "bdf.json");
    succeeded(&out);
    let from_bdf = freqs(&json);
    let (out, json) = modes("triangles.msh", &shell, "triangles.json");
    succeeded(&out);
    let triangles = freqs(&json);
    let nafems = [0.421, 1.029, 2.582, 3.306, 3.753, 6.555];
    for k in 0..6 {
        assert!(
            (from_msh[k] / from_bdf[k] - 1.0).abs() < 1e-9,
            "mode {}: {from_msh:?} {from_bdf:?}",
            k + 1
        );
        assert!(
            (from_msh[k] / nafems[k] - 1.0).abs() < 0.01,
            "mode {}: {from_msh:?}",
            k + 1
        );
        assert!(
            (triangles[k] / nafems[k] - 1.0).abs() < 0.01,
            "mode {}: {triangles:?}",
            k + 1
        );
    }
    // bad input
    let refused = |file: &str, extra: &[&str], what: &[&str]| {
        let (out, _) = modes(file, extra, "bad.json");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{extra:?}");
        for w in what {
            assert!(stderr.contains(w), "{extra:?}: {stderr}");
        }
    };
    refused("quads.msh", &material, &["--shell", "plate"]);
    refused(
        "quads.msh",
        &[&material[..], &["--shell", "edge=0.05"]].concat(),
        &["no physical group of surfaces edge", "plate"],
    );
    refused(
        "quads.msh",
        &[&material[..], &["--shell", "plate=0"]].concat(),
        &["positive"],
    );
    refused(
        "quads.msh",
        &[&material[..], &["--shell", "plate"]].concat(),
        &["GROUP=THICKNESS"],
    );
    refused("quadratic.msh", &shell, &["type 10", "line"]);
    // 8-node quadrangles (type 16: corners, then the midsides of edges 1-2, 2-3, 3-4, 4-1), 8 x 8,
    // against the same plate as a Nastran deck of CQUAD8 and against NAFEMS
    let n = 8;
    let id = |i: usize, j: usize| 1 + i + (2 * n + 1) * j;
    let points: Vec<(usize, f64, f64)> = (0..=2 * n)
        .flat_map(|j| (0..=2 * n).map(move |i| (i, j)))
        .filter(|(i, j)| i % 2 == 0 || j % 2 == 0)
        .map(|(i, j)| {
            (
                id(i, j),
                5.0 * i as f64 / n as f64,
                5.0 * j as f64 / n as f64,
            )
        })
        .collect();
    let quads: Vec<[usize; 8]> = (0..n)
        .flat_map(|j| (0..n).map(move |i| (2 * i, 2 * j)))
        .map(|(a, b)| {
            [
                id(a, b),
                id(a + 2, b),
                id(a + 2, b + 2),
                id(a, b + 2),
                id(a + 1, b),
                id(a + 2, b + 1),
                id(a + 1, b + 2),
                id(a, b + 1),
            ]
        })
        .collect();
    let mut msh8 = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 2 \"edge\"\n2 1 \"plate\"\n$EndPhysicalNames\n",
    );
    msh8.push_str(&format!("$Nodes\n{}\n", points.len()));
    for (k, x, y) in &points {
        msh8.push_str(&format!("{k} {x:e} {y:e} 0\n"));
    }
    msh8.push_str(&format!("$EndNodes\n$Elements\n{}\n", 2 * n + quads.len()));
    for j in 0..2 * n {
        msh8.push_str(&format!(
            "{} 1 2 2 2 {} {}\n",
            j + 1,
            id(0, j),
            id(0, j + 1)
        ));
    }
    let mut bdf8 = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    for (k, x, y) in &points {
        bdf8.push_str(&format!("GRID,{k},,{x},{y},0.\n"));
    }
    for (e, q) in quads.iter().enumerate() {
        let g: Vec<String> = q.iter().map(ToString::to_string).collect();
        msh8.push_str(&format!("{} 16 2 1 1 {}\n", 2 * n + e + 1, g.join(" ")));
        bdf8.push_str(&format!(
            "CQUAD8,{},7,{}\n,{}\n",
            2 * n + e + 1,
            g[..6].join(","),
            g[6..].join(",")
        ));
    }
    msh8.push_str("$EndElements\n");
    bdf8.push_str("PSHELL,7,3,0.05,3,,3\nMAT1,3,2.+11,,0.3,8000.\n");
    for j in 0..=2 * n {
        bdf8.push_str(&format!("SPC1,1,123456,{}\n", id(0, j)));
    }
    bdf8.push_str("ENDDATA\n");
    std::fs::write(dir.join("quads8.msh"), msh8).unwrap();
    std::fs::write(dir.join("fv16_8.bdf"), bdf8).unwrap();
    let (out, json) = modes("quads8.msh", &shell, "quads8.json");
    succeeded(&out);
    let from_msh = freqs(&json);
    let (out, json) = modes("fv16_8.bdf", &[], "bdf8.json");
    succeeded(&out);
    let info = femu()
        .args(["info", dir.join("fv16_8.bdf").to_str().unwrap()])
        .output()
        .unwrap();
    let info = String::from_utf8_lossy(&info.stdout);
    assert!(info.contains("shells: 64 of 8 nodes"), "{info}");
    let from_bdf = freqs(&json);
    // (the two models number their DOFs differently: the eigensolver's convergence, not the
    // models, sets the agreement, 2e-9 measured)
    for k in 0..6 {
        assert!(
            (from_msh[k] / from_bdf[k] - 1.0).abs() < 1e-8,
            "mode {}: {from_msh:?} {from_bdf:?}",
            k + 1
        );
        assert!(
            (from_msh[k] / nafems[k] - 1.0).abs() < 0.01,
            "mode {}: {from_msh:?}",
            k + 1
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The 1 m steel cantilever of a RECT 0.02 x 0.04 section read two ways: the four lowest
/// frequencies equal to 1e-9, and the first Euler-Bernoulli's, `1.8751^2 / (2 pi) sqrt(E I / (rho
/// A L^4))` with the smaller `I = 0.04 0.02^3 / 12`, to 0.1 % (a slender beam: L/h = 50).
fn steel_cantilever_frequencies(from_msh: &[f64], from_inp: &[f64]) {
    for k in 0..4 {
        assert!(
            (from_msh[k] / from_inp[k] - 1.0).abs() < 1e-9,
            "{from_msh:?} {from_inp:?}"
        );
    }
    let (e, rho, a, i) = (2.1e11, 7850.0, 0.02 * 0.04, 0.04 * 0.02f64.powi(3) / 12.0);
    let f1 = 1.8751f64.powi(2) / (2.0 * std::f64::consts::PI) * (e * i / (rho * a)).sqrt();
    assert!(
        (from_msh[0] / f1 - 1.0).abs() < 1e-3,
        "{} {f1}",
        from_msh[0]
    );
}

/// Three-node beams from a Gmsh mesh and an Abaqus deck: a 1 m steel cantilever along x as 10
/// three-node lines (Gmsh type 8: ends, then middle) made beams by `--beam frame=rect:0.02,0.04`
/// has the four lowest frequencies of the same beam read as B32 (nodes end, middle, end) to 1e-9,
/// the first Euler-Bernoulli's to 0.1 %, and the VTU written of it holds ten quadratic edges (VTK
/// type 21) on the ends and middle nodes in that order.
#[test]
fn gmsh_three_node_lines_and_b32_are_one_beam() {
    let dir = std::env::temp_dir().join(format!("femu-cli-gmsh-b32-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = 10;
    let mut msh = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n0 1 \"root\"\n1 2 \"frame\"\n$EndPhysicalNames\n",
    );
    msh.push_str(&format!("$Nodes\n{}\n", 2 * n + 1));
    let mut inp = String::from("*NODE\n");
    for i in 0..=2 * n {
        let x = i as f64 / (2 * n) as f64;
        msh.push_str(&format!("{} {x:e} 0 0\n", i + 1));
        inp.push_str(&format!("{}, {x:e}, 0., 0.\n", i + 1));
    }
    msh.push_str(&format!("$EndNodes\n$Elements\n{}\n1 15 2 1 1 1\n", n + 1));
    inp.push_str("*ELEMENT, TYPE=B32, ELSET=FRAME\n");
    for e in 0..n {
        let (a, m, b) = (2 * e + 1, 2 * e + 2, 2 * e + 3);
        msh.push_str(&format!("{} 8 2 2 2 {a} {b} {m}\n", e + 2));
        inp.push_str(&format!("{}, {a}, {m}, {b}\n", e + 2));
    }
    msh.push_str("$EndElements\n");
    inp.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *BEAM SECTION, ELSET=FRAME, MATERIAL=STEEL, SECTION=RECT\n0.02, 0.04\n0., 0., -1.\n\
         *BOUNDARY\n1, 1, 6\n",
    );
    std::fs::write(dir.join("beam.msh"), msh).unwrap();
    std::fs::write(dir.join("beam.inp"), inp).unwrap();
    let run = |file: &str, extra: &[&str]| {
        let json = dir.join(format!("{file}.json"));
        let out = femu()
            .args(["modes", dir.join(file).to_str().unwrap(), "--count", "4"])
            .args(extra)
            .args(["--json", json.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        succeeded(&out);
        json_of(&json)["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_f64().unwrap())
            .collect::<Vec<f64>>()
    };
    let vtu = dir.join("beam.vtu");
    let from_msh = run(
        "beam.msh",
        &[
            "--young",
            "2.1e11",
            "--poisson",
            "0.3",
            "--density",
            "7850",
            "--beam",
            "frame=rect:0.02,0.04",
            "--fix",
            "root",
            "--vtu",
            vtu.to_str().unwrap(),
        ],
    );
    let from_inp = run("beam.inp", &[]);
    steel_cantilever_frequencies(&from_msh, &from_inp);
    let text = std::fs::read_to_string(&vtu).unwrap();
    let types = text.split("Name=\"types\"").nth(1).unwrap();
    let types: Vec<&str> = types
        .split('>')
        .nth(1)
        .unwrap()
        .split('<')
        .next()
        .unwrap()
        .split_whitespace()
        .collect();
    assert_eq!(types, vec!["21"; n], "{types:?}");
    // the first edge: nodes 1, 3 and 2 (0-based 0, 2, 1)
    assert!(text.contains("\n0 2 1\n"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Beams from a Gmsh mesh: a 1 m steel cantilever along x as 20 two-node lines in a physical
/// curve "frame", clamped at a physical point "root", made beams by `--beam frame=rect:0.02,0.04`
/// (Abaqus' RECT: 0.02 along the section's 1-axis, n1 = (0, 0, -1) by default): the four lowest
/// frequencies equal those of the same beam read as an Abaqus deck of B31 with `*BEAM SECTION,
/// SECTION=RECT` to 1e-9, and the first is Euler-Bernoulli's `1.8751^2 / (2 pi) sqrt(E I / (rho
/// A L^4))` with the smaller `I = 0.04 0.02^3 / 12` to 0.1 % (a slender beam: L/h = 50). Refused:
/// a shape femu does not read, a wrong count of dimensions, no `=`, a group of points, and a beam
/// along z with the default n1 (its id named); with `@1,0,0` the vertical beam has the
/// horizontal one's frequencies to 1e-9.
#[test]
fn gmsh_lines_as_beams() {
    let dir = std::env::temp_dir().join(format!("femu-cli-gmsh-beams-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = 20;
    let msh = |axis: usize| {
        let mut s = String::from(
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n0 1 \"root\"\n1 2 \"frame\"\n$EndPhysicalNames\n",
        );
        s.push_str(&format!("$Nodes\n{}\n", n + 1));
        for i in 0..=n {
            let mut x = [0.0; 3];
            x[axis] = i as f64 / n as f64;
            s.push_str(&format!("{} {:e} {:e} {:e}\n", i + 1, x[0], x[1], x[2]));
        }
        s.push_str(&format!("$EndNodes\n$Elements\n{}\n1 15 2 1 1 1\n", n + 1));
        for i in 0..n {
            s.push_str(&format!("{} 1 2 2 2 {} {}\n", i + 2, i + 1, i + 2));
        }
        s.push_str("$EndElements\n");
        s
    };
    std::fs::write(dir.join("beam.msh"), msh(0)).unwrap();
    std::fs::write(dir.join("vertical.msh"), msh(2)).unwrap();
    let mut inp = String::from("*NODE\n");
    for i in 0..=n {
        inp.push_str(&format!("{}, {:e}, 0., 0.\n", i + 1, i as f64 / n as f64));
    }
    inp.push_str("*ELEMENT, TYPE=B31, ELSET=FRAME\n");
    for i in 0..n {
        inp.push_str(&format!("{}, {}, {}\n", i + 2, i + 1, i + 2));
    }
    inp.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n\
         *BEAM SECTION, ELSET=FRAME, MATERIAL=STEEL, SECTION=RECT\n0.02, 0.04\n0., 0., -1.\n\
         *BOUNDARY\n1, 1, 6\n",
    );
    std::fs::write(dir.join("beam.inp"), inp).unwrap();
    let material = ["--young", "2.1e11", "--poisson", "0.3", "--density", "7850"];
    let modes = |file: &str, extra: &[&str]| {
        let json = dir.join(format!("{file}.json"));
        let out = femu()
            .args(["modes", dir.join(file).to_str().unwrap(), "--count", "4"])
            .args(extra)
            .args(["--json", json.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        (out, json)
    };
    let freqs = |json: &std::path::Path| -> Vec<f64> {
        json_of(json)["frequencies_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_f64().unwrap())
            .collect()
    };
    let beam = [
        &material[..],
        &["--beam", "frame=rect:0.02,0.04", "--fix", "root"],
    ]
    .concat();
    let (out, json) = modes("beam.msh", &beam);
    succeeded(&out);
    let from_msh = freqs(&json);
    let (out, json) = modes("beam.inp", &[]);
    succeeded(&out);
    let from_inp = freqs(&json);
    steel_cantilever_frequencies(&from_msh, &from_inp);
    let refused = |file: &str, section: &str, what: &str| {
        let args = [&material[..], &["--beam", section, "--fix", "root"]].concat();
        let (out, _) = modes(file, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(what),
            "{section}: {stderr}"
        );
    };
    refused("beam.msh", "frame=ibeam:0.1,0.2", "RECT, CIRC and PIPE");
    refused("beam.msh", "frame=rect:0.02", "needs 2 positive");
    refused("beam.msh", "frame", "GROUP=SECTION");
    refused(
        "beam.msh",
        "root=rect:0.02,0.04",
        "no physical group of lines root",
    );
    refused(
        "vertical.msh",
        "frame=rect:0.02,0.04",
        "element 2: its orientation vector",
    );
    // with n1 given across the axis, the vertical beam is the horizontal one turned
    let args = [
        &material[..],
        &["--beam", "frame=rect:0.02,0.04@1,0,0", "--fix", "root"],
    ]
    .concat();
    let (out, json) = modes("vertical.msh", &args);
    succeeded(&out);
    let vertical = freqs(&json);
    for k in 0..4 {
        assert!(
            (vertical[k] / from_inp[k] - 1.0).abs() < 1e-9,
            "{vertical:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu modes --damped`: the complex modes of a deck's damping. A cantilevered plate of CQUAD4
/// whose two halves' MAT1 have `GE` 0.06 (clamped half) and 0.01: each damped mode's damping
/// coefficient lies between the two and they differ from mode to mode; with both `GE` 0.03 the
/// damping is proportional (`K_4 = 0.03 K`): every mode is real (an MPC of 1) to 1e-9 with the
/// root `p = i omega sqrt(1 + 0.03 i)` of its real mode's `omega`, computed here (frequency `Im p
/// / 2 pi`, damping `-2 Re p / Im p`, to 1e-9). The two-hex deck with Rayleigh damping, alpha 2
/// s^-1 and beta 1e-6 s, of its modes (`*MODAL DAMPING, RAYLEIGH`) or of its material (`*DAMPING,
/// ALPHA=, BETA=` in the `*MATERIAL`: `alpha M_e + beta K_e` of each element), and the plate with
/// Nastran's `PARAM,ALPHA1` and `ALPHA2` of the same values, keep their real modes with the ratio
/// `alpha / (2 omega) + beta omega / 2` of each (to 1e-9). A deck without damping
/// is refused with the reason.
#[test]
fn modes_damped_reports_the_complex_modes() {
    let dir = std::env::temp_dir().join(format!("femu-cli-damped-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = 8;
    let deck =
        |ge1: &str, ge2: &str, extra: &str| femu_testkit::damped_plate_deck(n, ge1, ge2, extra);
    let run = |name: &str, text: String| {
        std::fs::write(dir.join(name), text).unwrap();
        let json = dir.join(format!("{name}.json"));
        let out = femu()
            .args(["modes", dir.join(name).to_str().unwrap(), "--count", "6"])
            .args(["--damped", "--json", json.to_str().unwrap()])
            .output()
            .unwrap();
        (out, json)
    };
    let (out, json) = run("mixed.bdf", deck("0.06", "0.01", ""));
    succeeded(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("Damped modes") && stdout.contains("damping g"),
        "{stdout}"
    );
    let v = json_of(&json);
    let damped = v["damped"].as_array().unwrap();
    assert_eq!(damped.len(), 6);
    let g: Vec<f64> = damped
        .iter()
        .map(|d| d["damping"].as_f64().unwrap())
        .collect();
    assert!(g.iter().all(|e| *e > 0.01 && *e < 0.06), "{g:?}");
    assert!(
        g.iter().fold(0.0f64, |m, e| m.max(*e)) - g.iter().fold(1.0f64, |m, e| m.min(*e)) > 1e-3,
        "{g:?}"
    );
    let (out, json) = run("uniform.bdf", deck("0.03", "0.03", ""));
    succeeded(&out);
    let v = json_of(&json);
    // p = i omega sqrt(1 + i eta) = i omega (a + i b): a^2 - b^2 = 1, 2 a b = eta
    let eta: f64 = 0.03;
    let a = ((1.0 + (1.0 + eta * eta).sqrt()) / 2.0).sqrt();
    let b = eta / (2.0 * a);
    for (d, f) in v["damped"]
        .as_array()
        .unwrap()
        .iter()
        .zip(v["frequencies_hz"].as_array().unwrap())
    {
        let f = f.as_f64().unwrap();
        let close = |key: &str, want: f64| {
            let got = d[key].as_f64().unwrap();
            assert!(
                (got - want).abs() < 1e-9 * want.abs().max(1.0),
                "{key}: {d}"
            );
        };
        close("damping", 2.0 * b / a);
        close("frequency_hz", f * a);
        close("mpc", 1.0);
        let omega = 2.0 * std::f64::consts::PI * f;
        let p = &d["eigenvalue"];
        assert!(
            (p[0].as_f64().unwrap() + omega * b).abs() < 1e-9 * omega,
            "{d}"
        );
    }
    // Rayleigh damping on the two-hex deck: the modes' (*MODAL DAMPING) and the material's
    // (*DAMPING in *MATERIAL, alpha M_e + beta K_e of every element: the same C)
    let hexes = std::fs::read_to_string(fixture("two_hex.inp")).unwrap();
    let modal = hexes.replace(
        "*FREQUENCY\n4\n",
        "*FREQUENCY\n4\n*MODAL DAMPING, RAYLEIGH\n, , 2., 1e-6\n",
    );
    let material = hexes.replace("*DENSITY\n", "*DAMPING, ALPHA=2., BETA=1e-6\n*DENSITY\n");
    assert!(modal.contains("RAYLEIGH") && material.contains("ALPHA"));
    std::fs::copy(fixture("two_hex_nodes.inp"), dir.join("two_hex_nodes.inp")).unwrap();
    let nastran = deck("", "", "PARAM,ALPHA1,2.\nPARAM,ALPHA2,1e-6\n");
    for (name, text) in [
        ("rayleigh.inp", modal),
        ("material.inp", material),
        ("alpha.bdf", nastran),
    ] {
        let (out, json) = run(name, text);
        succeeded(&out);
        let v = json_of(&json);
        for (d, f) in v["damped"]
            .as_array()
            .unwrap()
            .iter()
            .zip(v["frequencies_hz"].as_array().unwrap())
        {
            let omega = 2.0 * std::f64::consts::PI * f.as_f64().unwrap();
            let zeta = 2.0 / (2.0 * omega) + 1e-6 * omega / 2.0;
            let ratio = d["damping_ratio"].as_f64().unwrap();
            assert!((ratio - zeta).abs() < 1e-9 * zeta, "{name}: {ratio} {zeta}");
            assert!((d["mpc"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{d}");
        }
    }
    let (out, _) = run("undamped.bdf", deck("", "", ""));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("has no damping"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu modes --uff`: the model's modes as a universal file. The cantilevered plate's six lowest
/// modes, read back: every node (2411) and each mode's frequency to the file's six digits (the
/// file's shapes against femu's own vectors are checked by pyuff in
/// `test_modes_written_as_a_universal_file`). With `--damped` on the plate of uniform `GE` 0.03,
/// each mode is complex data whose eigenvalue is the root `p = i omega sqrt(1 + 0.03 i)` of its
/// real mode (frequency `|p| / 2 pi`, ratio `-Re p / |p|`, to 1e-5: the file's digits), and `femu
/// correlate --damped` of the model against that file pairs each mode with itself, complex MAC 1
/// to 1e-6.
#[test]
fn modes_written_as_a_universal_file() {
    let dir = std::env::temp_dir().join(format!("femu-cli-modes-uff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("plate.bdf"),
        femu_testkit::damped_plate_deck(6, "0.03", "0.03", ""),
    )
    .unwrap();
    let deck = dir.join("plate.bdf");
    let run = |extra: &[&str], name: &str| {
        let (uff, json) = (
            dir.join(format!("{name}.unv")),
            dir.join(format!("{name}.json")),
        );
        let out = femu()
            .args(["modes", deck.to_str().unwrap(), "--count", "6", "--quiet"])
            .args([
                "--uff",
                uff.to_str().unwrap(),
                "--json",
                json.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap();
        succeeded(&out);
        (femu_io::uff::read_uff(&uff).unwrap(), json_of(&json), uff)
    };
    let (real, v, _) = run(&[], "real");
    assert_eq!(real.nodes.len(), 49);
    let f: Vec<f64> = v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(real.modes.len(), 6);
    for (m, f) in real.modes.iter().zip(&f) {
        assert!(
            (m.frequency_hz / f - 1.0).abs() < 1e-5,
            "{} {f}",
            m.frequency_hz
        );
        assert!(!m.complex);
    }
    let (damped, _, uff) = run(&["--damped"], "damped");
    let eta: f64 = 0.03;
    let a = ((1.0 + (1.0 + eta * eta).sqrt()) / 2.0).sqrt();
    let b = eta / (2.0 * a);
    for (m, f) in damped.modes.iter().zip(&f) {
        assert!(m.complex && m.imaginary.is_some());
        // p = i omega (a + i b): |p| = omega sqrt(a^2 + b^2), -Re p / |p| = b / sqrt(a^2 + b^2)
        let r = (a * a + b * b).sqrt();
        assert!((m.frequency_hz / (f * r) - 1.0).abs() < 1e-5, "{m:?}");
        assert!((m.damping / (b / r) - 1.0).abs() < 1e-4, "{}", m.damping);
    }
    let json = dir.join("corr.json");
    let out = femu()
        .args(["correlate", deck.to_str().unwrap(), uff.to_str().unwrap()])
        .args(["--damped", "--json", json.to_str().unwrap()])
        .output()
        .unwrap();
    succeeded(&out);
    let pairs = json_of(&json)["pairing"]["pairs"]
        .as_array()
        .unwrap()
        .clone();
    assert!(pairs.len() >= 4, "{pairs:?}");
    for p in &pairs {
        assert_eq!(p["test"], p["model"], "{p}");
        assert!(
            (p["complex_mac"].as_f64().unwrap() - 1.0).abs() < 1e-6,
            "{p}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `femu correlate --damped` compares complex shapes with the model's damped modes, so it needs
/// the model's damping: the undamped two-hex deck is refused with the reason (the same test
/// without `--damped` correlates).
#[test]
fn correlate_damped_needs_the_model_s_damping() {
    use femu_correlate::TestModes;
    let deck = fixture("two_hex.inp");
    let (modes, sensors, layout) = two_hex_case(4);
    let at = layout.measure_all(modes.vectors.as_ref()).unwrap();
    let f = modes.frequencies_hz();
    let shapes = femu_sparse::faer::Mat::from_fn(at.nrows(), 2, |i, j| at[(i, j)]);
    let test = TestModes::new(f[..2].to_vec(), None, shapes).unwrap();
    let dir = std::env::temp_dir().join(format!("femu-cli-corr-damped-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("test.csv");
    std::fs::write(&csv, femu_io::csv::test_csv_string(&sensors, &test)).unwrap();
    let args = ["correlate", deck.to_str().unwrap(), csv.to_str().unwrap()];
    stdout_of_success(&args);
    let err = stderr_of_failure(&[&args[..], &["--damped"]].concat());
    assert!(err.contains("has no damping"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
