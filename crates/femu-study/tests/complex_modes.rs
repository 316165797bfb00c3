//! Complex identified modes (universal file dataset 55, complex data) against the model: the
//! imaginary parts are kept beside the real shapes femu pairs with, and each pair gets its complex
//! MAC `|psi^H phi|^2 / ((psi^H psi)(phi^T phi))`, checked against that formula written here with
//! the values the file was written from.

use femu_correlate::{ModeSet, PairingOptions, correlate};
use femu_sparse::eigen::EigenOptions;
use femu_study::load::{ModelOptions, load_model, load_test};
use std::path::PathBuf;

/// Test modes `psi = c (phi_a + i s phi_b)` of the two-hex deck at its four tip nodes (x, y, z),
/// `phi` femu's own modes there: a complex file whose first two modes are complex and whose third
/// is a real mode stored as complex (`s = 0`, turned by `c`). The pairs are the
/// modes' own (MAC of the turned real parts), and each complex MAC equals the formula of the
/// written values to 1e-12; the third's is 1, as its real MAC. The Markdown table gains a
/// complex MAC column, and a real file's report has none.
#[test]
fn complex_test_modes_have_a_complex_mac() {
    let deck = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/inp/two_hex.inp");
    let loaded = load_model(&deck, &ModelOptions::default()).unwrap();
    let modes =
        femu_study::modes::lowest_for_test(&loaded, Some(8), 3, &EigenOptions::default()).unwrap();
    let nodes = [3u64, 6, 9, 12];
    let mesh = loaded.model.mesh();
    // phi at the tip nodes' x, y, z: sensors in the order the file lists them
    let phi = |j: usize| -> Vec<f64> {
        nodes
            .iter()
            .flat_map(|n| {
                let i = mesh.node_index(*n).unwrap();
                (0..3).map(move |c| (i, c))
            })
            .map(|(i, c)| modes.vectors[(loaded.sys.dofs.free_index(i, c).unwrap(), j)])
            .collect()
    };
    // (model mode, its partner, c, s): modes of distinct frequencies (the deck's square section
    // repeats modes 1-2 and 5-6, whose basis correlation turns towards the test)
    let cases = [
        (2, 3, (0.6, -0.8), 0.3),
        (3, 6, (-0.28, 0.96), 0.5),
        (6, 7, (0.8, 0.6), 0.0),
    ];
    let mut text = String::new();
    let mut written: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    for (j, (mode, partner, (cr, ci), s)) in cases.iter().enumerate() {
        let (a, b) = (phi(*mode), phi(*partner));
        // psi = c (a + i s b)
        let re: Vec<f64> = (0..12).map(|k| cr * a[k] - ci * s * b[k]).collect();
        let im: Vec<f64> = (0..12).map(|k| ci * a[k] + cr * s * b[k]).collect();
        let w = modes.values[*mode].sqrt();
        let zeta = 0.01;
        text.push_str(&format!(
            "    -1\n    55\nid1\nid2\nid3\nid4\nid5\n         1         3         2         8         5         3\n         2         6         1{:>10}\n{:.15E} {:.15E}  0.0D+00  0.0D+00  0.0D+00  0.0D+00\n",
            j + 1,
            -zeta * w,
            w * (1.0 - zeta * zeta).sqrt()
        ));
        for (n, node) in nodes.iter().enumerate() {
            text.push_str(&format!("{node:>10}\n"));
            for c in 0..3 {
                text.push_str(&format!(" {:.15E} {:.15E}", re[3 * n + c], im[3 * n + c]));
            }
            text.push('\n');
        }
        text.push_str("    -1\n");
        written.push((re, im));
    }
    let path = std::env::temp_dir().join(format!("femu-complex-{}.unv", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let t = load_test(&path, &loaded).unwrap();
    let imaginary = t
        .data
        .modes
        .imaginary
        .as_ref()
        .expect("imaginary parts kept");
    assert_eq!(imaginary.ncols(), 3);
    let report = correlate(
        &ModeSet::from_modes(&modes),
        &t.data.modes,
        &t.layout,
        &PairingOptions::default(),
    )
    .unwrap();
    assert_eq!(report.pairing.pairs.len(), 3);
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    for p in &report.pairing.pairs {
        assert_eq!(p.model, cases[p.test].0, "{p:?}");
        let (re, im) = &written[p.test];
        let f = phi(p.model);
        // |psi^H phi|^2 / ((psi^H psi)(phi^T phi)) for a real phi
        let expected = (dot(re, &f).powi(2) + dot(im, &f).powi(2))
            / ((dot(re, re) + dot(im, im)) * dot(&f, &f));
        let got = p.complex_mac.expect("complex MAC");
        assert!((got - expected).abs() < 1e-12, "{p:?}: {got} vs {expected}");
    }
    let third = report.pairing.pairs.iter().find(|p| p.test == 2).unwrap();
    assert!((third.complex_mac.unwrap() - 1.0).abs() < 1e-12);
    assert!((third.mac.unwrap() - 1.0).abs() < 1e-12);
    // the complex modes' complex MAC differs from the MAC of their turned real parts
    let first = report.pairing.pairs.iter().find(|p| p.test == 0).unwrap();
    assert!(
        (first.complex_mac.unwrap() - first.mac.unwrap()).abs() > 1e-3,
        "{first:?}"
    );
    let table = report.to_string();
    assert!(
        table.lines().next().unwrap().ends_with("| complex MAC |"),
        "{table}"
    );
    assert!(table.contains("complex MAC = |psi^H phi|^2"), "{table}");
    let json = serde_json::to_value(&report).unwrap();
    assert!(json["pairing"]["pairs"][0]["complex_mac"].is_f64());
    // a real file: no column, no key
    let real = report_without_imaginary(&modes, &t);
    assert!(!real.to_string().contains("complex MAC"));
    assert!(
        serde_json::to_value(&real).unwrap()["pairing"]["pairs"][0]
            .get("complex_mac")
            .is_none()
    );
    let _ = std::fs::remove_file(&path);
}

fn report_without_imaginary(
    modes: &femu_sparse::eigen::Modes,
    t: &femu_study::load::LoadedTest,
) -> femu_correlate::CorrelationReport {
    let mut real = t.data.modes.clone();
    real.imaginary = None;
    correlate(
        &ModeSet::from_modes(modes),
        &real,
        &t.layout,
        &PairingOptions::default(),
    )
    .unwrap()
}

/// The complex MAC with both sides complex: a cantilevered plate of CQUAD4 whose halves' MAT1 have
/// `GE` 0.06 and 0.01 (its damped modes complex), and a complex test written here from the model's
/// own damped modes at 12 grids (`psi = c Phi_a q_r`, each turned by a phase `c`). With
/// `damped`, each pair's complex MAC equals the formula `|psi^H phi|^2 / ((psi^H psi)(phi^H
/// phi))` of the written `psi` and `phi = Phi_a q` computed here (to 1e-12) and is 1 (to 1e-9);
/// against the real modes (no `damped`) it falls below 1 (0.99996 for the most complex of the
/// three: the damping is light). Asked of modes without their damped coordinates, correlation
/// refuses.
#[test]
fn damped_correlation_compares_complex_with_complex() {
    use faer::c64;
    let n = 8;
    let dir = std::env::temp_dir().join(format!("femu-damped-mac-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let id = |i: usize, j: usize| 1 + i + (n + 1) * j;
    let s = femu_testkit::damped_plate_deck(n, "0.06", "0.01", "");
    std::fs::write(dir.join("plate.bdf"), s).unwrap();
    let loaded = load_model(&dir.join("plate.bdf"), &ModelOptions::default()).unwrap();
    let modes =
        femu_study::modes::lowest_for_test(&loaded, Some(8), 3, &EigenOptions::default()).unwrap();
    let set = femu_study::modes::mode_set(&loaded, &modes, true).unwrap();
    let q = set.damped.clone().unwrap();
    let grids: Vec<u64> = [
        (2, 2),
        (4, 2),
        (6, 2),
        (8, 2),
        (2, 6),
        (4, 6),
        (6, 6),
        (8, 6),
        (8, 4),
        (6, 4),
        (4, 4),
        (8, 0),
    ]
    .iter()
    .map(|&(i, j)| id(i, j) as u64)
    .collect();
    let mesh = loaded.model.mesh();
    // Phi at the grids' x, y, z, in the file's order
    let rows: Vec<usize> = grids
        .iter()
        .flat_map(|g| {
            let i = mesh.node_index(*g).unwrap();
            (0..3).map(move |c| (i, c))
        })
        .map(|(i, c)| loaded.sys.dofs.free_index(i, c).unwrap())
        .collect();
    let damped_at = |r: usize| -> Vec<c64> {
        rows.iter()
            .map(|&f| {
                (0..modes.values.len())
                    .map(|j| q[(j, r)] * modes.vectors[(f, j)])
                    .sum()
            })
            .collect()
    };
    let mut text = String::new();
    let mut written: Vec<Vec<c64>> = Vec::new();
    for (k, (mode, c)) in [
        (0usize, c64::new(0.6, -0.8)),
        (1, c64::new(-0.28, 0.96)),
        (2, c64::new(1.0, 0.0)),
    ]
    .iter()
    .enumerate()
    {
        let psi: Vec<c64> = damped_at(*mode).iter().map(|v| c * v).collect();
        let w = modes.values[*mode].sqrt();
        text.push_str(&format!(
            "    -1\n    55\nid1\nid2\nid3\nid4\nid5\n         1         3         2         8         5         3\n         2         6         1{:>10}\n{:.15E} {:.15E}  0.0D+00  0.0D+00  0.0D+00  0.0D+00\n",
            k + 1,
            -0.01 * w,
            w
        ));
        for (g, node) in grids.iter().enumerate() {
            text.push_str(&format!("{node:>10}\n"));
            for comp in 0..3 {
                let v = psi[3 * g + comp];
                text.push_str(&format!(" {:.15E} {:.15E}", v.re, v.im));
            }
            text.push('\n');
        }
        text.push_str("    -1\n");
        written.push(psi);
    }
    std::fs::write(dir.join("test.unv"), text).unwrap();
    let t = load_test(&dir.join("test.unv"), &loaded).unwrap();
    let damped = PairingOptions {
        damped: true,
        ..Default::default()
    };
    let report = correlate(&set, &t.data.modes, &t.layout, &damped).unwrap();
    assert!(report.damped);
    assert_eq!(report.pairing.pairs.len(), 3);
    for p in &report.pairing.pairs {
        assert_eq!(p.test, p.model);
        let (psi, phi) = (&written[p.test], damped_at(p.model));
        let dot: c64 = psi.iter().zip(&phi).map(|(a, b)| a.conj() * b).sum();
        let norm = |v: &[c64]| v.iter().map(|x| x.norm_sqr()).sum::<f64>();
        let want = dot.norm_sqr() / (norm(psi) * norm(&phi));
        let got = p.complex_mac.unwrap();
        assert!((got - want).abs() < 1e-12, "{got} against {want}");
        assert!((got - 1.0).abs() < 1e-9, "{got}");
    }
    assert!(format!("{report}").contains("damped modes"));
    // against the real modes: the complex modes' complex MAC falls below 1
    let real = correlate(&set, &t.data.modes, &t.layout, &PairingOptions::default()).unwrap();
    let worst = real
        .pairing
        .pairs
        .iter()
        .map(|p| p.complex_mac.unwrap())
        .fold(1.0f64, f64::min);
    assert!(worst < 1.0 - 1e-6, "{worst}");
    // modes without their damped coordinates are refused
    let e = correlate(
        &ModeSet::from_modes(&modes),
        &t.data.modes,
        &t.layout,
        &damped,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no damped modes"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The complex modes of viscous and structural damping together: a cantilevered plate of CQUAD4
/// (3 x 3, 72 free DOFs) whose clamped half's `GE` is 0.04 and a grounded bushing at its free
/// corner with `B` of 20 N s/m in x, y and z, modes solved in the space of its real modes (`femu
/// modes --damped`). With every real mode kept:
/// - each root `p` makes the assembled `Q(p) = p^2 M + p C + K + i K_4` singular: its smallest
///   singular value is below 1e-16 of its largest for the lowest ten roots (measured 8e-17) and
///   below 1e-11 for all 72 (measured 4e-12, where the real modes themselves are least accurate);
/// - the roots equal those of the full problem written here as its own companion matrix, `[[0, I],
///   [-L^-1 (K + i K_4) L^-T, -L^-1 C L^-T]]` (`M = L L^T`, time scaled by the largest frequency,
///   the roots with `Im p > 0`), to 1e-9 of the largest root (measured 3e-12: that companion
///   matrix's own accuracy for its low roots is round-off times the square of the frequency ratio,
///   2e-7 relative on the first; its singular values there are 1e-14, femu's 5e-18).
///
/// With the lowest 12 real modes kept, the three lowest roots agree to 1e-5 (the Rayleigh-Ritz
/// error of the projection, measured 1.4e-6). The bushing's damping makes the modes complex (MPC
/// 0.994-0.998).
#[test]
fn viscous_and_structural_damped_modes_are_the_full_problem() {
    use faer::c64;
    use femu_sparse::eigen::Which;
    let dir = std::env::temp_dir().join(format!("femu-viscous-modes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = femu_testkit::damped_plate_deck(
        3,
        "0.04",
        "",
        "CBUSH,900,90,16,,1.,0.,0.,0\nPBUSH,90,K,1.e3,1.e3,1.e3,,,,+P\n+P,B,20.,20.,20.\n",
    );
    std::fs::write(dir.join("plate.bdf"), s).unwrap();
    let loaded = load_model(&dir.join("plate.bdf"), &ModelOptions::default()).unwrap();
    let dense = |a: &femu_sparse::SparseMatrix| femu_sparse::csc::to_dense(a);
    let (k, m) = (dense(&loaded.sys.k), dense(&loaded.sys.m));
    let dampers = loaded
        .asm
        .dampers(&loaded.model, femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    let (c, k4) = (
        dense(dampers.viscous.as_ref().unwrap()),
        dense(dampers.structural.as_ref().unwrap()),
    );
    let n = k.nrows();
    // in y = L^T x (M = L L^T) with the time scaled by the largest frequency, p = w p': L^-1 A
    // L^-T of K + i K_4 over w^2 and of C over w
    let llt = m.llt(faer::Side::Lower).unwrap();
    let congruent = |a: &faer::Mat<f64>| {
        let mut x = a.clone();
        llt.L().solve_lower_triangular_in_place(x.as_mut());
        let mut y = x.transpose().to_owned();
        llt.L().solve_lower_triangular_in_place(y.as_mut());
        y
    };
    let (sk, sk4, sc) = (congruent(&k), congruent(&k4), congruent(&c));
    let w = (0..n).fold(0.0f64, |a, i| a.max(sk[(i, i)])).sqrt();
    let a = faer::Mat::<c64>::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => c64::new(0.0, 0.0),
        (true, false) => c64::new(f64::from(u8::from(j - n == i)), 0.0),
        (false, true) => -c64::new(sk[(i - n, j)], sk4[(i - n, j)]) / (w * w),
        (false, false) => c64::new(-sc[(i - n, j - n)] / w, 0.0),
    });
    let evd = faer::linalg::solvers::Eigen::<f64>::new(a.as_ref()).unwrap();
    let mut direct: Vec<c64> = (0..2 * n)
        .map(|j| evd.S()[j] * w)
        .filter(|p| p.im > 0.0)
        .collect();
    direct.sort_by(|x, y| x.im.total_cmp(&y.im));
    assert_eq!(direct.len(), n);
    let top = direct[n - 1].norm();
    let damped = |count: usize| {
        let modes = loaded
            .sys
            .modes(Which::Lowest(count), &EigenOptions::default())
            .unwrap();
        femu_study::modes::damped_modes(&loaded, &modes, &mut Vec::new()).unwrap()
    };
    let root = |d: &femu_study::modes::DampedMode| c64::new(d.eigenvalue[0], d.eigenvalue[1]);
    let all = damped(n);
    assert_eq!(all.len(), n);
    let worst = all
        .iter()
        .zip(&direct)
        .map(|(d, p)| (root(d) - p).norm())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-9 * top, "{worst} of {top}");
    // each root makes the full Q(p) = p^2 M + p C + K + i K_4 singular: its smallest singular
    // value against its largest
    let singular = |p: c64| {
        let q = faer::Mat::<c64>::from_fn(n, n, |i, j| {
            p * p * m[(i, j)] + p * c[(i, j)] + c64::new(k[(i, j)], k4[(i, j)])
        });
        let sv = q.singular_values().unwrap();
        let (lo, hi) = sv.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
        lo / hi
    };
    let lowest = all[..10]
        .iter()
        .map(|d| singular(root(d)))
        .fold(0.0f64, f64::max);
    assert!(lowest < 1e-16, "{lowest:e}");
    let every = all.iter().map(|d| singular(root(d))).fold(0.0f64, f64::max);
    assert!(every < 1e-11, "{every:e}");
    assert!(all[..3].iter().all(|d| d.mpc < 1.0 - 1e-6), "{all:?}");
    for d in &all[..3] {
        let p = root(d);
        assert!((d.frequency_hz - p.im / (2.0 * std::f64::consts::PI)).abs() < 1e-12 * p.im);
        assert!((d.damping + 2.0 * p.re / p.im).abs() < 1e-12);
    }
    let some = damped(12);
    for (d, p) in some.iter().zip(&direct).take(3) {
        let e = (root(d) - p).norm() / p.norm();
        assert!(e < 1e-5, "{e}: {d:?} {p:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nastran's scalar dampers (QRG CDAMP1 with PDAMP, CDAMP2) beside scalar springs: a chain of two
/// CONM2 masses (1 and 2 kg) on grids moving along y, springs of 100 and 300 N/m and dampers of
/// 0.5 N s/m (CDAMP2) and 0.8 N s/m (CDAMP1 of the PDAMP's second property, 9. the first's). The
/// model's viscous damping is the hand-written `C = [[1.3, -0.8], [-0.8, 0.8]]` (1e-14) and its
/// damped modes are the roots of `det(p^2 M + p C + K) = 0` written here as the 4 x 4 companion
/// matrix of the hand-written `M`, `C`, `K` (1e-12).
#[test]
fn scalar_dampers_are_viscous_damping() {
    use faer::c64;
    use femu_sparse::eigen::Which;
    let dir = std::env::temp_dir().join(format!("femu-cdamp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = "SOL 103\nCEND\nSPC = 1\nBEGIN BULK\n\
        GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\n\
        CONM2,10,2,,1.\nCONM2,11,3,,2.\n\
        CELAS2,20,100.,1,2,2,2\nCELAS2,21,300.,2,2,3,2\n\
        CDAMP2,30,0.5,1,2,2,2\nCDAMP1,31,7,2,2,3,2\nPDAMP,5,9.,7,0.8\n\
        SPC1,1,123456,1\nSPC1,1,13456,2,3\nENDDATA\n";
    std::fs::write(dir.join("chain.bdf"), deck).unwrap();
    let loaded = load_model(&dir.join("chain.bdf"), &ModelOptions::default()).unwrap();
    let c = femu_sparse::csc::to_dense(
        loaded
            .asm
            .dampers(&loaded.model, loaded.sys.mass_kind)
            .unwrap()
            .viscous
            .as_ref()
            .unwrap(),
    );
    assert_eq!(c.nrows(), 2);
    let want_c = [[1.3, -0.8], [-0.8, 0.8]];
    for i in 0..2 {
        for j in 0..2 {
            assert!((c[(i, j)] - want_c[i][j]).abs() < 1e-14, "{c:?}");
        }
    }
    let modes = loaded
        .sys
        .modes(Which::Lowest(2), &EigenOptions::default())
        .unwrap();
    let damped = femu_study::modes::damped_modes(&loaded, &modes, &mut Vec::new()).unwrap();
    // the companion matrix of M^-1 K and M^-1 C, by hand
    let (m, k) = ([1.0, 2.0], [[400.0, -300.0], [-300.0, 300.0]]);
    let a = faer::Mat::<c64>::from_fn(4, 4, |i, j| match (i < 2, j < 2) {
        (true, true) => c64::new(0.0, 0.0),
        (true, false) => c64::new(f64::from(u8::from(j - 2 == i)), 0.0),
        (false, true) => c64::new(-k[i - 2][j] / m[i - 2], 0.0),
        (false, false) => c64::new(-want_c[i - 2][j - 2] / m[i - 2], 0.0),
    });
    let evd = faer::linalg::solvers::Eigen::<f64>::new(a.as_ref()).unwrap();
    let mut roots: Vec<c64> = (0..4).map(|j| evd.S()[j]).filter(|p| p.im > 0.0).collect();
    roots.sort_by(|x, y| x.im.total_cmp(&y.im));
    assert_eq!((roots.len(), damped.len()), (2, 2));
    for (d, p) in damped.iter().zip(&roots) {
        let got = c64::new(d.eigenvalue[0], d.eigenvalue[1]);
        assert!((got - p).norm() < 1e-12 * p.norm(), "{got:?} {p:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Abaqus' dashpots (`DASHPOT1` of a `*DASHPOT`, the `*SPRING` layout with a dashpot coefficient
/// on its second line): a 2 kg `*MASS` on a `SPRING1` of 800 N/m and a `DASHPOT1` of 4 N s/m
/// along y has the textbook root `p = -c / (2 m) + i sqrt(k / m - (c / (2 m))^2)` (1e-12); a
/// `DASHPOT1` element whose set is given a `*SPRING` is refused with the line.
#[test]
fn an_abaqus_dashpot_is_viscous_damping() {
    use femu_sparse::eigen::Which;
    let dir = std::env::temp_dir().join(format!("femu-dashpot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let deck = "*NODE\n1, 0., 0., 0.\n\
        *ELEMENT, TYPE=MASS, ELSET=M\n1, 1\n*MASS, ELSET=M\n2.\n\
        *ELEMENT, TYPE=SPRING1, ELSET=S\n2, 1\n*SPRING, ELSET=S\n2\n800.\n\
        *ELEMENT, TYPE=DASHPOT1, ELSET=D\n3, 1\n*DASHPOT, ELSET=D\n2\n4.\n\
        *BOUNDARY\n1, 1, 1\n1, 3, 3\n";
    std::fs::write(dir.join("sdof.inp"), deck).unwrap();
    let loaded = load_model(&dir.join("sdof.inp"), &ModelOptions::default()).unwrap();
    let modes = loaded
        .sys
        .modes(Which::Lowest(1), &EigenOptions::default())
        .unwrap();
    let damped = femu_study::modes::damped_modes(&loaded, &modes, &mut Vec::new()).unwrap();
    let (m, k, c) = (2.0f64, 800.0f64, 4.0f64);
    let want = [-c / (2.0 * m), (k / m - (c / (2.0 * m)).powi(2)).sqrt()];
    let got = damped[0].eigenvalue;
    assert!(
        (got[0] - want[0]).abs() < 1e-12 * want[1] && (got[1] - want[1]).abs() < 1e-12 * want[1],
        "{got:?} {want:?}"
    );
    let wrong = deck.replace("*DASHPOT, ELSET=D", "*SPRING, ELSET=D");
    std::fs::write(dir.join("wrong.inp"), wrong).unwrap();
    let e = load_model(&dir.join("wrong.inp"), &ModelOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("wrong.inp:13") && e.contains("takes a *DASHPOT"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
