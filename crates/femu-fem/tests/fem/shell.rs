//! The 4-node shell: rigid-body modes and mass of one element turned in space, membrane and
//! bending patch tests on a distorted mesh, a simply supported plate against Kirchhoff's
//! frequencies, no shear locking from thickness ratios 1/10 to 1/1000, and NAFEMS FV16.

use femu_fem::assembly::MassKind;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use femu_fem::shell::{Membrane, Shell};
use femu_fem::structural::{StructuralElement, StructuralKind};
use femu_sparse::eigen::{EigenOptions, Which};
use std::f64::consts::PI;

fn steel(t: f64) -> Shell {
    Shell {
        e: 2.0e11,
        nu: 0.3,
        rho: 8000.0,
        t,
        bending: 1.0,
        shear: Some(5.0 / 6.0),
        nsm: 0.0,
        material: None,
        offset: 0.0,
        membrane: Membrane::Incompatible,
    }
}

/// A rectangular plate `a x b` in the x-y plane of `nx x ny` shells, nodes `1 + i + (nx + 1) j`
/// (corners moved by `jitter(i, j)` in the plane), with its grid indices.
fn plate(
    a: f64,
    b: f64,
    nx: usize,
    ny: usize,
    s: Shell,
    jitter: impl Fn(usize, usize) -> [f64; 2],
) -> Model {
    let mut mesh = Mesh::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let d = jitter(i, j);
            let x = a * i as f64 / nx as f64 + d[0];
            let y = b * j as f64 / ny as f64 + d[1];
            mesh.add_node((1 + i + (nx + 1) * j) as u64, [x, y, 0.0])
                .unwrap();
        }
    }
    let mut model = Model::new(mesh).unwrap();
    let triangles = TRIANGLES.with(|t| t.get());
    for j in 0..ny {
        for i in 0..nx {
            let n = |i: usize, j: usize| i + (nx + 1) * j;
            let quad = [n(i, j), n(i + 1, j), n(i + 1, j + 1), n(i, j + 1)];
            let id = (1 + i + nx * j) as u64;
            let cells: Vec<(u64, Vec<usize>)> = if triangles {
                // alternate diagonals, so that the mesh has no preferred direction
                if (i + j) % 2 == 0 {
                    vec![
                        (2 * id, vec![quad[0], quad[1], quad[2]]),
                        (2 * id + 1, vec![quad[0], quad[2], quad[3]]),
                    ]
                } else {
                    vec![
                        (2 * id, vec![quad[0], quad[1], quad[3]]),
                        (2 * id + 1, vec![quad[1], quad[2], quad[3]]),
                    ]
                }
            } else {
                vec![(id, quad.to_vec())]
            };
            for (id, nodes) in cells {
                model
                    .add_structural(StructuralElement {
                        id,
                        nodes,
                        kind: StructuralKind::Shell(s),
                    })
                    .unwrap();
            }
        }
    }
    model
}

thread_local! {
    /// Whether [`plate`] meshes with triangles (each quadrilateral split in two).
    static TRIANGLES: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with [`plate`] meshing in triangles.
fn with_triangles<T>(f: impl FnOnce() -> T) -> T {
    TRIANGLES.with(|t| t.set(true));
    let out = f();
    TRIANGLES.with(|t| t.set(false));
    out
}

/// One element turned in space: its stiffness has exactly six zero eigenvalues (the drilling
/// stiffness leaves no spurious seventh), and its rigid translations carry `rho t A`.
#[test]
fn one_shell_has_six_rigid_body_modes_and_its_mass() {
    let s = steel(0.02);
    // a parallelogram-like quadrilateral in a turned plane
    let (e1, e2) = ([0.6, 0.8, 0.0], [0.0, 0.0, 1.0]);
    let local = [[0.0, 0.0], [1.0, 0.1], [1.2, 0.9], [0.1, 0.7]];
    let x: [[f64; 3]; 4] = std::array::from_fn(|i| {
        std::array::from_fn(|k| 0.3 + local[i][0] * e1[k] + local[i][1] * e2[k])
    });
    let (k, m) = femu_fem::shell::matrices(&s, &x, MassKind::Consistent).unwrap();
    let kd = nalgebra::DMatrix::from_row_slice(24, 24, &k);
    let vals = kd.symmetric_eigenvalues();
    let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let zeros = vals.iter().filter(|v| v.abs() < 1e-10 * top).count();
    assert_eq!(zeros, 6, "{vals:?}");
    let area = 0.5
        * (0..4)
            .map(|i| {
                let j = (i + 1) % 4;
                local[i][0] * local[j][1] - local[j][0] * local[i][1]
            })
            .sum::<f64>();
    for dir in 0..3 {
        let u: Vec<f64> = (0..24)
            .map(|i| if i % 6 == dir { 1.0 } else { 0.0 })
            .collect();
        let mu: f64 = (0..24)
            .map(|i| (0..24).map(|j| u[i] * m[i * 24 + j] * u[j]).sum::<f64>())
            .sum();
        assert!((mu / (8000.0 * 0.02 * area) - 1.0).abs() < 1e-12, "{mu}");
    }
}

/// A displacement field: the six DOFs at a point.
type Field = dyn Fn([f64; 3]) -> [f64; 6];

/// Patch tests on a distorted 2 x 2 mesh: under a linear in-plane field (with the drilling
/// rotations at its rotation) and under a constant-curvature bending field `w = (a x^2 + b y^2 +
/// c x y) / 2` (rotations `theta_x = w_,y`, `theta_y = -w_,x`), the interior node carries no
/// force: the membrane, the bending and the tied shear strains are exact for them.
#[test]
fn patch_tests_pass_on_a_distorted_mesh() {
    let s = steel(0.05);
    let model = plate(1.0, 1.0, 2, 2, s, |i, j| {
        if (i, j) == (1, 1) {
            [0.13, -0.08]
        } else {
            [0.0, 0.0]
        }
    });
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let dofs = &sys.dofs;
    let coords = model.mesh().coords();
    let centre = model.mesh().node_index(5).unwrap();
    let (a, b, c) = (0.3, -0.2, 0.5);
    let fields: [Box<Field>; 2] = [
        // u = 1e-3 (1 + 2x + 3y), v = 1e-3 (-1 + x - 4y): rotation (v_x - u_y) / 2 = -1e-3
        Box::new(|x: [f64; 3]| {
            [
                1e-3 * (1.0 + 2.0 * x[0] + 3.0 * x[1]),
                1e-3 * (-1.0 + x[0] - 4.0 * x[1]),
                0.0,
                0.0,
                0.0,
                -1e-3,
            ]
        }),
        Box::new(move |x: [f64; 3]| {
            let w = 0.5 * (a * x[0] * x[0] + b * x[1] * x[1] + c * x[0] * x[1]);
            let wx = a * x[0] + 0.5 * c * x[1];
            let wy = b * x[1] + 0.5 * c * x[0];
            [0.0, 0.0, w, wy, -wx, 0.0]
        }),
    ];
    for field in &fields {
        let mut u = vec![0.0; dofs.free_count()];
        for f in 0..dofs.free_count() {
            let (p, comp) = dofs.free_dof(f);
            let (node, rotation) = dofs.point_node(p);
            let v = field(coords[node]);
            u[f] = v[comp + if rotation { 3 } else { 0 }];
        }
        let mut ku = vec![0.0; u.len()];
        femu_sparse::csc::mul_vec(&sys.k, &u, &mut ku).unwrap();
        let scale = ku.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let rot = dofs.rotation_point(centre).unwrap();
        for p in [centre, rot] {
            for comp in 0..3 {
                let f = dofs.free_index(p, comp).unwrap();
                assert!(
                    ku[f].abs() < 1e-9 * scale,
                    "interior force {} of {scale}",
                    ku[f]
                );
            }
        }
    }
}

/// A simply supported square plate (hard support: `w` and the rotation along each edge fixed),
/// 1 m, 10 mm thick: Kirchhoff's `omega_mn = pi^2 (m^2 + n^2) sqrt(D / (rho t))` (Leissa,
/// "Vibration of Plates", 1969) for the modes (1,1), (1,2), (2,1), (2,2), approached from above
/// as the mesh is refined: 0.3 % to 1.2 % with 24 x 24 shells, 0.02 % to 0.16 % with 48 x 48
/// (Reissner-Mindlin's shear and rotary inertia lower the limit by about 0.07 % here).
#[test]
fn simply_supported_plate_matches_kirchhoff() {
    let t = 0.01;
    let s = steel(t);
    let d = 2.0e11 * t.powi(3) / (12.0 * (1.0 - 0.09));
    let base = PI.powi(4) * d / (8000.0 * t);
    let want = [2.0, 5.0, 5.0, 8.0].map(|k: f64| k * k * base);
    let mut previous = [f64::INFINITY; 4];
    for n in [24usize, 48] {
        let values = supported_plate(1.0, 1.0, n, s, 4);
        for (k, (got, w)) in values.iter().zip(want).enumerate() {
            let err = got / w - 1.0;
            assert!(
                err > -1e-3 && err < previous[k],
                "{n}: {got} against {w}: {err}"
            );
            previous[k] = err;
        }
    }
    assert!(previous.iter().all(|e| *e < 2e-3), "{previous:?}");
}

/// A cantilevered strip (1 m x 0.1 m, 20 x 2 shells) from a tenth to a thousandth of its length
/// thick: the first bending frequency divided by the thickness stays within 1 % from 1/100 to
/// 1/1000 (a locking element stiffens by orders of magnitude there), and it lies between
/// Euler-Bernoulli's with `E` and with `E / (1 - nu^2)` (a strip between a beam and a plate).
#[test]
fn no_shear_locking_from_thick_to_thin() {
    super::common::assert_no_shear_locking(|t| {
        let mut model = plate(1.0, 0.1, 20, 2, steel(t), |_, _| [0.0, 0.0]);
        for j in 0..=2 {
            model
                .fix_node_dofs((1 + 21 * j) as u64, &[0, 1, 2, 3, 4, 5])
                .unwrap();
        }
        model
    });
}

/// NAFEMS FV16 (cantilevered thin square plate: 10 m, 0.05 m thick, E = 200 GPa, nu = 0.3,
/// rho = 8000, clamped along one edge): the reference frequencies 0.421, 1.029, 2.582, 3.306,
/// 3.753 and 6.555 Hz (NAFEMS, "Selected Benchmarks for Natural Frequency Analysis", 1987;
/// Leissa's C-F-F-F plate), with a 16 x 16 mesh to 1 %.
#[test]
fn nafems_fv16_cantilevered_square_plate() {
    let n = 16;
    let mut model = plate(10.0, 10.0, n, n, steel(0.05), |_, _| [0.0, 0.0]);
    for j in 0..=n {
        model
            .fix_node_dofs((1 + (n + 1) * j) as u64, &[0, 1, 2, 3, 4, 5])
            .unwrap();
    }
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = sys
        .modes(Which::Lowest(6), &EigenOptions::default())
        .unwrap();
    femu_testkit::assert_frequencies(
        &modes.values,
        &[0.421, 1.029, 2.582, 3.306, 3.753, 6.555],
        1e-2,
        "FV16",
    );
}

/// NAFEMS FV12 (free thin square plate: 10 m, 0.05 m thick, E = 200 GPa, nu = 0.3, rho = 8000,
/// no support): six rigid-body modes, then the reference frequencies 1.622, 2.360, 2.922, 4.233,
/// 4.233 and 7.416 Hz (NAFEMS, "Selected Benchmarks for Natural Frequency Analysis", 1987), with
/// a 24 x 24 mesh to 1 % (0.03 % to 0.8 % measured; 16 x 16 is 1.4 % high on the sixth).
#[test]
fn nafems_fv12_free_square_plate() {
    let model = plate(10.0, 10.0, 24, 24, steel(0.05), |_, _| [0.0, 0.0]);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = sys
        .modes(Which::Lowest(12), &EigenOptions::default())
        .unwrap();
    let first = modes.values[6];
    for l in &modes.values[..6] {
        assert!(l.abs() < 1e-8 * first, "{:?}", modes.values);
    }
    let reference = [1.622, 2.360, 2.922, 4.233, 4.233, 7.416];
    for (l, r) in modes.values[6..].iter().zip(reference) {
        let f = l.sqrt() / (2.0 * PI);
        assert!((f / r - 1.0).abs() < 1e-2, "{f} Hz against {r}");
    }
}

/// The 3-node shell (MITC3): one triangle turned in space has six zero stiffness eigenvalues and
/// carries `rho t A`; on a distorted mesh of triangles the membrane and bending patch tests leave
/// no force on the interior node; NAFEMS FV16 with 32 x 32 x 2 triangles to 1 % (0.2-0.7 %
/// measured; the linear triangle converges more slowly than the quadrilateral: 16 x 16 x 2 is
/// 3.6 % high on the sixth mode); a strip's frequency over thickness changes by 0.1 % from t/L =
/// 1/100 to 1/1000 (no locking).
#[test]
fn triangles_pass_the_same_checks() {
    let s = steel(0.02);
    let (e1, e2) = ([0.6, 0.8, 0.0], [0.0, 0.0, 1.0]);
    let local = [[0.0, 0.0], [1.0, 0.1], [0.3, 0.9]];
    let x: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|k| 0.3 + local[i][0] * e1[k] + local[i][1] * e2[k])
    });
    let (k, m) = femu_fem::shell::matrices3(&s, &x, MassKind::Consistent).unwrap();
    let kd = nalgebra::DMatrix::from_row_slice(18, 18, &k);
    let vals = kd.symmetric_eigenvalues();
    let top = vals.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert_eq!(
        vals.iter().filter(|v| v.abs() < 1e-10 * top).count(),
        6,
        "{vals:?}"
    );
    let area = 0.5 * (local[1][0] * local[2][1] - local[2][0] * local[1][1]);
    let mu: f64 = (0..18)
        .map(|i| {
            (0..18)
                .map(|j| {
                    if i % 6 == 2 && j % 6 == 2 {
                        m[i * 18 + j]
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
        })
        .sum();
    assert!((mu / (8000.0 * 0.02 * area) - 1.0).abs() < 1e-12, "{mu}");
    with_triangles(|| {
        patch_tests_pass_on_a_distorted_mesh();
        let n = 32;
        let mut model = plate(10.0, 10.0, n, n, steel(0.05), |_, _| [0.0, 0.0]);
        for j in 0..=n {
            model
                .fix_node_dofs((1 + (n + 1) * j) as u64, &[0, 1, 2, 3, 4, 5])
                .unwrap();
        }
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let modes = sys
            .modes(Which::Lowest(6), &EigenOptions::default())
            .unwrap();
        for (l, r) in modes
            .values
            .iter()
            .zip([0.421, 1.029, 2.582, 3.306, 3.753, 6.555])
        {
            let f = l.sqrt() / (2.0 * PI);
            assert!((f / r - 1.0).abs() < 1e-2, "{f} Hz against {r}");
        }
        let mut per_t = Vec::new();
        for t in [0.01, 0.001] {
            let mut model = plate(1.0, 0.1, 20, 2, steel(t), |_, _| [0.0, 0.0]);
            for j in 0..=2 {
                model
                    .fix_node_dofs((1 + 21 * j) as u64, &[0, 1, 2, 3, 4, 5])
                    .unwrap();
            }
            let sys = model.assemble(MassKind::Consistent).unwrap();
            let modes = sys
                .modes(Which::Lowest(1), &EigenOptions::default())
                .unwrap();
            per_t.push(modes.values[0].sqrt() / t);
        }
        assert!((per_t[1] / per_t[0] - 1.0).abs() < 1e-2, "{per_t:?}");
    });
}

/// A mixed model: a cantilevered strip (1 m x 0.1 m x 0.01 m, steel) whose clamped half is hex20
/// solids (10 x 4 x 2) and whose free half is shells (10 x 4), joined by a rigid link from each
/// shell node of the interface to the column of solid nodes at its y (RBE2-like). Its first two
/// bending frequencies (8.154 and 51.09 Hz) lie within 0.5 % of the all-solid strip's (hex20,
/// independent of the shell code: 8.161, 51.19) and of the all-shell strip's (8.131, 50.99).
/// Tied by translations only to the solid's mid-line nodes (a hinge), the shells turn freely about
/// the joint: a zero-frequency mechanism, which the links remove.
#[test]
fn solid_and_shell_joined_by_rigid_links() {
    use femu_fem::generate::{BoxCells, BoxSpec, box_mesh};
    use femu_fem::material::Material;
    let (l, b, t) = (1.0, 0.1, 0.01);
    let steel_solid = || Material::isotropic("steel", 2.0e11, 0.3, 8000.0).unwrap();
    let first_two = |model: &Model| -> [f64; 2] {
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let modes = sys
            .modes(Which::Lowest(2), &EigenOptions::default())
            .unwrap();
        [modes.values[0], modes.values[1]]
    };
    // all solid: the reference independent of the shell element
    let mut solid =
        Model::new(box_mesh(&BoxSpec::new([l, b, t], [20, 4, 2], BoxCells::Hex, true)).unwrap())
            .unwrap();
    solid.set_material(None, steel_solid()).unwrap();
    solid.fix_set("xmin", &[0, 1, 2]).unwrap();
    let solid_f = first_two(&solid);
    // all shell, on the mid-surface
    let mut shell = plate(l, b, 40, 4, steel(t), |_, _| [0.0, 0.0]);
    for j in 0..=4 {
        shell
            .fix_node_dofs((1 + 41 * j) as u64, &[0, 1, 2, 3, 4, 5])
            .unwrap();
    }
    let shell_f = first_two(&shell);
    // mixed: solids on [0, l/2], shells on [l/2, l] at z = t/2, linked at x = l/2
    let mixed = |linked: bool| -> [f64; 2] {
        let mut mesh = box_mesh(&BoxSpec::new(
            [l / 2.0, b, t],
            [10, 4, 2],
            BoxCells::Hex,
            true,
        ))
        .unwrap();
        let first = 1_000_000u64;
        let id = |i: usize, j: usize| first + (i + 11 * j) as u64;
        for j in 0..=4 {
            for i in 0..=10 {
                let x = l / 2.0 + (l / 2.0) * i as f64 / 10.0;
                let y = b * j as f64 / 4.0;
                let z = t / 2.0;
                // at the interface the shell shares the solid's mid-line node when unlinked
                let _ = mesh.add_node(id(i, j), [x, y, z]);
            }
        }
        let face: Vec<(u64, [f64; 3])> = mesh
            .node_set("xmax")
            .unwrap()
            .iter()
            .map(|n| (mesh.node_id(*n), mesh.coords()[*n]))
            .collect();
        let mut model = Model::new(mesh).unwrap();
        model.set_material(None, steel_solid()).unwrap();
        model.fix_set("xmin", &[0, 1, 2]).unwrap();
        for j in 0..4 {
            for i in 0..10 {
                let nodes = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]
                    .map(|n| model.mesh().node_index(n).unwrap())
                    .to_vec();
                model
                    .add_structural(StructuralElement {
                        id: first + (i + 10 * j) as u64,
                        nodes,
                        kind: StructuralKind::Shell(steel(t)),
                    })
                    .unwrap();
            }
        }
        for j in 0..=4 {
            let y = b * j as f64 / 4.0;
            let column: Vec<u64> = face
                .iter()
                .filter(|(_, x)| (x[1] - y).abs() < 1e-9)
                .map(|(n, _)| *n)
                .collect();
            if linked {
                model
                    .add_rigid_link(id(0, j), &column, &[0, 1, 2], "interface")
                    .unwrap();
            } else {
                // a hinge: the shell node's translations tied to the solid's mid-thickness node
                let mid = face
                    .iter()
                    .find(|(_, x)| (x[1] - y).abs() < 1e-9 && (x[2] - t / 2.0).abs() < 1e-9)
                    .unwrap()
                    .0;
                for c in 0..3 {
                    model
                        .add_constraint((id(0, j), c), &[((mid, c), 1.0)], "hinge")
                        .unwrap();
                }
            }
        }
        first_two(&model)
    };
    let linked = mixed(true);
    for k in 0..2 {
        for reference in [solid_f[k], shell_f[k]] {
            let r = (linked[k] / reference).sqrt() - 1.0;
            assert!(
                r.abs() < 5e-3,
                "mode {k}: {linked:?} against {solid_f:?} and {shell_f:?}"
            );
        }
    }
    let hinged = mixed(false);
    assert!(
        hinged[0].abs() < 1e-6 * linked[0],
        "a hinged joint {hinged:?} against the linked {linked:?}"
    );
}

/// A thickness group (`t:SET`) is exact: `K(p)` and `M(p)` written from the shells' parts equal
/// the assembly of the same plate whose set has shells of thickness `t (1 + p)` (formed from
/// scratch at that thickness), consistent and lumped, quadrilaterals and triangles, with a
/// non-structural mass that does not scale; and the derivative products equal the central
/// difference of that direct assembly (a cubic in `p`: the difference's error is `h^2 K_3`).
#[test]
fn thickness_groups_equal_shells_of_the_changed_thickness() {
    use femu_fem::assembly::Assembler;
    use femu_fem::groups::{GroupLaw, ParameterGroups};
    let check = || {
        let mut s = steel(0.004);
        s.nsm = 3.0;
        s.bending = 0.8;
        let mut model = plate(0.4, 0.3, 4, 3, s, |i, j| {
            [0.01 * ((i * 7 + j * 3) % 5) as f64 / 5.0, 0.0]
        });
        let ids: Vec<u64> = model.structural().iter().take(5).map(|e| e.id).collect();
        model.add_structural_set("SKIN", &ids).unwrap();
        let with_thickness = |factor: f64| {
            let mut m = model.clone();
            for id in &ids {
                let i = m.structural_index(*id).unwrap();
                let mut el = m.structural()[i].clone();
                let StructuralKind::Shell(mut sh) = el.kind else {
                    unreachable!()
                };
                sh.t *= factor;
                el.kind = StructuralKind::Shell(sh);
                m.set_structural(i, el).unwrap();
            }
            m
        };
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let asm = Assembler::new(&model).unwrap();
            let base = asm.assemble(&model, mass).unwrap();
            let groups = ParameterGroups::from_element_sets(&model, &["t:SKIN"], mass).unwrap();
            assert_eq!(groups.law(0).unwrap(), GroupLaw::Thickness);
            let p = -0.15;
            let got = groups
                .parameterized(&model, &asm, &base, &[p], &[0.0])
                .unwrap();
            let direct = asm.assemble(&with_thickness(1.0 + p), mass).unwrap();
            for (what, a, b) in [("K", &got.k, &direct.k), ("M", &got.m, &direct.m)] {
                let scale = b.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                let worst = femu_sparse::csc::entries(a)
                    .zip(femu_sparse::csc::entries(b))
                    .map(|((i, j, x), (k, l, y))| {
                        assert_eq!((i, j), (k, l), "{what} patterns differ");
                        (x - y).abs()
                    })
                    .fold(0.0_f64, f64::max);
                assert!(
                    worst <= 1e-13 * scale,
                    "{mass:?} {what}: {worst:e} of {scale:e}"
                );
            }
            // derivative products against the central difference of direct assemblies
            let n = base.k.rows();
            let x: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 5.0).collect();
            let h = 1e-4;
            let (up, down) = (
                asm.assemble(&with_thickness(1.0 + p + h), mass).unwrap(),
                asm.assemble(&with_thickness(1.0 + p - h), mass).unwrap(),
            );
            for stiffness in [true, false] {
                let mut y = vec![0.0; n];
                if stiffness {
                    groups
                        .stiffness_derivative_product(&asm, 0, p, &x, &mut y)
                        .unwrap();
                } else {
                    groups
                        .mass_derivative_product(&asm, 0, p, &x, &mut y)
                        .unwrap();
                }
                let (a, b) = if stiffness {
                    (&up.k, &down.k)
                } else {
                    (&up.m, &down.m)
                };
                let (mut ya, mut yb) = (vec![0.0; n], vec![0.0; n]);
                femu_sparse::csc::mul_vec(a, &x, &mut ya).unwrap();
                femu_sparse::csc::mul_vec(b, &x, &mut yb).unwrap();
                let fd: Vec<f64> = ya
                    .iter()
                    .zip(&yb)
                    .map(|(u, d)| (u - d) / (2.0 * h))
                    .collect();
                let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
                let err = y
                    .iter()
                    .zip(&fd)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    norm > 0.0 && err <= 1e-6 * norm,
                    "{mass:?} stiffness {stiffness}: {err:e} of {norm:e}"
                );
            }
        }
    };
    check();
    with_triangles(check);
}

/// In-plane bending without parasitic shear (docs/MATH.md, "Shells"): a cantilevered strip of
/// membranes (MacNeal and Harder's straight beam, 6 x 0.2 x 0.1, six rectangles along it, one or
/// two through its depth) under an end couple `M` as consistent nodal forces. Beam theory gives the
/// tip's deflection `M L^2 / (2 E I)`, which the incompatible-mode membrane
/// ([`Membrane::Incompatible`], Nastran's CQUAD4) reproduces to the solve's round-off for `nu = 0`
/// and `nu = 0.3` (its modes `1 - xi^2` carry the bending's `-kappa x^2 / 2` and the Poisson
/// term `-nu kappa y^2 / 2`; 1e-9 asked, 1.1e-10 measured: a strip 30 times longer than deep
/// solved by LU); the fully integrated membrane ([`Membrane::Full`]) locks: its Gauss points see
/// a shear `kappa (x - x_c)` and the tip moves 0.074 of the beam's (one element deep, `nu = 0`;
/// 0.1 asked).
#[test]
fn in_plane_bending_has_no_parasitic_shear() {
    use faer::linalg::solvers::Solve;
    let (l, h, t, e, m) = (6.0, 0.2, 0.1, 1.0e7, 1.0);
    let tip = |deep: usize, nu: f64, membrane: Membrane| -> f64 {
        let s = Shell {
            nu,
            e,
            t,
            bending: 0.0,
            shear: None,
            membrane,
            ..steel(t)
        };
        let mut model = plate(l, h, 6, deep, s, |_, _| [0.0, 0.0]);
        let id = |i: usize, j: usize| (1 + i + 7 * j) as u64;
        // the root holds u and w, and v where the beam's v = -kappa nu y^2 / 2 is equal at every
        // held node (both corners of one element deep, the middle of two): no clamp on the
        // Poisson contraction
        for j in 0..=deep {
            let v = deep == 1 || j == 1;
            model
                .fix_node_dofs(id(0, j), if v { &[0, 1, 2] } else { &[0, 2] })
                .unwrap();
            for i in 1..=6 {
                model.fix_node_dofs(id(i, j), &[2]).unwrap();
            }
        }
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let k = femu_sparse::csc::to_dense(&sys.k);
        let mut f = faer::Mat::<f64>::zeros(k.nrows(), 1);
        // the linear stress sigma = 12 M y / (t h^3) on the end, at its nodes: F_j = int N_j sigma t dy
        let dy = h / deep as f64;
        for j in 0..deep {
            let (y0, y1) = (j as f64 * dy - h / 2.0, (j + 1) as f64 * dy - h / 2.0);
            let q = |y: f64| 12.0 * m * y / h.powi(3);
            for (node, share) in [
                (id(6, j), q(y0) * dy / 3.0 + q(y1) * dy / 6.0),
                (id(6, j + 1), q(y0) * dy / 6.0 + q(y1) * dy / 3.0),
            ] {
                let n = model.mesh().node_index(node).unwrap();
                f[(sys.dofs.free_index(n, 0).unwrap(), 0)] += share;
            }
        }
        let u = k.full_piv_lu().solve(&f);
        // the tip's deflection at the held node's height
        let n = model.mesh().node_index(id(6, deep / 2)).unwrap();
        u[(sys.dofs.free_index(n, 1).unwrap(), 0)]
    };
    // sigma > 0 at y > 0 stretches the top fibre, so the tip bends down by M L^2 / (2 E I)
    let beam = m * l * l / (2.0 * e * t * h.powi(3) / 12.0);
    for deep in [1, 2] {
        for nu in [0.0, 0.3] {
            let v = tip(deep, nu, Membrane::Incompatible);
            assert!(
                (-v / beam - 1.0).abs() < 1e-9,
                "{deep} {nu}: {v} against {beam}"
            );
        }
    }
    let locked = tip(1, 0.0, Membrane::Full).abs() / beam;
    assert!(locked < 0.1, "{locked}");
}

/// NAFEMS FV32 (cantilevered tapered membrane: 10 m long, 5 m wide at the clamped root tapering
/// symmetrically to 1 m at the tip, 0.05 m thick, E = 200 GPa, nu = 0.3, rho = 8000; in-plane
/// motion only): the reference frequencies 44.623, 130.03, 162.70, 246.05, 379.90 and 391.44 Hz
/// (NAFEMS, "Selected Benchmarks for Natural Frequency Analysis", 1987, test 32). The fully
/// integrated membrane is stiff in in-plane bending on coarse meshes: on 16 x 8 shells 0.08-3.5 %
/// high, on 32 x 16 0.02-1.06 %; with its shear at the centre (Nastran's CQUAD4) 0.07-3.3 % and
/// 0.014-0.78 %, the first two modes (the in-plane bending ones) four and two times closer. The
/// error falls about fourfold with each halving (second order), the rate the test asks for (at
/// least 3).
#[test]
fn nafems_fv32_cantilevered_tapered_membrane() {
    let reference = [44.623, 130.03, 162.70, 246.05, 379.90, 391.44];
    let error = |f: &[f64]| -> Vec<f64> {
        f.iter()
            .zip(reference)
            .map(|(f, r)| (f / r - 1.0).abs())
            .collect()
    };
    let mut first = Vec::new();
    for m in [Membrane::Full, Membrane::Incompatible] {
        let (coarse, fine) = (
            error(&fv32(16, 8, false, m)),
            error(&fv32(32, 16, false, m)),
        );
        for (c, f) in coarse.iter().zip(&fine) {
            assert!(*c > 3.0 * f, "{m:?}: {coarse:?} {fine:?}");
            assert!(*f < 1.2e-2, "{m:?}: {fine:?}");
        }
        first.push(coarse[0]);
    }
    assert!(first[1] < 0.25 * first[0], "{first:?}");
}

/// NAFEMS FV32 of membranes alone (a bending factor of 0: Nastran's PSHELL without MID2): the
/// nodes carry no rotations (three DOFs each, the out-of-plane one held), and the six frequencies
/// are the shells' in-plane ones to 2e-4 on 16 x 8 elements (3e-6 to 1.5e-4 measured, the
/// membranes lower: the shells' drilling stiffness, `1e-3 G t A`, and its rotary inertia are the
/// terms that differ).
#[test]
fn membranes_alone_are_the_shells_in_plane() {
    let shells = fv32(16, 8, false, Membrane::Incompatible);
    let membranes = fv32(16, 8, true, Membrane::Incompatible);
    for (a, b) in shells.iter().zip(&membranes) {
        assert!((a / b - 1.0).abs() < 2e-4, "{shells:?} {membranes:?}");
    }
    // a membrane has no transverse shear and no offset
    let membrane = Shell {
        bending: 0.0,
        shear: None,
        ..steel(0.01)
    };
    assert!(membrane.validate(1).is_ok());
    for bad in [
        Shell {
            shear: Some(5.0 / 6.0),
            ..membrane
        },
        Shell {
            offset: 0.005,
            ..membrane
        },
    ] {
        let e = bad.validate(1).unwrap_err().to_string();
        assert!(e.contains("it is a membrane"), "{e}");
    }
}

/// FV32's tapered membrane of `nx x ny` 4-node shells (or membranes alone), in-plane motion only,
/// clamped at the root: its six lowest frequencies (Hz).
fn fv32(nx: usize, ny: usize, membrane: bool, formulation: Membrane) -> Vec<f64> {
    let solve = |nx: usize, ny: usize| -> Vec<f64> {
        let mut mesh = Mesh::new();
        let id = |i: usize, j: usize| (1 + i + (nx + 1) * j) as u64;
        for j in 0..=ny {
            for i in 0..=nx {
                let x = 10.0 * i as f64 / nx as f64;
                // the width tapers from 5 m at x = 0 to 1 m at x = 10, symmetric about y = 2.5
                let half = 2.5 - 0.2 * x;
                let y = 2.5 - half + 2.0 * half * j as f64 / ny as f64;
                mesh.add_node(id(i, j), [x, y, 0.0]).unwrap();
            }
        }
        let mut model = Model::new(mesh).unwrap();
        for j in 0..ny {
            for i in 0..nx {
                let nodes = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]
                    .map(|n| model.mesh().node_index(n).unwrap());
                model
                    .add_structural(StructuralElement {
                        id: (1 + i + nx * j) as u64,
                        nodes: nodes.to_vec(),
                        kind: StructuralKind::Shell(Shell {
                            e: 2.0e11,
                            nu: 0.3,
                            rho: 8000.0,
                            t: 0.05,
                            bending: if membrane { 0.0 } else { 1.0 },
                            shear: if membrane { None } else { Some(5.0 / 6.0) },
                            nsm: 0.0,
                            material: None,
                            offset: 0.0,
                            membrane: formulation,
                        }),
                    })
                    .unwrap();
            }
        }
        // in-plane motion only: w and the bending rotations held everywhere, the root clamped
        // (a membrane's nodes have no rotations)
        for j in 0..=ny {
            for i in 0..=nx {
                let dofs: &[usize] = match (i == 0, membrane) {
                    (true, false) => &[0, 1, 2, 3, 4, 5],
                    (true, true) => &[0, 1, 2],
                    (false, false) => &[2, 3, 4],
                    (false, true) => &[2],
                };
                model.fix_node_dofs(id(i, j), dofs).unwrap();
            }
        }
        let sys = model.assemble(MassKind::Consistent).unwrap();
        if membrane {
            assert_eq!(sys.dofs.free_count(), 2 * nx * (ny + 1));
        }
        let modes = sys
            .modes(Which::Lowest(6), &EigenOptions::default())
            .unwrap();
        modes.values.iter().map(|l| l.sqrt() / (2.0 * PI)).collect()
    };
    solve(nx, ny)
}

/// A mass group scales its concentrated masses exactly: `M(q)` of a set holding a rigid mass
/// (offset and inertia) and a point mass equals the assembly of the plate with both masses made
/// `1 + q` times heavier (formed anew by the model), and `K` is untouched; with the consistent
/// mass and with the lumped one, which keeps the coupled rigid mass whole on the stiffness
/// pattern.
#[test]
fn mass_groups_equal_heavier_masses() {
    use femu_fem::assembly::Assembler;
    use femu_fem::groups::ParameterGroups;
    let build = |factor: f64| {
        let mut model = plate(0.4, 0.3, 4, 3, steel(0.004), |_, _| [0.0, 0.0]);
        let inertia = [[2e-3, 1e-4, 0.0], [1e-4, 3e-3, 0.0], [0.0, 0.0, 4e-3]];
        model
            .add_rigid_mass(
                7,
                0.5 * factor,
                [0.01, -0.02, 0.03],
                inertia.map(|r| r.map(|v| v * factor)),
            )
            .unwrap();
        let rigid = model.last_mass(true).unwrap();
        model.add_point_mass(13, 0.2 * factor).unwrap();
        let point = model.last_mass(false).unwrap();
        model.add_mass_set("EQUIPMENT", &[rigid, point]).unwrap();
        model
    };
    let model = build(1.0);
    let asm = Assembler::new(&model).unwrap();
    assert!(asm.lumped_on_pattern());
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let base = asm.assemble(&model, kind).unwrap();
        let groups = ParameterGroups::from_element_sets(&model, &["EQUIPMENT"], kind).unwrap();
        let q = 0.4;
        let got = groups
            .parameterized(&model, &asm, &base, &[0.0], &[q])
            .unwrap();
        let direct = asm.assemble(&build(1.0 + q), kind).unwrap();
        for (what, a, b) in [("K", &got.k, &direct.k), ("M", &got.m, &direct.m)] {
            let scale = b.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let (ea, eb): (Vec<_>, Vec<_>) = (
                femu_sparse::csc::entries(a).collect(),
                femu_sparse::csc::entries(b).collect(),
            );
            assert_eq!(ea.len(), eb.len(), "{what}");
            for ((i, j, x), (k, l, y)) in ea.iter().zip(&eb) {
                assert_eq!((i, j), (k, l), "{what}");
                assert!(
                    (x - y).abs() <= 1e-14 * scale,
                    "{what} at ({i}, {j}): {x} {y}"
                );
            }
        }
        assert_eq!(groups.group_mass(&model, 0).unwrap(), 0.7);
    }
}

/// An orthotropic ply (E1 = 140 GPa, E2 = 10 GPa, nu12 = 0.3, G12 = G13 = G23 = 5 GPa, 1600
/// kg/m^3) as a shell material: `Q11 = E1 / (1 - nu12 nu21)` and so on, in its own axes.
fn ply() -> femu_fem::shell::ShellMaterial {
    let (e1, e2, nu12, g12) = (140e9, 10e9, 0.3, 5e9);
    let nu21 = nu12 * e2 / e1;
    let den = 1.0 - nu12 * nu21;
    let q = [
        [e1 / den, nu12 * e2 / den, 0.0],
        [nu12 * e2 / den, e2 / den, 0.0],
        [0.0, 0.0, g12],
    ];
    femu_fem::shell::ShellMaterial {
        membrane: q,
        bending: q,
        shear: [[5e9, 0.0], [0.0, 5e9]],
        axis: [1.0, 0.0, 0.0],
    }
}

fn orthotropic(t: f64, material: femu_fem::shell::ShellMaterial) -> Shell {
    Shell {
        e: 0.0,
        nu: 0.0,
        rho: 1600.0,
        t,
        bending: 1.0,
        shear: Some(5.0 / 6.0),
        nsm: 0.0,
        material: Some(material),
        offset: 0.0,
        membrane: Membrane::Incompatible,
    }
}

/// A hard simply supported rectangular plate `a x b` of `n x n` shells: its lowest `count`
/// eigenvalues. Hard: `w = 0` and the rotation along each edge fixed (a soft support, `w` alone,
/// has a boundary layer that lowers the frequencies by `O(t/a)`).
fn supported_plate(a: f64, b: f64, n: usize, s: Shell, count: usize) -> Vec<f64> {
    let mut model = plate(a, b, n, n, s, |_, _| [0.0, 0.0]);
    for j in 0..=n {
        for i in 0..=n {
            let id = (1 + i + (n + 1) * j) as u64;
            if i == 0 || i == n {
                model.fix_node_dofs(id, &[0, 1, 2, 3]).unwrap();
            }
            if j == 0 || j == n {
                model.fix_node_dofs(id, &[0, 1, 2, 4]).unwrap();
            }
        }
    }
    let sys = model.assemble(MassKind::Consistent).unwrap();
    sys.modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap()
        .values
}

/// A specially orthotropic simply supported plate (1 m x 0.8 m, 4 mm, the ply along x, then along
/// y) approaches the classical frequencies `omega^2 = pi^4 (D11 (m/a)^4 + 2 (D12 + 2 D66)
/// (m/a)^2 (n/b)^2 + D22 (n/b)^4) / (rho t)` (Jones, "Mechanics of Composite Materials", 5.5)
/// from above as the mesh is refined, the ply along y giving them with D11 and D22 exchanged.
/// Measured on the four lowest modes: 0.35-5.6 % high on 24 x 24 shells, 0.03-1.3 % on 48 x 48,
/// the error falling four- to tenfold with the halving (the test asks for 3.5).
#[test]
fn orthotropic_plate_matches_the_classical_frequencies() {
    let t: f64 = 0.004;
    let q = ply().bending;
    let d = |i: usize, j: usize| q[i][j] * t.powi(3) / 12.0;
    let (a, b) = (1.0, 0.8);
    let classical = |along_y: bool| -> Vec<f64> {
        let (d11, d22) = if along_y {
            (d(1, 1), d(0, 0))
        } else {
            (d(0, 0), d(1, 1))
        };
        let mut w: Vec<f64> = (1..8)
            .flat_map(|m| (1..8).map(move |n| (m as f64 / a, n as f64 / b)))
            .map(|(p, r)| {
                PI.powi(4)
                    * (d11 * p.powi(4)
                        + 2.0 * (d(0, 1) + 2.0 * d(2, 2)) * p * p * r * r
                        + d22 * r.powi(4))
                    / (1600.0 * t)
            })
            .collect();
        w.sort_by(f64::total_cmp);
        w.truncate(4);
        w
    };
    for along_y in [false, true] {
        let mut material = ply();
        if along_y {
            material.axis = [0.0, 1.0, 0.0];
        }
        let want = classical(along_y);
        let errors = |n: usize| -> Vec<f64> {
            let got = supported_plate(a, b, n, orthotropic(t, material), 4);
            got.iter().zip(&want).map(|(g, w)| g / w - 1.0).collect()
        };
        let (coarse, fine) = (errors(24), errors(48));
        for (c, f) in coarse.iter().zip(&fine) {
            assert!(
                *f > -2e-3 && *f < 1.5e-2 && *c > 3.5 * f,
                "along y {along_y}: {coarse:?} then {fine:?}"
            );
        }
    }
}

/// The ply turned 30 degrees from the element axes gives the same frequencies as the turned
/// stiffnesses written out by the textbook formulas (`Q-bar`, Jones 2.6; the shear `C-bar_44`,
/// `C-bar_55`, `C-bar_45`) with the axes of the elements: the rotation is the material's.
#[test]
fn a_turned_ply_is_its_turned_stiffness() {
    let th = 30f64.to_radians();
    let (c, s) = (th.cos(), th.sin());
    let q = ply().membrane;
    let (q11, q12, q22, q66) = (q[0][0], q[0][1], q[1][1], q[2][2]);
    let (c2, s2) = (c * c, s * s);
    let qb11 = q11 * c2 * c2 + 2.0 * (q12 + 2.0 * q66) * s2 * c2 + q22 * s2 * s2;
    let qb12 = (q11 + q22 - 4.0 * q66) * s2 * c2 + q12 * (s2 * s2 + c2 * c2);
    let qb22 = q11 * s2 * s2 + 2.0 * (q12 + 2.0 * q66) * s2 * c2 + q22 * c2 * c2;
    let qb16 = (q11 - q12 - 2.0 * q66) * s * c2 * c + (q12 - q22 + 2.0 * q66) * s2 * s * c;
    let qb26 = (q11 - q12 - 2.0 * q66) * s2 * s * c + (q12 - q22 + 2.0 * q66) * s * c2 * c;
    let qb66 = (q11 + q22 - 2.0 * q12 - 2.0 * q66) * s2 * c2 + q66 * (s2 * s2 + c2 * c2);
    let qb = [[qb11, qb12, qb16], [qb12, qb22, qb26], [qb16, qb26, qb66]];
    // unequal transverse shear moduli, so that their rotation shows too
    let (g13, g23) = (5e9, 3e9);
    let shear = [
        [g13 * c2 + g23 * s2, (g13 - g23) * c * s],
        [(g13 - g23) * c * s, g13 * s2 + g23 * c2],
    ];
    let mut turned = ply();
    turned.shear = [[g13, 0.0], [0.0, g23]];
    turned.axis = [c, s, 0.0];
    let written = femu_fem::shell::ShellMaterial {
        membrane: qb,
        bending: qb,
        shear,
        axis: [1.0, 0.0, 0.0],
    };
    // a thick plate (t/a = 1/20), so that the shear matters
    let (a, b) = (1.0, 0.8);
    let x = supported_plate(a, b, 8, orthotropic(0.05, turned), 10);
    let y = supported_plate(a, b, 8, orthotropic(0.05, written), 10);
    for (p, r) in x.iter().zip(&y) {
        assert!((p / r - 1.0).abs() < 1e-10, "{x:?} {y:?}");
    }
}

/// Two shells of thickness `t` on the same grids, offset `+t/2` and `-t/2` from them (Nastran's
/// ZOFFS), are one plate `2t` thick: their membranes at `z = +-t/2` give the parallel-axis term
/// `2 E t (t/2)^2 / (1 - nu^2)` that makes `E (2t)^3 / 12 (1 - nu^2)`, and the offset masses the
/// rotary inertia. With the fully integrated membrane ([`Membrane::Full`]) a cantilevered square
/// plate's six lowest frequencies agree with the single plate's to 1e-6 (7e-9 to 6e-8 measured:
/// the drilling rotation's inertia, `rho t^3 / 12` per layer against `rho (2t)^3 / 12`, is the
/// one term that differs); with the incompatible-mode membrane ([`Membrane::Incompatible`]) the
/// layers' membranes also carry the enrichment, which relaxes their share `z kappa` of the
/// bending, so the pair is slightly softer than the plate (9e-5 to 1.5e-3 measured; bound 2e-3);
/// without the offsets the pair is four times softer in bending per mass, half the frequencies.
#[test]
fn two_offset_layers_are_one_plate_twice_as_thick() {
    let (t, n) = (0.01, 12);
    let clamp = |model: &mut Model| {
        for j in 0..=n {
            model
                .fix_node_dofs((1 + (n + 1) * j) as u64, &[0, 1, 2, 3, 4, 5])
                .unwrap();
        }
    };
    let frequencies = |model: &Model| -> Vec<f64> {
        let sys = model.assemble(MassKind::Consistent).unwrap();
        sys.modes(Which::Lowest(6), &EigenOptions::default())
            .unwrap()
            .values
            .iter()
            .map(|l| l.sqrt() / (2.0 * PI))
            .collect()
    };
    let full = |t: f64| Shell {
        membrane: Membrane::Full,
        ..steel(t)
    };
    let mut single = plate(1.0, 1.0, n, n, full(2.0 * t), |_, _| [0.0, 0.0]);
    clamp(&mut single);
    let layers = |offset: f64, membrane: Membrane| {
        let mut top = Shell {
            membrane,
            ..steel(t)
        };
        top.offset = offset;
        let mut model = plate(1.0, 1.0, n, n, top, |_, _| [0.0, 0.0]);
        let mut bottom = top;
        bottom.offset = -offset;
        let cells: Vec<StructuralElement> = model.structural().to_vec();
        for el in cells {
            model
                .add_structural(StructuralElement {
                    id: el.id + 10_000,
                    nodes: el.nodes.clone(),
                    kind: StructuralKind::Shell(bottom),
                })
                .unwrap();
        }
        clamp(&mut model);
        model
    };
    let (want, got, enriched, loose) = (
        frequencies(&single),
        frequencies(&layers(t / 2.0, Membrane::Full)),
        frequencies(&layers(t / 2.0, Membrane::Incompatible)),
        frequencies(&layers(0.0, Membrane::Full)),
    );
    for (((w, g), r), l) in want.iter().zip(&got).zip(&enriched).zip(&loose) {
        assert!((g / w - 1.0).abs() < 1e-6, "{got:?} against {want:?}");
        assert!(r < w && r / w > 1.0 - 2e-3, "{enriched:?} against {want:?}");
        // bending modes of the unbonded pair: half the frequency (stiffness 2/8, mass 1)
        assert!(l / w < 0.51, "{loose:?} against {want:?}");
    }
}

/// A thickness group given by hand with a solid element index, in range or not, on a model without
/// solids is refused with what is wrong (it once looked the element up before checking the range).
#[test]
fn a_thickness_group_of_solids_is_refused_without_a_panic() {
    use femu_fem::groups::{ParameterGroup, ParameterGroups};
    let model = plate(0.4, 0.3, 2, 2, steel(0.004), |_, _| [0.0, 0.0]);
    let mut group = ParameterGroup::thickness("t:BAD", vec![0]);
    group.elements = vec![3];
    let e = ParameterGroups::new(&model, vec![group], MassKind::Consistent)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("t:BAD") && e.contains("index 3 (out of range)"),
        "{e}"
    );
}

/// `femu_fem::shell::laminate` by hand: a `[0/90/90/0]` cross-ply's membrane `A/T` (the two
/// orientations' mean: `(Q11 + Q22)/2` on both diagonals) and bending `12 D/T^3` (the outer
/// plies' share `1 - (1/2)^3 = 7/8` of `Q11`, the inner ones' `1/8`), its density and shear; one
/// isotropic ply is the isotropic section (the element's `K` and `M` to 1e-12 of their largest
/// entries); refusals: no ply, a ply of no thickness, an unsymmetric `[0/90]`, plies of different
/// transverse shear.
#[test]
fn laminates_by_hand() {
    use femu_fem::shell::{LaminateError, Ply, laminate};
    let (q11, q12, q22, q66) = (140.0, 3.0, 10.0, 5.0);
    let q = [[q11, q12, 0.0], [q12, q22, 0.0], [0.0, 0.0, q66]];
    let ply = |theta: f64, rho: f64| Ply {
        q,
        shear: None,
        rho,
        t: 0.25,
        theta,
    };
    let s = laminate(&[ply(0.0, 1.0), ply(90.0, 3.0), ply(90.0, 3.0), ply(0.0, 1.0)]).unwrap();
    let m = s.material.unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    assert!(close(s.t, 1.0) && close(s.rho, 2.0) && s.shear.is_none());
    let mean = (q11 + q22) / 2.0;
    let want_a = [[mean, q12, 0.0], [q12, mean, 0.0], [0.0, 0.0, q66]];
    let want_d = [
        [q11 * 7.0 / 8.0 + q22 / 8.0, q12, 0.0],
        [q12, q22 * 7.0 / 8.0 + q11 / 8.0, 0.0],
        [0.0, 0.0, q66],
    ];
    for r in 0..3 {
        for c in 0..3 {
            assert!(close(m.membrane[r][c], want_a[r][c]), "{:?}", m.membrane);
            assert!(close(m.bending[r][c], want_d[r][c]), "{:?}", m.bending);
        }
    }
    // one isotropic ply is the isotropic section
    let (e, nu, g) = (2.0e11, 0.3, 2.0e11 / 2.6);
    let d = e / (1.0 - nu * nu);
    let iso = laminate(&[Ply {
        q: [[d, d * nu, 0.0], [d * nu, d, 0.0], [0.0, 0.0, g]],
        shear: Some([[g, 0.0], [0.0, g]]),
        rho: 7850.0,
        t: 0.01,
        theta: 30.0,
    }])
    .unwrap();
    let homogeneous = Shell {
        e,
        nu,
        rho: 7850.0,
        t: 0.01,
        bending: 1.0,
        shear: Some(5.0 / 6.0),
        nsm: 0.0,
        material: None,
        offset: 0.0,
        membrane: Membrane::Incompatible,
    };
    let x = [
        [0.0, 0.0, 0.0],
        [1.0, 0.1, 0.0],
        [0.9, 1.2, 0.0],
        [-0.1, 0.8, 0.0],
    ];
    let (ka, ma) = femu_fem::shell::matrices(&iso, &x, MassKind::Consistent).unwrap();
    let (kb, mb) = femu_fem::shell::matrices(&homogeneous, &x, MassKind::Consistent).unwrap();
    for (a, b) in [(&ka, &kb), (&ma, &mb)] {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (u, v) in a.iter().zip(b.iter()) {
            assert!((u - v).abs() <= 1e-12 * scale, "{u} vs {v}");
        }
    }
    assert_eq!(laminate(&[]), Err(LaminateError::Ply(0)));
    let mut thin = ply(0.0, 1.0);
    thin.t = 0.0;
    assert_eq!(laminate(&[ply(0.0, 1.0), thin]), Err(LaminateError::Ply(1)));
    assert!(matches!(
        laminate(&[ply(0.0, 1.0), ply(90.0, 1.0)]),
        Err(LaminateError::Unsymmetric(r)) if r > 0.1
    ));
    let sheared = |theta: f64| Ply {
        shear: Some([[5.0, 0.0], [0.0, 3.0]]),
        ..ply(theta, 1.0)
    };
    assert_eq!(
        laminate(&[sheared(0.0), sheared(90.0), sheared(90.0), sheared(0.0)]),
        Err(LaminateError::Shear)
    );
}
