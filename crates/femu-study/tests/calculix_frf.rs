//! femu's modal FRFs against CalculiX's `*STEADY STATE DYNAMICS` on the same deck: a clamped hex8
//! bar written by femu-io, its 8 lowest modes (`*FREQUENCY, STORAGE=YES`) superposed by CalculiX
//! with 2 % modal damping (`*MODAL DAMPING`) for a unit force at the tip in z, the displacements
//! at two nodes printed (7 digits, real and imaginary parts) at CalculiX's own lines (its points
//! between the band's ends and the eigenfrequencies, the eigenfrequencies included). femu
//! superposes its own 8 modes with the same ratio and no residual flexibility (CalculiX adds
//! none). `.ci/run` installs CalculiX and sets `FEMU_REQUIRE_CCX=1`.

use faer::c64;
use femu_correlate::frf::{Damping, FrfOptions, ResponseKind, modal_frf};
use femu_correlate::{Sensor, SensorLayout};
use femu_fem::prelude::*;

/// A node's row of a `.dat` block: its id and three values.
type NodeRow = (u64, [f64; 3]);

/// `(hz, node, [u; 3])` per line and node from the `.dat` file's "displacements (vx,vy,vz)"
/// blocks: a block of real parts followed by one of imaginary parts at the same time (Hz).
fn ccx_displacements(dat: &str) -> Vec<(f64, u64, [c64; 3])> {
    let mut blocks: Vec<(f64, Vec<NodeRow>)> = Vec::new();
    let mut lines = dat.lines().peekable();
    while let Some(l) = lines.next() {
        let Some(rest) = l.trim().strip_prefix("displacements (vx,vy,vz) for set") else {
            continue;
        };
        let time: f64 = rest.split_whitespace().last().unwrap().parse().unwrap();
        let mut rows = Vec::new();
        // a blank line, then one row per node until the next blank line
        let _ = lines.next();
        while let Some(r) = lines.peek() {
            let f: Vec<&str> = r.split_whitespace().collect();
            if f.len() != 4 {
                break;
            }
            rows.push((
                f[0].parse().unwrap(),
                [
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                    f[3].parse().unwrap(),
                ],
            ));
            lines.next();
        }
        blocks.push((time, rows));
    }
    assert!(
        blocks.len().is_multiple_of(2) && !blocks.is_empty(),
        "{} blocks",
        blocks.len()
    );
    blocks
        .chunks(2)
        .flat_map(|pair| {
            let (hz, re) = &pair[0];
            let (hz_im, im) = &pair[1];
            assert_eq!(hz, hz_im);
            re.iter()
                .zip(im)
                .map(|((n, a), (m, b))| {
                    assert_eq!(n, m);
                    (*hz, *n, [0, 1, 2].map(|c| c64::new(a[c], b[c])))
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Every receptance CalculiX prints (2 nodes x 3 components, 36 lines from 10 to 5000 Hz with 4
/// modes inside, their eigenfrequencies among the lines) equals femu's to 1e-5 of its function's
/// peak (measured: 6.0e-6, CalculiX's 7 printed digits and the eigenvalues' 1e-6 agreement
/// magnified by 1 / (2 zeta) at the peaks).
#[test]
fn modal_frfs_agree_with_calculix_steady_state_dynamics() {
    if !femu_testkit::ccx::available() {
        return;
    }
    let model = femu_testkit::bar([6, 1, 1], true);
    let mesh = model.mesh();
    let node_at = |x: [f64; 3]| {
        let i = mesh
            .coords()
            .iter()
            .position(|c| (0..3).all(|k| (c[k] - x[k]).abs() < 1e-12))
            .unwrap();
        mesh.node_id(i)
    };
    let tip = node_at([0.2, 0.0, 0.02]);
    let mid = node_at([0.1, 0.04, 0.02]);
    let mut deck = femu_io::inp::inp_string(&model, None).unwrap();
    deck.push_str(&format!(
        "*NSET, NSET=OUT\n{tip}, {mid}\n*STEP\n*FREQUENCY, STORAGE=YES\n8\n*END STEP\n\
         *STEP\n*STEADY STATE DYNAMICS\n10., 5000., 8, 1.\n*MODAL DAMPING\n1, 8, 0.02\n\
         *CLOAD\n{tip}, 3, 1.\n*NODE PRINT, NSET=OUT\nU\n*END STEP\n"
    ));
    let dir = std::env::temp_dir().join(format!("femu-ccx-ssd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), &deck).unwrap();
    femu_testkit::ccx::run(&dir, "bar");
    let dat = std::fs::read_to_string(dir.join("bar.dat")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let ccx = ccx_displacements(&dat);
    let mut lines: Vec<f64> = ccx.iter().map(|r| r.0).collect();
    lines.dedup();
    // femu: its 8 lowest modes, the same ratio, no residual flexibility
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = femu_sparse::eigen::eigs(
        &sys.k,
        &sys.m,
        femu_sparse::eigen::Which::Lowest(8),
        &Default::default(),
    )
    .unwrap();
    let inside = modes
        .frequencies_hz()
        .iter()
        .filter(|f| **f > 10.0 && **f < 5000.0)
        .count();
    assert!(inside >= 2, "{:?}", modes.frequencies_hz());
    let outputs: Vec<Sensor> = [tip, mid]
        .iter()
        .flat_map(|n| (0..3).map(|c| Sensor::axis(*n, c)))
        .collect();
    let outputs = SensorLayout::new(mesh, &sys.dofs, outputs).unwrap();
    let inputs = SensorLayout::new(mesh, &sys.dofs, vec![Sensor::axis(tip, 2)]).unwrap();
    let frf = modal_frf(
        &modes.values,
        modes.vectors.as_ref(),
        None,
        &outputs,
        &inputs,
        &lines,
        &FrfOptions {
            damping: Damping::Ratio(0.02),
            kind: ResponseKind::Receptance,
        },
    )
    .unwrap();
    // each of the 6 functions against its own peak
    let mut worst = 0.0f64;
    for (o, (node, c)) in [tip, mid]
        .iter()
        .flat_map(|n| (0..3).map(move |c| (*n, c)))
        .enumerate()
    {
        let theirs: Vec<c64> = ccx.iter().filter(|r| r.1 == node).map(|r| r.2[c]).collect();
        assert_eq!(theirs.len(), lines.len());
        let peak = theirs.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (l, t) in theirs.iter().enumerate() {
            let ours = frf.h[l][(o, 0)];
            let e = (ours - t).norm() / peak;
            worst = worst.max(e);
            assert!(
                e < 1e-5,
                "node {node} component {c} at {} Hz: femu {ours} CalculiX {t} ({e:.1e} of the peak {peak:.3e})",
                lines[l]
            );
        }
    }
    eprintln!(
        "{} lines, worst {worst:.2e} of a function's peak",
        lines.len()
    );
}
