use super::*;

/// `mw^T w` and the Euclidean norms of `w`'s columns, summed here entry by entry.
fn gram_of(w: &Mat<f64>, mw: &Mat<f64>) -> Gram {
    let (n, k) = (w.nrows(), w.ncols());
    Gram {
        g: Mat::<f64>::from_fn(k, k, |a, b| (0..n).map(|i| mw[(i, a)] * w[(i, b)]).sum()),
        norms: (0..k)
            .map(|j| (0..n).map(|i| w[(i, j)] * w[(i, j)]).sum::<f64>().sqrt())
            .collect(),
    }
}

/// `R` and `Q` of `w = Q R` by modified Gram-Schmidt, twice, in the M inner product of the
/// diagonal `m`: the reference for [`cholesky_qr2`].
fn gram_schmidt_m(w: &Mat<f64>, m: &[f64]) -> (Mat<f64>, Mat<f64>) {
    let (n, k) = (w.nrows(), w.ncols());
    let mut q = w.clone();
    let mut r = Mat::<f64>::zeros(k, k);
    let m_dot = |a: &Mat<f64>, i: usize, b: &Mat<f64>, j: usize| -> f64 {
        (0..n).map(|p| a[(p, i)] * m[p] * b[(p, j)]).sum()
    };
    for j in 0..k {
        // modified Gram-Schmidt, twice
        for _ in 0..2 {
            for i in 0..j {
                let c = m_dot(&q, i, &q, j);
                r[(i, j)] += c;
                for p in 0..n {
                    q[(p, j)] -= c * q[(p, i)];
                }
            }
        }
        let nrm = m_dot(&q, j, &q, j).sqrt();
        r[(j, j)] = nrm;
        for p in 0..n {
            q[(p, j)] /= nrm;
        }
    }
    (q, r)
}

/// [`cholesky_qr2`] against the Gram-Schmidt above: the same `R` and `Q`, `Q` M-orthonormal
/// to round-off and its images `M Q`, on blocks conditioned from about 1 to about 1e4 (rows
/// split between threads; the best conditioned takes one pass, its Gram matrix after it the
/// identity to 6.7e-16, the others two, theirs 7.5e-11 and 2.3e-7 from it); and a dependent
/// column, a vanished one and one that kept only 1e-6 of its norm through the projection
/// declined with the block left as it was.
#[test]
fn cholesky_qr2_matches_an_m_gram_schmidt_and_declines_dependent_blocks() {
    let (n, k) = (2 * PROJECT_ROWS + 9, 4);
    let m: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 * 0.5).collect();
    let images = |w: &Mat<f64>| Mat::<f64>::from_fn(n, w.ncols(), |i, j| m[i] * w[(i, j)]);
    for closeness in [1.0, 1e-2, 1e-4] {
        let mut w = Mat::<f64>::from_fn(n, k, |i, j| {
            ((i * 5 + j * 13 + (i * j) % 11) % 17) as f64 - 8.0
        });
        // the last column near the first: the block's condition grows as 1 / closeness
        for i in 0..n {
            w[(i, k - 1)] = w[(i, 0)] + closeness * w[(i, k - 1)];
        }
        let (q_ref, r_ref) = gram_schmidt_m(&w, &m);
        let before: Vec<f64> = (0..k).map(|j| w.col(j).norm_l2()).collect();
        let mut q = w.clone();
        let mut mq = images(&w);
        let gram = gram_of(&q, &mq);
        let r = cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram)
            .expect("a well-conditioned block");
        let scale = r_ref[(0, 0)];
        for i in 0..k {
            for j in 0..k {
                let expected = if i <= j { r_ref[(i, j)] } else { 0.0 };
                assert!(
                    (r[(i, j)] - expected).abs() <= 1e-12 * scale,
                    "closeness {closeness}: R[{i}, {j}] = {} against {expected}",
                    r[(i, j)]
                );
            }
        }
        let exact_images = images(&q);
        for j in 0..k {
            // the images follow by linearity, so they carry round-off times the block's
            // condition (about 1 / closeness); measured about one eps of the column's largest
            // image entry times that
            let scale = (0..n)
                .map(|p| exact_images[(p, j)].abs())
                .fold(0.0, f64::max);
            for i in 0..k {
                let g: f64 = (0..n).map(|p| q[(p, i)] * m[p] * q[(p, j)]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (g - expected).abs() <= 1e-13,
                    "closeness {closeness}: (Q^T M Q)[{i}, {j}] = {g}"
                );
            }
            for p in 0..n {
                // Q agrees with the Gram-Schmidt's to the block's condition times round-off
                assert!((q[(p, j)] - q_ref[(p, j)]).abs() <= 1e-15 / closeness * 1e3);
                let err = (mq[(p, j)] - exact_images[(p, j)]).abs();
                assert!(
                    err <= 8.0 * f64::EPSILON * scale / closeness,
                    "image ({p}, {j})"
                );
            }
        }
    }
    // a well-conditioned block whose last column kept only 1e-6 of its norm through the
    // projection (what is left is round-off, not a direction): declined, untouched
    let w = Mat::<f64>::from_fn(n, k, |i, j| {
        ((i * 5 + j * 13 + (i * j) % 11) % 17) as f64 - 8.0
    });
    let mut before: Vec<f64> = (0..k).map(|j| w.col(j).norm_l2()).collect();
    before[k - 1] *= 1e6;
    let (mut q, mut mq) = (w.clone(), images(&w));
    let mq0 = mq.clone();
    let gram = gram_of(&q, &mq);
    assert!(cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram).is_none());
    assert!(q == w && mq == mq0);
    // a dependent column, and a column that vanished in the projection: declined, untouched
    let w = Mat::<f64>::from_fn(n, k, |i, j| match j {
        2 => 2.0 * ((i % 13) as f64 - 6.0) - ((i % 5) as f64),
        0 => (i % 13) as f64 - 6.0,
        1 => -((i % 5) as f64),
        _ => ((i * 7) % 3) as f64,
    });
    for before in [vec![1.0; k], vec![1.0, 1.0, 1.0, 1e12]] {
        let (mut q, mut mq) = (w.clone(), images(&w));
        let mq0 = mq.clone();
        let gram = gram_of(&q, &mq);
        assert!(cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram).is_none());
        assert!(q == w && mq == mq0);
    }
}

/// [`project_out`] on more rows than one thread's part (so that, with two or more threads,
/// the coefficients are summed from parts): against the coefficients `v^T w` and the
/// projected block computed here by hand, with `M = I` (`mv = v`).
#[test]
fn project_out_matches_the_hand_computed_projection() {
    let (n, m, k) = (3 * PROJECT_ROWS + 17, 7, 4);
    // orthonormal columns: disjoint supports, each scaled to unit length
    let v = Mat::<f64>::from_fn(n, m, |i, j| {
        if i % m == j {
            1.0 / ((n - j).div_ceil(m) as f64).sqrt()
        } else {
            0.0
        }
    });
    let w0 = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 11) % 23) as f64 - 11.0);
    let mut w = w0.clone();
    let c = project_out(v.as_ref(), v.as_ref(), w.as_mut());
    for a in 0..m {
        for b in 0..k {
            let expected: f64 = (0..n).map(|i| v[(i, a)] * w0[(i, b)]).sum();
            assert!(
                (c[(a, b)] - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                "c[{a}, {b}] = {} against {expected}",
                c[(a, b)]
            );
        }
    }
    for i in 0..n {
        for b in 0..k {
            let expected = w0[(i, b)] - (0..m).map(|a| v[(i, a)] * c[(a, b)]).sum::<f64>();
            assert!((w[(i, b)] - expected).abs() <= 1e-12 * w0[(i, b)].abs().max(1.0));
        }
    }
}

/// [`project_block`] with a diagonal `M` (not the identity), two locked columns and eight basis
/// columns, M-orthonormal by construction (disjoint supports, each scaled here to unit
/// M-norm), the local pass on the last two. A block nearly in the span of the basis (`1e-8`
/// of it outside, as near an invariant subspace) loses about `eps / 1e-8` of orthogonality in
/// one pass: the test must ask for the second pass and end orthogonal to working precision.
/// A block whose large part lies on the local columns passes with one. In both, the
/// coefficients are the M inner products computed here by hand and `mw` is `M w`.
#[test]
fn project_block_reprojects_only_when_one_pass_cannot_be_orthogonal() {
    let (n, classes) = (3 * PROJECT_ROWS + 17, 10);
    let mdiag: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
    let mut t = sprs::TriMat::new((n, n));
    for (i, d) in mdiag.iter().enumerate() {
        t.add_triplet(i, i, *d);
    }
    let m: SparseMatrix = t.to_csc();
    // column c of the ten lives on the rows i with i % 10 == c, with unit M-norm
    let unit: Vec<f64> = (0..classes)
        .map(|c| {
            let s: f64 = (0..n).filter(|i| i % classes == c).map(|i| mdiag[i]).sum();
            1.0 / s.sqrt()
        })
        .collect();
    let cols = |from: usize, k: usize| {
        Mat::<f64>::from_fn(n, k, |i, j| {
            if i % classes == from + j {
                unit[from + j]
            } else {
                0.0
            }
        })
    };
    let images =
        |a: &Mat<f64>| Mat::<f64>::from_fn(a.nrows(), a.ncols(), |i, j| mdiag[i] * a[(i, j)]);
    let (x, v) = (cols(0, 2), cols(2, 8));
    let (mx, mv) = (images(&x), images(&v));
    let generic = |i: usize, j: usize| ((i as f64) * 0.37 + (j as f64) * 1.3).sin();
    for (outside, on_all, expect_again) in [(1e-8, true, true), (1.0, false, false)] {
        // w0 = V C + X D + outside R: C on every basis column, or only on the local two
        let w0 = Mat::<f64>::from_fn(n, 3, |i, j| {
            let mut s = outside * generic(i, j);
            for a in 0..8 {
                if on_all || a >= 6 {
                    s += (1.0 + a as f64 + 3.0 * j as f64) * v[(i, a)];
                }
            }
            s + 0.5 * x[(i, 0)] - 0.25 * x[(i, 1)]
        });
        let mut w = w0.clone();
        let mut mw = Mat::<f64>::zeros(n, 3);
        let Projected {
            coef,
            again,
            before,
            gram,
        } = project_block(
            &m,
            (x.as_ref(), mx.as_ref()),
            (v.as_ref(), mv.as_ref()),
            6,
            w.as_mut(),
            mw.as_mut(),
        );
        assert_eq!(again, expect_again, "outside {outside:e}");
        // the norms before, and the Gram matrix and norms after, against sums written here
        for j in 0..3 {
            let b: f64 = (0..n).map(|i| w0[(i, j)] * w0[(i, j)]).sum::<f64>().sqrt();
            assert!((before[j] - b).abs() <= 1e-14 * b, "norm before {j}");
            let a: f64 = (0..n).map(|i| w[(i, j)] * w[(i, j)]).sum::<f64>().sqrt();
            assert!((gram.norms[j] - a).abs() <= 1e-13 * a, "norm after {j}");
            for c in 0..3 {
                let g: f64 = (0..n).map(|i| mdiag[i] * w[(i, j)] * w[(i, c)]).sum();
                let scale = gram.g[(j, j)].max(gram.g[(c, c)]);
                assert!(
                    (gram.g[(j, c)] - g).abs() <= 1e-13 * scale,
                    "outside {outside:e}: G[{j}, {c}] = {} against {g}",
                    gram.g[(j, c)]
                );
            }
        }
        for j in 0..3 {
            let m_norm = (0..n)
                .map(|i| mdiag[i] * w[(i, j)] * w[(i, j)])
                .sum::<f64>()
                .sqrt();
            let scale = (0..n)
                .map(|i| mdiag[i] * w0[(i, j)] * w0[(i, j)])
                .sum::<f64>()
                .sqrt();
            for (name, basis) in [("locked", &x), ("basis", &v)] {
                for a in 0..basis.ncols() {
                    let ip: f64 = (0..n).map(|i| basis[(i, a)] * mdiag[i] * w[(i, j)]).sum();
                    assert!(
                        ip.abs() <= 1e-14 * m_norm,
                        "outside {outside:e}: column {j} against {name} {a}: {ip:e} of {m_norm:e}"
                    );
                }
            }
            for a in 0..8 {
                let exact: f64 = (0..n).map(|i| v[(i, a)] * mdiag[i] * w0[(i, j)]).sum();
                assert!(
                    (coef[(a, j)] - exact).abs() <= 1e-13 * scale,
                    "outside {outside:e}: coefficient ({a}, {j}) {} against {exact}",
                    coef[(a, j)]
                );
            }
            for i in 0..n {
                assert!((mw[(i, j)] - mdiag[i] * w[(i, j)]).abs() <= 1e-15 * scale);
            }
        }
    }
}
