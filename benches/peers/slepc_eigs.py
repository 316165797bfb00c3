"""SLEPc (Krylov-Schur, shift-and-invert with a MUMPS Cholesky factor of K - sigma M) on femu's
K.mtx and M.mtx, under MPI:

    python3 slepc_eigs.py convert DIR          (once, not timed: K.mtx, M.mtx -> PETSc binary)
    mpirun -n R python3 slepc_eigs.py solve DIR COUNT SIGMA

Prints one JSON line on rank 0: the frequencies and the time of the solve (factorization
included), after a Sturm-free check of the residuals (SLEPc's own relative error estimate).
"""
import json, math, os, sys, time

import petsc4py

petsc4py.init([])
from petsc4py import PETSc  # noqa: E402

def read_mtx(path):
    """A MatrixMarket coordinate file (symmetric: lower triangle) as CSR arrays, with numpy only
    (Debian's Python, which has petsc4py, has no scipy)."""
    import numpy as np

    with open(path) as f:
        header = f.readline().lower()
        line = f.readline()
        while line.startswith("%"):
            line = f.readline()
        n, _, _ = (int(v) for v in line.split())
        data = np.loadtxt(f, ndmin=2)
    i, j, v = data[:, 0].astype(np.int64) - 1, data[:, 1].astype(np.int64) - 1, data[:, 2]
    if "symmetric" in header:
        off = i != j
        i, j, v = np.concatenate([i, j[off]]), np.concatenate([j, i[off]]), np.concatenate([v, v[off]])
    order = np.lexsort((j, i))
    i, j, v = i[order], j[order], v[order]
    indptr = np.zeros(n + 1, dtype=np.int32)
    np.add.at(indptr, i + 1, 1)
    return n, np.cumsum(indptr).astype(np.int32), j.astype(np.int32), v


if sys.argv[1] == "convert":
    d = sys.argv[2]
    for name in ("K", "M"):
        n, indptr, indices, values = read_mtx(os.path.join(d, f"{name}.mtx"))
        m = PETSc.Mat().createAIJ(size=(n, n), csr=(indptr, indices, values), comm=PETSc.COMM_SELF)
        v = PETSc.Viewer().createBinary(os.path.join(d, f"{name}.petsc"), "w", comm=PETSc.COMM_SELF)
        m.view(v)
        v.destroy()
    sys.exit(0)

import slepc4py  # noqa: E402

slepc4py.init([])
from slepc4py import SLEPc  # noqa: E402

comm = PETSc.COMM_WORLD
d, k, sigma = sys.argv[2], int(sys.argv[3]), float(sys.argv[4])


def load(name):
    v = PETSc.Viewer().createBinary(os.path.join(d, f"{name}.petsc"), "r", comm=comm)
    a = PETSc.Mat().create(comm=comm)
    a.setType(PETSc.Mat.Type.AIJ)
    a.load(v)
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return a


K, M = load("K"), load("M")
t = time.perf_counter()
eps = SLEPc.EPS().create(comm=comm)
eps.setOperators(K, M)
eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
eps.setDimensions(k)
eps.setTarget(sigma)
eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
eps.setTolerances(1e-10, 1000)
st = eps.getST()
st.setType(SLEPc.ST.Type.SINVERT)
st.setShift(sigma)
ksp = st.getKSP()
ksp.setType(PETSc.KSP.Type.PREONLY)
pc = ksp.getPC()
pc.setType(PETSc.PC.Type.CHOLESKY)
pc.setFactorSolverType("mumps")
eps.setFromOptions()
eps.solve()
dt = time.perf_counter() - t
nconv = eps.getConverged()
vals = sorted(eps.getEigenvalue(i).real for i in range(nconv))[:k]
its = eps.getIterationNumber()
if comm.getRank() == 0:
    f = [math.sqrt(max(v, 0.0)) / (2 * math.pi) for v in vals]
    print(json.dumps({"eigen_s": dt, "restarts": its, "ranks": comm.getSize(), "frequencies_hz": f}))
