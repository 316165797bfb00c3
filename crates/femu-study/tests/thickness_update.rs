//! Updating a shell panel's thickness: a Nastran panel of CQUAD4 in two properties, a CBAR
//! stiffener along its middle, a grounded CBUSH at a free corner and a CONM2, clamped along one
//! edge. The "real" panel has its outer half 10 % thinner, its bushing 25 % softer and its CONM2
//! half as heavy again; its modes come from a deck twice as fine (four shells for each, the
//! thickness written on its PSHELL: the element is formed at that thickness, not through the
//! parameter's law). femu reads the
//! nominal, coarse deck and updates the thicknesses (`t:PID1`, `t:PID2`) beside the stiffener's
//! and the bushing's stiffness factors and the CONM2's mass (`CONM2_7000`).

use femu_sparse::eigen::EigenOptions;
use femu_study::load::{ModelOptions, load_model, load_test};
use femu_study::modes::{ModesOptions, solve_modes};

const A: f64 = 0.6;
const B: f64 = 0.4;
const T: f64 = 0.003;
const K_BUSH: f64 = 2.0e4;
/// The CONM2's mass in the model, and in the real panel (half as heavy again).
const MASS: f64 = 0.2;
const REAL_MASS: f64 = 0.3;

/// The panel deck with `nx x ny` shells; the outer half's thickness `t2`, the bushing's `k`, the
/// CONM2's mass `m`.
fn deck(nx: usize, ny: usize, t2: f64, k: f64, m: f64) -> String {
    let mut s = String::from("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nPARAM,COUPMASS,1\n");
    let id = |i: usize, j: usize| 1 + i + (nx + 1) * j;
    for j in 0..=ny {
        for i in 0..=nx {
            s.push_str(&format!(
                "GRID,{},,{:.12e},{:.12e},0.\n",
                id(i, j),
                A * i as f64 / nx as f64,
                B * j as f64 / ny as f64
            ));
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let pid = if 2 * i < nx { 1 } else { 2 };
            s.push_str(&format!(
                "CQUAD4,{},{pid},{},{},{},{}\n",
                1000 + i + nx * j,
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            ));
        }
    }
    // the stiffener: along y = B / 2, a 6 x 10 mm bar standing in z
    for i in 0..nx {
        s.push_str(&format!(
            "CBAR,{},10,{},{},0.,1.,0.\n",
            5000 + i,
            id(i, ny / 2),
            id(i + 1, ny / 2)
        ));
    }
    s.push_str(&format!(
        "PSHELL,1,1,{T:e},1,,1\nPSHELL,2,1,{t2:e},1,,1\nMAT1,1,2.1e11,,0.3,7850.\n\
         PBARL,10,1,,BAR\n,0.006,0.010\n\
         CBUSH,6000,30,{},,,,,0\nPBUSH,30,K,0.,0.,{k:e},0.,0.,0.\n\
         CONM2,7000,{},,{m:e}\nSPC1,1,123456,{}\nENDDATA\n",
        id(nx, ny),
        id(nx, 0),
        (0..=ny)
            .map(|j| id(0, j).to_string())
            .collect::<Vec<_>>()
            .join(",")
    ));
    s
}

/// The nominal deck (`nx x ny` shells) read, and the test made of the real deck's (refined
/// `real_refinement` times) first eight modes, `z` at every other coarse grid off the clamp; the
/// real panel's total mass; the folder to remove.
fn case(
    (nx, ny): (usize, usize),
    real_refinement: usize,
    tag: &str,
) -> (
    femu_study::load::LoadedModel,
    femu_study::load::LoadedTest,
    f64,
    std::path::PathBuf,
) {
    let sensors: Vec<(usize, usize)> = (0..=ny)
        .step_by(2)
        .flat_map(|jj| (2..=nx).step_by(2).map(move |ii| (ii, jj)))
        .collect();
    case_with((nx, ny), real_refinement, tag, &sensors, false)
}

/// The panel deck without its stiffener and bushing.
fn bare(deck: String) -> String {
    deck.lines()
        .filter(|l| {
            !["CBAR", "PBARL", ",0.006", "CBUSH", "PBUSH"]
                .iter()
                .any(|c| l.starts_with(c))
        })
        .map(|l| format!("{l}\n"))
        .collect()
}

/// [`case`] with `z` sensors at the coarse grid indices `sensors`, and without the stiffener and
/// the bushing when `plain`.
fn case_with(
    (nx, ny): (usize, usize),
    real_refinement: usize,
    tag: &str,
    sensors: &[(usize, usize)],
    plain: bool,
) -> (
    femu_study::load::LoadedModel,
    femu_study::load::LoadedTest,
    f64,
    std::path::PathBuf,
) {
    let dir = std::env::temp_dir().join(format!(
        "femu-thickness-update-{nx}-{real_refinement}-{tag}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let real_path = dir.join("real.bdf");
    let r = real_refinement;
    let real_deck = deck(r * nx, r * ny, 0.9 * T, 0.75 * K_BUSH, REAL_MASS);
    std::fs::write(&real_path, if plain { bare(real_deck) } else { real_deck }).unwrap();
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
        for &(ii, jj) in sensors {
            let fine = 1 + r * ii + (r * nx + 1) * (r * jj);
            let n = mesh.node_index(fine as u64).unwrap();
            csv.push_str(&format!(
                "{},{f:.15e},{},z,{:.15e}\n",
                j + 1,
                1 + ii + (nx + 1) * jj,
                u[3 * n + 2]
            ));
        }
    }
    let test_path = dir.join("test.csv");
    std::fs::write(&test_path, csv).unwrap();
    let model_path = dir.join("panel.bdf");
    let model_deck = deck(nx, ny, T, K_BUSH, MASS);
    std::fs::write(
        &model_path,
        if plain { bare(model_deck) } else { model_deck },
    )
    .unwrap();
    let loaded = load_model(&model_path, &ModelOptions::default()).unwrap();
    let test = load_test(&test_path, &loaded).unwrap();
    let real_mass = real.model.total_mass().unwrap();
    (loaded, test, real_mass, dir)
}

/// The update study a request (study-file text) asks of `loaded` against `test`.
fn study_of(
    loaded: &femu_study::load::LoadedModel,
    test: &femu_study::load::LoadedTest,
    request: &str,
) -> Result<femu_study::updating::UpdateStudy, femu_study::StudyError> {
    let request: femu_study::updating::UpdateRequest = toml::from_str(request).unwrap();
    femu_study::updating::update_loaded(
        loaded,
        test,
        &request,
        &EigenOptions::default(),
        None,
        |_| {},
    )
}

/// The nominal deck's update against the real one ([`case`]); `sets` the candidates, `select`
/// the selection.
fn update(
    (nx, ny): (usize, usize),
    real_refinement: usize,
    sets: &str,
    select: &str,
) -> femu_study::updating::UpdateStudy {
    let (loaded, test, _, dir) = case((nx, ny), real_refinement, select);
    let study = study_of(
        &loaded,
        &test,
        &format!("sets = [{sets}]\nselect = \"{select}\""),
    )
    .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    study
}

const SETS: &str = "\"t:PID1\", \"t:PID2\", \"PID10\", \"PID30\", \"CONM2_7000\"";

fn value(study: &femu_study::updating::UpdateStudy, name: &str) -> f64 {
    let r = &study.result;
    let k = r.names.iter().position(|n| n == name).unwrap_or_else(|| {
        panic!("{name} not updated: {:?} = {:?}", r.names, r.theta);
    });
    r.theta[k]
}

/// The real panel on the same mesh: the thinner half, the softer bushing and the heavier CONM2
/// are found exactly (-0.1, -0.25, +0.5 to 1e-6; 4e-11, 4e-10, 3e-9 measured), the untouched
/// thickness and stiffener at 0. Scaling the outer half's modulus instead could not give these
/// modes (its membrane and bending would move together).
#[test]
fn the_same_mesh_gives_the_thickness_change_exactly() {
    let study = update((8, 6), 1, SETS, "all");
    assert!((value(&study, "t:PID2") + 0.1).abs() < 1e-6);
    assert!((value(&study, "k:PID30") + 0.25).abs() < 1e-6);
    assert!((value(&study, "m:CONM2_7000") - 0.5).abs() < 1e-6);
    assert!(value(&study, "t:PID1").abs() < 1e-6);
    assert!(value(&study, "k:PID10").abs() < 1e-6);
}

/// The real panel twice as fine as the model: the model's discretisation error is absorbed by the
/// parameters, and shrinks with the mesh. Measured: on 8 x 6 shells (all five selected) `t:PID2`
/// -0.131, `k:PID30` -0.141, `m:CONM2_7000` +0.155, `k:PID10` -0.46 (the stiffener softened for
/// the coarse shells' stiffness), `t:PID1` -0.037; on 16 x 12 (the forward selection leaves
/// `t:PID1` out) -0.111, -0.258, +0.449, `k:PID10` -0.008.
#[test]
fn a_finer_real_panel_gives_the_thickness_change_within_discretisation() {
    let error = |(nx, ny)| {
        let study = update((nx, ny), 2, SETS, "forward");
        [
            (value(&study, "t:PID2") + 0.1).abs(),
            (value(&study, "k:PID30") + 0.25).abs(),
            (value(&study, "m:CONM2_7000") - 0.5).abs(),
        ]
    };
    let (coarse, fine) = (error((8, 6)), error((16, 12)));
    assert!((0..3).all(|i| fine[i] < coarse[i]), "{coarse:?} {fine:?}");
    assert!(
        fine[0] < 0.015 && fine[1] < 0.015 && fine[2] < 0.06,
        "{fine:?}"
    );
}

/// A thickness asked of a set that holds no shell is refused with the element named.
#[test]
fn a_thickness_of_beams_is_refused() {
    let dir = std::env::temp_dir().join(format!("femu-thickness-beams-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("panel.bdf");
    std::fs::write(&path, deck(4, 2, T, K_BUSH, MASS)).unwrap();
    let loaded = load_model(&path, &ModelOptions::default()).unwrap();
    let err = femu_fem::groups::ParameterGroups::from_element_sets(
        &loaded.model,
        &["t:PID10"],
        femu_fem::assembly::MassKind::Consistent,
    )
    .unwrap_err()
    .to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        err.contains("t:PID10") && err.contains("element 5000 is a beam"),
        "{err}"
    );
}

/// SB-EBE with a thickness and a CONM2 mass: without the measured total mass the study refuses it
/// (its force residual shrinks with the model: unguarded, both went to their lower bound), and
/// with the real panel's weighed mass as the guard it finds the thinner half, the softer bushing
/// and the heavier CONM2 on the same mesh (-0.1, -0.25, +0.5 to 1e-4).
#[test]
fn sbebe_takes_a_thickness_with_the_measured_mass() {
    use femu_fem::assembly::MassKind;
    use femu_update::{Corrections, MassGuard, SbebeOptions, UpdateModel, UpdateOptions, sb_ebe};
    let (loaded, test, real_mass, dir) = case((8, 6), 1, "sbebe");
    let e = study_of(
        &loaded,
        &test,
        &format!("sets = [{SETS}]\nselect = \"all\"\nmethod = \"sbebe\""),
    )
    .map(|_| ())
    .unwrap_err()
    .to_string();
    assert!(e.contains("measured total mass"), "{e}");
    let sets = ["t:PID1", "t:PID2", "PID10", "PID30", "CONM2_7000"];
    let mut up = UpdateModel::from_element_sets(
        &loaded.model,
        &sets,
        MassKind::Consistent,
        Corrections::Stiffness,
    )
    .unwrap();
    let options = SbebeOptions {
        update: UpdateOptions {
            mass_guard: MassGuard::Measured(real_mass),
            ..Default::default()
        },
        ..Default::default()
    };
    let r = sb_ebe(&mut up, &test.layout, &test.data.modes, &options, |_| {}).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let want = [0.0, -0.1, 0.0, -0.25, 0.5];
    for (k, w) in want.iter().enumerate() {
        assert!(
            (r.theta[k] - w).abs() < 1e-4,
            "{:?} = {:?}",
            r.names,
            r.theta
        );
    }
}

/// A thin panel (t/L = 1/200, without the stiffener and the bushing) with 28 `z` sensors in a
/// checkerboard off the clamp: the
/// minimum-residual expansion's saddle-point system has rotation columns weighted by the inverse
/// of a rotary inertia `(L/t)^2` below the translations' mass; regularised by one number it did
/// not refine ("singular or nearly so") and stopped every update. With each row regularised by its
/// own column's scale the update finds the panel's changes on the same mesh (1e-6).
#[test]
fn a_thin_panel_with_a_checkerboard_of_sensors_updates() {
    let (nx, ny) = (8, 6);
    let sensors: Vec<(usize, usize)> = (0..=ny)
        .flat_map(|jj| (1..=nx).map(move |ii| (ii, jj)))
        .filter(|(ii, jj)| (ii + jj) % 2 == 0)
        .collect();
    assert_eq!(sensors.len(), 28);
    let (loaded, test, _, dir) = case_with((nx, ny), 1, "checkerboard", &sensors, true);
    let study = study_of(
        &loaded,
        &test,
        "sets = [\"t:PID1\", \"t:PID2\", \"CONM2_7000\"]\nselect = \"all\"",
    )
    .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!((value(&study, "t:PID2") + 0.1).abs() < 1e-6);
    assert!((value(&study, "m:CONM2_7000") - 0.5).abs() < 1e-6);
}
