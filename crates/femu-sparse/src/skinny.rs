//! The supernodal solve's dense work for a few right-hand sides (docs/SCALING.md, "The solve's
//! own kernels for a few right-hand sides").
//!
//! A supernode's columns of the factor, `[L11; L21]` (`c + b` rows, `c` columns), meet the
//! right-hand sides twice in a solve: `w1 <- L11^-1 w1`, `w2 -= L21 w1` on the way up and
//! `w1 <- L11^-T (w1 - L21^T w2)` on the way down, with 1 to 4 right-hand sides in the
//! eigensolver. faer's GEMM and triangular solves pack the factor into panels before they
//! multiply, which for so few right-hand sides reads it twice and writes it once. Here the two
//! parts are one: the right-hand sides' rows of the front, `w = [w1; w2]`, sit in one buffer,
//! and the columns are taken in tiles of [`TILE`]: the tile's small triangle is solved, then
//! every row below it is updated from the tile's columns (on the way up), or the tile's rows
//! take their dot products with everything below them (on the way down). Each entry of the
//! factor is read once, a few long column streams at a time, with `w` in cache. The loops use the
//! machine's vector instructions through `pulp`'s dispatch (AVX-512 here, AVX2 and FMA on
//! machines without it); the sums are
//! taken in a fixed order, so a solve gives the same bits on every run on one machine.

use pulp::{Simd, WithSimd};

/// The most right-hand sides the kernels take; more go to faer's GEMM, which is then efficient.
pub(crate) const MAX_RHS: usize = 8;

/// Right-hand sides handled by one pass of a kernel (more are taken in groups of this many).
const GROUP: usize = 4;

/// Columns of the factor taken at once: their triangle is solved by plain loops, the rows below
/// them by the vector kernels. Eight column streams at once read 20-23 GB/s on one thread of this
/// machine from supernodes of 128 and 400 pivots, where all their columns at once read 7-9 and
/// faer's GEMM 11-13 (docs/SCALING.md, "The solve's own kernels for a few right-hand sides").
pub(crate) const TILE: usize = 8;

/// Rows below a tile from which the way up splits them between two threads.
const PARALLEL_ROWS: usize = 2048;

/// A column-major block of the factor: entry `(r, j)` at `data[j * ld + r]`, `rows x cols`.
#[derive(Clone, Copy)]
pub(crate) struct Panel<'a> {
    data: &'a [f64],
    ld: usize,
    rows: usize,
    cols: usize,
}

impl<'a> Panel<'a> {
    /// The `rows x cols` block at the start of `data`, columns `ld` apart.
    ///
    /// # Panics
    /// When `data` is too short for it (an internal error: the callers cut it from the factor).
    pub(crate) fn new(data: &'a [f64], ld: usize, rows: usize, cols: usize) -> Self {
        assert!(
            rows <= ld || cols <= 1,
            "a panel's rows within its column stride"
        );
        assert!(
            rows == 0 || cols == 0 || data.len() >= (cols - 1) * ld + rows,
            "a panel within its data"
        );
        Panel {
            data,
            ld,
            rows,
            cols,
        }
    }

    /// The block of `rows x cols` entries from `(r0, c0)`.
    fn sub(self, r0: usize, c0: usize, rows: usize, cols: usize) -> Self {
        assert!(
            r0 + rows <= self.rows && c0 + cols <= self.cols,
            "a block inside its panel"
        );
        if rows == 0 || cols == 0 {
            return Panel {
                data: &[],
                ld: self.ld,
                rows,
                cols,
            };
        }
        Panel::new(&self.data[c0 * self.ld + r0..], self.ld, rows, cols)
    }

    /// Its columns.
    pub(crate) fn cols(&self) -> usize {
        self.cols
    }

    /// As a matrix view.
    pub(crate) fn mat(&self) -> faer::MatRef<'a, f64> {
        faer::MatRef::from_column_major_slice_with_stride(self.data, self.rows, self.cols, self.ld)
    }

    /// Entry `(r, j)`.
    #[inline(always)]
    pub(crate) fn at(&self, r: usize, j: usize) -> f64 {
        self.data[j * self.ld + r]
    }

    /// Column `j`.
    #[inline(always)]
    fn col(&self, j: usize) -> &'a [f64] {
        if self.rows == 0 {
            return &[];
        }
        &self.data[j * self.ld..j * self.ld + self.rows]
    }
}

/// The `k` right-hand sides' rows `offset..offset + rows` of a buffer of `stride` rows each
/// (`k` at most [`MAX_RHS`]).
fn rows_of(
    w: &mut [f64],
    (stride, offset): (usize, usize),
    k: usize,
    rows: usize,
) -> Vec<&mut [f64]> {
    assert!(
        k <= MAX_RHS && w.len() == stride * k && offset + rows <= stride,
        "a chunk's rows of the right-hand sides"
    );
    w.chunks_exact_mut(stride)
        .map(|wq| &mut wq[offset..offset + rows])
        .collect()
}

/// The way up through one chunk of a supernode's columns (a supernode in faer's layout is one
/// chunk): `w` holds the `k` right-hand sides' rows of the front, `stride` each (column-major,
/// `k` at most [`MAX_RHS`]), of which the chunk's are `offset..offset + ld`
/// (`place = (stride, offset)`); `l` is `[L11; L21]`
/// (`ld x c`, the unit lower triangle of `L11` read, its diagonal and upper part not). On return
/// `w1 = L11^-1 w1` and `w2 -= L21 w1` in those rows.
pub(crate) fn forward(
    l: Panel<'_>,
    w: &mut [f64],
    place: (usize, usize),
    k: usize,
    parallel: bool,
) {
    forward_on(pulp::Arch::new(), l, w, place, k, parallel);
}

/// [`forward`] with the vector instructions of `arch`.
fn forward_on(
    arch: pulp::Arch,
    l: Panel<'_>,
    w: &mut [f64],
    place: (usize, usize),
    k: usize,
    parallel: bool,
) {
    let (ld, c) = (l.rows, l.cols);
    let mut w = rows_of(w, place, k, ld);
    for j0 in (0..c).step_by(TILE) {
        let j1 = (j0 + TILE).min(c);
        let mut z = [[0.0; TILE]; MAX_RHS];
        for (q, wq) in w.iter_mut().enumerate() {
            for j in j0..j1 {
                let wj = wq[j];
                for i in j + 1..j1 {
                    wq[i] -= l.at(i, j) * wj;
                }
                z[q][j - j0] = wj;
            }
        }
        if j1 < ld {
            let tile = l.sub(j1, j0, ld - j1, j1 - j0);
            let mut below: Vec<&mut [f64]> = w.iter_mut().map(|wq| &mut wq[j1..]).collect();
            product(
                arch,
                &mut below,
                tile,
                &z[..k],
                parallel && ld - j1 >= PARALLEL_ROWS,
            );
        }
    }
}

/// The way down through one chunk: `w` as in [`forward`], `w1` holding `D^-1` times the way
/// up's result and `w2` the solution at the rows below the chunk's pivots. On return
/// `w1 = L11^-T (w1 - L21^T w2)`.
pub(crate) fn backward(
    l: Panel<'_>,
    w: &mut [f64],
    place: (usize, usize),
    k: usize,
    parallel: bool,
) {
    backward_on(pulp::Arch::new(), l, w, place, k, parallel);
}

/// [`backward`] with the vector instructions of `arch`.
fn backward_on(
    arch: pulp::Arch,
    l: Panel<'_>,
    w: &mut [f64],
    place: (usize, usize),
    k: usize,
    parallel: bool,
) {
    let (ld, c) = (l.rows, l.cols);
    let mut w = rows_of(w, place, k, ld);
    for j0 in (0..c).step_by(TILE).rev() {
        let j1 = (j0 + TILE).min(c);
        if j1 < ld {
            let tile = l.sub(j1, j0, ld - j1, j1 - j0);
            let below: Vec<&[f64]> = w.iter().map(|wq| &wq[j1..]).collect();
            let d = if parallel && tile.rows * tile.cols >= PARALLEL_ROWS * TILE / 2 {
                let mid = tile.cols / 2;
                let (a, b) = rayon::join(
                    || dots(arch, tile.sub(0, 0, tile.rows, mid), &below),
                    || dots(arch, tile.sub(0, mid, tile.rows, tile.cols - mid), &below),
                );
                let mut d = a;
                for (dq, bq) in d.iter_mut().zip(&b) {
                    dq[mid..tile.cols].copy_from_slice(&bq[..tile.cols - mid]);
                }
                d
            } else {
                dots(arch, tile, &below)
            };
            for (q, wq) in w.iter_mut().enumerate() {
                for t in 0..j1 - j0 {
                    wq[j0 + t] -= d[q][t];
                }
            }
        }
        for wq in w.iter_mut() {
            for j in (j0..j1).rev() {
                let mut s = 0.0;
                for i in j + 1..j1 {
                    s += l.at(i, j) * wq[i];
                }
                wq[j] -= s;
            }
        }
    }
}

/// `u[q] -= b z[q]` for each right-hand side `q` (`b`: `rows x cols`, `cols` at most [`TILE`],
/// `u[q]` at least `rows` long); the two halves of the rows on two threads when `parallel`.
fn product(
    arch: pulp::Arch,
    u: &mut [&mut [f64]],
    b: Panel<'_>,
    z: &[[f64; TILE]],
    parallel: bool,
) {
    if parallel {
        let mid = b.rows / 2;
        let (mut top, mut bottom): (Vec<&mut [f64]>, Vec<&mut [f64]>) = u
            .iter_mut()
            .map(|uq| uq[..b.rows].split_at_mut(mid))
            .unzip();
        let (b0, b1) = (
            b.sub(0, 0, mid, b.cols),
            b.sub(mid, 0, b.rows - mid, b.cols),
        );
        rayon::join(
            || product(arch, &mut top, b0, z, false),
            || product(arch, &mut bottom, b1, z, false),
        );
        return;
    }
    for (uq, zq) in u.chunks_mut(GROUP).zip(z.chunks(GROUP)) {
        match uq {
            [a, b_, c_, d] => arch.dispatch(Product {
                u: [a, b_, c_, d],
                b,
                z: [&zq[0], &zq[1], &zq[2], &zq[3]],
            }),
            [a, b_, c_] => arch.dispatch(Product {
                u: [a, b_, c_],
                b,
                z: [&zq[0], &zq[1], &zq[2]],
            }),
            [a, b_] => arch.dispatch(Product {
                u: [a, b_],
                b,
                z: [&zq[0], &zq[1]],
            }),
            [a] => arch.dispatch(Product {
                u: [a],
                b,
                z: [&zq[0]],
            }),
            _ => unreachable!("chunks of 1 to GROUP"),
        }
    }
}

/// `b^T y[q]` for each right-hand side `q` (`b`: `rows x cols`, `cols` at most [`TILE`], `y[q]`
/// `rows` long): `d[q][j]` for `j < cols`.
fn dots(arch: pulp::Arch, b: Panel<'_>, y: &[&[f64]]) -> Vec<[f64; TILE]> {
    let mut d = vec![[0.0; TILE]; y.len()];
    // four columns at once with AVX-512's 32 registers (sixteen accumulators for four
    // right-hand sides), three with AVX2's 16 (twelve); the last one or two alone
    let most = if arch.dispatch(Lanes) >= 8 { 4 } else { 3 };
    for (dq, yq) in d.chunks_mut(GROUP).zip(y.chunks(GROUP)) {
        let mut j = 0;
        while j < b.cols {
            let take = if b.cols - j >= most { most } else { 1 };
            let part = b.sub(0, j, b.rows, take);
            macro_rules! run {
                ($g:literal, $jt:literal) => {{
                    let r: [[f64; $jt]; $g] = arch.dispatch(Dots::<$g, $jt> {
                        b: part,
                        y: std::array::from_fn(|g| yq[g]),
                    });
                    for g in 0..$g {
                        dq[g][j..j + $jt].copy_from_slice(&r[g]);
                    }
                }};
            }
            match (yq.len(), take) {
                (4, 4) => run!(4, 4),
                (3, 4) => run!(3, 4),
                (2, 4) => run!(2, 4),
                (1, 4) => run!(1, 4),
                (4, 3) => run!(4, 3),
                (3, 3) => run!(3, 3),
                (2, 3) => run!(2, 3),
                (1, 3) => run!(1, 3),
                (4, _) => run!(4, 1),
                (3, _) => run!(3, 1),
                (2, _) => run!(2, 1),
                _ => run!(1, 1),
            }
            j += take;
        }
    }
    d
}

/// The `f64` lanes of the machine's vector registers (8 with AVX-512, 4 with AVX2).
struct Lanes;

impl WithSimd for Lanes {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> usize {
        S::F64_LANES
    }
}

/// `u[g] -= B z[g]` for `G` right-hand sides, a block of rows at a time held in vector registers
/// while the (at most [`TILE`]) columns of `B` stream.
struct Product<'a, 'b, const G: usize> {
    u: [&'a mut [f64]; G],
    b: Panel<'b>,
    z: [&'a [f64; TILE]; G],
}

impl<const G: usize> WithSimd for Product<'_, '_, G> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Product { u, b, z } = self;
        // two vector registers of rows: with four right-hand sides, 8 of the 16 AVX2 registers
        const BLOCK: usize = 2;
        let step = BLOCK * S::F64_LANES;
        let full = b.rows - b.rows % step;
        for r in (0..full).step_by(step) {
            let mut acc = [[simd.splat_f64s(0.0); BLOCK]; G];
            for j in 0..b.cols {
                let (bv, _) = S::as_simd_f64s(&b.data[j * b.ld + r..j * b.ld + r + step]);
                for g in 0..G {
                    let zj = simd.splat_f64s(z[g][j]);
                    for i in 0..BLOCK {
                        acc[g][i] = simd.mul_add_f64s(bv[i], zj, acc[g][i]);
                    }
                }
            }
            for g in 0..G {
                let (uv, _) = S::as_mut_simd_f64s(&mut u[g][r..r + step]);
                for i in 0..BLOCK {
                    uv[i] = simd.sub_f64s(uv[i], acc[g][i]);
                }
            }
        }
        for r in full..b.rows {
            let mut acc = [0.0; G];
            for j in 0..b.cols {
                let v = b.at(r, j);
                for g in 0..G {
                    acc[g] += v * z[g][j];
                }
            }
            for g in 0..G {
                u[g][r] -= acc[g];
            }
        }
    }
}

/// The dot products of `JT` columns of `B` with `G` right-hand sides, each in one vector
/// register of partial sums (summed in a fixed order at the end).
struct Dots<'a, 'b, const G: usize, const JT: usize> {
    b: Panel<'b>,
    y: [&'a [f64]; G],
}

impl<const G: usize, const JT: usize> WithSimd for Dots<'_, '_, G, JT> {
    type Output = [[f64; JT]; G];

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> [[f64; JT]; G] {
        let Dots { b, y } = self;
        let full = b.rows - b.rows % S::F64_LANES;
        let yv: [&[S::f64s]; G] = std::array::from_fn(|g| S::as_simd_f64s(&y[g][..full]).0);
        let bv: [&[S::f64s]; JT] = std::array::from_fn(|t| S::as_simd_f64s(&b.col(t)[..full]).0);
        let mut acc = [[simd.splat_f64s(0.0); JT]; G];
        for i in 0..full / S::F64_LANES {
            let bs: [S::f64s; JT] = std::array::from_fn(|t| bv[t][i]);
            for g in 0..G {
                let yi = yv[g][i];
                for t in 0..JT {
                    acc[g][t] = simd.mul_add_f64s(bs[t], yi, acc[g][t]);
                }
            }
        }
        let mut out = [[0.0; JT]; G];
        for g in 0..G {
            for t in 0..JT {
                let mut s = simd.reduce_sum_f64s(acc[g][t]);
                for r in full..b.rows {
                    s += b.at(r, t) * y[g][r];
                }
                out[g][t] = s;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An entry of a test matrix: a hand-made pattern of multiples of 1/16.
    fn entry(i: usize, j: usize, salt: usize) -> f64 {
        ((i * 7 + j * 13 + salt * 5) % 11) as f64 / 16.0 - 5.0 / 16.0
    }

    /// A supernode's columns `[L11; L21]` (`c + b` rows, `c` columns) with NaN on and above the
    /// diagonal of `L11` (never read), the unit lower `L` they stand for, and right-hand sides.
    fn supernode(
        c: usize,
        b: usize,
        k: usize,
    ) -> (Vec<f64>, impl Fn(usize, usize) -> f64, Vec<f64>) {
        let ld = c + b;
        let lower = move |i: usize, j: usize| match i.cmp(&j) {
            std::cmp::Ordering::Greater => entry(i, j, 1),
            std::cmp::Ordering::Equal => 1.0,
            std::cmp::Ordering::Less => 0.0,
        };
        let data = (0..ld * c)
            .map(|p| {
                let (i, j) = (p % ld, p / ld);
                if i > j { lower(i, j) } else { f64::NAN }
            })
            .collect();
        let w = (0..ld * k).map(|p| entry(p % ld, p / ld, 2)).collect();
        (data, lower, w)
    }

    /// Every instruction set this machine runs, not only the one the dispatch picks: the best
    /// (AVX-512 or AVX2), AVX2 where there is AVX-512, and the plain scalar code, so that the
    /// kernels' paths for 32 and 16 vector registers and for none are all tested here.
    fn archs() -> Vec<pulp::Arch> {
        let mut archs = vec![pulp::Arch::new(), pulp::Arch::Scalar];
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = pulp::x86::V3::try_new() {
            archs.push(pulp::Arch::V3(v3));
        }
        archs
    }

    fn close(got: &[f64], want: &[f64], what: &str) {
        let scale = want.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g - w).abs() <= 1e-13 * scale,
                "{what}: entry {i}: {g} against {w}"
            );
        }
    }

    #[test]
    fn the_way_up_and_down_match_the_plain_loops() {
        // c around the tile and the three-column groups, b around the vector blocks and the
        // parallel split, 1 to 8 right-hand sides; the references by the textbook loops:
        // forward substitution with L11, then w2 - L21 w1; and w1 - L21^T w2, then back
        // substitution with L11^T. The substitutions' values are not short binary fractions, so
        // the kernels' other order of additions may change the last bits: 1e-13 relative (a
        // wrong or missing term is a difference of a sixteenth or more)
        for &c in &[1, 2, 3, 7, 8, 9, 17, 40] {
            for &b in &[0, 1, 5, 8, 9, 16, 17, 100, 2100] {
                for k in [1, 2, 3, 4, 5, 8] {
                    for (arch, parallel) in
                        archs().into_iter().flat_map(|a| [(a, false), (a, true)])
                    {
                        let ld = c + b;
                        let (data, lower, w) = supernode(c, b, k);
                        let l = Panel::new(&data, ld, ld, c);
                        // the front's rows 2.. of a buffer of ld + 3 rows per right-hand side
                        // (a chunk's rows of a front's): the rows around them stay as they are
                        let (stride, offset) = (ld + 3, 2);
                        let padded = |w: &[f64]| -> Vec<f64> {
                            let mut p = vec![7.5; stride * k];
                            for q in 0..k {
                                p[q * stride + offset..q * stride + offset + ld]
                                    .copy_from_slice(&w[q * ld..(q + 1) * ld]);
                            }
                            p
                        };
                        let inner = |p: &[f64]| -> Vec<f64> {
                            for q in 0..k {
                                let col = &p[q * stride..(q + 1) * stride];
                                assert!(
                                    col[..offset]
                                        .iter()
                                        .chain(&col[offset + ld..])
                                        .all(|&v| v == 7.5),
                                    "rows outside the chunk's changed"
                                );
                            }
                            (0..k)
                                .flat_map(|q| {
                                    p[q * stride + offset..q * stride + offset + ld].to_vec()
                                })
                                .collect()
                        };
                        let mut up = padded(&w);
                        forward_on(arch, l, &mut up, (stride, offset), k, parallel);
                        let up = inner(&up);
                        let mut want = w.clone();
                        for q in 0..k {
                            let wq = &mut want[q * ld..(q + 1) * ld];
                            for i in 0..c {
                                for j in 0..i {
                                    wq[i] -= lower(i, j) * wq[j];
                                }
                            }
                            for i in c..ld {
                                for j in 0..c {
                                    wq[i] -= lower(i, j) * wq[j];
                                }
                            }
                        }
                        close(
                            &up,
                            &want,
                            &format!("forward: c {c}, b {b}, {k} rhs, {parallel}, {arch:?}"),
                        );

                        let mut down = padded(&w);
                        backward_on(arch, l, &mut down, (stride, offset), k, parallel);
                        let down = inner(&down);
                        let mut want = w.clone();
                        for q in 0..k {
                            let wq = &mut want[q * ld..(q + 1) * ld];
                            for j in 0..c {
                                for i in c..ld {
                                    wq[j] -= lower(i, j) * wq[i];
                                }
                            }
                            for j in (0..c).rev() {
                                for i in j + 1..c {
                                    wq[j] -= lower(i, j) * wq[i];
                                }
                            }
                        }
                        close(
                            &down,
                            &want,
                            &format!("backward: c {c}, b {b}, {k} rhs, {parallel}, {arch:?}"),
                        );
                    }
                }
            }
        }
    }
}
