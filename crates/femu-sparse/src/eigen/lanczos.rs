//! One shift-invert block Lanczos run at a factored shift: expansion, selective
//! reorthogonalisation, Rayleigh-Ritz, locking and thick restarts.

use super::*;

/// A block's single pass of Gram-Schmidt against the basis is repeated when a column keeps less
/// than this fraction of its M-norm (ARPACK's `0.717`, about `1 / sqrt(2)`): Kahan and Parlett's
/// "twice is enough" bound then no longer makes one pass orthogonal to working precision.
pub(super) const REORTHOGONALIZE: f64 = 0.717;

/// The first basis column whose stored projection couples it to the columns `applied..hi` about
/// to be expanded (`h[i][j]` nonzero, `i < applied <= j`), or `applied` when none does. By the
/// symmetry of the projection, `v_i^T M OP v_j = h[i][j]`, and `v_i^T M OP v_j = 0` where `v_j`
/// was made after `OP v_i` was (it is orthogonal to everything `OP v_i` spans): columns before
/// the returned one hold only round-off of `OP V_j` (docs/MATH.md, "Selective
/// reorthogonalisation"). After a thick restart the Ritz vectors all couple to the block: 0.
pub(super) fn coupled_from(h: &[Vec<f64>], applied: usize, hi: usize) -> usize {
    (0..applied.min(h.len()))
        .find(|&i| (applied..hi).any(|j| h[i].get(j).is_some_and(|v| *v != 0.0)))
        .unwrap_or(applied)
}

/// A zero-energy pair locked before the iteration ([`Pencil::zero_energy_pairs`]): the
/// M-normalised vector, its M image, its Rayleigh quotient and what the shifted residual at any
/// shift needs (`||r||` with `r = K x - lambda M x`, and the inner products of `K x` and `M x`), so
/// that no `K` product is repeated for each Lanczos run.
pub(super) struct Known {
    pub(super) x: Vec<f64>,
    pub(super) mx: Vec<f64>,
    pub(super) lambda: f64,
    pub(super) r_norm: f64,
    pub(super) kk: f64,
    pub(super) km: f64,
    pub(super) mm: f64,
}

impl Known {
    /// `||K x - lambda M x|| / ||(K - sigma M) x||`.
    pub(super) fn shifted_residual(&self, sigma: f64) -> f64 {
        let s2 = self.kk - 2.0 * sigma * self.km + sigma * sigma * self.mm;
        self.r_norm / s2.max(0.0).sqrt().max(f64::MIN_POSITIVE)
    }
}

/// A probe's Lanczos cycle: its basis, the basis's M images, the projection `h` (as in
/// [`Lanczos::run`]), the columns `OP` was applied to, and the random generator's state after it.
pub(super) struct Probed {
    pub(super) basis: Columns,
    pub(super) mbasis: Columns,
    pub(super) h: Vec<Vec<f64>>,
    pub(super) applied: usize,
    pub(super) rng: u64,
}

pub(super) struct Lanczos<'p, 'a> {
    pub(super) pencil: &'p Pencil<'a>,
    /// `LDL^T` of `K - sigma M`, owned so that it can be released while the Sturm check factors
    /// another shift: two factors alive at once set femu's peak memory (about 2x CalculiX's).
    pub(super) op: Option<Ldlt>,
    pub(super) sigma: f64,
    pub(super) params: EigenOptions,
    pub(super) n: usize,
    /// locked eigenvectors, their M images and eigenvalues
    pub(super) x: Columns,
    pub(super) mx: Columns,
    pub(super) values: Vec<f64>,
    pub(super) shifted_res: Vec<f64>,
    pub(super) force_random_start: bool,
    /// How many of the locked pairs were given ([`Known`]): they take no room in the basis.
    pub(super) known: usize,
    /// The probe's Krylov basis, kept for [`Lanczos::run`] to continue from when the shift stays
    /// where the probe ran.
    pub(super) probed: Option<Probed>,
    /// Set when the hook of [`with_interrupt`] asked to stop.
    pub(super) stop: bool,
    pub(super) rng: u64,
    /// Whether `M` has a zero (or negative) diagonal entry: massless DOFs (a lumped beam's
    /// rotations). Random vectors are then purified, `OP r` instead of `r`, so that the basis
    /// stays in the range of `OP`, where the `M` inner product is definite (Nour-Omid, Parlett,
    /// Ericsson and Jensen, "How to implement the spectral transformation", 1987).
    pub(super) m_singular: bool,
    /// The dimension of the space the basis can span: `n`, or with massless DOFs the number of
    /// DOFs with mass (the finite eigenvalues are no more).
    pub(super) rank: usize,
}

impl<'p, 'a> Lanczos<'p, 'a> {
    /// A Lanczos iteration at `sigma` with the `known` zero-energy pairs locked from the start.
    pub(super) fn new(
        pencil: &'p Pencil<'a>,
        op: Ldlt,
        sigma: f64,
        params: &EigenOptions,
        known: &[Known],
    ) -> Self {
        let mut lanczos = Self {
            pencil,
            op: Some(op),
            sigma,
            params: params.clone(),
            n: pencil.dim(),
            x: Columns::new(pencil.dim()),
            mx: Columns::new(pencil.dim()),
            values: vec![],
            shifted_res: vec![],
            force_random_start: false,
            known: 0,
            probed: None,
            stop: false,
            rng: params.seed,
            m_singular: false,
            rank: pencil.dim(),
        };
        let with_mass = crate::csc::diagonal(pencil.m)
            .iter()
            .filter(|d| **d > 0.0)
            .count();
        if with_mass < lanczos.n {
            lanczos.m_singular = true;
            lanczos.rank = with_mass;
        }
        for k in known {
            lanczos.x.push(&k.x);
            lanczos.mx.push(&k.mx);
            lanczos.values.push(k.lambda);
            lanczos.shifted_res.push(k.shifted_residual(sigma));
        }
        lanczos.known = known.len();
        lanczos
    }

    pub(super) fn random_vector(&mut self) -> Vec<f64> {
        let r = self.plain_random_vector();
        if !self.m_singular {
            return r;
        }
        let Some(op) = self.op.as_ref() else {
            return r;
        };
        let image = self.m_times(&r);
        let mut mr = faer::Mat::from_fn(self.n, 1, |i, _| image[i]);
        op.solve_in_place(mr.as_mut());
        (0..self.n).map(|i| mr[(i, 0)]).collect()
    }

    fn plain_random_vector(&mut self) -> Vec<f64> {
        (0..self.n)
            .map(|_| {
                self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = self.rng;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    pub(super) fn m_times(&self, v: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        crate::csc::mul_vec(self.pencil.m, v, &mut out).expect("sizes checked");
        out
    }

    /// Two passes of classical Gram-Schmidt (CGS2) of `w` against the locked vectors and the
    /// basis columns `..upto`, M inner products through the stored M images; returns the
    /// coefficients on those basis columns.
    pub(super) fn orthogonalize_upto(
        &self,
        w: &mut [f64],
        basis: &Columns,
        mbasis: &Columns,
        upto: usize,
    ) -> Vec<f64> {
        let nl = self.x.len();
        let vs: Vec<&[f64]> = (0..nl)
            .map(|j| self.x.col(j))
            .chain((0..upto).map(|j| basis.col(j)))
            .collect();
        let mvs: Vec<&[f64]> = (0..nl)
            .map(|j| self.mx.col(j))
            .chain((0..upto).map(|j| mbasis.col(j)))
            .collect();
        let mut coef = vec![0.0; upto];
        for _ in 0..2 {
            let cs: Vec<f64> = mvs.par_iter().map(|mv| dot(mv, w)).collect();
            let neg: Vec<f64> = cs.iter().map(|c| -c).collect();
            add_combination(w, &vs, &neg);
            coef.iter_mut().zip(&cs[nl..]).for_each(|(a, c)| *a += c);
        }
        coef
    }

    /// CGS2 of `w` against the locked vectors and the whole basis; the coefficients on `basis`.
    pub(super) fn orthogonalize(
        &self,
        w: &mut [f64],
        basis: &Columns,
        mbasis: &Columns,
    ) -> Vec<f64> {
        self.orthogonalize_upto(w, basis, mbasis, basis.len())
    }

    /// The M-norm of `w` (already orthogonal to the locked vectors and the basis) with its image
    /// `mw`, or `None` when `w` vanished relative to `before` (the Krylov space is invariant).
    pub(super) fn usable_norm(w: &[f64], mw: &[f64], before: f64) -> Option<f64> {
        if !(norm(w) > 1e-10 * before) {
            return None;
        }
        let nrm = dot(mw, w).max(0.0).sqrt();
        (nrm > 0.0).then_some(nrm)
    }

    /// Appends `w / nrm` and its image `mw / nrm`.
    pub(super) fn push_scaled(
        mut w: Vec<f64>,
        mut mw: Vec<f64>,
        nrm: f64,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) {
        w.iter_mut().for_each(|v| *v /= nrm);
        mw.iter_mut().for_each(|v| *v /= nrm);
        basis.push(&w);
        mbasis.push(&mw);
    }

    /// Appends `w` to the basis after orthogonalisation; returns (coefficients, norm before the
    /// final normalisation). A vector that vanishes (invariant subspace found) is replaced by a
    /// random one, with zero coefficient.
    pub(super) fn append(
        &mut self,
        mut w: Vec<f64>,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) -> (Vec<f64>, f64) {
        // Breakdown is judged on the Euclidean norm: no extra M product per vector.
        let before = norm(&w);
        let coef = self.orthogonalize(&mut w, basis, mbasis);
        (coef, self.push_or_replace(w, before, basis, mbasis))
    }

    /// Pushes the orthogonalised `w` with its M image, or on breakdown a random vector
    /// orthogonalised in its place; returns the norm of `w` (0 when replaced).
    pub(super) fn push_or_replace(
        &mut self,
        w: Vec<f64>,
        before: f64,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) -> f64 {
        let mw = self.m_times(&w);
        if let Some(nrm) = Self::usable_norm(&w, &mw, before) {
            Self::push_scaled(w, mw, nrm, basis, mbasis);
            return nrm;
        }
        let (r, mr, nrm) = self.replacement(basis, mbasis, basis.len(), (w, mw));
        Self::push_scaled(r, mr, nrm, basis, mbasis);
        0.0
    }

    /// On breakdown (the Krylov space is invariant): a fresh random direction orthogonalised
    /// against the locked vectors and the basis columns `..upto`, with its M image and M-norm
    /// (the vector and image still to be divided by it). When no independent direction is found
    /// in five tries (the basis spans the space to round-off) the last one, so that the basis and
    /// its projection keep their size; `last` is the vector that broke down.
    pub(super) fn replacement(
        &mut self,
        basis: &Columns,
        mbasis: &Columns,
        upto: usize,
        mut last: (Vec<f64>, Vec<f64>),
    ) -> (Vec<f64>, Vec<f64>, f64) {
        for _ in 0..5 {
            let mut r = self.random_vector();
            let b = norm(&r);
            let _ = self.orthogonalize_upto(&mut r, basis, mbasis, upto);
            let mr = self.m_times(&r);
            if let Some(nrm) = Self::usable_norm(&r, &mr, b) {
                return (r, mr, nrm);
            }
            last = (r, mr);
        }
        let nrm = dot(&last.1, &last.0).max(f64::MIN_POSITIVE).sqrt();
        (last.0, last.1, nrm)
    }

    /// Applies `OP` to the basis vectors `applied..` block by block until `max_basis` columns have
    /// their image, extending the basis; returns the new `applied`. Each block of solved vectors
    /// is projected out of the locked vectors and the basis by GEMMs ([`project_block`]), then
    /// orthonormalised within itself ([`cholesky_qr2`], or column by column near dependence).
    pub(super) fn expand(
        &mut self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        mut applied: usize,
        max_basis: usize,
        stats: &mut EigenStats,
    ) -> usize {
        let p = self.params.block_size.max(1);
        let cap = self.rank.saturating_sub(self.values.len());
        while applied < basis.len() && applied < max_basis {
            let hi = (applied + p).min(basis.len()).min(max_basis);
            let block = hi - applied;
            let len0 = basis.len();
            let t = Instant::now();
            // The block is solved where it will stay: its right-hand sides (the M images of the
            // columns it extends) are copied into the basis's reserved columns, and everything
            // below works there and in the M images' columns, with no copy of the block
            // (docs/SCALING.md, "The block in place").
            basis.push_mat(mbasis.range(applied, hi));
            self.op
                .as_ref()
                .expect("the factor is present while iterating")
                .solve_in_place(basis.split_mut(len0).1);
            stats.solve_seconds += t.elapsed().as_secs_f64();
            stats.solved_vectors += block;
            if interrupted(stats.solved_vectors) {
                basis.truncate(len0);
                self.stop = true;
                return applied;
            }
            let t = Instant::now();
            let (head, mut w) = basis.split_mut(len0);
            // the block against the locked vectors and the basis (the recurrence's columns, one
            // pass against all, a second only where needed), with its M images in the images'
            // reserved columns
            let lo = coupled_from(h, applied, hi);
            mbasis.push_zeros(block);
            let (mhead, mw) = mbasis.split_mut(len0);
            let projected = project_block(
                self.pencil.m,
                (self.x.mat(), self.mx.mat()),
                (head, mhead),
                lo,
                w.as_mut(),
                mw,
            );
            stats.reorthogonalized_blocks += usize::from(projected.again);
            // the block within itself: by CholQR2 when it is well conditioned and fits
            let qr = if len0 + block <= cap {
                let (_, w) = basis.split_mut(len0);
                let (_, mw) = mbasis.split_mut(len0);
                cholesky_qr2(w, mw, &projected.before, &projected.gram)
            } else {
                None
            };
            let (coef0, before) = (&projected.coef, &projected.before);
            match qr {
                Some(r) => {
                    for j in 0..block {
                        let mut coef: Vec<f64> = coef0.col(j).iter().copied().collect();
                        coef.extend((0..=j).map(|i| r[(i, j)]));
                        h.push(coef);
                    }
                }
                None => self.orthonormalise_by_columns(basis, mbasis, h, coef0, before),
            }
            applied = hi;
            stats.orthogonalization_seconds += t.elapsed().as_secs_f64();
        }
        applied
    }

    /// The block in the basis's columns from `len0 = coef0.nrows()` on (projected out of the
    /// locked vectors and the basis with coefficients `coef0`, its Euclidean norms before that
    /// `before`), near dependence: each column Gram-Schmidted twice against the block's columns
    /// before it and M-normalised, a vanished column replaced by a random one
    /// ([`Lanczos::replacement`]), a column beyond the space's dimension dropped; each column's
    /// coefficients pushed to `h`. The path of a block that [`cholesky_qr2`] declines.
    pub(super) fn orthonormalise_by_columns(
        &mut self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        coef0: &Mat<f64>,
        before: &[f64],
    ) {
        let (len0, block) = (coef0.nrows(), coef0.ncols());
        let cap = self.rank.saturating_sub(self.values.len());
        // near dependence: CGS2 of each column against the block's columns before it, then
        // M-normalised, a vanished column replaced
        let mut kept = 0;
        for j in 0..block {
            let mut coef: Vec<f64> = coef0.col(j).iter().copied().collect();
            let (_, mut w) = basis.split_mut(len0);
            let (_, mut mw) = mbasis.split_mut(len0);
            let (done, mut rest) = w.as_mut().split_at_col_mut(j);
            let mut inner = Mat::<f64>::zeros(kept, 1);
            for _ in 0..2 {
                inner += project_out(
                    done.as_ref().subcols(0, kept),
                    mw.as_ref().subcols(0, kept),
                    rest.as_mut().subcols_mut(0, 1),
                );
            }
            let (mdone, mut mrest) = mw.as_mut().split_at_col_mut(j);
            faer::linalg::matmul::matmul(
                mrest.as_mut().subcols_mut(0, 1),
                faer::Accum::Add,
                mdone.as_ref().subcols(0, kept),
                inner.as_ref(),
                -1.0,
                faer::get_global_parallelism(),
            );
            coef.extend(inner.col(0).iter().copied());
            if len0 + kept >= cap {
                // the basis spans the space: the column is not kept (nor any after it)
                h.push(coef);
                continue;
            }
            let col = rest.col_mut(0).try_as_col_major_mut().expect("contiguous");
            let mcol = mrest.col_mut(0).try_as_col_major_mut().expect("contiguous");
            let (col, mcol) = (col.as_slice_mut(), mcol.as_slice_mut());
            let nrm = match Self::usable_norm(col, mcol, before[j]) {
                Some(nrm) => {
                    scale_in_place(col, nrm);
                    scale_in_place(mcol, nrm);
                    nrm
                }
                None => {
                    let broken = (col.to_vec(), mcol.to_vec());
                    let (r, mr, nrm) = self.replacement(basis, mbasis, len0 + j, broken);
                    // in the broken column's place
                    let slot = (len0 + j) * self.n..(len0 + j + 1) * self.n;
                    for (to, from) in [(&mut basis.data, &r), (&mut mbasis.data, &mr)] {
                        to[slot.clone()]
                            .iter_mut()
                            .zip(from)
                            .for_each(|(t, v)| *t = v / nrm);
                    }
                    0.0
                }
            };
            coef.push(nrm);
            h.push(coef);
            kept += 1;
        }
        basis.truncate(len0 + kept);
        mbasis.truncate(len0 + kept);
    }

    /// One Lanczos cycle from random vectors, no locking: rough estimates of the `count`
    /// eigenvalues nearest the shift (to place a better shift), from a basis of `size` vectors.
    pub(super) fn estimate(
        &mut self,
        count: usize,
        size: usize,
        stats: &mut EigenStats,
    ) -> Vec<f64> {
        let p = self.params.block_size.max(1);
        let (mut basis, mut mbasis, mut h) =
            (Columns::new(self.n), Columns::new(self.n), Vec::new());
        // the run that continues this basis for `count` pairs grows it to its own size: room for
        // that now, so that the basis is not moved (and held twice) when the run begins
        let room = self.basis_size(count).max(size) + p;
        basis.reserve(room);
        mbasis.reserve(room);
        for _ in 0..p.min(self.rank) {
            let r = self.random_vector();
            self.append(r, &mut basis, &mut mbasis);
        }
        let max_basis = size.min(self.rank);
        let m = self.expand(&mut basis, &mut mbasis, &mut h, 0, max_basis, stats);
        if self.stop {
            return Vec::new();
        }
        let (eig, order) = rayleigh_ritz(&h, m);
        // Only the better-converged half: the trailing Ritz values of a short cycle overestimate
        // their eigenvalues by orders of magnitude.
        let mut v: Vec<f64> = order
            .iter()
            .take(count.min(m / 2).max(1))
            .filter(|r| eig.eigenvalues[**r] != 0.0)
            .map(|r| self.sigma + 1.0 / eig.eigenvalues[*r])
            .collect();
        v.sort_by(f64::total_cmp);
        self.probed = Some(Probed {
            basis,
            mbasis,
            h,
            applied: m,
            rng: self.rng,
        });
        v
    }

    /// The largest basis of a run for `want` pairs ([`EigenOptions::max_basis`], or about three
    /// times the count the iteration must find: the given pairs are deflated, not in the basis),
    /// fixed for the whole run. Measured at 52,920 DOF: 163 solved vectors and 2 restarts against
    /// 207 and 10 at twice the count; on the free-free plate of 199,200 DOF with its six
    /// rigid-body modes given, 73 solved vectors and no restart at 59 columns, 75 at 77.
    pub(super) fn basis_size(&self, want: usize) -> usize {
        let p = self.params.block_size.max(1);
        let cap = self.rank.saturating_sub(self.values.len());
        if self.params.max_basis > 0 {
            self.params.max_basis
        } else {
            let find = want.saturating_sub(self.known);
            (3 * find + 2 * p).max(find + 4 * p).max(24)
        }
        .min(cap)
    }

    /// Runs thick-restarted block Lanczos until `want` pairs are locked.
    ///
    /// Basis `V` (M-orthonormal, deflated against the locked vectors) and the projection
    /// `h[col][row] = v_row^T M OP v_col` for the columns where `OP` was applied. At a restart the
    /// best Ritz vectors `Y = V S` are kept with `OP Y = Y Theta + V_extra H_extra S` (thick
    /// restart), so no solve is repeated and no Krylov information is lost.
    pub(super) fn run(&mut self, want: usize, stats: &mut EigenStats) -> Result<(), SparseError> {
        let p = self.params.block_size.max(1);
        // Continue from the probe's Krylov basis when it ran at this shift: its solves are not
        // repeated (a clamped model's probe was 23 of 154 solved vectors at 52,920 DOF).
        let (mut basis, mut mbasis, mut h, mut applied) = match self.probed.take() {
            Some(probed) => {
                // its random vectors are not drawn again
                self.rng = probed.rng;
                (probed.basis, probed.mbasis, probed.h, probed.applied)
            }
            None => (Columns::new(self.n), Columns::new(self.n), Vec::new(), 0),
        };
        // room for every pair the run locks, allocated at once: a locked set that doubled as it
        // grew copied itself (and cleared its new pages) at each doubling, 0.1 s of the 199,200-DOF
        // plate's Rayleigh-Ritz (docs/SCALING.md, "The locked set's room")
        self.x.reserve(want);
        self.mx.reserve(want);
        let mut restarts = 0;
        loop {
            let need = want.saturating_sub(self.values.len());
            if need == 0 {
                return Ok(());
            }
            let cap = self.rank.saturating_sub(self.values.len());
            let max_basis = self.basis_size(want);
            // the whole basis at once (measured: 50 MB of the peak at 47,628 DOF when the basis
            // and its images doubled from 64 to 128 columns)
            basis.reserve(max_basis + p);
            mbasis.reserve(max_basis + p);
            let t = Instant::now();
            if self.force_random_start || applied > max_basis {
                // Missed modes (or a probe's basis larger than this run's): discard the basis and
                // start afresh, deflated against the locked.
                basis.clear();
                mbasis.clear();
                h.clear();
                applied = 0;
                self.force_random_start = false;
            }
            while basis.len() < applied + p.min(cap - applied.min(cap)) && basis.len() < cap {
                let r = self.random_vector();
                self.append(r, &mut basis, &mut mbasis);
            }
            stats.orthogonalization_seconds += t.elapsed().as_secs_f64();
            // Convergence is checked after every block once the basis can hold the wanted pairs
            // (a Rayleigh-Ritz of at most max_basis columns costs far less than a solve), not
            // only when the basis is full: pairs lock as soon as they converge, and a cycle ends
            // early when every wanted pair has.
            let checkpoint = (applied + p).max((need + 2 * p).min(max_basis));
            applied = self.expand(
                &mut basis,
                &mut mbasis,
                &mut h,
                applied,
                checkpoint.min(max_basis),
                stats,
            );
            if self.stop {
                return Err(SparseError::Interrupted {
                    solved_vectors: stats.solved_vectors,
                });
            }
            let t = Instant::now();
            let full = applied >= max_basis || basis.len() >= cap;
            // Rayleigh-Ritz on the square part.
            let m = applied;
            let (eig, order) = rayleigh_ritz(&h, m);
            let extra = basis.len() - m;
            // coupling[e][r] = (H_extra S)[e, r]: the residual of Ritz pair r on extra vector e
            let coupling: Vec<Vec<f64>> = (0..extra)
                .map(|e| {
                    (0..m)
                        .map(|r| {
                            (0..m)
                                .map(|j| {
                                    h[j].get(m + e).copied().unwrap_or(0.0)
                                        * eig.eigenvectors[(j, r)]
                                })
                                .sum()
                        })
                        .collect()
                })
                .collect();
            let est_of = |r: usize| {
                (0..extra)
                    .map(|e| coupling[e][r] * coupling[e][r])
                    .sum::<f64>()
                    .sqrt()
                    / eig.eigenvalues[r].abs().max(f64::MIN_POSITIVE)
            };
            // The first `need` Ritz pairs are the wanted ones. `est` only screens them; the true
            // residual decides. The shifted residual of a Ritz pair is `est` times the spread of
            // the unconverged part (measured 100 to 1,000 times `est` at 52,920 DOF), so a pair
            // with `est` above `tol / 100` would fail the check anyway.
            let candidates: Vec<usize> = order
                .iter()
                .take(need)
                .copied()
                .filter(|&r| eig.eigenvalues[r] != 0.0 && est_of(r) < SCREEN * self.params.tol)
                .collect();
            if !full && candidates.len() < p.min(need) {
                // Before the basis is full, lock only a block's worth of pairs at once (or all
                // that are still needed): each locking ends in a restart that rewrites the basis
                // (two GEMMs over it), measured at 6.3 s of 27 s at 199,200 DOF when done for
                // every pair as it converged.
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                continue;
            }
            let locked = self.lock_candidates(&basis, m, &eig, &candidates)?;
            let keep: Vec<usize> = order.iter().copied().filter(|&r| !locked[r]).collect();
            let locked_now = m - keep.len();
            if locked_now > 0 && !keep.is_empty() {
                // a mode far nearer the shift than the rest was just locked: the basis built
                // before carries its round-off into every other Ritz vector; start afresh,
                // deflated against it
                let next = 1.0 / eig.eigenvalues[keep[0]].abs().max(f64::MIN_POSITIVE);
                let fresh = &self.values[self.values.len() - locked_now..];
                if fresh
                    .iter()
                    .any(|v| (v - self.sigma).abs() < CLOSE_LOCK * next)
                {
                    self.force_random_start = true;
                }
            }
            if self.values.len() >= want {
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                return Ok(());
            }
            if !full {
                if locked_now > 0 {
                    // deflate the pairs just locked: keep every other Ritz vector (the same
                    // subspace without the locked directions) and the unapplied block
                    self.thick_restart(
                        &mut basis,
                        &mut mbasis,
                        &mut h,
                        m,
                        keep.len(),
                        &keep,
                        &eig,
                        &coupling,
                    );
                    applied = keep.len();
                }
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                continue;
            }
            stats.ritz_seconds += t.elapsed().as_secs_f64();
            restarts += 1;
            stats.restarts += 1;
            if restarts > self.params.max_restarts {
                return Err(SparseError::NoConvergence {
                    reason: format!(
                        "{} of {} eigenpairs converged after {} restarts: ask for fewer modes, or \
                         solve nearer the wanted ones (a shift), or allow more restarts",
                        self.values.len(),
                        want,
                        restarts - 1
                    ),
                });
            }
            // Thick restart: keep the best unlocked Ritz vectors and the extra (residual) vectors.
            let kk = keep
                .len()
                .min(((need + p).max(m / 2)).min(m.saturating_sub(p).max(1)));
            let t = Instant::now();
            self.thick_restart(
                &mut basis,
                &mut mbasis,
                &mut h,
                m,
                kk,
                &keep,
                &eig,
                &coupling,
            );
            applied = kk;
            stats.ritz_seconds += t.elapsed().as_secs_f64();
        }
    }

    /// Locks the Ritz pairs `candidates` of the first `m` basis columns that converge; which of
    /// the `m` pairs locked. Their Ritz vectors `V_m S` come by one GEMM, their K and M images by
    /// one sparse product each.
    fn lock_candidates(
        &mut self,
        basis: &Columns,
        m: usize,
        eig: &nalgebra::SymmetricEigen<f64, nalgebra::Dyn>,
        candidates: &[usize],
    ) -> Result<Vec<bool>, SparseError> {
        let mut locked = vec![false; m];
        if candidates.is_empty() {
            return Ok(locked);
        }
        let s_c = Mat::from_fn(m, candidates.len(), |j, c| {
            eig.eigenvectors[(j, candidates[c])]
        });
        let y = basis.range(0, m) * &s_c;
        let ky = crate::csc::sym_mul_mat(self.pencil.k, y.as_ref())?;
        let my = crate::csc::sym_mul_mat(self.pencil.m, y.as_ref())?;
        // Ritz vectors of a basis deflated against the locked vectors are M-orthogonal to
        // them and to each other to round-off. One block projection (two GEMMs) makes the
        // first exact and the Gram matrix checks the second, so that a pair locks without
        // a Gram-Schmidt of its own against every locked vector (0.43 s of a 10 s solve
        // at 199,200 DOF). A candidate the projection moves, or a block that is not
        // orthogonal, takes the pair-by-pair path of `lock_with` from the unprojected
        // vector, whose images `ky`, `my` are.
        let mut projected = y.clone();
        let mut clean = self.project_locked(&mut projected, &my);
        let gram = my.transpose() * &projected;
        let nc = candidates.len();
        let diag = |i: usize| gram[(i, i)].abs().sqrt();
        if (0..nc).any(|i| (0..i).any(|j| gram[(i, j)].abs() > 1e-10 * diag(i) * diag(j))) {
            clean.iter_mut().for_each(|c| *c = false);
        }
        for (c, &r) in candidates.iter().enumerate() {
            let col = |a: &Mat<f64>| -> Vec<f64> { a.col(c).iter().copied().collect() };
            let (yc, kyc, myc) = (slice(&y, c), slice(&ky, c), slice(&my, c));
            let lambda = self.sigma + 1.0 / eig.eigenvalues[r];
            let (rho, eta, relative) = self.residuals_of(yc, kyc, myc, 1.0, lambda);
            // With the shift on (or within round-off of) an eigenvalue, `(K - sigma M) x`
            // vanishes and the shifted residual cannot be small: the classical relative
            // residual decides; rigid-body modes can only meet the backward error.
            let converged =
                rho < self.params.tol || eta < BACKWARD_LOCK || relative < self.params.tol;
            locked[r] = converged
                && if clean[c] {
                    self.push_normalised(slice(&projected, c), kyc, myc)
                } else {
                    self.lock_with(col(&y), col(&ky), col(&my))
                };
        }
        Ok(locked)
    }

    /// Thick restart: the basis becomes the Ritz vectors `keep[..kk]` of its first `m` columns
    /// (GEMMs) followed by its unapplied columns, with the projection `diag(theta)` and the Ritz
    /// pairs' coupling to those columns.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn thick_restart(
        &self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        m: usize,
        kk: usize,
        keep: &[usize],
        eig: &nalgebra::SymmetricEigen<f64, nalgebra::Dyn>,
        coupling: &[Vec<f64>],
    ) {
        let keep = &keep[..kk];
        let extra = basis.len() - m;
        let sk = Mat::from_fn(m, kk, |j, c| eig.eigenvectors[(j, keep[c])]);
        basis.rotate_front(m, sk.as_ref());
        mbasis.rotate_front(m, sk.as_ref());
        let mut nh: Vec<Vec<f64>> = Vec::with_capacity(kk);
        for (i, r) in keep.iter().enumerate() {
            let mut col = vec![0.0; kk + extra];
            col[i] = eig.eigenvalues[*r];
            for e in 0..extra {
                col[kk + e] = coupling[e][*r];
            }
            nh.push(col);
        }
        *h = nh;
        // The Rayleigh-Ritz phase's and the solves' temporaries (Ritz vectors and their images,
        // the sparse products' row-major copies) are freed into glibc's arenas by the threads
        // that used them and stay resident there, under the basis that grows until the next
        // restart: returned here, the peaks of the 52,920-DOF block and the 47,628-DOF plate fell
        // by 7-42 and 9-19 MB in four alternated pairs each, for about 10 ms (docs/SCALING.md,
        // "Memory the allocator keeps").
        crate::multifrontal::release_free_memory();
    }

    /// Locks a converged Ritz vector: M-orthonormalised against the locked set, eigenvalue from
    /// its Rayleigh quotient. Returns false if it was not independent of the locked vectors.
    /// [`Lanczos::lock`] of a Ritz vector whose `K` and `M` images are known: they are reused
    /// when the orthogonalisation against the locked vectors leaves the vector as it was (it is
    /// already orthogonal to them to round-off), and recomputed otherwise.
    pub(super) fn lock_with(&mut self, mut y: Vec<f64>, ky: Vec<f64>, my: Vec<f64>) -> bool {
        let before: Vec<f64> = y.clone();
        let empty = Columns::new(self.n);
        let _ = self.orthogonalize(&mut y, &empty, &empty);
        let moved = norm(
            &y.iter()
                .zip(&before)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        );
        if moved > 1e-10 * norm(&before) {
            return self.lock(y);
        }
        self.push_normalised(&y, &ky, &my)
    }

    /// `w -= X c` with `c = (M X)^T w` against the locked vectors `X`, for the columns of `w`
    /// whose M images are `mw`; per column, whether the projection left it as it was (`||c||`,
    /// the M-norm of what was removed, at most `1e-10` of the column's M-norm), so that its images
    /// still hold.
    pub(super) fn project_locked(&self, w: &mut Mat<f64>, mw: &Mat<f64>) -> Vec<bool> {
        let c = project_out(self.x.mat(), self.mx.mat(), w.as_mut());
        (0..w.ncols())
            .map(|j| {
                let m_norm = dot(slice(mw, j), slice(w, j)).abs().sqrt();
                c.col(j).norm_l2() <= 1e-10 * m_norm
            })
            .collect()
    }

    /// Locks `y` (M-orthogonal to the locked vectors) with its images `K y`, `M y`, normalised:
    /// the M-normalised vector and its M image are written into the locked set directly, and the
    /// Rayleigh quotient and residual are taken from the normalised values as they are made, with
    /// no copies. Returns false if its M-norm is below 0.5 (it was not independent of the locked
    /// vectors).
    pub(super) fn push_normalised(&mut self, y: &[f64], ky: &[f64], my: &[f64]) -> bool {
        let nrm = dot(my, y).max(0.0).sqrt();
        if nrm.is_nan() || nrm <= 0.5 {
            return false;
        }
        let lambda = ky.iter().zip(y).map(|(k, x)| (k / nrm) * (x / nrm)).sum();
        let rho = self.residuals_of(y, ky, my, nrm, lambda).0;
        self.x.push_divided(y, nrm);
        self.mx.push_divided(my, nrm);
        self.values.push(lambda);
        self.shifted_res.push(rho);
        true
    }

    /// Stores a locked M-normalised vector with its images; eigenvalue from its Rayleigh quotient.
    pub(super) fn push_locked(&mut self, x: Vec<f64>, kx: Vec<f64>, mx: Vec<f64>) {
        let lambda = dot(&kx, &x);
        let rho = self.residuals_of(&x, &kx, &mx, 1.0, lambda).0;
        self.x.push(&x);
        self.mx.push(&mx);
        self.values.push(lambda);
        self.shifted_res.push(rho);
    }

    pub(super) fn lock(&mut self, mut y: Vec<f64>) -> bool {
        let empty = Columns::new(self.n);
        let _ = self.orthogonalize(&mut y, &empty, &empty);
        let my = self.m_times(&y);
        let nrm = dot(&my, &y).max(0.0).sqrt();
        if nrm.is_nan() || nrm <= 0.5 {
            return false;
        }
        let x: Vec<f64> = y.iter().map(|v| v / nrm).collect();
        let mx: Vec<f64> = my.iter().map(|v| v / nrm).collect();
        let mut kx = vec![0.0; self.n];
        crate::csc::mul_vec(self.pencil.k, &x, &mut kx).expect("sizes checked");
        self.push_locked(x, kx, mx);
        true
    }

    /// `(||K x - lambda M x|| / ||(K - sigma M) x||, backward error, ||K x - lambda M x|| / ||K x||)`
    /// from `K x` and `M x`, for `x`, `K x`, `M x` the given vectors divided by `scale` (1: as
    /// they are), in one pass without copies. A pair is converged when the first or the third
    /// is below `tol` or the backward error is at round-off (1e-13): rigid-body modes, with
    /// `K x` pure round-off, can only meet the latter.
    pub(super) fn residuals_of(
        &self,
        x: &[f64],
        kx: &[f64],
        mx: &[f64],
        scale: f64,
        lambda: f64,
    ) -> (f64, f64, f64) {
        let (mut rr, mut ss, mut xx, mut kk) = (0.0, 0.0, 0.0, 0.0);
        for ((x, k), m) in x.iter().zip(kx).zip(mx) {
            let (x, k, m) = (x / scale, k / scale, m / scale);
            let (r, s) = (k - lambda * m, k - self.sigma * m);
            rr += r * r;
            ss += s * s;
            xx += x * x;
            kk += k * k;
        }
        let (rn, sn, xn, kn) = (rr.sqrt(), ss.sqrt(), xx.sqrt(), kk.sqrt());
        let eta = rn
            / ((self.pencil.k_norm + lambda.abs() * self.pencil.m_norm) * xn)
                .max(f64::MIN_POSITIVE);
        (
            rn / sn.max(f64::MIN_POSITIVE),
            eta,
            rn / kn.max(f64::MIN_POSITIVE),
        )
    }

    pub(super) fn finish(
        &self,
        mut sel: Vec<usize>,
        sigma: f64,
        sturm: SturmCheck,
        requested: usize,
        mut stats: EigenStats,
    ) -> Modes {
        let t = Instant::now();
        sel.sort_by(|a, b| self.values[*a].total_cmp(&self.values[*b]));
        let vectors = Mat::from_fn(self.n, sel.len(), |i, j| self.x.col(sel[j])[i]);
        // K X for every returned mode in one product (K read once, not once per mode)
        let kx = crate::csc::sym_mul_mat(self.pencil.k, vectors.as_ref()).expect("sizes checked");
        let (residuals, residual_kinds): (Vec<f64>, Vec<ResidualKind>) = sel
            .iter()
            .enumerate()
            .map(|(j, &s)| {
                residual_from(
                    slice(&kx, j),
                    self.pencil.norms(),
                    self.x.col(s),
                    self.mx.col(s),
                    self.values[s],
                )
            })
            .unzip();
        stats.ritz_seconds += t.elapsed().as_secs_f64();
        Modes {
            values: sel.iter().map(|s| self.values[*s]).collect(),
            vectors,
            residuals,
            residual_kinds,
            shifted_residuals: sel.iter().map(|s| self.shifted_res[*s]).collect(),
            requested,
            shift: sigma,
            sturm,
            stats,
            factor: None,
        }
    }
}
