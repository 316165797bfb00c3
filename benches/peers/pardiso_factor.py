"""MKL PARDISO's numeric factorization of K - sigma M alone (pypardiso), with its own ordering and
with femu's (DIR/ordering.txt, written by `peer_modes export`), so that both solvers factor the
same L and their rates can be taken at one flop count:

    pardiso_factor.py DIR SIGMA REPS

For each ordering: the analysis (phase 11), then REPS numeric factorizations (phase 22) one after
the other (the first of its own ordering touches fresh memory, the others may reuse what MKL
kept), PARDISO's count of the factor's entries (iparm 18) and of its flops (iparm 19). Last,
PARDISO's flop count of a dense 1000 x 1000 SPD matrix against the classical count
`sum_j (b_j^2 + 2 b_j)` femu reports (`b_j` the entries below the diagonal of column j): PARDISO
counts more for the same elimination (docs/SCALING.md, "PARDISO's flop count"). Prints one JSON
line.
"""
import json, sys, time
import numpy as np
import scipy.io, scipy.sparse as sp
import pypardiso


def factorize(a_upper, reps, perm=None):
    n = a_upper.shape[0]
    ps = pypardiso.PyPardisoSolver(mtype=2)  # real symmetric positive definite
    if perm is not None:
        # iparm 1: not the defaults; 2: METIS (unused with a given permutation); 5: perm is given
        ps.set_iparm(1, 1)
        ps.set_iparm(2, 2)
        ps.set_iparm(5, 1)
        ps.perm = (perm + 1).astype(np.int32)
    ps.set_iparm(18, -1)
    ps.set_iparm(19, -1)
    ps._check_A(a_upper)
    ps.factorized_A = a_upper.copy()
    rhs = np.zeros((n, 1))
    t = time.perf_counter()
    ps.set_phase(11)
    ps._call_pardiso(a_upper, rhs)
    analysis_s = time.perf_counter() - t
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        ps.set_phase(22)
        ps._call_pardiso(a_upper, rhs)
        times.append(time.perf_counter() - t)
    out = {"analysis_s": analysis_s, "factor_s": times, "factor_nnz": int(ps.get_iparm(18)), "factor_gflop": ps.get_iparm(19) * 1e-3}
    ps.free_memory(everything=True)
    return out


def dense_calibration(n=1000):
    rng = np.random.default_rng(1)
    b = rng.standard_normal((n, n))
    a = sp.triu(sp.csr_matrix(b @ b.T + n * np.eye(n)), format="csr")
    got = factorize(a, 1)["factor_gflop"]
    classical = sum(k * k + 2 * k for k in range(n)) * 1e-9
    return {"n": n, "pardiso_gflop": got, "classical_gflop": classical}


d, sigma, reps = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
K = scipy.io.mmread(f"{d}/K.mtx").tocsr()
M = scipy.io.mmread(f"{d}/M.mtx").tocsr()
A = sp.triu((K - sigma * M).tocsr(), format="csr")
A.sort_indices()
fwd = np.loadtxt(f"{d}/ordering.txt", dtype=np.int64)
if sorted(fwd.tolist()) != list(range(A.shape[0])):
    raise SystemExit(f"{d}/ordering.txt is not a permutation of 0..{A.shape[0] - 1}")
# MKL's perm as femu writes it, the original row of each pivot: with it PARDISO reports the
# entries and flops of femu's factor (its inverse, tried, gave a factor of another size)
own = factorize(A, reps)
femu_order = factorize(A, reps, fwd)
calibration = dense_calibration()  # last: the factorizations above start on fresh memory
print(json.dumps({"dense": calibration, "own": own, "femu_ordering": femu_order}))
