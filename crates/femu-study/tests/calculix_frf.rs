//! femu's modal FRFs against CalculiX's `*STEADY STATE DYNAMICS` on the same deck: a clamped hex8
//! bar written by femu-io, its 8 lowest modes (`*FREQUENCY, STORAGE=YES`) superposed by CalculiX
//! with 2 % modal damping (`*MODAL DAMPING`) for a unit force at the tip in z, the displacements
//! at two nodes printed (7 digits, real and imaginary parts) at CalculiX's own lines (its points
//! between the band's ends and the eigenfrequencies, the eigenfrequencies included). femu
//! superposes its own 8 modes with the ratios it reads from the same deck's `*MODAL DAMPING` and no
//! residual flexibility (CalculiX adds
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

/// CalculiX run on `deck` (as `bar.inp` in a folder of its own named by `tag`): its `bar.dat`.
fn calculix_dat(deck: &str, tag: &str) -> String {
    let dir = std::env::temp_dir().join(format!("femu-ccx-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bar.inp"), deck).unwrap();
    femu_testkit::ccx::run(&dir, "bar");
    let dat = std::fs::read_to_string(dir.join("bar.dat")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    dat
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
    let ccx = ccx_displacements(&calculix_dat(&deck, "ssd"));
    // femu reads the same deck's *MODAL DAMPING: modes 1 to 8 at 2 %
    let read = femu_io::inp::parse_inp(&deck, "bar.inp")
        .unwrap()
        .to_model()
        .unwrap();
    let ratios: Vec<f64> = (1..=8).map(|r| read.mode_ratio(r).unwrap()).collect();
    assert_eq!(ratios, vec![0.02; 8]);
    assert_eq!(read.mode_ratio(9), Some(0.0));
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
            damping: Damping::Ratios(ratios),
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

/// A clamped 6 x 1 x 1 hex8 bar of two materials, each with its own structural damping
/// (`*DAMPING, STRUCTURAL=` in the `*MATERIAL`, CalculiX's and Abaqus' material damping): steel
/// (0.06) on the clamped half, aluminium (0.01) on the free half; the steps that CalculiX runs on
/// it appended by the caller. Returns the deck and the ids of the tip and a mid-length node.
fn two_material_bar() -> (String, u64, u64) {
    let (nx, l, w, h) = (6usize, 0.2, 0.04, 0.02);
    let id = |i: usize, j: usize, k: usize| (1 + i + (nx + 1) * (j + 2 * k)) as u64;
    let mut deck = String::from("*NODE\n");
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..=nx {
                deck.push_str(&format!(
                    "{}, {}, {}, {}\n",
                    id(i, j, k),
                    l * i as f64 / nx as f64,
                    w * j as f64,
                    h * k as f64
                ));
            }
        }
    }
    for (set, range) in [("EA", 0..3), ("EB", 3..nx)] {
        deck.push_str(&format!("*ELEMENT, TYPE=C3D8, ELSET={set}\n"));
        for i in range {
            let c = [
                id(i, 0, 0),
                id(i + 1, 0, 0),
                id(i + 1, 1, 0),
                id(i, 1, 0),
                id(i, 0, 1),
                id(i + 1, 0, 1),
                id(i + 1, 1, 1),
                id(i, 1, 1),
            ];
            let c: Vec<String> = c.iter().map(u64::to_string).collect();
            deck.push_str(&format!("{}, {}\n", i + 1, c.join(", ")));
        }
    }
    deck.push_str(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n2.1e11, 0.3\n*DENSITY\n7850.\n*DAMPING, STRUCTURAL=0.06\n\
         *MATERIAL, NAME=ALU\n*ELASTIC\n7.0e10, 0.33\n*DENSITY\n2700.\n*DAMPING, STRUCTURAL=0.01\n\
         *SOLID SECTION, ELSET=EA, MATERIAL=STEEL\n*SOLID SECTION, ELSET=EB, MATERIAL=ALU\n*BOUNDARY\n",
    );
    for k in 0..2 {
        for j in 0..2 {
            deck.push_str(&format!("{}, 1, 3\n", id(0, j, k)));
        }
    }
    (deck, id(nx, 0, 1), id(3, 1, 1))
}

/// The structural damping of each material, read from `*DAMPING, STRUCTURAL=` into
/// `K_4 = sum_e GE_e K_e`, is the damping CalculiX builds from the same deck: CalculiX's
/// `*STEADY STATE DYNAMICS` on its 12 lowest modes (the material damping projected on them, a
/// full modal damping matrix) equals, to 1e-5 of each function's peak, the same projection of
/// femu's `K`, `M` and `K_4` computed densely in the test, and femu's modal route with its dampers
/// projected on the same modes (`modal_frf_coupled`); femu's direct route
/// (`(K + i K_4 - w^2 M) u = f`, every mode) equals the dense solve of that system to round-off,
/// and differs from CalculiX's 12 modes by what those modes leave out, printed.
#[test]
fn material_structural_damping_agrees_with_calculix() {
    use faer::linalg::solvers::Solve;
    use femu_correlate::frf::{DirectSystem, direct_frf};
    if !femu_testkit::ccx::available() {
        return;
    }
    let (mut deck, tip, mid) = two_material_bar();
    // CalculiX's ARPACK takes at most 12 of this bar's 72 free DOFs' modes
    let modes = 12;
    let femu_deck = deck.clone();
    deck.push_str(&format!(
        "*NSET, NSET=OUT\n{tip}, {mid}\n*STEP\n*FREQUENCY, STORAGE=YES\n{modes}\n*END STEP\n\
         *STEP\n*STEADY STATE DYNAMICS\n10., 9000., 6, 1.\n*CLOAD\n{tip}, 3, 1.\n\
         *NODE PRINT, NSET=OUT\nU\n*END STEP\n"
    ));
    let ccx = ccx_displacements(&calculix_dat(&deck, "damping"));
    let mut lines: Vec<f64> = ccx.iter().map(|r| r.0).collect();
    lines.dedup();

    // femu reads the deck (its material damping among it)
    let model = femu_io::inp::parse_inp(&femu_deck, "bar.inp")
        .unwrap()
        .to_model()
        .unwrap();
    assert_eq!(model.element_damping().len(), 6);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let asm = femu_fem::assembly::Assembler::new(&model).unwrap();
    let dampers = asm
        .dampers(&model, femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    let k4 = dampers.structural.as_ref().expect("the materials' damping");
    let (kd, md, k4d) = (
        femu_sparse::csc::to_dense(&sys.k),
        femu_sparse::csc::to_dense(&sys.m),
        femu_sparse::csc::to_dense(k4),
    );
    let n = kd.nrows();
    let eig = femu_sparse::dense::generalized_symmetric_eigen(kd.as_ref(), md.as_ref()).unwrap();
    let phi = eig.vectors.subcols(0, modes).to_owned();
    let pdp = phi.transpose() * &k4d * &phi;
    let outputs: Vec<Sensor> = [tip, mid]
        .iter()
        .flat_map(|n| (0..3).map(|c| Sensor::axis(*n, c)))
        .collect();
    let outputs = SensorLayout::new(model.mesh(), &sys.dofs, outputs).unwrap();
    let inputs = SensorLayout::new(model.mesh(), &sys.dofs, vec![Sensor::axis(tip, 2)]).unwrap();
    let rows: Vec<usize> = (0..6)
        .map(|o| {
            let (node, c) = ([tip, mid][o / 3], o % 3);
            let i = model.mesh().node_index(node).unwrap();
            sys.dofs.free_index(i, c).unwrap()
        })
        .collect();
    let force = rows[2];
    let direct = direct_frf(
        &DirectSystem {
            k: &sys.k,
            m: &sys.m,
            viscous: None,
            structural: Some(k4),
        },
        &outputs,
        &inputs,
        &lines,
        &FrfOptions {
            damping: Damping::Ratio(0.0),
            kind: ResponseKind::Receptance,
        },
    )
    .unwrap();
    // femu's modal route with the dampers projected on the same 12 modes
    let coupled = femu_correlate::frf::modal_frf_coupled(
        &eig.values[..modes],
        phi.as_ref(),
        None,
        &outputs,
        &inputs,
        &lines,
        &FrfOptions {
            damping: Damping::Ratio(0.0),
            kind: ResponseKind::Receptance,
        },
        Some(&femu_correlate::frf::ModalDampers::project(Some(k4), None, phi.as_ref()).unwrap()),
    )
    .unwrap();
    let (mut worst_modal, mut worst_direct, mut truncation) = (0.0f64, 0.0f64, 0.0f64);
    let mut worst_coupled = 0.0f64;
    for o in 0..6 {
        let (node, c) = ([tip, mid][o / 3], o % 3);
        let theirs: Vec<c64> = ccx.iter().filter(|r| r.1 == node).map(|r| r.2[c]).collect();
        assert_eq!(theirs.len(), lines.len());
        let peak = theirs.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (l, &hz) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * hz;
            // the 12 modes with the projected damping, densely
            let z = faer::Mat::<c64>::from_fn(modes, modes, |i, j| {
                let diag = if i == j { eig.values[i] - w * w } else { 0.0 };
                c64::new(diag, pdp[(i, j)])
            });
            let rhs = faer::Mat::<c64>::from_fn(modes, 1, |i, _| c64::new(phi[(force, i)], 0.0));
            let q = z.as_ref().partial_piv_lu().solve(&rhs);
            let modal: c64 = (0..modes).map(|i| q[(i, 0)] * phi[(rows[o], i)]).sum();
            // every mode: the whole damped system, densely
            let a = faer::Mat::<c64>::from_fn(n, n, |i, j| {
                c64::new(kd[(i, j)] - w * w * md[(i, j)], k4d[(i, j)])
            });
            let mut f = faer::Mat::<c64>::zeros(n, 1);
            f[(force, 0)] = c64::new(1.0, 0.0);
            let full = a.as_ref().partial_piv_lu().solve(&f)[(rows[o], 0)];
            let ours = direct.frf.h[l][(o, 0)];
            let e = (modal - theirs[l]).norm() / peak;
            assert!(
                e < 1e-5,
                "node {node} component {c} at {hz} Hz: CalculiX {} against the 12 modes {modal} ({e:.1e} of the peak)",
                theirs[l]
            );
            worst_modal = worst_modal.max(e);
            let ec = (coupled.h[l][(o, 0)] - theirs[l]).norm() / peak;
            assert!(
                ec < 1e-5,
                "node {node} component {c} at {hz} Hz: femu's coupled modal route {} against CalculiX {} ({ec:.1e} of the peak)",
                coupled.h[l][(o, 0)],
                theirs[l]
            );
            worst_coupled = worst_coupled.max(ec);
            worst_direct = worst_direct.max((ours - full).norm() / full.norm().max(1e-300));
            truncation = truncation.max((ours - theirs[l]).norm() / peak);
        }
    }
    assert!(
        worst_direct < 1e-9,
        "direct route against the dense solve: {worst_direct:.1e}"
    );
    eprintln!(
        "{} lines: CalculiX against its 12 modes {worst_modal:.1e} of a peak, femu's modal route on them {worst_coupled:.1e}, femu's direct route against the dense solve {worst_direct:.1e}, against CalculiX (the modes left out) {truncation:.1e}",
        lines.len()
    );
}
