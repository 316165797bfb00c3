//! Evidence for the sparse core: factorizations and inertia against dense references, the
//! eigensolver against the dense generalized eigensolver and an analytic spectrum.

use faer::Mat;
use faer::linalg::solvers::Solve;
use femu_sparse::cholesky::{Factorization, SymbolicFactor};
use femu_sparse::csc::to_dense;
use femu_sparse::dense::{generalized_symmetric_eigen, generalized_symmetric_eigenvalues};
use femu_sparse::eigen::{EigenOptions, MAX_BLOCK, Pencil, Which, eigs};
use femu_sparse::ordering::Ordering;
use femu_sparse::{SparseError, SparseMatrix};
use proptest::prelude::*;
use sprs::TriMat;

use femu_testkit::Rng;

/// A random sparse SPD pencil: `K` diagonally dominant on a random pattern, `M` SPD on a
/// sub-pattern of `K`'s (as FE matrices: M's pattern inside K's).
fn random_pencil(n: usize, density: f64, seed: u64) -> (SparseMatrix, SparseMatrix) {
    let mut rng = Rng(seed);
    let (mut kt, mut mt) = (TriMat::new((n, n)), TriMat::new((n, n)));
    let (mut kd, mut md) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        for j in 0..i {
            if rng.next_f64() < density {
                let v = rng.next_f64() - 0.5;
                kt.add_triplet(i, j, v);
                kt.add_triplet(j, i, v);
                kd[i] += v.abs();
                kd[j] += v.abs();
                if rng.next_f64() < 0.5 {
                    let w = 0.2 * (rng.next_f64() - 0.5);
                    mt.add_triplet(i, j, w);
                    mt.add_triplet(j, i, w);
                    md[i] += w.abs();
                    md[j] += w.abs();
                }
            }
        }
    }
    for i in 0..n {
        kt.add_triplet(i, i, kd[i] + 0.1 + 10.0 * rng.next_f64());
        mt.add_triplet(i, i, md[i] + 0.5 + rng.next_f64());
    }
    (kt.to_csc(), mt.to_csc())
}

use femu_testkit::laplacian_3d;

/// The lowest `count` eigenvalues of [`laplacian_3d`].
fn laplacian_spectrum(nn: usize, count: usize) -> Vec<f64> {
    let mut v = femu_testkit::laplacian_3d_spectrum(nn);
    v.truncate(count);
    v
}

#[test]
fn llt_and_ldlt_solve_like_dense_with_every_ordering() {
    let (k, m) = random_pencil(120, 0.05, 1);
    let b: Vec<f64> = (0..120).map(|i| (i as f64).sin()).collect();
    let kd = to_dense(&k);
    // dense reference solution
    let x_ref = kd
        .llt(faer::Side::Lower)
        .unwrap()
        .solve(Mat::from_fn(120, 1, |i, _| b[i]));
    for ordering in [
        Ordering::NestedDissection,
        Ordering::Amd,
        Ordering::Identity,
    ] {
        let sym = SymbolicFactor::new(&k, ordering).unwrap();
        let llt = sym.llt(&k, "K").unwrap();
        let mut x = b.clone();
        llt.solve(&mut x);
        let err = (0..120)
            .map(|i| (x[i] - x_ref[(i, 0)]).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{ordering:?}: {err}");
        // Shifted LDLT on the same symbolic analysis: K - 0.7 M is indefinite here or not; its
        // inertia equals the dense count of eigenvalues below 0.7.
        let mut a = k.clone();
        for (v, (r, c)) in m.iter() {
            *a.get_mut(r, c).unwrap() -= 0.7 * v;
        }
        let ldlt = sym.ldlt(&a, "K - sigma M").unwrap();
        let dense = generalized_symmetric_eigenvalues(to_dense(&k).as_ref(), to_dense(&m).as_ref())
            .unwrap();
        assert_eq!(
            ldlt.inertia().negative,
            dense.iter().filter(|l| **l < 0.7).count()
        );
        let mut y = b.clone();
        ldlt.solve(&mut y);
        let mut ay = vec![0.0; 120];
        femu_sparse::csc::mul_vec(&a, &y, &mut ay).unwrap();
        let res = ay
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(res < 1e-10, "{ordering:?}: LDLT residual {res}");
    }
}

#[test]
fn nested_dissection_reduces_fill_on_a_3d_grid() {
    let a = laplacian_3d(12);
    let nd = SymbolicFactor::new(&a, Ordering::NestedDissection)
        .unwrap()
        .factor_len();
    let amd = SymbolicFactor::new(&a, Ordering::Amd).unwrap().factor_len();
    let id = SymbolicFactor::new(&a, Ordering::Identity)
        .unwrap()
        .factor_len();
    assert!(nd < id / 2, "ND fill {nd} vs natural {id}");
    assert!((nd as f64) < 1.5 * amd as f64, "ND fill {nd} vs AMD {amd}");
}

#[test]
fn indefinite_and_bad_input_are_errors_with_the_place() {
    let (k, _) = random_pencil(30, 0.1, 2);
    let mut neg = k.clone();
    *neg.get_mut(17, 17).unwrap() = -100.0;
    let sym = SymbolicFactor::new(&neg, Ordering::Identity).unwrap();
    assert!(!sym.is_supernodal());
    let got = sym.llt(&neg, "K");
    assert!(
        matches!(
            got,
            Err(SparseError::NotPositiveDefinite {
                matrix: "K",
                index: 17
            })
        ),
        "{got:?}"
    );
    // The supernodal path (a 3D grid) names the same original index, through the ordering.
    let mut lap = laplacian_3d(12);
    *lap.get_mut(700, 700).unwrap() = -50.0;
    for ordering in [
        Ordering::NestedDissection,
        Ordering::Amd,
        Ordering::Identity,
    ] {
        let sym = SymbolicFactor::new(&lap, ordering).unwrap();
        let got = sym.llt(&lap, "K");
        // Every pivot eliminated before node 700 belongs to a positive definite principal
        // submatrix, so the first failure is node 700 whatever the ordering.
        assert!(
            matches!(
                got,
                Err(SparseError::NotPositiveDefinite { index: 700, .. })
            ),
            "{ordering:?}: {got:?}"
        );
        if ordering == Ordering::NestedDissection {
            assert!(sym.is_supernodal());
        }
    }
    let sym = SymbolicFactor::new(&k, Ordering::NestedDissection).unwrap();
    let mut other = TriMat::new((30, 30));
    other.add_triplet(0, 0, 1.0);
    assert!(sym.llt(&other.to_csc(), "K").is_err());
    let mut t = TriMat::new((2, 2));
    t.add_triplet(0, 1, 1.0);
    t.add_triplet(0, 0, 1.0);
    t.add_triplet(1, 1, 1.0);
    let asym: SparseMatrix = t.to_csc();
    assert!(matches!(
        eigs(
            &asym,
            &SparseMatrix::eye(2),
            Which::Lowest(1),
            &EigenOptions::default()
        ),
        Err(SparseError::NotSymmetric { .. })
    ));
}

/// Random sparse pencils with a consistent (non-diagonal) M: eigenvalues to 1e-10 relative
/// against the dense generalized eigensolver, residuals below 1e-8, M-orthonormal vectors, and
/// the Sturm check verified.
#[test]
fn eigensolver_matches_dense_on_random_pencils() {
    for seed in 0..4 {
        let n = 160;
        let (k, m) = random_pencil(n, 0.04, 10 + seed);
        let dense =
            generalized_symmetric_eigen(to_dense(&k).as_ref(), to_dense(&m).as_ref()).unwrap();
        for which in [
            Which::Lowest(12),
            Which::Nearest {
                shift: dense.values[40] * 1.0001,
                count: 7,
            },
        ] {
            let modes = eigs(&k, &m, which, &EigenOptions::default()).unwrap();
            assert!(modes.sturm.verified(), "{which:?}: {:?}", modes.sturm);
            let first = match which {
                Which::Lowest(_) => 0,
                _ => {
                    let mut idx: Vec<usize> = (0..n).collect();
                    idx.sort_by(|a, b| {
                        (dense.values[*a] - dense.values[40])
                            .abs()
                            .total_cmp(&(dense.values[*b] - dense.values[40]).abs())
                    });
                    *idx[..7].iter().min().unwrap()
                }
            };
            for (j, l) in modes.values.iter().enumerate() {
                let d = dense.values[first + j];
                assert!(
                    (l / d - 1.0).abs() < 1e-10,
                    "seed {seed} {which:?} mode {j}: {l} vs {d}"
                );
                assert!(modes.residuals[j] < 1e-8, "residual {}", modes.residuals[j]);
            }
            let x = &modes.vectors;
            let g = x.transpose() * to_dense(&m) * x;
            for i in 0..g.nrows() {
                for j in 0..g.ncols() {
                    assert!((g[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-10);
                }
            }
        }
    }
}

/// Settings no solve can run with are refused, each by name, before any work: a block size of 0
/// or above `MAX_BLOCK` (a block of 100,000 asked the allocator for 152 GB on a 47,628-DOF
/// plate), and a tolerance that is not a relative residual in `(0, 1)`.
#[test]
fn impossible_eigensolver_settings_are_refused() {
    let a = laplacian_3d(4);
    let m = SparseMatrix::eye(64);
    let cases = [
        (0, 1e-10, "block size 0"),
        (MAX_BLOCK + 1, 1e-10, "block size 65"),
        (100_000, 1e-10, "block size 100000"),
        (4, 0.0, "tolerance 0"),
        (4, -1e-8, "tolerance -0.00000001"),
        (4, 1.0, "tolerance 1"),
        (4, f64::NAN, "tolerance NaN"),
        (4, f64::INFINITY, "tolerance inf"),
    ];
    for (block_size, tol, what) in cases {
        let params = EigenOptions {
            block_size,
            tol,
            ..EigenOptions::default()
        };
        match eigs(&a, &m, Which::Lowest(3), &params) {
            Err(e @ SparseError::InvalidRequest { .. }) => {
                let text = e.to_string();
                assert!(text.contains(what), "{what}: {text}");
            }
            other => panic!("{what}: expected InvalidRequest, got {other:?}"),
        }
    }
}

/// The 3D Laplacian (M = I) has highly repeated eigenvalues (the cube's symmetry: multiplicities
/// 1, 3, 3, 3, 6, ...). All copies among the lowest 20 are found, to 1e-10 of the analytic values.
#[test]
fn repeated_eigenvalues_of_the_3d_laplacian_are_all_found() {
    let nn = 9;
    let a = laplacian_3d(nn);
    let m = SparseMatrix::eye(nn * nn * nn);
    // 1, the default 4, and the widest allowed (`MAX_BLOCK`, wider than the basis a run for 20
    // pairs would otherwise hold)
    for block_size in [1, 4, MAX_BLOCK] {
        let params = EigenOptions {
            block_size,
            ..EigenOptions::default()
        };
        let modes = eigs(&a, &m, Which::Lowest(20), &params).unwrap();
        let exact = laplacian_spectrum(nn, modes.values.len());
        assert!(modes.values.len() >= 20);
        for (j, (l, e)) in modes.values.iter().zip(&exact).enumerate() {
            assert!(
                (l / e - 1.0).abs() < 1e-10,
                "block {block_size}, mode {j}: {l} vs {e}"
            );
        }
        assert!(modes.sturm.verified());
    }
    // Every eigenvalue in a band.
    let (lo, hi) = (0.5, 0.9);
    let modes = eigs(&a, &m, Which::Band { lo, hi }, &EigenOptions::default()).unwrap();
    let exact: Vec<f64> = laplacian_spectrum(nn, nn * nn * nn)
        .into_iter()
        .filter(|l| *l >= lo && *l <= hi)
        .collect();
    assert_eq!(modes.values.len(), exact.len());
    for (l, e) in modes.values.iter().zip(&exact) {
        assert!((l / e - 1.0).abs() < 1e-10);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// The Sturm count at a random shift equals the number of dense eigenvalues below it.
    #[test]
    fn sturm_count_equals_dense_count(seed in 0u64..10_000, frac in 0.0f64..1.0) {
        let (k, m) = random_pencil(60, 0.08, seed);
        let dense = generalized_symmetric_eigenvalues(to_dense(&k).as_ref(), to_dense(&m).as_ref()).unwrap();
        let shift = dense[0] * 0.5 + frac * (dense[59] * 1.1 - dense[0] * 0.5);
        // keep away from an eigenvalue (the count is ambiguous exactly on one)
        prop_assume!(dense.iter().all(|l| (l - shift).abs() > 1e-9 * l.abs()));
        let pencil = Pencil::new(&k, &m, Ordering::NestedDissection).unwrap();
        prop_assert_eq!(pencil.count_below(shift).unwrap(), dense.iter().filter(|l| **l < shift).count());
    }
}

/// Solves of several right-hand sides at once (split over the threads in column chunks, odd
/// counts included) give, column by column, the dense solution.
#[test]
fn multi_column_solves_match_dense_column_by_column() {
    let (k, m) = random_pencil(150, 0.04, 7);
    let sym = SymbolicFactor::new(&k, Ordering::NestedDissection).unwrap();
    let llt = sym.llt(&k, "K").unwrap();
    let mut a = k.clone();
    for (v, (r, c)) in m.iter() {
        *a.get_mut(r, c).unwrap() -= 0.9 * v;
    }
    let ldlt = sym.ldlt(&a, "K - sigma M").unwrap();
    let (kd, ad) = (to_dense(&k), to_dense(&a));
    for cols in 1..=7 {
        let b = Mat::<f64>::from_fn(150, cols, |i, j| ((i * (j + 2)) as f64 * 0.37).sin());
        let k_ref = kd.llt(faer::Side::Lower).unwrap().solve(&b);
        let a_ref = ad.lblt(faer::Side::Lower).solve(&b);
        for (f, reference, name) in [
            (&llt as &dyn Factorization, &k_ref, "LL^T"),
            (&ldlt as &dyn Factorization, &a_ref, "LDL^T"),
        ] {
            let mut x = b.clone();
            f.solve_in_place(x.as_mut());
            let err = (0..150)
                .flat_map(|i| (0..cols).map(move |j| (i, j)))
                .map(|(i, j)| (x[(i, j)] - reference[(i, j)]).abs())
                .fold(0.0, f64::max);
            let scale = reference.norm_max();
            assert!(err < 1e-11 * scale, "{name}, {cols} columns: {err:e}");
        }
    }
}

/// The flop count of the symbolic analysis against the hand count `sum_j (b_j^2 + 2 b_j)`: a dense
/// matrix of order `n` (column `j` has `n - 1 - j` entries below the diagonal), and a block
/// diagonal matrix of two dense blocks (the sum of the two).
#[test]
fn flop_count_matches_the_hand_count() {
    let dense = |n: usize| -> f64 {
        (0..n)
            .map(|j| {
                let b = (n - 1 - j) as f64;
                b * b + 2.0 * b
            })
            .sum()
    };
    let dense_matrix = |sizes: &[usize]| -> SparseMatrix {
        let n: usize = sizes.iter().sum();
        let mut t = TriMat::new((n, n));
        let mut start = 0;
        for &s in sizes {
            for i in 0..s {
                for j in 0..s {
                    let v = if i == j { 2.0 * s as f64 } else { 1.0 };
                    t.add_triplet(start + i, start + j, v);
                }
            }
            start += s;
        }
        t.to_csc()
    };
    // n = 60: (59 * 60 * 119) / 6 + 59 * 60 = 70,210 + 3,540
    assert_eq!(dense(60), 73_750.0);
    let sym = SymbolicFactor::new(&dense_matrix(&[60]), Ordering::Identity).unwrap();
    assert_eq!(sym.flops(), 73_750.0);
    let sym = SymbolicFactor::new(&dense_matrix(&[30, 45]), Ordering::Identity).unwrap();
    assert_eq!(sym.flops(), dense(30) + dense(45));
}

/// The nested-dissection ordering is a function of the graph alone, also when orderings are
/// computed on several threads at once. METIS's random numbers come from one process-wide
/// generator; before the calls were serialised, concurrent orderings of the same graph differed
/// (a sensor-space expansion near a model eigenvalue then fell back or not from run to run).
#[test]
fn nested_dissection_is_the_same_on_concurrent_threads() {
    let a = laplacian_3d(10);
    let reference = femu_sparse::ordering::fill_reducing_ordering(&a, Ordering::NestedDissection)
        .unwrap()
        .unwrap();
    std::thread::scope(|s| {
        let runs: Vec<_> = (0..4)
            .map(|_| {
                s.spawn(|| {
                    (0..25)
                        .map(|_| {
                            femu_sparse::ordering::fill_reducing_ordering(
                                &a,
                                Ordering::NestedDissection,
                            )
                            .unwrap()
                            .unwrap()
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for run in runs {
            for (fwd, inv) in run.join().unwrap() {
                assert!(fwd == reference.0 && inv == reference.1);
            }
        }
    });
}

/// `K - sigma I` of the 3D Laplacian on the shared analysis, by the subtree-parallel
/// multifrontal `LDL^T` (the default) and by faer's left-looking one: the same solutions to
/// round-off, the inertia both report equal to the analytic count of eigenvalues below `sigma`,
/// on one, two and three threads, and again after the first factor was dropped (its values are
/// reused: a leftover of the old factor would change the solution). On one thread the solve is
/// faer's supernodal one, on more (for the 30^3 grid, whose factor is large enough) femu's
/// subtree-parallel one: both against faer's solve with faer's factor. The eigensolver's
/// factorization of `K - sigma M` (`Pencil`, `M = I`), which reads `K` and `M` in place instead of
/// their sum, gives the same inertia, count and solutions.
#[test]
fn subtree_parallel_ldlt_agrees_with_left_looking_and_the_analytic_inertia() {
    for (nn, sigma) in [(14, 0.0), (14, 1.3), (30, -0.5), (30, 0.4)] {
        let a = laplacian_3d(nn);
        let n = a.rows();
        let sym = SymbolicFactor::new(&a, Ordering::NestedDissection).unwrap();
        assert!(
            sym.is_supernodal(),
            "{nn}: the multifrontal path is the supernodal one"
        );
        let mut values = a.data().to_vec();
        for (v, (r, c)) in values.iter_mut().zip(a.iter().map(|(_, rc)| rc)) {
            if r == c {
                *v -= sigma;
            }
        }
        let spectrum = laplacian_spectrum(nn, n);
        let below = spectrum.iter().filter(|l| **l < sigma).count();
        // the condition number of A - sigma I, from its analytic spectrum
        let kappa = spectrum
            .iter()
            .fold(0.0_f64, |m, l| m.max((l - sigma).abs()))
            / spectrum
                .iter()
                .fold(f64::INFINITY, |m, l| m.min((l - sigma).abs()));
        // three right-hand sides: the solves on several threads take them all at once
        let b: Vec<f64> = (0..3 * n).map(|i| ((i * 37) % 101) as f64 - 50.0).collect();
        let solve = |f: &dyn Factorization| {
            let mut x = b.clone();
            f.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 3));
            x
        };
        // and ten, more than the solve's own kernels take (faer's GEMM and triangular solves
        // then do each supernode's work)
        let b10: Vec<f64> = (0..10 * n).map(|i| ((i * 53) % 97) as f64 - 48.0).collect();
        let solve10 = |f: &dyn Factorization| {
            let mut x = b10.clone();
            f.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 10));
            x
        };
        let reference = sym.ldlt_left_looking(&a, &values, "A").unwrap();
        assert_eq!(reference.inertia().negative, below, "{nn}, {sigma}: faer");
        // faer's own supernodal solve (one thread; on more, femu's subtree-parallel solve)
        let x_ref = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| solve(&reference));
        let x10_ref = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| solve10(&reference));
        let scale = x_ref.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let scale10 = x10_ref.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let largest_difference = |x: &[f64]| {
            x.iter()
                .zip(&x_ref)
                .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()))
        };
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            // faer's factor solved on these threads (the subtree-parallel solve reads its layout)
            let of_faer = pool.install(|| solve(&reference));
            let (first, second, count, x10) = pool.install(|| {
                let f = sym.ldlt_values(&a, &values, "A").unwrap();
                let (inertia, x, x10) = (f.inertia(), solve(&f), solve10(&f));
                drop(f);
                let g = sym.ldlt_values(&a, &values, "A").unwrap();
                let count = sym.inertia_values(&a, &values, "A").unwrap();
                ((inertia, x), (g.inertia(), solve(&g)), count, x10)
            });
            let diff10 = x10
                .iter()
                .zip(&x10_ref)
                .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
            assert!(
                diff10 < 100.0 * f64::EPSILON * kappa * scale10,
                "{nn}, {sigma}, {threads}: ten right-hand sides {diff10:e}"
            );
            assert_eq!(
                first.0,
                reference.inertia(),
                "{nn}, {sigma}, {threads} threads"
            );
            assert_eq!(second.0, first.0);
            assert_eq!(count, first.0, "{nn}, {sigma}: inertia without the factor");
            let diff = largest_difference(&first.1);
            // two backward-stable solves differ by their round-off times the condition number
            // (measured up to 12 eps kappa of the solution's size)
            assert!(
                diff < 100.0 * f64::EPSILON * kappa * scale,
                "{nn}, {sigma}, {threads}: {diff:e} (kappa {kappa:e})"
            );
            let diff_faer = largest_difference(&of_faer);
            assert!(
                diff_faer < 100.0 * f64::EPSILON * kappa * scale,
                "{nn}, {sigma}, {threads}: faer's factor {diff_faer:e}"
            );
            assert!(
                first.1 == second.1,
                "{nn}, {sigma}, {threads}: reused values"
            );
            // the eigensolver's factors of K - sigma M, read from K and M where they are (here
            // M = I, whose pattern is only the diagonal of K's)
            let (shifted, shifted_count) = pool.install(|| {
                let m = SparseMatrix::eye(n);
                let pencil = Pencil::new(&a, &m, Ordering::NestedDissection).unwrap();
                let f = pencil.factor_shifted(sigma).unwrap();
                ((f.inertia(), solve(&f)), pencil.count_below(sigma).unwrap())
            });
            assert_eq!(shifted.0, reference.inertia(), "{nn}, {sigma}: K - sigma M");
            assert_eq!(
                shifted_count, below,
                "{nn}, {sigma}: the count of K - sigma M"
            );
            let diff = largest_difference(&shifted.1);
            assert!(
                diff < 100.0 * f64::EPSILON * kappa * scale,
                "{nn}, {sigma}, {threads}: K - sigma M {diff:e} (kappa {kappa:e})"
            );
        }
    }
}

/// An exactly zero pivot (a zeroed row and column) is reported with its original index by both
/// factorizations and by the inertia-only count.
#[test]
fn zero_pivot_is_reported_at_its_dof_by_both_factorizations() {
    let a = laplacian_3d(14);
    let sym = SymbolicFactor::new(&a, Ordering::NestedDissection).unwrap();
    for dof in [0, 1234, a.rows() - 1] {
        let values: Vec<f64> = a
            .iter()
            .map(|(v, (r, c))| if r == dof || c == dof { 0.0 } else { *v })
            .collect();
        let index = |e: SparseError| match e {
            SparseError::Singular { index, .. } => index,
            other => panic!("{other}"),
        };
        assert_eq!(index(sym.ldlt_values(&a, &values, "A").unwrap_err()), dof);
        assert_eq!(
            index(sym.ldlt_left_looking(&a, &values, "A").unwrap_err()),
            dof
        );
        assert_eq!(
            index(sym.inertia_values(&a, &values, "A").unwrap_err()),
            dof
        );
    }
}

/// The symmetry defect `max |a_ij - a_ji| / max |a_ij|` and its place, against the dense matrix
/// entry by entry: on random patterns with perturbed values and with entries whose mirror is not
/// stored, in CSC and CSR storage, and 0 on a symmetric matrix.
#[test]
fn symmetry_defect_matches_the_dense_entrywise_maximum() {
    for seed in 1..6 {
        let (k, _) = random_pencil(3000, 0.002, seed);
        assert_eq!(femu_sparse::csc::symmetry_defect(&k).0, 0.0);
        let mut rng = Rng(seed + 100);
        let mut t = TriMat::new((3000, 3000));
        for (v, (r, c)) in k.iter() {
            let bump = if rng.next_f64() < 0.01 {
                1e-3 * rng.next_f64()
            } else {
                0.0
            };
            t.add_triplet(r, c, v + bump);
        }
        // entries whose mirror is missing
        for _ in 0..5 {
            let (r, c) = (
                (rng.next_f64() * 3000.0) as usize,
                (rng.next_f64() * 3000.0) as usize,
            );
            if r != c && k.get(r, c).is_none() {
                t.add_triplet(r, c, 0.3 * rng.next_f64());
            }
        }
        for a in [t.to_csc(), t.to_csr()] {
            let d = to_dense(&a);
            let scale = a.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let mut worst = (0.0, 0, 0);
            for r in 0..3000 {
                for c in 0..3000 {
                    let e = (d[(r, c)] - d[(c, r)]).abs() / scale;
                    if e > worst.0 {
                        worst = (e, r, c);
                    }
                }
            }
            let (defect, r, c) = femu_sparse::csc::symmetry_defect(&a);
            assert_eq!(defect, worst.0, "seed {seed}");
            // the place: the entry or its mirror (both have the same defect)
            assert!((r, c) == (worst.1, worst.2) || (c, r) == (worst.1, worst.2));
        }
    }
}

/// The eigensolver reads `K` and `M` in place, so `M`'s pattern must lie inside `K`'s: an entry
/// of `M` that `K` does not store is an error naming its column and row, not a wrong factor; a
/// diagonal `M` (inside) is accepted, and its shifted values are `K`'s with `sigma` off the
/// diagonal's entries, as written out here.
#[test]
fn mass_entries_outside_the_stiffness_pattern_are_refused() {
    let k = laplacian_3d(4);
    let n = k.rows();
    let mut t = TriMat::new((n, n));
    for i in 0..n {
        t.add_triplet(i, i, 1.0);
    }
    // (0, n - 1): the grid's first and last nodes are not neighbours
    t.add_triplet(0, n - 1, 0.1);
    t.add_triplet(n - 1, 0, 0.1);
    let m: SparseMatrix = t.to_csc();
    match Pencil::new(&k, &m, Ordering::NestedDissection) {
        Err(SparseError::DimensionMismatch { expected, got, .. }) => {
            assert_eq!((expected, got), (0, n - 1))
        }
        other => panic!("{other:?}"),
    }
    let eye = SparseMatrix::eye(n);
    let pencil = Pencil::new(&k, &eye, Ordering::NestedDissection).unwrap();
    let shifted = pencil.shifted_values(2.5);
    for ((v, (r, c)), s) in k.iter().zip(&shifted) {
        let expected = if r == c { v - 2.5 } else { *v };
        assert_eq!(*s, expected, "({r}, {c})");
    }
}

/// `a` without the entries `(r, c)` listed (their values dropped).
fn without(a: &SparseMatrix, drop: &[(usize, usize)]) -> SparseMatrix {
    let mut t = TriMat::new((a.rows(), a.cols()));
    for (v, (r, c)) in a.iter() {
        if !drop.contains(&(r, c)) {
            t.add_triplet(r, c, *v);
        }
    }
    t.to_csc()
}

/// A pattern given by its arrays is checked as sprs checks a matrix: each broken rule is an
/// error naming what and which column, never a panic inside METIS or faer; a valid one is the
/// matrix's own pattern (same fingerprint).
#[test]
fn a_pattern_from_its_arrays_is_checked() {
    use femu_sparse::ordering::Pattern;
    let a = laplacian_3d(3);
    let n = a.rows();
    let ptr = a.indptr().into_raw_storage().to_vec();
    let idx = a.indices().to_vec();
    let p = Pattern::new(n, &ptr, &idx).unwrap();
    assert_eq!(p.fingerprint(), Pattern::of(&a).unwrap().fingerprint());
    assert_eq!((p.dim(), p.nnz()), (n, a.nnz()));
    // the 7-point stencil has (7 n - 6 * 3 * 3) entries in all (boundary faces lack neighbours),
    // the diagonal and half of the rest on and below it
    assert_eq!(p.lower_nnz(), n + (a.nnz() - n) / 2);
    let message = |r: Result<Pattern<'_>, SparseError>| match r {
        Err(SparseError::InvalidPattern { reason }) => reason,
        other => panic!("{other:?}"),
    };
    assert!(message(Pattern::new(n + 1, &ptr, &idx)).contains("column pointers for"));
    let mut shifted = ptr.clone();
    shifted[0] = 1;
    assert!(message(Pattern::new(n, &shifted, &idx)).contains("run from 1"));
    let mut back = ptr.clone();
    back[6] = back[5] - 1;
    assert!(message(Pattern::new(n, &back, &idx)).contains("column 5 ends before it starts"));
    // a pointer beyond the rows in the middle (the last one is right)
    let mut far = ptr.clone();
    far[3] = idx.len() + 40;
    assert!(message(Pattern::new(n, &far, &idx)).contains("column 2 ends at"));
    let mut beyond = idx.clone();
    beyond[ptr[4]] = n + 3;
    let m = message(Pattern::new(n, &ptr, &beyond));
    assert!(
        m.contains("column 4 has row") && m.contains(&format!("{}", n + 3)),
        "{m}"
    );
    let mut twice = idx.clone();
    twice[ptr[9] + 1] = twice[ptr[9]];
    assert!(message(Pattern::new(n, &ptr, &twice)).contains("column 9: rows"));
}

/// Nested dissection needs a symmetric graph. A pattern with an upper entry whose mirror is
/// missing is ordered as its symmetric closure: the same permutation as the full symmetric
/// pattern's, where no edge had to be added. And a pencil with such a `K` is refused by its
/// checks (which run beside the analysis), not by a crash in the ordering.
#[test]
fn an_asymmetric_pattern_is_ordered_as_its_symmetric_closure() {
    use femu_sparse::ordering::fill_reducing_ordering;
    let full = laplacian_3d(6);
    // grid neighbours (0, 1) and (7, 13): drop the entry above the diagonal of each pair
    let half = without(&full, &[(0, 1), (7, 13)]);
    assert_eq!(half.nnz(), full.nnz() - 2);
    let reference = fill_reducing_ordering(&full, Ordering::NestedDissection)
        .unwrap()
        .unwrap();
    let closed = fill_reducing_ordering(&half, Ordering::NestedDissection)
        .unwrap()
        .unwrap();
    assert!(closed == reference);
    let eye = SparseMatrix::eye(full.rows());
    match Pencil::new(&half, &eye, Ordering::NestedDissection) {
        Err(SparseError::NotSymmetric { matrix: "K", .. }) => {}
        other => panic!("{other:?}"),
    }
}

/// An analysis knows the pattern it was made for: new values on it are its matrix, a pattern of
/// the same size and number of entries with one entry moved is not.
#[test]
fn an_analysis_knows_its_pattern() {
    let a = laplacian_3d(5);
    let sym = SymbolicFactor::new(&a, Ordering::NestedDissection).unwrap();
    assert!(sym.is_for(&a));
    let scaled = a.map(|v| 3.0 * v + 1.0);
    assert!(sym.is_for(&scaled));
    // move the pair (0, 1) to (0, 2): same dimension and entry count, another pattern
    let mut moved = TriMat::new((a.rows(), a.cols()));
    for (v, (r, c)) in without(&a, &[(0, 1), (1, 0)]).iter() {
        moved.add_triplet(r, c, *v);
    }
    moved.add_triplet(0, 2, -1.0);
    moved.add_triplet(2, 0, -1.0);
    let moved: SparseMatrix = moved.to_csc();
    assert_eq!(moved.nnz(), a.nnz());
    assert!(!sym.is_for(&moved));
    assert!(!sym.is_for(&laplacian_3d(4)));
    assert!(sym.seconds() > 0.0);
    // a detached copy is the same analysis
    let copy = sym.detached();
    assert!(copy.is_for(&a));
    assert_eq!(copy.factor_len(), sym.factor_len());
}

/// Checks made ahead of a solve (`PencilChecks`, made beside an assembly's analysis) serve only
/// the matrices they were made on. On them the pencil has the norms the pencil's own checks find
/// (the hand sums of absolute column values), and its modes are the dense ones; on matrices
/// changed after the checks (one value made asymmetric, one made NaN, one bit of one value
/// flipped, all values scaled), the fingerprint differs and the pencil is checked again: the
/// errors with their place, the new norms. The fingerprint is the same on one and three threads.
#[test]
fn checks_made_ahead_serve_only_their_matrices() {
    use femu_sparse::eigen::PencilChecks;
    let (k, m) = random_pencil(120, 0.05, 77);
    let hand_norm = |a: &SparseMatrix| -> f64 {
        let d = to_dense(a);
        (0..d.ncols())
            .map(|j| (0..d.nrows()).map(|i| d[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let checks = PencilChecks::of(&k, &m).unwrap();
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| PencilChecks::of(&k, &m).unwrap())
    };
    assert_eq!(on(1), checks);
    assert_eq!(on(3), checks);
    let symbolic = || SymbolicFactor::new(&k, Ordering::NestedDissection).unwrap();
    let pencil = Pencil::with_checks(&k, &m, symbolic(), &checks).unwrap();
    let (kn, mn) = pencil.norms();
    assert!((kn - hand_norm(&k)).abs() <= 1e-12 * kn && (mn - hand_norm(&m)).abs() <= 1e-12 * mn);
    let modes = pencil
        .solve(Which::Lowest(6), &EigenOptions::default())
        .unwrap();
    let dense = generalized_symmetric_eigen(to_dense(&k).as_ref(), to_dense(&m).as_ref()).unwrap();
    for (l, d) in modes.values.iter().zip(&dense.values) {
        assert!((l / d - 1.0).abs() < 1e-10, "{l} against {d}");
    }
    // an off-diagonal value of K changed on one side only
    let (p, row, col) = k
        .iter()
        .enumerate()
        .find(|(_, (_, (r, c)))| r > c)
        .map(|(p, (_, (r, c)))| (p, r, c))
        .unwrap();
    let mut asym = k.clone();
    asym.data_mut()[p] += 1.0;
    assert!(!checks.are_for(&asym, &m));
    match Pencil::with_checks(&asym, &m, symbolic(), &checks) {
        Err(SparseError::NotSymmetric {
            matrix: "K",
            row: r,
            col: c,
            ..
        }) => assert!((r, c) == (row, col) || (r, c) == (col, row)),
        other => panic!("an asymmetric K after the checks: {other:?}"),
    }
    let mut nan = m.clone();
    nan.data_mut()[3] = f64::NAN;
    assert!(matches!(
        Pencil::with_checks(&k, &nan, symbolic(), &checks),
        Err(SparseError::NonFinite { matrix: "M", .. })
    ));
    let mut flipped = k.clone();
    let last = flipped.nnz() - 1;
    flipped.data_mut()[last] = f64::from_bits(flipped.data()[last].to_bits() ^ 1);
    assert!(!checks.are_for(&flipped, &m));
    let doubled = k.map(|v| 2.0 * v);
    assert!(!checks.are_for(&doubled, &m));
    let pencil = Pencil::with_checks(&doubled, &m, symbolic(), &checks).unwrap();
    assert!((pencil.norms().0 - 2.0 * hand_norm(&k)).abs() <= 1e-12 * pencil.norms().0);
}
