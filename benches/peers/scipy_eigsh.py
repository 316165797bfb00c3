"""scipy's eigsh (ARPACK, shift-invert) on femu's K.mtx and M.mtx, with the factorization of
K - sigma M by SuperLU (scipy's default), MKL PARDISO (pypardiso) or CHOLMOD (scikit-sparse):

    scipy_eigsh.py DIR COUNT SIGMA [superlu|pardiso|cholmod] [residuals]

With `residuals` ARPACK also returns its eigenvectors (not in a timed run), and the line gains the
largest relative residual `||K x - lambda M x|| / ||K x||` of the modes with strain energy (femu's
convergence measure at its shift below the spectrum) and the largest normwise backward error of
the zero-energy ones, to compare the solvers' work at the same residual (FEMU_TOL in
examples/peer_modes.rs).

Prints one JSON line: the frequencies, the time of the eigensolve (factorization included) and of
the numeric factorization alone (PARDISO: with its analysis time, its factor's entries and its
flop count), the number of operator applications (solves) and the BLAS libraries
loaded (threadpoolctl).
"""
import json, math, sys, time
import numpy as np
import scipy.io, scipy.sparse.linalg as sla

d, k, sigma = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
solver = sys.argv[4] if len(sys.argv) > 4 else "superlu"
K = scipy.io.mmread(f"{d}/K.mtx").tocsc()
M = scipy.io.mmread(f"{d}/M.mtx").tocsc()
n = K.shape[0]
t = time.perf_counter()
applications = [0]
factor_s = None
extra = {}
if solver == "superlu":
    opinv = None
else:
    A = (K - sigma * M).tocsr()
    if solver == "pardiso":
        import pypardiso

        ps = pypardiso.PyPardisoSolver(mtype=2)  # real symmetric positive definite
        A_upper = __import__("scipy.sparse", fromlist=["triu"]).triu(A, format="csr")
        # ps.factorize(A_upper) in its two phases, to time the numeric factorization alone:
        # analysis (11), then numeric factorization (22), with PARDISO's own count of the
        # factor's entries (iparm 18) and of its flops (iparm 19, in millions)
        ps.set_iparm(18, -1)
        ps.set_iparm(19, -1)
        ps._check_A(A_upper)
        ps.factorized_A = ps._hash_csr_matrix(A_upper) if A_upper.nnz > ps.size_limit_storage else A_upper.copy()
        rhs = np.zeros((n, 1))
        tf = time.perf_counter()
        ps.set_phase(11)
        ps._call_pardiso(A_upper, rhs)
        analysis_s = time.perf_counter() - tf
        tf = time.perf_counter()
        ps.set_phase(22)
        ps._call_pardiso(A_upper, rhs)
        factor_s = time.perf_counter() - tf
        extra = {"analysis_s": analysis_s, "factor_nnz": int(ps.get_iparm(18)), "factor_gflop": ps.get_iparm(19) * 1e-3}

        def solve(b):
            applications[0] += 1
            return ps.solve(A_upper, np.asarray(b, dtype=np.float64))
    elif solver == "cholmod":
        from sksparse.cholmod import cholesky

        tf = time.perf_counter()
        factor = cholesky(A.tocsc())
        factor_s = time.perf_counter() - tf

        def solve(b):
            applications[0] += 1
            return factor(np.asarray(b, dtype=np.float64))
    else:
        raise SystemExit(f"unknown solver {solver}")
    opinv = sla.LinearOperator((n, n), matvec=solve, dtype=np.float64)
residuals = len(sys.argv) > 5 and sys.argv[5] == "residuals"
out = sla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=opinv, return_eigenvectors=residuals)
dt = time.perf_counter() - t
if residuals:
    vals, vecs = out
    # the 1-norms of K and M (largest absolute column sums), as femu's backward error takes them
    k1 = abs(K).sum(axis=0).max()
    m1 = abs(M).sum(axis=0).max()
    rel, backward = [], []
    for j, lam in enumerate(vals):
        x = vecs[:, j]
        kx, mx = K @ x, M @ x
        r = np.linalg.norm(kx - lam * mx)
        if np.linalg.norm(kx) <= 1e-11 * k1 * np.linalg.norm(x):
            backward.append(r / ((k1 + abs(lam) * m1) * np.linalg.norm(x)))
        else:
            rel.append(r / np.linalg.norm(kx))
    extra["max_relative_residual"] = max(rel, default=None)
    extra["max_backward_error"] = max(backward, default=None)
else:
    vals = out
f = sorted(math.sqrt(max(v, 0.0)) / (2 * math.pi) for v in vals)
try:
    from threadpoolctl import threadpool_info

    blas = sorted({f"{i['internal_api']} {i.get('version')} ({i['num_threads']} threads)" for i in threadpool_info() if i.get("user_api") == "blas"})
except ImportError:
    blas = ["threadpoolctl not installed"]
print(json.dumps({"eigen_s": dt, "factor_s": factor_s, "applications": applications[0] or None, "blas": blas, **extra, "frequencies_hz": f}))
