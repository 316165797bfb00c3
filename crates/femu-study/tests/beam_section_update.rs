//! Updating beam section properties (docs/MATH.md, "Beam section parameters"): a Nastran
//! cantilever of 24 CBARs in two properties (PBAR, Euler-Bernoulli: K1 and K2 blank) with a CONM2
//! at its tip. The "real" cantilever has its root half's `I2` 40 % larger and its tip half's `I1`
//! 20 % smaller, written on its PBARs (the elements are formed at those inertias, not through the
//! parameters' law); its modes at every fourth grid, in y and z, are the test. femu updates the
//! nominal deck over both halves' `EI1` and `EI2`.

use femu_sparse::eigen::EigenOptions;
use femu_study::load::{ModelOptions, load_model, load_test};
use femu_study::modes::{ModesOptions, solve_modes};

const N: usize = 24;
const I1: f64 = 2.0e-8;
const I2: f64 = 4.5e-8;

/// The cantilever with the root half's inertias `(i1a, i2a)` and the tip half's `(i1b, i2b)`.
fn deck(a: (f64, f64), b: (f64, f64)) -> String {
    let mut s = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    for i in 0..=N {
        s.push_str(&format!(
            "GRID,{},,{:.12e},0.,0.\n",
            i + 1,
            i as f64 / N as f64
        ));
    }
    for i in 0..N {
        let pid = if 2 * i < N { 1 } else { 2 };
        s.push_str(&format!(
            "CBAR,{},{pid},{},{},0.,1.,0.\n",
            100 + i,
            i + 1,
            i + 2
        ));
    }
    s.push_str(&format!(
        "PBAR,1,1,6.e-4,{:e},{:e},5.e-8\nPBAR,2,1,6.e-4,{:e},{:e},5.e-8\n\
         MAT1,1,2.1e11,,0.3,7850.\nCONM2,900,{},,0.5\nSPC1,1,123456,1\nENDDATA\n",
        a.0,
        a.1,
        b.0,
        b.1,
        N + 1
    ));
    s
}

/// EI1 and EI2 of both halves updated against the real cantilever's first eight modes on the
/// same mesh: the root half's `EI2` is found +0.4 and the tip half's `EI1` -0.2 to 1e-6, the other
/// two at 0 (1e-6). Scaling either half's modulus instead could not give these modes (both planes
/// would move together). A section parameter on the CONM2's set, or on a set of shells, is refused
/// by name.
#[test]
fn section_parameters_find_the_changed_inertias() {
    let dir = std::env::temp_dir().join(format!("femu-beam-section-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let real_path = dir.join("real.bdf");
    std::fs::write(&real_path, deck((I1, 1.4 * I2), (0.8 * I1, I2))).unwrap();
    let real = load_model(&real_path, &ModelOptions::default()).unwrap();
    let options = ModesOptions {
        count: Some(8),
        ..Default::default()
    };
    let (modes, _) = solve_modes(&real, &options).unwrap();
    let mut csv = String::from("mode,frequency_hz,node,direction,value\n");
    let mesh = real.model.mesh();
    for j in 0..modes.values.len() {
        let f = modes.values[j].sqrt() / (2.0 * std::f64::consts::PI);
        let free: Vec<f64> = modes.vectors.col(j).iter().copied().collect();
        let u = real.sys.dofs.expand(&free).unwrap();
        for g in (5..=N + 1).step_by(4) {
            let n = mesh.node_index(g as u64).unwrap();
            for (c, d) in [(1, "y"), (2, "z")] {
                csv.push_str(&format!(
                    "{},{f:.15e},{g},{d},{:.15e}\n",
                    j + 1,
                    u[3 * n + c]
                ));
            }
        }
    }
    let test_path = dir.join("test.csv");
    std::fs::write(&test_path, csv).unwrap();
    let model_path = dir.join("beam.bdf");
    std::fs::write(&model_path, deck((I1, I2), (I1, I2))).unwrap();
    let loaded = load_model(&model_path, &ModelOptions::default()).unwrap();
    let test = load_test(&test_path, &loaded).unwrap();
    let run = |sets: &str| {
        let request: femu_study::updating::UpdateRequest =
            toml::from_str(&format!("sets = [{sets}]\nselect = \"all\"")).unwrap();
        femu_study::updating::update_loaded(
            &loaded,
            &test,
            &request,
            &EigenOptions::default(),
            None,
            |_| {},
        )
    };
    let study = run("\"EI1:PID1\", \"EI2:PID1\", \"EI1:PID2\", \"EI2:PID2\"").unwrap();
    let r = &study.result;
    let value = |name: &str| {
        let k = r
            .names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("{name} not updated: {:?} = {:?}", r.names, r.theta));
        r.theta[k]
    };
    assert!(
        (value("EI2:PID1") - 0.4).abs() < 1e-6,
        "{:?} {:?}",
        r.names,
        r.theta
    );
    assert!(
        (value("EI1:PID2") + 0.2).abs() < 1e-6,
        "{:?} {:?}",
        r.names,
        r.theta
    );
    assert!(value("EI1:PID1").abs() < 1e-6 && value("EI2:PID2").abs() < 1e-6);
    let e = run("\"EA:CONM2_900\"").unwrap_err().to_string();
    assert!(e.contains("CONM2_900"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
