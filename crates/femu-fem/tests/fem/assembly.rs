//! Assembly evidence: against a dense sum of element matrices, symmetry, definiteness, mass,
//! rigid-body modes of a free-free model, parameter groups, thread-count independence.

use femu_fem::assembly::{Assembler, CHUNK_POINTS, MassKind};
use femu_fem::generate::{BoxCells, BoxSpec, box_mesh};
use femu_fem::groups::ParameterGroups;
use femu_fem::kernel;
use femu_fem::material::Material;
use femu_fem::model::Model;
use femu_sparse::csc::{bilinear, mul_vec, symmetry_defect, to_dense};
use femu_sparse::dense::{generalized_symmetric_eigen, generalized_symmetric_eigenvalues};

fn small_plate(quadratic: bool) -> Model {
    femu_testkit::mixed_steel_aluminium_plate(2, quadratic)
}

/// The assembled K and M equal a plain dense sum of element matrices (written here without the
/// pattern, colouring or parallelism), with fixed DOFs removed.
#[test]
fn assembly_equals_dense_sum_of_element_matrices() {
    for quadratic in [false, true] {
        let mut model = small_plate(quadratic);
        model.fix_set("xmin", &[0, 1, 2]).unwrap();
        model.fix_set("ymin", &[2]).unwrap();
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let n = sys.dofs.free_count();
        let mesh = model.mesh();
        let (mut kd, mut md) = (faer::Mat::<f64>::zeros(n, n), faer::Mat::<f64>::zeros(n, n));
        let mut x = Vec::new();
        for el in mesh.elements() {
            mesh.element_coords(el.index, &mut x);
            let mat = model.material_of(el.index).unwrap();
            let nd = 3 * el.kind.num_nodes();
            let (mut ke, mut me) = (vec![0.0; nd * nd], vec![0.0; nd * nd]);
            kernel::element_stiffness(el.kind, &x, &mat.elasticity_matrix(), &mut ke).unwrap();
            kernel::element_mass(el.kind, &x, mat.density, &mut me).unwrap();
            let dofs: Vec<Option<usize>> = el
                .nodes
                .iter()
                .flat_map(|n| sys.dofs.node_dofs(*n))
                .collect();
            for (r, dr) in dofs.iter().enumerate() {
                for (c, dc) in dofs.iter().enumerate() {
                    if let (Some(i), Some(j)) = (dr, dc) {
                        kd[(*i, *j)] += ke[r * nd + c];
                        md[(*i, *j)] += me[r * nd + c];
                    }
                }
            }
        }
        let (ks, ms) = (to_dense(&sys.k), to_dense(&sys.m));
        let kmax = (0..n).map(|i| kd[(i, i)]).fold(0.0, f64::max);
        let mmax = (0..n).map(|i| md[(i, i)]).fold(0.0, f64::max);
        for j in 0..n {
            for i in 0..n {
                assert!(
                    (ks[(i, j)] - kd[(i, j)]).abs() <= 1e-13 * kmax,
                    "K({i},{j})"
                );
                assert!(
                    (ms[(i, j)] - md[(i, j)]).abs() <= 1e-13 * mmax,
                    "M({i},{j})"
                );
            }
        }
        assert_eq!(symmetry_defect(&sys.k).0, 0.0);
        assert_eq!(symmetry_defect(&sys.m).0, 0.0);
        // The consistent mass couples a node's x only to x (M_e = m_ab delta_ij): stored, it is
        // exactly K's entries between DOFs of one direction, a third of them, none zero (the
        // linear elements' scalar masses m_ab are all positive).
        let direction = |f: usize| sys.dofs.full_of_free(f) % 3;
        let same: Vec<(usize, usize)> = sys
            .k
            .iter()
            .map(|(_, (r, c))| (r, c))
            .filter(|&(r, c)| direction(r) == direction(c))
            .collect();
        if !quadratic {
            let stored: Vec<(usize, usize)> = sys.m.iter().map(|(_, rc)| rc).collect();
            assert_eq!(stored, same);
            assert!(sys.m.data().iter().all(|v| *v != 0.0));
        }
        assert!(sys.m.nnz() <= same.len() && 3 * sys.m.nnz() < sys.k.nnz() + 3 * n);
        // The pattern is the node graph: every stored column is sorted and K has no empty column.
        assert!(sys.k.indptr().raw_storage().windows(2).all(|w| w[1] > w[0]));
        // M positive definite and K positive definite once constrained (dense eigensolver).
        let e = generalized_symmetric_eigen(ks.as_ref(), ms.as_ref()).unwrap();
        assert!(
            e.values[0] > 0.0,
            "constrained K not definite: {}",
            e.values[0]
        );
    }
}

/// Colouring: every element is in exactly one chunk, no two chunks of a colour share a node, and
/// a model large enough has several chunks per colour (the parallel work); the result does not
/// depend on the number of threads, not even in round-off (the chunks fix the summation order).
#[test]
fn colouring_is_valid_and_thread_count_does_not_change_the_result() {
    let spec = BoxSpec::new([0.3, 0.2, 0.1], [12, 10, 6], BoxCells::Hex, true);
    let mut boxed = Model::new(box_mesh(&spec).unwrap()).unwrap();
    boxed.set_material(None, Material::steel()).unwrap();
    boxed.fix_set("xmin", &[0, 1, 2]).unwrap();
    for (model, many) in [(small_plate(true), false), (boxed, true)] {
        let asm = Assembler::new(&model).unwrap();
        let mesh = model.mesh();
        // the colour and chunk that last touched each node
        let mut owner = vec![(usize::MAX, usize::MAX); mesh.node_count()];
        let mut chunk_of = vec![usize::MAX; mesh.element_count()];
        for (c, color) in asm.colors().iter().enumerate() {
            for &ch in color {
                for e in asm.chunk(ch) {
                    assert_eq!(chunk_of[e], usize::MAX, "element {e} in two chunks");
                    chunk_of[e] = ch;
                    for n in mesh.element(e).nodes {
                        if owner[*n].0 == c {
                            assert_eq!(owner[*n].1, ch, "chunks of colour {c} share node {n}");
                        }
                        owner[*n] = (c, ch);
                    }
                }
            }
        }
        assert!(
            chunk_of.iter().all(|c| *c != usize::MAX),
            "an element in no chunk"
        );
        if many {
            // 720 hex20 elements in chunks of the fewest elements with CHUNK_POINTS nodes (26 of
            // 20 nodes: 28 chunks), several per colour
            let chunks: usize = asm.colors().iter().map(Vec::len).sum();
            assert_eq!(chunks, 720usize.div_ceil(CHUNK_POINTS.div_ceil(20)));
            assert!(asm.colors().iter().any(|c| c.len() >= 2));
        }
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| asm.assemble(&model, MassKind::Consistent).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.k.data(), b.k.data());
        assert_eq!(a.m.data(), b.m.data());
    }
}

/// u^T M u for a unit rigid translation equals rho * V summed over materials, consistent and
/// lumped, for every generated mesh kind; the lumped mass is diagonal and positive.
#[test]
fn generated_meshes_carry_their_mass() {
    let rho = 7850.0;
    for cells in [
        BoxCells::Hex,
        BoxCells::Wedge,
        BoxCells::Tet5,
        BoxCells::Tet6,
    ] {
        for quadratic in [false, true] {
            let mesh =
                box_mesh(&BoxSpec::new([0.3, 0.2, 0.1], [3, 2, 2], cells, quadratic)).unwrap();
            let mut model = Model::new(mesh).unwrap();
            model.set_material(None, Material::steel()).unwrap();
            for mass in [MassKind::Consistent, MassKind::Lumped] {
                let sys = model.assemble(mass).unwrap();
                for i in 0..3 {
                    let u: Vec<f64> = (0..sys.dofs.free_count())
                        .map(|f| {
                            if sys.dofs.full_of_free(f) % 3 == i {
                                1.0
                            } else {
                                0.0
                            }
                        })
                        .collect();
                    let m = bilinear(&sys.m, &u, &u).unwrap();
                    assert!(
                        (m / (rho * 0.006) - 1.0).abs() < 1e-12,
                        "{cells:?} q={quadratic} {mass:?}: {m}"
                    );
                }
                if mass == MassKind::Lumped {
                    assert_eq!(sys.m.nnz(), sys.dofs.free_count());
                    assert!(sys.m.data().iter().all(|v| *v > 0.0));
                }
            }
        }
    }
    // Mixed materials: total mass of the plate with an aluminium tet block.
    let model = small_plate(false);
    let sys = model.assemble(MassKind::Lumped).unwrap();
    let u: Vec<f64> = (0..sys.dofs.free_count())
        .map(|f| {
            if sys.dofs.full_of_free(f) % 3 == 2 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let tet_volume = 0.02 * 0.02 * 0.01;
    let expect = 7850.0 * (0.06 * 0.04 * 0.01 - tet_volume) + 2700.0 * tet_volume;
    assert!((bilinear(&sys.m, &u, &u).unwrap() / expect - 1.0).abs() < 1e-12);
    assert!((model.total_mass().unwrap() / expect - 1.0).abs() < 1e-12);
}

/// A free-free model (no constraint) has exactly six zero eigenvalues: the six rigid-body modes,
/// no mechanism anywhere in the mixed mesh.
#[test]
fn free_free_plate_has_exactly_six_rigid_body_modes() {
    for quadratic in [false, true] {
        let model = small_plate(quadratic);
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let e = generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
            .unwrap();
        let first_elastic = e.values[6];
        assert!(first_elastic > 0.0);
        assert!(
            e.values[..6].iter().all(|l| l.abs() < 1e-8 * first_elastic),
            "quadratic={quadratic}: {:?}",
            &e.values[..8]
        );
        // The two dense paths (nalgebra eigenpairs, faer eigenvalues only) agree.
        let values =
            generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
                .unwrap();
        for i in 6..20 {
            assert!(
                (values[i] / e.values[i] - 1.0).abs() < 1e-10,
                "mode {i}: {} vs {}",
                values[i],
                e.values[i]
            );
        }
        // ...and the six are the rigid motions: K annihilates them exactly.
        let x = model.mesh().coords();
        let n = sys.dofs.free_count();
        let knorm = sys.k.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for i in 0..6 {
            let r: Vec<f64> = (0..n)
                .map(|f| {
                    let d = sys.dofs.full_of_free(f);
                    let (p, c) = (x[d / 3], d % 3);
                    if i < 3 {
                        if c == i { 1.0 } else { 0.0 }
                    } else {
                        let w: [f64; 3] =
                            std::array::from_fn(|k| if k == i - 3 { 1.0 } else { 0.0 });
                        [
                            w[1] * p[2] - w[2] * p[1],
                            w[2] * p[0] - w[0] * p[2],
                            w[0] * p[1] - w[1] * p[0],
                        ][c]
                    }
                })
                .collect();
            let mut kr = vec![0.0; n];
            mul_vec(&sys.k, &r, &mut kr).unwrap();
            assert!(
                kr.iter().all(|v| v.abs() < 1e-12 * knorm),
                "rigid motion {i} is not in the null space of K"
            );
            // the model's own rigid-body motions (the eigensolver's null-space hint) span it
            let off = super::common::distance_from_span(sys.rigid_body.vectors(), &r);
            assert!(off < 1e-13, "rigid motion {i}: {off:e} off the hint's span");
        }
    }
}

/// The rigid-body motions as the eigensolver's null-space hint (`SystemMatrices::modes`, docs/MATH.md
/// "Known null vectors") on a plate supported in z only along its `x = 0` edge face: four
/// zero-energy motions remain (the two in-plane translations, the rotation about z and the rotation
/// about the supported line, a combination of a rotation about the centroid and a z translation).
/// The solve with the hint has as many zero eigenvalues as the dense spectrum, the same elastic
/// eigenvalues, a verified Sturm count, and fewer solved vectors than the solve without it; on the
/// clamped plate no combination is zero-energy and the result is the same as without the hint. On
/// the free-free plate the lowest 3 modes need no solve at all: the six given ones hold them and
/// their guard pairs.
#[test]
fn the_rigid_body_hint_finds_the_motions_the_supports_allow() {
    use femu_sparse::eigen::{EigenOptions, Which, eigs};
    for (quadratic, fixed) in [(false, 2usize), (true, 2), (false, 3)] {
        let mut model = small_plate(quadratic);
        let components: Vec<usize> = if fixed == 3 { vec![0, 1, 2] } else { vec![2] };
        model.fix_set("xmin", &components).unwrap();
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let dense =
            generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
                .unwrap();
        let top = *dense.last().unwrap();
        let zeros = dense.iter().filter(|v| v.abs() < 1e-9 * top).count();
        assert_eq!(zeros, if fixed == 3 { 0 } else { 4 }, "{:?}", &dense[..6]);
        let count = 10;
        let with = sys
            .modes(Which::Lowest(count), &EigenOptions::default())
            .unwrap();
        let plain = eigs(
            &sys.k,
            &sys.m,
            Which::Lowest(count),
            &EigenOptions::default(),
        )
        .unwrap();
        assert!(with.sturm.verified());
        let case = format!("quadratic {quadratic}, fixed {components:?}");
        for (j, v) in with.values.iter().enumerate().take(count) {
            if j < zeros {
                assert!(v.abs() < 1e-9 * top, "{case}: mode {j} {v:e}");
            } else {
                assert!(
                    (v / dense[j] - 1.0).abs() < 1e-9,
                    "{case}: mode {j} {v} vs {}",
                    dense[j]
                );
            }
        }
        if zeros > 0 {
            assert!(
                with.stats.solved_vectors < plain.stats.solved_vectors,
                "{case}: {} solved vectors with the hint, {} without",
                with.stats.solved_vectors,
                plain.stats.solved_vectors
            );
        } else {
            assert_eq!(with.values, plain.values, "{case}");
        }
    }
    // free-free: the six given modes hold the lowest 3 and their 3 guard pairs, so no vector is
    // solved; the zero cluster is returned whole and the Sturm count (the dense count) proves it
    let sys = small_plate(false).assemble(MassKind::Consistent).unwrap();
    let dense =
        generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
            .unwrap();
    let top = *dense.last().unwrap();
    let modes = sys
        .modes(Which::Lowest(3), &EigenOptions::default())
        .unwrap();
    assert_eq!(modes.stats.solved_vectors, 0);
    assert_eq!(modes.values.len(), 6, "{:?}", modes.values);
    assert!(modes.values.iter().all(|v| v.abs() < 1e-9 * top));
    assert!(modes.sturm.verified());
    assert_eq!(
        modes.sturm.count,
        dense.iter().filter(|v| **v < modes.sturm.upper).count()
    );
}

/// Parameter groups: K(p) equals re-assembly with the group's Young's modulus scaled by (1 + p)
/// (K is linear in E); M(q) equals re-assembly with the density scaled by (1 + q); K_g x from
/// element matrices equals the assembled K_g times x; and the element-by-element groups sum to K.
#[test]
fn parameter_groups_match_reassembly() {
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let mut model = small_plate(false);
        model.fix_set("xmin", &[0, 1, 2]).unwrap();
        let asm = Assembler::new(&model).unwrap();
        let base = asm.assemble(&model, mass).unwrap();
        let groups = ParameterGroups::from_element_sets(&model, &["penta", "tet"], mass).unwrap();
        let (p, q) = ([-0.3, 0.25], [0.1, -0.2]);
        let updated = groups.parameterized(&model, &asm, &base, &p, &q).unwrap();

        let mut truth = model.clone();
        truth
            .set_material(
                Some("penta"),
                Material::isotropic("s", 210e9 * 0.7, 0.3, 7850.0 * 1.1).unwrap(),
            )
            .unwrap();
        truth
            .set_material(
                Some("tet"),
                Material::isotropic("a", 70e9 * 1.25, 0.33, 2700.0 * 0.8).unwrap(),
            )
            .unwrap();
        let reference = asm.assemble(&truth, mass).unwrap();
        let close = |a: &[f64], b: &[f64]| {
            let s = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-13 * s)
        };
        assert!(
            close(updated.k.data(), reference.k.data()),
            "{mass:?}: K(p) differs"
        );
        assert!(
            close(updated.m.data(), reference.m.data()),
            "{mass:?}: M(q) differs"
        );

        // K_g x element by element against the assembled K_g.
        let n = base.dofs.free_count();
        let x: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let kg = groups.group_stiffness(&model, &asm, 1).unwrap();
        let (mut y1, mut y2) = (vec![0.0; n], vec![0.0; n]);
        groups
            .stiffness_product(&model, &asm, 1, &x, &mut y1)
            .unwrap();
        mul_vec(&kg, &x, &mut y2).unwrap();
        assert!(close(&y1, &y2));
        assert!(
            groups
                .stiffness_product(&model, &asm, 2, &x, &mut y1)
                .is_err()
        );
        assert!(
            groups
                .parameterized(&model, &asm, &base, &[0.0], &q)
                .is_err()
        );
    }
    // Element by element: sum of all K_g x equals K x.
    let model = small_plate(true);
    let asm = Assembler::new(&model).unwrap();
    let base = asm.assemble(&model, MassKind::Consistent).unwrap();
    let groups = ParameterGroups::elementwise(&model, MassKind::Consistent).unwrap();
    assert_eq!(groups.len(), model.mesh().element_count());
    let n = base.dofs.free_count();
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut y = vec![0.0; n];
    let mut ym = vec![0.0; n];
    for g in 0..groups.len() {
        groups
            .stiffness_product(&model, &asm, g, &x, &mut y)
            .unwrap();
        groups.mass_product(&model, &asm, g, &x, &mut ym).unwrap();
    }
    let (mut kx, mut mx) = (vec![0.0; n], vec![0.0; n]);
    mul_vec(&base.k, &x, &mut kx).unwrap();
    mul_vec(&base.m, &x, &mut mx).unwrap();
    let err = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            .sqrt()
            / b.iter().map(|q| q * q).sum::<f64>().sqrt()
    };
    assert!(err(&y, &kx) < 1e-13 && err(&ym, &mx) < 1e-13);
}

/// Re-assembly into existing storage (updating loops) equals a fresh assembly, and storage of
/// another pattern is refused rather than written.
#[test]
fn assemble_into_reuses_storage() {
    let mut model = small_plate(true);
    let asm = Assembler::new(&model).unwrap();
    let mut sys = asm.assemble(&model, MassKind::Consistent).unwrap();
    model
        .set_material(
            Some("hex"),
            Material::isotropic("soft", 150e9, 0.28, 7000.0).unwrap(),
        )
        .unwrap();
    asm.assemble_into(&model, &mut sys).unwrap();
    let fresh = Assembler::new(&model)
        .unwrap()
        .assemble(&model, MassKind::Consistent)
        .unwrap();
    assert_eq!(sys.k.data(), fresh.k.data());
    assert_eq!(sys.m.data(), fresh.m.data());
    let other = small_plate(false);
    let mut foreign = other.assemble(MassKind::Consistent).unwrap();
    assert!(asm.assemble_into(&model, &mut foreign).is_err());
    assert!(
        Assembler::new(&other)
            .unwrap()
            .assemble_into(&other, &mut sys)
            .is_err()
    );
}

/// Point masses: a rigid translation carries the solid's mass plus every point mass, with the
/// consistent and the lumped mass (`u^T M u = rho V + sum m`); an anisotropic mass carries its
/// mass in each direction (`e_i^T M_p e_i`) and its coupling (`e_x^T M e_y`); bad masses are
/// refused naming the node.
#[test]
fn point_masses_add_their_mass_to_rigid_motions() {
    use femu_fem::prelude::*;
    let mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.1, 0.05],
        [4, 2, 1],
        BoxCells::Hex,
        true,
    ))
    .unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    let solid = 7850.0 * 0.2 * 0.1 * 0.05;
    model.add_point_mass(1, 0.75).unwrap();
    model.add_point_mass(5, 0.25).unwrap();
    let aniso = [[0.5, 0.1, 0.0], [0.1, 0.3, 0.0], [0.0, 0.0, 0.2]];
    model.add_point_mass_matrix(7, aniso).unwrap();
    assert!((model.total_mass().unwrap() - (solid + 1.0 + (0.5 + 0.3 + 0.2) / 3.0)).abs() < 1e-12);
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let sys = model.assemble(kind).unwrap();
        let n = sys.dofs.free_count();
        let along = |c: usize| -> Vec<f64> {
            (0..n)
                .map(|f| {
                    if sys.dofs.full_of_free(f) % 3 == c {
                        1.0
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        for c in 0..3 {
            let u = along(c);
            let m = femu_sparse::csc::bilinear(&sys.m, &u, &u).unwrap();
            let want = solid + 1.0 + aniso[c][c];
            assert!(
                (m / want - 1.0).abs() < 1e-12,
                "{kind:?} direction {c}: {m} vs {want}"
            );
        }
        if kind == MassKind::Consistent {
            // the coupling of the anisotropic mass: e_x^T M e_y picks it up (the solid's rigid
            // translations are M-orthogonal)
            let xy = femu_sparse::csc::bilinear(&sys.m, &along(0), &along(1)).unwrap();
            assert!((xy - 0.1).abs() < 1e-12, "{xy}");
        }
    }
    let e = model.add_point_mass(999, 1.0).unwrap_err().to_string();
    assert_eq!(e, "unknown node 999");
    let e = model.add_point_mass(2, -1.0).unwrap_err().to_string();
    assert!(
        e.starts_with("material \"point mass on node 2\": the mass must be positive"),
        "{e}"
    );
    let e = model
        .add_point_mass_matrix(2, [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        .unwrap_err()
        .to_string();
    assert!(e.contains("is not symmetric"), "{e}");
    let e = model.add_point_mass(2, f64::NAN).unwrap_err().to_string();
    assert!(e.contains("is not finite"), "{e}");
}

/// The analysis made beside the assembly is `K`'s and is used by `SystemMatrices::modes` (no
/// analysis time in the solve's statistics); the modes are the dense ones. A `K` replaced by one
/// of another pattern (a coupling between two far nodes added) is analysed again by the solve,
/// whose modes are again the dense ones of the new `K`, not a factorization on the old structure.
#[test]
fn the_analysis_beside_the_assembly_serves_the_matrices_it_was_made_for() {
    use femu_sparse::SparseMatrix;
    use femu_sparse::eigen::{EigenOptions, Which};
    let mut model = small_plate(false);
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let mut sys = model.assemble(MassKind::Consistent).unwrap();
    let analysis = sys.analysis().expect("made beside the assembly");
    assert!(analysis.is_for(&sys.k) && analysis.dim() == sys.k.rows());
    let count = 6;
    let check = |sys: &femu_fem::assembly::SystemMatrices, given: bool| {
        let dense =
            generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
                .unwrap();
        let modes = sys
            .modes(Which::Lowest(count), &EigenOptions::default())
            .unwrap();
        assert!(modes.sturm.verified());
        assert_eq!(modes.stats.symbolic_seconds == 0.0, given);
        for j in 0..count {
            assert!(
                (modes.values[j] / dense[j] - 1.0).abs() < 1e-9,
                "mode {j}: {} against {}",
                modes.values[j],
                dense[j]
            );
        }
    };
    check(&sys, true);
    // a spring of 1 % of the largest diagonal entry between the first and the last free DOF
    let n = sys.k.rows();
    let s = 0.01
        * (0..n)
            .map(|i| sys.k.get(i, i).copied().unwrap_or(0.0))
            .fold(0.0, f64::max);
    let mut t = sprs::TriMat::new((n, n));
    for (v, (r, c)) in sys.k.iter() {
        t.add_triplet(r, c, *v);
    }
    for (r, c, v) in [(0, 0, s), (n - 1, n - 1, s), (0, n - 1, -s), (n - 1, 0, -s)] {
        t.add_triplet(r, c, v);
    }
    let k: SparseMatrix = t.to_csc();
    assert!(k.nnz() == sys.k.nnz() + 2, "the spring adds two entries");
    sys.k = k;
    assert!(sys.analysis().is_none());
    check(&sys, false);
}

/// The eigensolver's checks of `K` and `M` made beside the assembly serve those matrices only:
/// values changed after the assembly (same pattern, so the analysis still serves) are checked
/// again by the solve, which reports a NaN put into `K` and an asymmetry put into `M` with their
/// matrix, and solves a `K` scaled by 4 to the dense eigenvalues of the scaled pencil (4 times
/// the first ones).
#[test]
fn the_checks_beside_the_assembly_serve_the_matrices_they_were_made_for() {
    use femu_sparse::SparseError;
    use femu_sparse::eigen::{EigenOptions, Which};
    let mut model = small_plate(false);
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let opts = EigenOptions::default();
    let dense =
        generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
            .unwrap();
    let first = sys.modes(Which::Lowest(4), &opts).unwrap();
    for j in 0..4 {
        assert!((first.values[j] / dense[j] - 1.0).abs() < 1e-9);
    }
    let mut nan = sys.clone();
    nan.k.data_mut()[5] = f64::NAN;
    assert!(nan.analysis().is_some(), "the same pattern");
    assert!(matches!(
        nan.modes(Which::Lowest(4), &opts),
        Err(SparseError::NonFinite { matrix: "K", .. })
    ));
    let mut asym = sys.clone();
    let p = asym
        .m
        .iter()
        .position(|(_, (r, c))| r > c)
        .expect("an entry below the diagonal");
    asym.m.data_mut()[p] *= 1.5;
    assert!(matches!(
        asym.modes(Which::Lowest(4), &opts),
        Err(SparseError::NotSymmetric { matrix: "M", .. })
    ));
    let mut scaled = sys.clone();
    scaled.k.data_mut().iter_mut().for_each(|v| *v *= 4.0);
    let modes = scaled.modes(Which::Lowest(4), &opts).unwrap();
    for j in 0..4 {
        assert!(
            (modes.values[j] / (4.0 * dense[j]) - 1.0).abs() < 1e-9,
            "mode {j}: {} against {}",
            modes.values[j],
            4.0 * dense[j]
        );
    }
}
