//! Repeated and clustered eigenvalues at every position of a request: shifts below, on, inside and
//! above a cluster, counts that end inside one, band ends on an eigenvalue, rigid-body zeros.
//! Every result is checked against the dense generalized eigensolver (the reference) and the
//! analytic spectrum of the pencils (tensor products of 1D linear finite elements, whose
//! eigenvalues are sums `mu_i + mu_j (+ mu_k)` of the 1D ones, so a cube's triples and sextuples and
//! a square's pairs are exact), and its Sturm interval is recounted from the dense spectrum.

use femu_sparse::SparseError;
use femu_sparse::SparseMatrix;
use femu_sparse::csc::to_dense;
use femu_sparse::dense::generalized_symmetric_eigenvalues;
use femu_sparse::eigen::{EigenOptions, Modes, NullSpaceHint, ResidualKind, Which, eigs};
use sprs::TriMat;

/// 1D linear elements on [0, 1] with `ne` elements: `(K, M)` dense, Dirichlet at both ends
/// (interior nodes) or free (all nodes).
fn bar(ne: usize, free: bool) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let h = 1.0 / ne as f64;
    let nodes = ne + 1;
    let mut k = vec![vec![0.0; nodes]; nodes];
    let mut m = vec![vec![0.0; nodes]; nodes];
    for e in 0..ne {
        for (a, b, kv, mv) in [
            (e, e, 1.0, 2.0),
            (e + 1, e + 1, 1.0, 2.0),
            (e, e + 1, -1.0, 1.0),
            (e + 1, e, -1.0, 1.0),
        ] {
            k[a][b] += kv / h;
            m[a][b] += mv * h / 6.0;
        }
    }
    if free {
        (k, m)
    } else {
        let cut = |a: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            a[1..nodes - 1]
                .iter()
                .map(|r| r[1..nodes - 1].to_vec())
                .collect()
        };
        (cut(k), cut(m))
    }
}

/// The 1D eigenvalues `mu_k = (6 / h^2) (1 - cos t) / (2 + cos t)`, `t = k pi / ne`.
fn bar_spectrum(ne: usize, free: bool) -> Vec<f64> {
    let h = 1.0 / ne as f64;
    let ks: Vec<usize> = if free {
        (0..=ne).collect()
    } else {
        (1..ne).collect()
    };
    ks.into_iter()
        .map(|k| {
            let c = (k as f64 * std::f64::consts::PI / ne as f64).cos();
            6.0 / (h * h) * (1.0 - c) / (2.0 + c)
        })
        .collect()
}

fn kron(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let (na, nb) = (a.len(), b.len());
    let mut out = vec![vec![0.0; na * nb]; na * nb];
    for i in 0..na {
        for j in 0..na {
            for p in 0..nb {
                for q in 0..nb {
                    out[i * nb + p][j * nb + q] = a[i][j] * b[p][q];
                }
            }
        }
    }
    out
}

fn add(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter()
        .zip(b)
        .map(|(r, s)| r.iter().zip(s).map(|(x, y)| x + y).collect())
        .collect()
}

/// `copies` uncoupled copies of `a` (the components of a vector field).
fn block_diagonal(a: &[Vec<f64>], copies: usize) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut out = vec![vec![0.0; n * copies]; n * copies];
    for c in 0..copies {
        for i in 0..n {
            for j in 0..n {
                out[c * n + i][c * n + j] = a[i][j];
            }
        }
    }
    out
}

/// `a` stored on the pattern of `a` and `b` together (the trilinear stiffness has exact zeros
/// where the mass has entries: K's pattern must hold M's).
fn sparse(a: &[Vec<f64>], b: &[Vec<f64>]) -> SparseMatrix {
    let n = a.len();
    let mut t = TriMat::new((n, n));
    for i in 0..n {
        for j in 0..n {
            if a[i][j] != 0.0 || b[i][j] != 0.0 {
                t.add_triplet(i, j, a[i][j]);
            }
        }
    }
    t.to_csc()
}

/// The tensor-product pencil of `dim` (2 or 3) bars, `copies` components.
fn pencil(ne: usize, dim: usize, free: bool, copies: usize) -> (SparseMatrix, SparseMatrix) {
    let (k1, m1) = bar(ne, free);
    let (k, m) = if dim == 2 {
        (add(&kron(&k1, &m1), &kron(&m1, &k1)), kron(&m1, &m1))
    } else {
        let mm = kron(&m1, &m1);
        let k = add(
            &add(&kron(&k1, &mm), &kron(&m1, &kron(&k1, &m1))),
            &kron(&mm, &k1),
        );
        (k, kron(&m1, &mm))
    };
    let (k, m) = (block_diagonal(&k, copies), block_diagonal(&m, copies));
    (sparse(&k, &m), sparse(&m, &m))
}

fn analytic(ne: usize, dim: usize, free: bool, copies: usize) -> Vec<f64> {
    let mu = bar_spectrum(ne, free);
    let mut v = Vec::new();
    for a in &mu {
        for b in &mu {
            if dim == 2 {
                v.push(a + b);
            } else {
                for c in &mu {
                    v.push(a + b + c);
                }
            }
        }
    }
    let mut all: Vec<f64> = v.iter().flat_map(|x| vec![*x; copies]).collect();
    all.sort_by(f64::total_cmp);
    all
}

struct Case {
    k: SparseMatrix,
    m: SparseMatrix,
    dense: Vec<f64>,
    /// the tie tolerance of the reference: equal eigenvalues of the pencil agree to this
    tie: f64,
    /// the accuracy of the reference (1e-13 of the largest eigenvalue, 500 round-offs)
    exact: f64,
}

impl Case {
    fn new(ne: usize, dim: usize, free: bool, copies: usize) -> Self {
        let (k, m) = pencil(ne, dim, free, copies);
        let dense = generalized_symmetric_eigenvalues(to_dense(&k).as_ref(), to_dense(&m).as_ref())
            .unwrap();
        let exact = analytic(ne, dim, free, copies);
        let top = *exact.last().unwrap();
        for (d, e) in dense.iter().zip(&exact) {
            assert!((d - e).abs() <= 1e-11 * top, "dense {d} vs analytic {e}");
        }
        Case {
            k,
            m,
            dense,
            tie: 1e-9 * top,
            exact: 1e-13 * top,
        }
    }

    /// Dense eigenvalues in `(lo, hi]`.
    fn count(&self, lo: Option<f64>, hi: f64) -> usize {
        self.dense
            .iter()
            .filter(|v| lo.is_none_or(|l| **v > l) && **v <= hi)
            .count()
    }

    /// How many dense eigenvalues equal `v` (within the tie tolerance).
    fn multiplicity(&self, v: f64) -> usize {
        self.dense
            .iter()
            .filter(|d| (*d - v).abs() <= self.tie)
            .count()
    }

    /// The checks every result must pass; returns the result for case-specific ones.
    fn check(&self, which: Which) -> Modes {
        self.check_with(which, &EigenOptions::default())
    }

    /// [`Case::check`] with the given settings.
    fn check_with(&self, which: Which, params: &EigenOptions) -> Modes {
        let modes =
            eigs(&self.k, &self.m, which, params).unwrap_or_else(|e| panic!("{which:?}: {e}"));
        let s = &modes.sturm;
        assert!(s.verified(), "{which:?}: {s:?}");
        // the inertia count is the dense count in the same interval
        assert_eq!(s.count, self.count(s.lower, s.upper), "{which:?}: {s:?}");
        // the interval's ends lie in gaps, not on or among eigenvalues
        for end in s.lower.into_iter().chain([s.upper]) {
            assert!(
                self.dense.iter().all(|d| (d - end).abs() > self.exact),
                "{which:?}: end {end} on an eigenvalue"
            );
        }
        // every value is an eigenvalue, and every copy of each is returned
        let mut seen = Vec::new();
        for (j, v) in modes.values.iter().enumerate() {
            assert!(
                self.dense.iter().any(|d| (d - v).abs() <= self.tie),
                "{which:?}: {v} is not an eigenvalue"
            );
            assert!(
                modes.residuals[j] < 1e-8,
                "{which:?}: residual {}",
                modes.residuals[j]
            );
            if !seen.iter().any(|s: &f64| (s - v).abs() <= self.tie) {
                seen.push(*v);
                let returned = modes
                    .values
                    .iter()
                    .filter(|w| (*w - v).abs() <= self.tie)
                    .count();
                assert_eq!(returned, self.multiplicity(*v), "{which:?}: copies of {v}");
            }
        }
        // never fewer than asked, and more only to complete the last cluster
        if !matches!(which, Which::Band { .. }) {
            assert!(modes.values.len() >= modes.requested, "{which:?}");
        }
        modes
    }
}

/// The distinct eigenvalues of `dense` with their multiplicities.
fn clusters(case: &Case) -> Vec<(f64, usize)> {
    let mut out: Vec<(f64, usize)> = Vec::new();
    for d in &case.dense {
        match out.last_mut() {
            Some((v, m)) if (d - *v).abs() <= case.tie => *m += 1,
            _ => out.push((*d, 1)),
        }
    }
    out
}

/// A cube (3D, Dirichlet): multiplicities 1, 3, 3, 3, 1, 6, ... Lowest counts ending at every position
/// inside the first clusters; the nearest modes at shifts below, exactly on, just above a cluster
/// and midway between two; bands with both ends exactly on eigenvalues.
#[test]
fn cube_triples_and_sextuples_at_every_shift_and_edge() {
    let case = Case::new(7, 3, false, 1);
    let cl = clusters(&case);
    assert_eq!(
        cl.iter().take(6).map(|c| c.1).collect::<Vec<_>>(),
        [1, 3, 3, 3, 1, 6],
        "the cube's multiplicities"
    );
    for k in 1..=14 {
        let modes = case.check(Which::Lowest(k));
        // the lowest, complete: the first len values of the dense spectrum
        for (v, d) in modes.values.iter().zip(&case.dense) {
            assert!((v - d).abs() <= case.tie);
        }
    }
    for c in 1..6 {
        let (v, mult) = cl[c];
        let (prev, next) = (cl[c - 1].0, cl[c + 1].0);
        for shift in [
            v,                       // on the cluster: K - v M is singular
            v * (1.0 - 1e-12),       // inside its round-off
            v * (1.0 + 1e-6),        // just above
            0.5 * (v + prev) + 1e-3, // between, nearer the lower
            0.5 * (v + next) - 1e-3, // between, nearer the upper
        ] {
            for count in [1, mult, mult + 1] {
                let modes = case.check(Which::Nearest { shift, count });
                // nearest: no eigenvalue outside the result is nearer than one inside
                let far = modes
                    .values
                    .iter()
                    .map(|x| (x - shift).abs())
                    .fold(0.0, f64::max);
                let nearer = case
                    .dense
                    .iter()
                    .filter(|d| (*d - shift).abs() < far - case.tie)
                    .count();
                assert!(nearer <= modes.values.len(), "shift {shift} count {count}");
            }
        }
        // a band whose ends are exactly eigenvalues holds both end clusters
        let modes = case.check(Which::Band { lo: v, hi: next });
        assert_eq!(modes.values.len(), mult + cl[c + 1].1);
    }
}

/// A square (2D, Dirichlet): pairs (the symmetric plate's double modes) at the end of Lowest
/// requests and around shifts.
#[test]
fn square_pairs() {
    let case = Case::new(9, 2, false, 1);
    let cl = clusters(&case);
    assert_eq!(
        cl.iter().take(4).map(|c| c.1).collect::<Vec<_>>(),
        [1, 2, 1, 2]
    );
    for k in 1..=8 {
        let modes = case.check(Which::Lowest(k));
        let pairs_cut = cl
            .iter()
            .scan(0, |acc, c| {
                *acc += c.1;
                Some(*acc)
            })
            .find(|acc| *acc >= k)
            .unwrap();
        assert_eq!(
            modes.values.len(),
            pairs_cut,
            "Lowest({k}) ends on a whole cluster"
        );
    }
    for (v, _) in cl.iter().take(6).skip(1) {
        for count in 1..=3 {
            case.check(Which::Nearest { shift: *v, count });
        }
    }
}

/// Free-free: a three-component field has a triple zero eigenvalue (the rigid-body translations)
/// and every elastic eigenvalue three times. `Lowest(2)` returns the three zeros, said by
/// `requested`; zero-energy modes report the backward error, elastic ones the relative residual; a
/// band from 0 holds the zeros.
#[test]
fn rigid_body_cluster_is_completed_and_reports_the_backward_error() {
    let case = Case::new(4, 3, true, 3);
    let modes = case.check(Which::Lowest(2));
    assert_eq!((modes.requested, modes.values.len()), (2, 3));
    assert!(
        modes
            .residual_kinds
            .iter()
            .all(|k| *k == ResidualKind::Backward)
    );
    assert!(
        modes.residuals.iter().all(|r| *r < 1e-12),
        "{:?}",
        modes.residuals
    );
    let modes = case.check(Which::Lowest(4));
    // the first elastic eigenvalue of the scalar cube is triple, and three components make it 9
    assert_eq!(
        modes.values.len(),
        12,
        "3 zeros and the first elastic cluster"
    );
    assert!(
        modes.residual_kinds[..3]
            .iter()
            .all(|k| *k == ResidualKind::Backward)
    );
    assert!(
        modes.residual_kinds[3..]
            .iter()
            .all(|k| *k == ResidualKind::Relative)
    );
    let first_elastic = clusters(&case)[1].0;
    let modes = case.check(Which::Band {
        lo: 0.0,
        hi: first_elastic,
    });
    assert_eq!(modes.values.len(), 12);
    // the nearest modes to 0 on a free-free pencil: the shift is on the triple zero
    case.check(Which::Nearest {
        shift: 0.0,
        count: 3,
    });
}

/// Requests that cannot be met are errors that say why.
#[test]
fn impossible_requests_say_why() {
    let case = Case::new(4, 2, false, 1);
    let n = case.dense.len();
    let e = eigs(
        &case.k,
        &case.m,
        Which::Lowest(n + 1),
        &EigenOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{} modes requested, but the model has only {n} free degrees of freedom (at most {n} modes): ask for fewer",
            n + 1
        )
    );
    let e = eigs(
        &case.k,
        &case.m,
        Which::Band { lo: 2.0, hi: 1.0 },
        &EigenOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("lower below the upper"), "{e}");
    // all of them: the whole spectrum
    let modes = case.check(Which::Lowest(n));
    assert_eq!(modes.values.len(), n);
}

/// The interrupt hook: asked to stop after the first block, the solve returns `Interrupted` with
/// the vectors solved; a hook that never stops leaves the result as without it; the hook is gone
/// once `with_interrupt` returns.
#[test]
fn a_hook_stops_the_solve_at_a_block_boundary() {
    use femu_sparse::eigen::{EigenOptions, Which, eigs, with_interrupt};
    let (k, m) = pencil(12, 2, false, 1);
    let plain = eigs(&k, &m, Which::Lowest(6), &EigenOptions::default()).unwrap();
    let calls = std::rc::Rc::new(std::cell::Cell::new(0usize));
    let c = calls.clone();
    let e = with_interrupt(
        move |_| {
            c.set(c.get() + 1);
            true
        },
        || eigs(&k, &m, Which::Lowest(6), &EigenOptions::default()),
    )
    .unwrap_err();
    assert!(
        matches!(e, femu_sparse::SparseError::Interrupted { solved_vectors } if solved_vectors > 0),
        "{e}"
    );
    assert_eq!(calls.get(), 1);
    let seen = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let s = seen.clone();
    let hooked = with_interrupt(
        move |n| {
            s.borrow_mut().push(n);
            false
        },
        || eigs(&k, &m, Which::Lowest(6), &EigenOptions::default()),
    )
    .unwrap();
    let same = |a: &[f64], b: &[f64]| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-12 * y.abs().max(1.0))
    };
    assert!(same(&hooked.values, &plain.values));
    assert!(!seen.borrow().is_empty());
    assert!(seen.borrow().windows(2).all(|w| w[0] < w[1]));
    let after = eigs(&k, &m, Which::Lowest(6), &EigenOptions::default()).unwrap();
    assert!(same(&after.values, &plain.values));
}

/// A null-space hint (docs/MATH.md, "Known null vectors") on the free-free cube of three
/// components, whose null space is the three constant fields, one per component (the pencil is
/// block diagonal by component). With those three as the hint, the zero modes are locked before
/// the iteration: the result passes every check of [`Case::check`] against the dense spectrum,
/// with fewer solved vectors than without the hint. A hint that holds one null vector among
/// vectors that are not (a random field, a dependent copy) locks that one and gives the same
/// verified result. A hint of the wrong length or with a NaN is refused.
#[test]
fn a_null_space_hint_locks_the_zero_modes_and_changes_no_result() {
    let case = Case::new(4, 3, true, 3);
    let n = case.k.rows();
    let block = n / 3;
    let constant = |c: usize, j: usize| if j / block == c { 1.0 } else { 0.0 };
    let hinted = |v: faer::Mat<f64>| EigenOptions {
        null_space_hint: Some(NullSpaceHint::new(v)),
        ..EigenOptions::default()
    };
    let exact = hinted(faer::Mat::from_fn(n, 3, |j, c| constant(c, j)));
    for count in [2, 4, 13] {
        let plain = case.check(Which::Lowest(count));
        let with = case.check_with(Which::Lowest(count), &exact);
        assert_eq!(with.values.len(), plain.values.len(), "Lowest({count})");
        assert!(
            with.residual_kinds[..3]
                .iter()
                .all(|k| *k == ResidualKind::Backward)
                && with.residuals[..3].iter().all(|r| *r < 1e-13),
            "Lowest({count}): {:?} {:?}",
            with.residual_kinds,
            with.residuals
        );
        assert!(
            with.stats.solved_vectors < plain.stats.solved_vectors,
            "Lowest({count}): {} solved vectors with the hint, {} without",
            with.stats.solved_vectors,
            plain.stats.solved_vectors
        );
    }
    // one null vector among others: a pseudo-random field and a multiple of the null vector
    let mut rng = femu_testkit::Rng(7);
    let noise: Vec<f64> = (0..n).map(|_| rng.sym()).collect();
    let mixed = hinted(faer::Mat::from_fn(n, 3, |j, c| match c {
        0 => constant(1, j),
        1 => noise[j],
        _ => -2.5 * constant(1, j),
    }));
    for count in [4, 13] {
        case.check_with(Which::Lowest(count), &mixed);
    }
    // bad hints are errors, not wrong results
    for (bad, what) in [
        (faer::Mat::from_fn(n - 1, 1, |_, _| 1.0), "rows"),
        (
            faer::Mat::from_fn(n, 1, |j, _| if j == 5 { f64::NAN } else { 1.0 }),
            "not finite at DOF 5",
        ),
    ] {
        match eigs(&case.k, &case.m, Which::Lowest(4), &hinted(bad)) {
            Err(SparseError::InvalidRequest { reason }) => {
                assert!(reason.contains(what), "{reason}")
            }
            other => panic!("{what}: {other:?}"),
        }
    }
}

/// A spectrum of five distinct eigenvalues, each seven times (`K` diagonal, `M = I`, n = 35): a
/// block Krylov space of 4 random vectors is invariant after 20 columns, so the solved vectors
/// break down (vanish after their projection) and are replaced by random directions in their
/// place in the basis. The copies a run misses are found after the Sturm count (a Krylov method
/// cannot tell how many copies there are); in the end the vectors are M-orthonormal and the
/// values the diagonal's.
#[test]
fn a_krylov_space_that_breaks_down_continues_with_fresh_directions() {
    let levels = [1.0, 2.0, 3.0, 5.0, 8.0];
    let n = 7 * levels.len();
    let mut t = TriMat::new((n, n));
    for i in 0..n {
        // interleaved, so that no copy sits next to another
        t.add_triplet(i, i, levels[i % levels.len()]);
    }
    let k: SparseMatrix = t.to_csc();
    let m = SparseMatrix::eye(n);
    for (want, returned, top) in [(20, 21, 3.0), (30, 35, 8.0)] {
        let modes = eigs(&k, &m, Which::Lowest(want), &EigenOptions::default())
            .unwrap_or_else(|e| panic!("Lowest({want}): {e}"));
        assert!(modes.sturm.verified(), "{:?}", modes.sturm);
        assert_eq!(modes.values.len(), returned, "Lowest({want})");
        let mut expected: Vec<f64> = (0..n).map(|i| levels[i % levels.len()]).collect();
        expected.sort_by(f64::total_cmp);
        for (v, e) in modes.values.iter().zip(&expected) {
            assert!((v - e).abs() < 1e-12, "Lowest({want}): {v} against {e}");
        }
        assert!(
            (modes.values.last().unwrap() - top).abs() < 1e-12,
            "Lowest({want})"
        );
        let x = &modes.vectors;
        let gram = x.transpose() * x;
        for i in 0..returned {
            for j in 0..returned {
                let d = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (gram[(i, j)] - d).abs() < 1e-12,
                    "Lowest({want}): X^T X at ({i}, {j})"
                );
            }
        }
    }
}

/// The chain of `2 masses + 1` unit springs' DOFs between two fixed ends: `K` tridiagonal
/// `(-1, 2, -1)`, `M` diagonal with a unit mass on DOFs 1, 3, 5, ... and none on 0, 2, 4, ...
fn half_massless_chain(masses: usize) -> (SparseMatrix, SparseMatrix) {
    let n = 2 * masses + 1;
    let mut k = TriMat::new((n, n));
    let mut m = TriMat::new((n, n));
    for i in 0..n {
        k.add_triplet(i, i, 2.0);
        if i + 1 < n {
            k.add_triplet(i, i + 1, -1.0);
            k.add_triplet(i + 1, i, -1.0);
        }
        m.add_triplet(i, i, if i % 2 == 1 { 1.0 } else { 0.0 });
    }
    (k.to_csc(), m.to_csc())
}

/// A fixed-fixed chain of unit springs whose every other DOF is massless (a lumped beam's
/// rotations stand in the same place): the massless DOFs condense exactly, leaving a chain of
/// springs of stiffness 1/2 between unit masses, whose eigenvalues are
/// `2 k (1 - cos(j pi / (n + 1)))` with `k = 1/2` (n masses). The solver keeps its basis in the
/// range of the operator (the M inner product is only semi-definite), returns these to 1e-10
/// and proves them by the Sturm count.
#[test]
fn massless_dofs_leave_the_condensed_spectrum() {
    let masses = 150;
    let (k, m) = half_massless_chain(masses);
    let want = 12;
    let modes = eigs(&k, &m, Which::Lowest(want), &EigenOptions::default()).unwrap();
    assert!(modes.sturm.verified(), "{:?}", modes.sturm);
    for (j, got) in modes.values.iter().enumerate() {
        let exact =
            (1.0 - ((j + 1) as f64 * std::f64::consts::PI / (masses + 1) as f64).cos()) * 1.0;
        assert!(
            (got / exact - 1.0).abs() < 1e-10,
            "mode {j}: {got} against {exact}"
        );
    }
}

/// The same chain with few masses, asked for up to every finite eigenvalue: the request is
/// measured against the DOFs with mass (six here, among 13 DOFs), not the matrix's order, so
/// that asking five or six of six converges and asking seven is refused as too many.
#[test]
fn massless_dofs_with_requests_near_the_finite_count() {
    let masses = 6;
    let n = 2 * masses + 1;
    let (k, m) = half_massless_chain(masses);
    for want in [3, 4, 5, 6] {
        let modes = eigs(&k, &m, Which::Lowest(want), &EigenOptions::default()).unwrap();
        assert!(modes.sturm.verified(), "{want}: {:?}", modes.sturm);
        assert_eq!(modes.vectors.nrows(), n);
        for (j, got) in modes.values.iter().enumerate() {
            let exact = 1.0 - ((j + 1) as f64 * std::f64::consts::PI / (masses + 1) as f64).cos();
            assert!(
                (got / exact - 1.0).abs() < 1e-10,
                "{want}: mode {j}: {got} against {exact}"
            );
        }
    }
    let e = eigs(&k, &m, Which::Lowest(7), &EigenOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            SparseError::TooManyModes {
                requested: 7,
                dim: 6
            }
        ),
        "{e}"
    );
}

/// [`EigenOptions::keep_factor`]: a band reaching below zero counts its lower end after the
/// iteration and keeps that factor; a lowest-mode solve keeps its own. On the free cube (zero
/// triples at the bottom) and on the same pencil shifted by `-c M` (`K - c M`: eigenvalues below
/// the band's lower end, which the deferred count must subtract) every result passes the cluster
/// checks against the dense spectrum, equals the solve without the option, and the kept factor's
/// inertia is the dense count below its shift.
#[test]
fn a_kept_factor_changes_no_result() {
    let mut case = Case::new(4, 3, true, 3);
    let keep = EigenOptions {
        keep_factor: true,
        ..EigenOptions::default()
    };
    let first_elastic = case.dense.iter().copied().find(|v| *v > case.tie).unwrap();
    for shift in [0.0, 1.5 * first_elastic] {
        if shift > 0.0 {
            // K - c M on K's pattern (M's pattern is K's here), and its spectrum moved by -c
            let (k, m) = (to_dense(&case.k), to_dense(&case.m));
            let shifted: Vec<Vec<f64>> = (0..k.nrows())
                .map(|i| {
                    (0..k.ncols())
                        .map(|j| k[(i, j)] - shift * m[(i, j)])
                        .collect()
                })
                .collect();
            let mm: Vec<Vec<f64>> = (0..m.nrows())
                .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
                .collect();
            case.k = sparse(&shifted, &mm);
            case.dense = generalized_symmetric_eigenvalues(
                to_dense(&case.k).as_ref(),
                to_dense(&case.m).as_ref(),
            )
            .unwrap();
        }
        let top = 4.0 * first_elastic;
        for which in [
            Which::Band {
                lo: -1e-6 * top,
                hi: top,
            },
            Which::Lowest(7),
        ] {
            if shift > 0.0 && matches!(which, Which::Lowest(_)) {
                // an indefinite K has no lowest-mode shift below its spectrum: refused either way
                continue;
            }
            let plain = case.check(which);
            let kept = case.check_with(which, &keep);
            assert_eq!(
                kept.values.len(),
                plain.values.len(),
                "{which:?}, shift {shift}"
            );
            for (a, b) in kept.values.iter().zip(&plain.values) {
                assert!(
                    (a - b).abs() <= case.tie,
                    "{which:?}, shift {shift}: {a} {b}"
                );
            }
            assert!(plain.factor.is_none());
            let f = kept.factor.as_ref().expect("kept");
            assert!(kept.values.iter().all(|v| *v > f.sigma), "{which:?}");
            assert_eq!(
                f.ldlt.inertia().negative,
                case.count(None, f.sigma),
                "{which:?}, shift {shift}: inertia at {}",
                f.sigma
            );
            if shift > 0.0 {
                assert!(f.ldlt.inertia().negative > 0, "eigenvalues below the band");
            }
        }
    }
}
