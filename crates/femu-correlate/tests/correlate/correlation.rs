//! Correlation measures against hand computations, Table 2 of the paper, and pairing.

use super::common::*;
use faer::Mat;
use femu_correlate::correlation::*;
use femu_correlate::{PairingOptions, pair_modes};
use femu_fem::prelude::*;

/// Table 2: the eigenvalue gaps from Table 1's frequencies are 24.65e5, 1.34e5, 8.68e5 and
/// 152.78e5 s^-2 (to the paper's printed digits), and Table 1's relative errors 1.8, 0.0, 0.1,
/// 1.6 %.
#[test]
fn paper_table_2_gaps_from_table_1() {
    let test = [1311.2, 2421.9, 2968.9, 3414.9];
    let model = [1334.8, 2421.2, 2972.6, 3471.1];
    let gaps = [24.65e5, 1.34e5, 8.68e5, 152.78e5];
    let printed_errors = [1.8, 0.0, 0.1, 1.6];
    for i in 0..4 {
        let g = eigenvalue_gap_hz(test[i], model[i]);
        // printed to 0.01e5: agreement to half a unit of the last digit
        assert!(
            (g - gaps[i]).abs() <= 0.5 * 0.01e5,
            "mode {}: {g:e} vs {:e}",
            i + 1,
            gaps[i]
        );
        let e = 100.0 * frequency_error(test[i], model[i]).abs();
        assert!((e - printed_errors[i]).abs() <= 0.05, "mode {}: {e}", i + 1);
    }
}

/// MAC, MSD and the modal scale factor by hand on 3-vectors.
#[test]
fn measures_by_hand() {
    let x = [1.0, 2.0, 2.0]; // |x| = 3
    let phi = [2.0, 0.0, 0.0];
    // x.phi = 2, |phi| = 2: MAC = 4 / (9 * 4) = 1/9
    assert!((mac(&x, &phi).unwrap() - 1.0 / 9.0).abs() < 1e-15);
    // MSF = 2 / 4 = 0.5; x - 0.5 phi = (0, 2, 2): MSD = sqrt(8) / 3 = sin theta
    assert!((modal_scale_factor(&x, &phi).unwrap() - 0.5).abs() < 1e-15);
    assert!((msd(&x, &phi).unwrap() - 8f64.sqrt() / 3.0).abs() < 1e-15);
    // With M = diag(1, 4, 1): x^T M x = 1 + 16 + 4 = 21, phi^T M phi = 4, x^T M phi = 2:
    // MAC_M = 4 / 84; MSD_M^2 = 2 (1 - cos) with cos = 2 / sqrt(84)
    let m = sparse(&Mat::from_fn(3, 3, |i, j| {
        if i == j { [1.0, 4.0, 1.0][i] } else { 0.0 }
    }));
    assert!((mac_m(&m, &x, &phi).unwrap() - 4.0 / 84.0).abs() < 1e-15);
    let cos = 2.0 / 84f64.sqrt();
    assert!((msd_m(&m, &x, &phi).unwrap() - (2.0 * (1.0 - cos)).sqrt()).abs() < 1e-15);
    // scale and sign invariance
    let xs: Vec<f64> = x.iter().map(|v| -7.5 * v).collect();
    assert!((mac_m(&m, &xs, &phi).unwrap() - 4.0 / 84.0).abs() < 1e-15);
    assert!((msd_m(&m, &xs, &phi).unwrap() - msd_m(&m, &x, &phi).unwrap()).abs() < 1e-15);
    // MSD_M = ||x_hat - phi_hat||_M with explicit normalisation and sign alignment
    let nx = 21f64.sqrt();
    let d: Vec<f64> = (0..3).map(|i| x[i] / nx - phi[i] / 2.0).collect();
    let dm = [1.0, 4.0, 1.0];
    let direct: f64 = (0..3).map(|i| dm[i] * d[i] * d[i]).sum::<f64>().sqrt();
    assert!((msd_m(&m, &x, &phi).unwrap() - direct).abs() < 1e-15);
    // zero vectors are errors
    assert!(mac(&[0.0; 3], &phi).is_err());
    assert!(msd(&x, &[0.0; 3]).is_err());
}

/// Model modes against themselves: MAC_M matrix and cross-orthogonality are the identity, the
/// AutoMAC on sensors is symmetric with unit diagonal; COMAC of a mode set against itself is 1.
#[test]
fn matrices_on_model_modes() {
    let model = bar([8, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = femu_sparse::eigen::eigs(
        &sys.k,
        &sys.m,
        femu_sparse::eigen::Which::Lowest(5),
        &Default::default(),
    )
    .unwrap();
    let phi = modes.vectors.as_ref();
    let mm = mac_m_matrix(&sys.m, phi, phi).unwrap();
    let xo = cross_orthogonality(&sys.m, phi, phi).unwrap();
    for i in 0..5 {
        for j in 0..5 {
            let d = if i == j { 1.0 } else { 0.0 };
            assert!((mm[(i, j)] - d).abs() < 1e-9);
            assert!((xo[(i, j)] - d).abs() < 1e-9);
        }
    }
    let tips: Vec<u64> = model
        .mesh()
        .node_set("xmax")
        .unwrap()
        .iter()
        .map(|&n| model.mesh().node_id(n))
        .collect();
    let layout = femu_correlate::SensorLayout::triaxial(model.mesh(), &sys.dofs, &tips).unwrap();
    let pa = layout.measure_all(phi).unwrap();
    let am = auto_mac(pa.as_ref()).unwrap();
    for i in 0..5 {
        assert!((am[(i, i)] - 1.0).abs() < 1e-14);
        for j in 0..5 {
            assert!((am[(i, j)] - am[(j, i)]).abs() < 1e-14);
        }
    }
    let scaled = Mat::from_fn(pa.nrows(), 5, |i, j| {
        pa[(i, j)] * (j as f64 + 2.0) * if j % 2 == 0 { 1.0 } else { -1.0 }
    });
    let co = comac(
        scaled.as_ref(),
        pa.as_ref(),
        &[(0, 0), (1, 1), (2, 2), (3, 3), (4, 4)],
    )
    .unwrap();
    assert!(co.iter().all(|c| (c - 1.0).abs() < 1e-12));
    // mass_normalise
    let mut v = Mat::from_fn(phi.nrows(), 2, |i, j| phi[(i, j)] * 3.0);
    mass_normalise(&sys.m, v.as_mut()).unwrap();
    assert!((mac_m_matrix(&sys.m, v.as_ref(), phi).unwrap()[(0, 0)] - 1.0).abs() < 1e-12);
    let xo = cross_orthogonality(&sys.m, v.as_ref(), phi).unwrap();
    assert!((xo[(0, 0)] - 1.0).abs() < 1e-9 && (xo[(1, 1)] - 1.0).abs() < 1e-9);
}

/// COMAC by hand: two modes, two sensors, one sensor disagreeing in sign pattern.
#[test]
fn comac_by_hand() {
    // test modes (columns) and model modes at two sensors
    let x = Mat::from_fn(2, 2, |i, j| [[1.0, 1.0], [1.0, -1.0]][i][j]);
    let p = Mat::from_fn(2, 2, |i, j| [[1.0, 1.0], [1.0, 1.0]][i][j]);
    // pair 0: MSF = 1; pair 1: MSF = (1 - 1)/2 = 0 -> scaled model vector 0
    let c = comac(x.as_ref(), p.as_ref(), &[(0, 0), (1, 1)]).unwrap();
    // sensor i: num = |1*1| + |x_i1 * 0| = 1; sum x^2 = 2; sum q^2 = 1 -> 1/2
    assert!((c[0] - 0.5).abs() < 1e-15 && (c[1] - 0.5).abs() < 1e-15);
}

/// Pairing: swapped modes are both paired by assignment; a mode with no partner above the
/// threshold stays unpaired; a case where greedy pairing would lose a pair.
#[test]
fn pairing_swapped_missing_and_greedy_trap() {
    let ft = [100.0, 200.0, 300.0];
    let fm = [101.0, 198.0, 330.0];
    // test 0 <-> model 1, test 1 <-> model 0 (swapped), test 2 has no partner
    let mac = Mat::from_fn(3, 3, |i, j| {
        [[0.05, 0.95, 0.0], [0.97, 0.02, 0.1], [0.1, 0.3, 0.5]][i][j]
    });
    let p = pair_modes(mac.as_ref(), &ft, &fm, &PairingOptions::default()).unwrap();
    assert_eq!(p.index_pairs(), vec![(0, 1), (1, 0)]);
    assert_eq!(p.unpaired_test, vec![2]);
    // accepted on MAC alone at +98 % and -49.5 %: both named
    assert_eq!(
        p.warnings,
        [
            "test mode 1 is paired with model mode 2 on MAC 0.950 alone at +98.0 % frequency error: check the pair, or set a frequency window",
            "test mode 2 is paired with model mode 1 on MAC 0.970 alone at -49.5 % frequency error: check the pair, or set a frequency window",
        ]
    );
    // a 10 % window makes both pairs inadmissible and says why each test mode is unpaired
    let windowed = PairingOptions {
        max_frequency_error: Some(0.1),
        ..PairingOptions::default()
    };
    let w = pair_modes(mac.as_ref(), &ft, &fm, &windowed).unwrap();
    assert!(w.pairs.is_empty());
    assert_eq!(w.unpaired_test, vec![0, 1, 2]);
    assert_eq!(w.warnings.len(), 2, "{:?}", w.warnings);
    assert!(w.warnings[0].starts_with("test mode 1 is unpaired"));
    // a window of 100 % admits them again, without warnings
    let wide = PairingOptions {
        max_frequency_error: Some(1.0),
        ..PairingOptions::default()
    };
    let w = pair_modes(mac.as_ref(), &ft, &fm, &wide).unwrap();
    assert_eq!(w.index_pairs(), vec![(0, 1), (1, 0)]);
    assert!(w.warnings.is_empty());
    let bad = PairingOptions {
        max_frequency_error: Some(-0.1),
        ..PairingOptions::default()
    };
    assert!(pair_modes(mac.as_ref(), &ft, &fm, &bad).is_err());
    let pair = p.of_test(0).unwrap();
    assert!((pair.frequency_error - (198.0 - 100.0) / 100.0).abs() < 1e-15);
    assert!(
        (pair.eigenvalue_gap
            - (4.0 * std::f64::consts::PI.powi(2) * (198.0f64.powi(2) - 100.0f64.powi(2))))
        .abs()
            < 1e-6
    );
    // Greedy picks (0,0) = 0.9 and leaves test 1 with 0.1 (unpaired); assignment pairs both.
    let trap = Mat::from_fn(2, 2, |i, j| [[0.9, 0.85], [0.88, 0.1]][i][j]);
    let p = pair_modes(
        trap.as_ref(),
        &ft[..2],
        &fm[..2],
        &PairingOptions::default(),
    )
    .unwrap();
    assert_eq!(p.index_pairs(), vec![(0, 1), (1, 0)]);
    assert!(p.unpaired_test.is_empty());
    // More test modes than model modes.
    let tall = Mat::from_fn(3, 1, |i, _| [0.3, 0.9, 0.85][i]);
    let p = pair_modes(tall.as_ref(), &ft, &fm[..1], &PairingOptions::default()).unwrap();
    assert_eq!(p.index_pairs(), vec![(1, 0)]);
    assert_eq!(p.unpaired_test, vec![0, 2]);
    // A stricter threshold unpairs.
    let p = pair_modes(
        trap.as_ref(),
        &ft[..2],
        &fm[..2],
        &PairingOptions {
            mac_threshold: 0.89,
            ..PairingOptions::default()
        },
    )
    .unwrap();
    assert_eq!(p.index_pairs(), vec![(0, 0)]);
    // Bad input
    let nan = Mat::from_fn(1, 1, |_, _| f64::NAN);
    assert!(pair_modes(nan.as_ref(), &ft[..1], &fm[..1], &PairingOptions::default()).is_err());
    assert!(
        pair_modes(
            trap.as_ref(),
            &ft[..2],
            &fm[..2],
            &PairingOptions {
                mac_threshold: 0.0,
                ..PairingOptions::default()
            }
        )
        .is_err()
    );
    assert!(pair_modes(trap.as_ref(), &ft, &fm[..2], &PairingOptions::default()).is_err());
}

/// The one-call workflow: test modes of a "real" structure (20 % softer near the clamp) measured
/// by triaxial sensors at the free end and the middle, listed out of order; `correlate` pairs them
/// back, its MAC entries equal the direct computation, and `estimate` on full-length vectors gives
/// intervals that each hold a model eigenvalue (dense reference).
#[test]
fn correlate_and_estimate_reports() {
    use femu_correlate::modes::eigenvalue_of_hz;
    use femu_correlate::{
        ModeSet, ModelSpectrum, SensorLayout, SpectrumProof, TestModes, correlate, estimate,
    };
    let model = bar([8, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let eig = full_eigen(&sys);
    let modes = ModeSet::new(
        eig.values[..6].to_vec(),
        eig.vectors.as_ref().subcols(0, 6).to_owned(),
        true,
    )
    .unwrap();
    let mesh = model.mesh();
    let nodes: Vec<u64> = mesh
        .node_set("xmax")
        .unwrap()
        .iter()
        .chain(
            mesh.node_set("ymin")
                .unwrap()
                .iter()
                .filter(|&&n| (mesh.coords()[n][0] - 0.1).abs() < 1e-9),
        )
        .map(|&n| mesh.node_id(n))
        .collect();
    let layout = SensorLayout::triaxial(mesh, &sys.dofs, &nodes).unwrap();
    // truth modes 0..4, listed as test modes in the order 0, 2, 1, 3
    let order = [0, 2, 1, 3];
    let truth: Vec<(f64, Vec<f64>)> = order
        .iter()
        .map(|&j| perturbed_mode(&model, 0.05, 0.8, j))
        .collect();
    let n = sys.dofs.free_count();
    let full = Mat::from_fn(n, 4, |i, j| truth[j].1[i]);
    let at_sensors = layout.measure_all(full.as_ref()).unwrap();
    let f_test: Vec<f64> = truth
        .iter()
        .map(|(l, _)| femu_correlate::modes::hz_of_eigenvalue(*l))
        .collect();
    let test = TestModes::new(f_test.clone(), None, at_sensors.clone()).unwrap();
    let report = correlate(&modes, &test, &layout, &PairingOptions::default()).unwrap();
    assert_eq!(
        report.pairing.index_pairs(),
        vec![(0, 0), (1, 2), (2, 1), (3, 3)]
    );
    let phia = layout.measure_all(modes.shapes.as_ref()).unwrap();
    for p in &report.pairing.pairs {
        let direct = mac(
            &at_sensors.col(p.test).iter().copied().collect::<Vec<_>>(),
            &phia.col(p.model).iter().copied().collect::<Vec<_>>(),
        )
        .unwrap();
        assert!((report.mac[p.test][p.model] - direct).abs() < 1e-15);
        assert!(p.mac.unwrap() > 0.9);
        // the real structure is softer: every model frequency is above the test one
        assert!(p.frequency_error > 0.0);
    }
    assert_eq!(report.comac.len(), layout.len());
    let table = report.to_string();
    assert!(
        table.starts_with("| test | f test (Hz)")
            && table.lines().filter(|l| l.starts_with('|')).count() == 6
            && table.contains("error = (f model - f test) / f test")
            && !table.contains("warning"),
        "{table}"
    );
    // estimate: every interval holds a model eigenvalue; the rigorous T2 holds.
    let spectrum = ModelSpectrum {
        values: eig.values.clone(),
        proof: SpectrumProof::Complete,
        lambda_max: *eig.values.last().unwrap(),
        mu_min: None,
    };
    let lambdas: Vec<f64> = f_test.iter().map(|f| eigenvalue_of_hz(*f)).collect();
    let paired: Vec<Option<usize>> = (0..4)
        .map(|t| report.pairing.of_test(t).map(|p| p.model))
        .collect();
    let assessments = estimate(
        &sys.k,
        &sys.m,
        &lambdas,
        full.as_ref(),
        &spectrum,
        Some(&modes),
        &paired,
    )
    .unwrap();
    for a in &assessments {
        let (lo, hi) = a.norms.eigenvalue_interval();
        assert!(eig.values.iter().any(|l| *l >= lo && *l <= hi));
        for b in a.bounds.iter().filter(|b| b.theorem) {
            assert_eq!(b.holds(), Some(true), "test {}: {b:?}", a.test);
        }
        let (flo, fhi) = a.frequency_interval_hz;
        assert!(flo <= f_test[a.test] && f_test[a.test] <= fhi);
    }
}

/// A sensor on a node that a rigid link makes dependent reads that node's displacement, the
/// combination `u = T z` (its row of `T`), in any direction; a sensor on a fixed DOF is an error.
#[test]
fn sensors_on_linked_nodes_read_the_linked_motion() {
    use femu_correlate::SensorLayout;
    use femu_correlate::sensors::Sensor;
    let mut mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.1, 0.05],
        [4, 2, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    mesh.add_node(77, [0.25, 0.05, 0.0]).unwrap();
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let end: Vec<u64> = mesh
        .node_set("xmax")
        .unwrap()
        .iter()
        .map(|i| mesh.node_id(*i))
        .collect();
    model.add_rigid_link(77, &end, &[0, 1, 2], "end").unwrap();
    let dofs = model.dof_map().unwrap();
    let dir = [0.3, -0.5, 0.8];
    let layout = SensorLayout::new(
        model.mesh(),
        &dofs,
        vec![Sensor::axis(end[2], 1), Sensor::new(end[5], dir)],
    )
    .unwrap();
    let z: Vec<f64> = (0..dofs.free_count())
        .map(|i| ((i * 7) % 13) as f64 - 6.0)
        .collect();
    let u = dofs.expand(&z).unwrap();
    let y = layout.measure(&z).unwrap();
    let (a, b) = (
        mesh.node_index(end[2]).unwrap(),
        mesh.node_index(end[5]).unwrap(),
    );
    let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    let want_b: f64 = (0..3).map(|c| dir[c] / norm * u[3 * b + c]).sum();
    assert!((y[0] - u[3 * a + 1]).abs() < 1e-12 && (y[1] - want_b).abs() < 1e-12);
    let fixed = mesh.node_id(mesh.node_set("xmin").unwrap()[0]);
    assert!(SensorLayout::new(model.mesh(), &dofs, vec![Sensor::axis(fixed, 0)]).is_err());
}

/// A simulated test must not depend on the arbitrary sign of an eigenvector: flipping columns
/// gives the same signed shapes, also for a shape antisymmetric in the reading order (mirror
/// pairs `v, -v`), whose plain sum vanishes.
#[test]
fn canonical_signs_do_not_depend_on_the_eigenvector_sign() {
    let mut rng = Rng(7);
    let mut y = Mat::from_fn(30, 6, |i, j| {
        if j == 5 {
            if i < 15 {
                (i + 1) as f64
            } else {
                -((30 - i) as f64)
            }
        } else {
            rng.sym()
        }
    });
    assert_eq!(y.col(5).iter().sum::<f64>(), 0.0);
    let mut flipped = y.clone();
    for j in [0, 2, 5] {
        flipped.col_mut(j).iter_mut().for_each(|v| *v = -*v);
    }
    femu_correlate::modes::canonical_signs(&mut y);
    femu_correlate::modes::canonical_signs(&mut flipped);
    assert_eq!(y, flipped);
    // and the sign is the one of the weighted sum, by hand for the antisymmetric shape:
    // sum_i (1 + frac(0.618 i)) y_i over mirror pairs
    let w = |i: usize| 1.0 + (0.618_033_988_749_894_9 * i as f64).fract();
    let s: f64 = (0..30).map(|i| w(i) * y[(i, 5)]).sum();
    assert!(s > 0.0);
}

/// A repeated eigenvalue (values 2, 2): the model's basis of its plane, turned by any angle, is
/// turned back onto the test's by `align_repeated`, so each test mode of the pair has MAC 1 with
/// one model mode whatever basis the eigensolver returned; a mode that is not repeated is left as
/// it is; a single test mode in the plane is matched by the first mode of the cluster. Reference:
/// the readings written by hand, MAC by its definition.
#[test]
fn repeated_modes_are_turned_towards_the_test() {
    use femu_correlate::correlation::align_repeated;
    let s = 6;
    let a: Vec<f64> = vec![1.0, 0.5, -0.3, 0.2, 0.0, -0.7];
    let b: Vec<f64> = vec![0.1, -0.4, 0.9, 0.3, -0.6, 0.2];
    let c: Vec<f64> = vec![0.3, 0.3, 0.3, -0.2, 0.8, 0.1];
    let mac = |x: &[f64], y: &[f64]| {
        let d: f64 = x.iter().zip(y).map(|(p, q)| p * q).sum();
        d * d / (x.iter().map(|p| p * p).sum::<f64>() * y.iter().map(|q| q * q).sum::<f64>())
    };
    // the test: c (mode 1), then a and b (the pair), scaled and with a sign flipped
    let test = Mat::from_fn(s, 3, |i, j| match j {
        0 => 2.0 * c[i],
        1 => -3.0 * a[i],
        _ => 0.5 * b[i],
    });
    let values = [1.0, 2.0, 2.0 * (1.0 + 1e-12)];
    let mut previous: Option<Mat<f64>> = None;
    for angle in [0.0_f64, 30.0, 45.0, 60.0, 90.0, 137.0] {
        let (sn, cs) = angle.to_radians().sin_cos();
        let phia = Mat::from_fn(s, 3, |i, j| match j {
            0 => c[i],
            1 => cs * a[i] + sn * b[i],
            _ => -sn * a[i] + cs * b[i],
        });
        let (turned, clusters) = align_repeated(&values, phia.as_ref(), test.as_ref()).unwrap();
        assert_eq!(clusters.len(), 1);
        assert_eq!(clusters[0].0, vec![1, 2]);
        let col = |m: &Mat<f64>, j: usize| -> Vec<f64> { m.col(j).iter().copied().collect() };
        // the single mode is untouched, the pair matches a and b
        assert_eq!(col(&turned, 0), c);
        assert!(
            (mac(&col(&turned, 1), &a) - 1.0).abs() < 1e-12,
            "angle {angle}"
        );
        assert!(
            (mac(&col(&turned, 2), &b) - 1.0).abs() < 1e-12,
            "angle {angle}"
        );
        // the same readings whatever the starting basis (up to round-off)
        if let Some(p) = &previous {
            for j in 0..3 {
                for i in 0..s {
                    assert!((turned[(i, j)] - p[(i, j)]).abs() < 1e-12, "angle {angle}");
                }
            }
        }
        previous = Some(turned);
        // one test mode in the plane (a + b, unit weights): the first mode of the pair matches it
        let one = Mat::from_fn(s, 1, |i, _| a[i] + b[i]);
        let (t1, _) = align_repeated(&values, phia.as_ref(), one.as_ref()).unwrap();
        let ab: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p + q).collect();
        assert!(
            (mac(&col(&t1, 1), &ab) - 1.0).abs() < 1e-12,
            "angle {angle}"
        );
    }
}

/// The complex MAC by hand: `a = (1, i)` against the real `b = (1, 1)`: `a^H b = 1 - i`, so
/// `|a^H b|^2 = 2` over `(a^H a)(b^H b) = 4`: 0.5 (the MAC of `a`'s real part is also 0.5, of its
/// imaginary part 0.5: neither alone tells). A complex multiple of `a` gives 1; real vectors give
/// the real MAC; a zero vector and mismatched lengths are errors.
#[test]
fn complex_mac_by_hand() {
    let v = complex_mac(&[1.0, 0.0], &[0.0, 1.0], &[1.0, 1.0], &[0.0, 0.0]).unwrap();
    assert!((v - 0.5).abs() < 1e-15, "{v}");
    // a = (1 + 2i, -0.5i, 3), b = (0.6 - 0.8i) a
    let (ar, ai) = ([1.0, 0.0, 3.0], [2.0, -0.5, 0.0]);
    let (cr, ci) = (0.6, -0.8);
    let br: Vec<f64> = (0..3).map(|k| cr * ar[k] - ci * ai[k]).collect();
    let bi: Vec<f64> = (0..3).map(|k| cr * ai[k] + ci * ar[k]).collect();
    assert!((complex_mac(&ar, &ai, &br, &bi).unwrap() - 1.0).abs() < 1e-15);
    // (1, 2, 0) and (2, 1, 1): (2 + 2)^2 / (5 * 6) = 16 / 30
    let real = complex_mac(&[1.0, 2.0, 0.0], &[0.0; 3], &[2.0, 1.0, 1.0], &[0.0; 3]).unwrap();
    assert!((real - 16.0 / 30.0).abs() < 1e-15);
    assert!((real - mac(&[1.0, 2.0, 0.0], &[2.0, 1.0, 1.0]).unwrap()).abs() < 1e-15);
    assert!(complex_mac(&[0.0; 2], &[0.0; 2], &[1.0, 1.0], &[0.0; 2]).is_err());
    assert!(complex_mac(&[1.0; 2], &[0.0; 3], &[1.0, 1.0], &[0.0; 2]).is_err());
}
