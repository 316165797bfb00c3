//! Multipoint constraints: the reduced matrices against a transformation `T` written here from the
//! rigid-link formula, rigid-body motions of linked structures, an analytic two-DOF system of
//! rigidly linked masses, RBE3's weighted average and rigid-motion property, parameter groups
//! through `T`, and the errors of conflicting constraints.

use femu_fem::prelude::*;
use femu_sparse::csc::{mul_vec, to_dense};
use femu_sparse::dense::generalized_symmetric_eigenvalues;

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A box mesh with extra nodes (ids and positions) appended, which no element uses.
fn box_with(size: [f64; 3], cells: [usize; 3], quadratic: bool, extra: &[(u64, [f64; 3])]) -> Mesh {
    let mut mesh = box_mesh(&BoxSpec::new(size, cells, BoxCells::Hex, quadratic)).unwrap();
    for (id, x) in extra {
        mesh.add_node(*id, *x).unwrap();
    }
    mesh
}

fn set_ids(mesh: &Mesh, set: &str) -> Vec<u64> {
    mesh.node_set(set)
        .unwrap()
        .iter()
        .map(|i| mesh.node_id(*i))
        .collect()
}

fn rel_diff(a: &faer::Mat<f64>, b: &faer::Mat<f64>) -> f64 {
    let scale = (0..a.nrows())
        .flat_map(|i| (0..a.ncols()).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max(b[(i, j)].abs()));
    (0..a.nrows())
        .flat_map(|i| (0..a.ncols()).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max((a[(i, j)] - b[(i, j)]).abs()))
        / scale
}

/// `K_r = T^T K T` and `M_r = T^T M T` for a rigid link, with `T` written here from
/// `u_m = u_r + theta x (x_m - x_r)` and `K`, `M` assembled without the link (consistent and
/// lumped mass, point masses on the reference and on a linked node, a clamped face).
#[test]
fn rigid_link_matrices_equal_the_dense_transformation() {
    let xr = [0.35, 0.05, 0.07];
    let mesh = box_with([0.3, 0.1, 0.05], [3, 2, 1], true, &[(9001, xr)]);
    let mut plain = Model::new(mesh.clone()).unwrap();
    plain.set_material(None, Material::steel()).unwrap();
    plain.fix_set("xmin", &[0, 1, 2]).unwrap();
    let linked_ids = set_ids(&mesh, "xmax");
    plain.add_point_mass(9001, 3.0).unwrap();
    plain.add_point_mass(linked_ids[2], 0.5).unwrap();
    let mut model = plain.clone();
    model
        .add_rigid_link(9001, &linked_ids, &[0, 1, 2], "RBE2 1")
        .unwrap();
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let red = model.assemble(kind).unwrap();
        let full = plain.assemble(kind).unwrap();
        let (n, nu) = (red.dofs.free_count(), full.dofs.free_count());
        // T: unconstrained free DOF -> reduced free DOFs, from the rigid-link formula
        let r = mesh.node_index(9001).unwrap();
        let rot = red.dofs.rotation_point(r).unwrap();
        let linked: Vec<usize> = linked_ids
            .iter()
            .map(|id| mesh.node_index(*id).unwrap())
            .collect();
        let mut t = faer::Mat::<f64>::zeros(nu, n);
        for g in 0..nu {
            let (p, c) = full.dofs.free_dof(g);
            if linked.contains(&p) {
                let x = mesh.coords()[p];
                let d = [x[0] - xr[0], x[1] - xr[1], x[2] - xr[2]];
                t[(g, red.dofs.free_index(r, c).unwrap())] = 1.0;
                for j in 0..3 {
                    let mut e = [0.0; 3];
                    e[j] = 1.0;
                    let w = cross(e, d)[c];
                    if w != 0.0 {
                        t[(g, red.dofs.free_index(rot, j).unwrap())] = w;
                    }
                }
            } else {
                t[(g, red.dofs.free_index(p, c).unwrap())] = 1.0;
            }
        }
        let kr = t.transpose() * to_dense(&full.k) * &t;
        let mr = t.transpose() * to_dense(&full.m) * &t;
        let (dk, dm) = (
            rel_diff(&to_dense(&red.k), &kr),
            rel_diff(&to_dense(&red.m), &mr),
        );
        assert!(dk < 1e-13 && dm < 1e-13, "{kind:?}: K {dk:e}, M {dm:e}");
        // every vector femu writes carries the linked nodes: expand = T z
        let z: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        let u = red.dofs.expand(&z).unwrap();
        let tz = &t * faer::Mat::from_fn(n, 1, |i, _| z[i]);
        for g in 0..nu {
            let d = full.dofs.full_of_free(g);
            assert!((u[d] - tz[(g, 0)]).abs() < 1e-12, "DOF {d}");
        }
    }
}

/// The rigid-body motions of a free-free structure with a rigid link (a reference off the body
/// carrying 2 kg) have zero strain energy, and there are exactly six of them.
#[test]
fn rigid_body_motions_of_a_linked_structure_have_zero_strain_energy() {
    let xr = [0.1, -0.08, 0.02];
    let mesh = box_with([0.2, 0.1, 0.04], [4, 2, 1], false, &[(7001, xr)]);
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
        .add_rigid_link(7001, &set_ids(&mesh, "ymin"), &[0, 1, 2], "RBE2 5")
        .unwrap();
    model.add_point_mass(7001, 2.0).unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let n = sys.dofs.free_count();
    let r = mesh.node_index(7001).unwrap();
    let rot = sys.dofs.rotation_point(r).unwrap();
    let knorm = to_dense(&sys.k).norm_max();
    for (t, th) in [
        ([1.0, 0.0, 0.0], [0.0; 3]),
        ([0.0, 1.0, 0.0], [0.0; 3]),
        ([0.0, 0.0, 1.0], [0.0; 3]),
        ([0.0; 3], [1.0, 0.0, 0.0]),
        ([0.0; 3], [0.0, 1.0, 0.0]),
        ([0.0; 3], [0.0, 0.0, 1.0]),
    ] {
        let z: Vec<f64> = (0..n)
            .map(|f| {
                let (p, c) = sys.dofs.free_dof(f);
                if p == rot {
                    th[c]
                } else {
                    t[c] + cross(th, mesh.coords()[p])[c]
                }
            })
            .collect();
        let mut kz = vec![0.0; n];
        mul_vec(&sys.k, &z, &mut kz).unwrap();
        let worst = kz.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            worst < 1e-11 * knorm,
            "rigid motion {t:?} {th:?}: |Kz| {worst:e}"
        );
        // the model's own rigid-body motions (the eigensolver's null-space hint) span it, with the
        // reference's rotation DOFs
        let off = super::common::distance_from_span(sys.rigid_body.vectors(), &z);
        assert!(
            off < 1e-13,
            "rigid motion {t:?} {th:?}: {off:e} off the hint's span"
        );
    }
    assert_eq!(sys.rigid_body.vectors().ncols(), 6);
    let vals =
        generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
            .unwrap();
    let top = vals.last().copied().unwrap();
    let zero = vals.iter().filter(|v| v.abs() < 1e-9 * top).count();
    assert_eq!(zero, 6, "{:?}", &vals[..8]);
}

/// Two rigid faces carrying masses on a clamped two-element bar (Poisson's ratio 0, so uniform
/// axial strain is exact in hex8): the two axial modes solve the 2x2 problem
/// `k [[2, -1], [-1, 1]]`, `rho A h [[2/3, 1/6], [1/6, 1/3]] + diag(m1, m2)`, `k = E A / h`,
/// solved here by the quadratic formula. A mass linked to a node it sits on is the same mass on
/// the node.
#[test]
fn rigidly_linked_masses_match_the_analytic_two_dof_system() {
    let (l, a, b) = (0.2, 0.02, 0.03);
    let (r1, r2) = ([l / 2.0, a / 2.0, b / 2.0], [l, a / 2.0, b / 2.0]);
    let mesh = box_with([l, a, b], [2, 1, 1], false, &[(501, r1), (502, r2)]);
    let mut model = Model::new(mesh.clone()).unwrap();
    let (e, rho) = (70e9, 2700.0);
    model
        .set_material(None, Material::isotropic("al", e, 0.0, rho).unwrap())
        .unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let mid: Vec<u64> = (0..mesh.node_count())
        .filter(|i| (mesh.coords()[*i][0] - l / 2.0).abs() < 1e-12 && *i < mesh.node_count() - 2)
        .map(|i| mesh.node_id(i))
        .collect();
    assert_eq!(mid.len(), 4);
    let end = set_ids(&mesh, "xmax");
    model.add_rigid_link(501, &mid, &[0, 1, 2], "mid").unwrap();
    model.add_rigid_link(502, &end, &[0, 1, 2], "end").unwrap();
    let (m1, m2) = (0.3, 0.2);
    model.add_point_mass(501, m1).unwrap();
    model.add_point_mass(502, m2).unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let vals =
        generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
            .unwrap();
    let (h, area) = (l / 2.0, a * b);
    let k = e * area / h;
    let c = rho * area * h;
    // det([[2k - w(2c/3 + m1), -k - w c/6], [-k - w c/6, k - w(c/3 + m2)]]) = 0, a quadratic in w
    let (p11, p12, p22) = (2.0 * c / 3.0 + m1, c / 6.0, c / 3.0 + m2);
    let qa = p11 * p22 - p12 * p12;
    let qb = -(2.0 * k * p22 + k * p11 + 2.0 * k * p12);
    let qc = 2.0 * k * k - k * k;
    let disc = (qb * qb - 4.0 * qa * qc).sqrt();
    for w in [(-qb - disc) / (2.0 * qa), (-qb + disc) / (2.0 * qa)] {
        let near = vals
            .iter()
            .map(|v| (v - w).abs() / w)
            .fold(f64::INFINITY, f64::min);
        assert!(
            near < 1e-11,
            "analytic {w}: nearest femu value off by {near:e}"
        );
    }

    // a mass linked to the node it sits on equals the mass on that node
    let tip = end[0];
    let x = mesh.coords()[mesh.node_index(tip).unwrap()];
    let mesh2 = box_with([l, a, b], [2, 1, 1], false, &[(600, x)]);
    let mut linked = Model::new(mesh2).unwrap();
    linked
        .set_material(None, Material::isotropic("al", e, 0.3, rho).unwrap())
        .unwrap();
    linked.fix_set("xmin", &[0, 1, 2]).unwrap();
    // the direct model leaves node 600 out (nothing connects it)
    let mut direct = linked.clone();
    direct.add_point_mass(tip, 1.5).unwrap();
    direct.fix_nodes(&[600], &[0, 1, 2]).unwrap();
    linked
        .add_rigid_link(600, &[tip], &[0, 1, 2], "on node")
        .unwrap();
    linked.add_point_mass(600, 1.5).unwrap();
    let s1 = linked.assemble(MassKind::Consistent).unwrap();
    let s2 = direct.assemble(MassKind::Consistent).unwrap();
    // the reference's rotations reach nothing (it sits on the node): they are fixed
    assert_eq!(s1.dofs.free_count(), s2.dofs.free_count());
    // the same matrices, node 600's DOFs standing for the tip's
    let m2 = linked.mesh();
    let (tip_i, ref_i) = (m2.node_index(tip).unwrap(), m2.node_index(600).unwrap());
    let map: Vec<usize> = (0..s1.dofs.free_count())
        .map(|f| {
            let (p, c) = s1.dofs.free_dof(f);
            s2.dofs
                .free_index(if p == ref_i { tip_i } else { p }, c)
                .unwrap()
        })
        .collect();
    let (k1, k2, mm1, mm2) = (
        to_dense(&s1.k),
        to_dense(&s2.k),
        to_dense(&s1.m),
        to_dense(&s2.m),
    );
    let k_perm = faer::Mat::from_fn(map.len(), map.len(), |i, j| k2[(map[i], map[j])]);
    let m_perm = faer::Mat::from_fn(map.len(), map.len(), |i, j| mm2[(map[i], map[j])]);
    assert!(rel_diff(&k1, &k_perm) < 1e-15 && rel_diff(&mm1, &m_perm) < 1e-15);
}

/// RBE3: a reference at the weighted centroid moves with the weighted average of its nodes; one
/// off the centroid follows a rigid motion of the nodes exactly; the reference adds no stiffness.
#[test]
fn weighted_average_is_the_average_and_follows_rigid_motions() {
    let base = box_with([0.2, 0.1, 0.04], [4, 2, 1], false, &[]);
    let top = set_ids(&base, "zmax");
    let weights: Vec<f64> = (0..top.len()).map(|i| 1.0 + (i % 4) as f64).collect();
    let wsum: f64 = weights.iter().sum();
    let mut xc = [0.0; 3];
    for (id, w) in top.iter().zip(&weights) {
        let x = base.coords()[base.node_index(*id).unwrap()];
        for i in 0..3 {
            xc[i] += w * x[i] / wsum;
        }
    }
    let pairs: Vec<(u64, f64)> = top.iter().copied().zip(weights.iter().copied()).collect();
    for (reference, at_centroid) in [(xc, true), ([0.31, 0.02, 0.11], false)] {
        let mesh = box_with([0.2, 0.1, 0.04], [4, 2, 1], false, &[(800, reference)]);
        let mut model = Model::new(mesh.clone()).unwrap();
        model.set_material(None, Material::steel()).unwrap();
        model
            .add_weighted_average(800, &[0, 1, 2], &pairs, "RBE3 9")
            .unwrap();
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let n = sys.dofs.free_count();
        let r = mesh.node_index(800).unwrap();
        if at_centroid {
            let z: Vec<f64> = (0..n)
                .map(|i| ((i * 13 + 5) % 17) as f64 / 17.0 - 0.4)
                .collect();
            let u = sys.dofs.expand(&z).unwrap();
            for c in 0..3 {
                let avg: f64 = pairs
                    .iter()
                    .map(|(id, w)| w * u[3 * mesh.node_index(*id).unwrap() + c])
                    .sum::<f64>()
                    / wsum;
                assert!((u[3 * r + c] - avg).abs() < 1e-14, "component {c}");
            }
            // no stiffness of its own: K equals the model without the reference node
            let mut plain = Model::new(base.clone()).unwrap();
            plain.set_material(None, Material::steel()).unwrap();
            let k0 = plain.assemble(MassKind::Consistent).unwrap().k;
            assert!(rel_diff(&to_dense(&sys.k), &to_dense(&k0)) < 1e-15);
        } else {
            let (t, th) = ([0.3, -0.2, 0.5], [0.7, 0.1, -0.4]);
            let z: Vec<f64> = (0..n)
                .map(|f| {
                    let (p, c) = sys.dofs.free_dof(f);
                    t[c] + cross(th, mesh.coords()[p])[c]
                })
                .collect();
            let u = sys.dofs.expand(&z).unwrap();
            let want = cross(th, reference);
            for c in 0..3 {
                assert!(
                    (u[3 * r + c] - (t[c] + want[c])).abs() < 1e-13,
                    "component {c}"
                );
            }
        }
    }
}

/// Parameter groups act through `T`: `K(p)` equals the assembly of the model whose materials are
/// scaled, and `K_g x` equals the assembled group matrix times `x`.
#[test]
fn parameter_groups_act_through_the_constraints() {
    let mesh = box_with(
        [0.2, 0.1, 0.04],
        [4, 2, 1],
        true,
        &[(900, [0.25, 0.05, 0.02])],
    );
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
        .add_rigid_link(900, &set_ids(&mesh, "xmax"), &[0, 1, 2], "RBE2 2")
        .unwrap();
    model.add_point_mass(900, 1.0).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let last: Vec<usize> = (0..mesh.element_count())
        .filter(|e| {
            mesh.element(*e)
                .nodes
                .iter()
                .any(|n| mesh.coords()[*n][0] > 0.199)
        })
        .collect();
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let asm = Assembler::new(&model).unwrap();
        let base = asm.assemble(&model, kind).unwrap();
        let groups = ParameterGroups::new(
            &model,
            vec![ParameterGroup::solids("tip", last.clone())],
            kind,
        )
        .unwrap();
        let out = groups
            .parameterized(&model, &asm, &base, &[-0.3], &[0.2])
            .unwrap();
        // the same model with the tip elements' material scaled
        let mut mesh2 = mesh.clone();
        mesh2.add_element_set_indices("tip", last.clone());
        let mut m2 = Model::new(mesh2).unwrap();
        m2.set_material(None, Material::steel()).unwrap();
        let steel = Material::steel();
        let femu_fem::material::Elasticity::Isotropic { e, nu } = steel.elasticity else {
            unreachable!()
        };
        m2.set_material(
            Some("tip"),
            Material::isotropic("tip", 0.7 * e, nu, 1.2 * steel.density).unwrap(),
        )
        .unwrap();
        m2.add_rigid_link(900, &set_ids(&mesh, "xmax"), &[0, 1, 2], "RBE2 2")
            .unwrap();
        m2.add_point_mass(900, 1.0).unwrap();
        m2.fix_set("xmin", &[0, 1, 2]).unwrap();
        let want = m2.assemble(kind).unwrap();
        assert!(
            rel_diff(&to_dense(&out.k), &to_dense(&want.k)) < 1e-13,
            "{kind:?} K"
        );
        assert!(
            rel_diff(&to_dense(&out.m), &to_dense(&want.m)) < 1e-13,
            "{kind:?} M"
        );
        let n = base.dofs.free_count();
        let x: Vec<f64> = (0..n).map(|i| ((i * 5 + 1) % 9) as f64 - 4.0).collect();
        let mut y = vec![0.0; n];
        groups
            .stiffness_product(&model, &asm, 0, &x, &mut y)
            .unwrap();
        let kg = groups.group_stiffness(&model, &asm, 0).unwrap();
        let mut y2 = vec![0.0; n];
        mul_vec(&kg, &x, &mut y2).unwrap();
        let scale = y2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in y.iter().zip(&y2) {
            assert!((a - b).abs() < 1e-12 * scale);
        }
    }
}

/// Conflicting constraints are errors naming both, the DOF and the node.
#[test]
fn conflicting_constraints_are_named() {
    let mesh = box_with(
        [0.1, 0.1, 0.1],
        [1, 1, 1],
        false,
        &[(50, [0.5, 0.5, 0.5]), (51, [0.6, 0.5, 0.5])],
    );
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    let ids = set_ids(&mesh, "xmax");
    model
        .add_rigid_link(50, &ids, &[0, 1, 2], "RBE2 10 (a.bdf line 4)")
        .unwrap();
    model
        .add_rigid_link(51, &ids[..1], &[0], "RBE2 11 (a.bdf line 5)")
        .unwrap();
    let e = model.dof_map().unwrap_err().to_string();
    assert!(
        e.starts_with("constraint RBE2 11 (a.bdf line 5): its dependent DOF, node ")
            && e.contains("is already dependent in RBE2 10 (a.bdf line 4)"),
        "{e}"
    );
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
        .add_rigid_link(50, &ids, &[0, 1, 2], "RBE2 10")
        .unwrap();
    model.fix_nodes(&ids[..1], &[2]).unwrap();
    let e = model
        .assemble(MassKind::Consistent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("RBE2 10") && e.contains("is also fixed"), "{e}");
    let mut model = Model::new(mesh.clone()).unwrap();
    model
        .add_constraint((50, 0), &[((51, 0), 1.0)], "EQ 1")
        .unwrap();
    model
        .add_constraint((51, 0), &[((50, 0), 2.0)], "EQ 2")
        .unwrap();
    let e = model.dof_map().unwrap_err().to_string();
    assert!(
        e.contains("cycle") && e.contains("EQ 1") && e.contains("EQ 2"),
        "{e}"
    );
    let e = model
        .add_constraint((ids[0], 4), &[((50, 0), 1.0)], "EQ 3")
        .unwrap_err()
        .to_string();
    assert!(e.contains("has no DOF 5"), "{e}");
    let e = model
        .add_rigid_link(50, &ids, &[3], "RBE2 12")
        .unwrap_err()
        .to_string();
    assert!(e.contains("component 4"), "{e}");
    let e = model
        .add_weighted_average(51, &[0], &[(ids[0], -1.0)], "RBE3 1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("weights must be positive"), "{e}");
}

/// A rigid mass (mass, offset centre of gravity, full inertia tensor) on a rigid link's reference:
/// for every rigid motion `u = t + w x x` of the linked structure its kinetic energy form is
/// `m |t + w x x_cg|^2 + w^T J w` (written here from the definition), with consistent and lumped
/// mass; it counts in the total mass; a node without rotations refuses it.
#[test]
fn rigid_masses_on_reference_nodes_have_the_rigid_body_kinetic_energy() {
    let xr = [0.25, 0.05, 0.02];
    let mesh = box_with([0.2, 0.1, 0.04], [4, 2, 1], false, &[(700, xr)]);
    let mut plain = Model::new(mesh.clone()).unwrap();
    plain.set_material(None, Material::steel()).unwrap();
    plain
        .add_rigid_link(700, &set_ids(&mesh, "xmax"), &[0, 1, 2], "RBE2 1")
        .unwrap();
    let mut model = plain.clone();
    let (m, d) = (3.5, [0.04, -0.02, 0.07]);
    let j = [[0.2, 0.03, -0.01], [0.03, 0.15, 0.02], [-0.01, 0.02, 0.1]];
    model.add_rigid_mass(700, m, d, j).unwrap();
    assert!(
        (model.total_mass().unwrap() - plain.total_mass().unwrap() - m).abs() < 1e-12,
        "total mass"
    );
    let xcg = [xr[0] + d[0], xr[1] + d[1], xr[2] + d[2]];
    for kind in [MassKind::Consistent, MassKind::Lumped] {
        let (a, b) = (model.assemble(kind).unwrap(), plain.assemble(kind).unwrap());
        assert_eq!(a.dofs, b.dofs);
        let n = a.dofs.free_count();
        let rot = a
            .dofs
            .rotation_point(mesh.node_index(700).unwrap())
            .unwrap();
        let mut rng = super::common::Rng(11);
        for _ in 0..4 {
            let t = [rng.sym(), rng.sym(), rng.sym()];
            let w = [rng.sym(), rng.sym(), rng.sym()];
            let z: Vec<f64> = (0..n)
                .map(|f| {
                    let (p, c) = a.dofs.free_dof(f);
                    if p == rot {
                        w[c]
                    } else {
                        t[c] + cross(w, mesh.coords()[p])[c]
                    }
                })
                .collect();
            let e = femu_sparse::csc::bilinear(&a.m, &z, &z).unwrap()
                - femu_sparse::csc::bilinear(&b.m, &z, &z).unwrap();
            let v = cross(w, xcg);
            let vt: f64 = (0..3).map(|i| (t[i] + v[i]).powi(2)).sum();
            let jw: f64 = (0..3)
                .map(|i| (0..3).map(|k| w[i] * j[i][k] * w[k]).sum::<f64>())
                .sum();
            let want = m * vt + jw;
            assert!((e - want).abs() < 1e-12 * want, "{kind:?}: {e} vs {want}");
        }
    }
    let e = model
        .add_rigid_mass(set_ids(&mesh, "xmin")[0], 1.0, d, j)
        .unwrap_err()
        .to_string();
    assert!(e.contains("the node has no rotations"), "{e}");
}
