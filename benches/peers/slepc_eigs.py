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

if sys.argv[1] == "convert":
    import scipy.io

    d = sys.argv[2]
    for name in ("K", "M"):
        a = scipy.io.mmread(os.path.join(d, f"{name}.mtx")).tocsr()
        m = PETSc.Mat().createAIJ(size=a.shape, csr=(a.indptr, a.indices, a.data), comm=PETSc.COMM_SELF)
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
