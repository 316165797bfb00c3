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
