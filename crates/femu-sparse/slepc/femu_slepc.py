"""femu's SLEPc driver: the eigenproblem K x = lambda M x handed to SLEPc (Krylov-Schur with
shift-and-invert, MUMPS factors) under MPI, with the count of eigenvalues by the inertia of
K - sigma M factored by MUMPS. femu writes the request and reads the result back.

    mpirun -n N python3 femu_slepc.py DIR

DIR holds K.petsc and M.petsc (PETSc binary AIJ, written by femu), request.json:
  {"kind": "lowest", "count": n, "sigma": s} | {"kind": "nearest", "count": n, "sigma": s}
  | {"kind": "band", "lo": a, "hi": b}, with "tol", "extra" (eigenpairs beyond the count, to find
  a gap above), "max_it", "ncv" (0: SLEPc's choice);
and receives result.json (eigenvalues, the counted interval and its count by inertia, the solves
made and the entries of MUMPS's factor, timings)
and vectors.bin (the eigenvectors, float64 little-endian, one after another), or error.json.
"""

import json
import os
import sys
import time
import traceback

import petsc4py

petsc4py.init(sys.argv[2:])
from petsc4py import PETSc  # noqa: E402
import slepc4py  # noqa: E402

slepc4py.init(sys.argv[2:])
from slepc4py import SLEPc  # noqa: E402

COMM = PETSc.COMM_WORLD
RANK = COMM.getRank()


def write_json(path, value):
    if RANK == 0:
        with open(path + ".part", "w") as f:
            json.dump(value, f)
        os.replace(path + ".part", path)


def load(directory, name):
    viewer = PETSc.Viewer().createBinary(os.path.join(directory, name), "r", comm=COMM)
    a = PETSc.Mat().create(comm=COMM)
    a.setType(PETSc.Mat.Type.AIJ)
    a.load(viewer)
    viewer.destroy()
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    return a


def mumps(pc):
    pc.setType(PETSc.PC.Type.CHOLESKY)
    pc.setFactorSolverType("mumps")


def count_below(k, m, sigma):
    """Eigenvalues of (K, M) below sigma: the negative inertia of K - sigma M (M positive
    definite, Sylvester's law), from MUMPS's symmetric indefinite factor."""
    a = k.copy()
    a.axpy(-sigma, m, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    a.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    a.setOption(PETSc.Mat.Option.SPD, False)
    ksp = PETSc.KSP().create(comm=COMM)
    ksp.setOperators(a)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    mumps(pc)
    # the inertia of a parallel MUMPS factor is exact only without ScaLAPACK at the root, and
    # PETSc reports it only with null-pivot detection on
    PETSc.Options().setValue("mat_mumps_icntl_13", 1)
    PETSc.Options().setValue("mat_mumps_icntl_24", 1)
    ksp.setFromOptions()
    ksp.setUp()
    nneg, nzero, _ = pc.getFactorMatrix().getInertia()
    ksp.destroy()
    a.destroy()
    return int(nneg), int(nzero)


def main(directory):
    req = json.load(open(os.path.join(directory, "request.json")))
    t0 = time.perf_counter()
    k = load(directory, "K.petsc")
    m = load(directory, "M.petsc")
    t_load = time.perf_counter() - t0
    eps = SLEPc.EPS().create(comm=COMM)
    eps.setOperators(k, m)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    ksp = st.getKSP()
    ksp.setType(PETSc.KSP.Type.PREONLY)
    mumps(ksp.getPC())
    kind = req["kind"]
    if kind == "band":
        # spectrum slicing: SLEPc counts by inertia itself; femu counts again below
        eps.setWhichEigenpairs(SLEPc.EPS.Which.ALL)
        eps.setInterval(req["lo"], req["hi"])
        # the slices factor with the spectral transformation's prefix (and, in parallel, their
        # own): exact inertia needs these MUMPS settings on every factor
        for prefix in ("", "st_", "eps_slice_st_"):
            PETSc.Options().setValue(prefix + "mat_mumps_icntl_13", 1)
            PETSc.Options().setValue(prefix + "mat_mumps_icntl_24", 1)
    else:
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(req["sigma"])
        nev = req["count"] + req["extra"]
        ncv = req.get("ncv", 0) or PETSc.DECIDE
        eps.setDimensions(nev=nev, ncv=ncv)
    eps.setTolerances(tol=req["tol"], max_it=req["max_it"])
    eps.setFromOptions()
    # PETSc's log counts the shift-and-invert's solves (one KSPSolve per vector)
    PETSc.Log.begin()
    solves = PETSc.Log.Event("KSPSolve")
    solves_before = solves.getPerfInfo()["count"]
    t1 = time.perf_counter()
    eps.solve()
    t_solve = time.perf_counter() - t1
    solved = int(solves.getPerfInfo()["count"] - solves_before)
    factor_entries = None
    if kind != "band":
        # the entries of MUMPS's factor of K - sigma M (INFOG(29), in millions when negative);
        # spectrum slicing factors by its own sub-solvers, whose factors are not reported
        infog29 = ksp.getPC().getFactorMatrix().getMumpsInfog(29)
        factor_entries = infog29 if infog29 >= 0 else -infog29 * 1000000
    nconv = eps.getConverged()
    its = eps.getIterationNumber()
    want = req.get("count", 0) + req.get("extra", 0) if kind != "band" else 0
    if kind != "band" and nconv < want:
        raise RuntimeError(
            f"SLEPc converged {nconv} of {want} eigenpairs in {its} iterations "
            f"(tolerance {req['tol']:g}): raise the iterations or the basis size"
        )
    values = [eps.getEigenvalue(i).real for i in range(nconv)]
    vr = k.createVecRight()
    scatter, v0 = PETSc.Scatter.toZero(vr)
    vectors = []
    for i in range(nconv):
        eps.getEigenvector(i, vr)
        scatter.scatter(vr, v0, False, PETSc.Scatter.Mode.FORWARD)
        if RANK == 0:
            vectors.append(v0.getArray().copy())
    # the counts by inertia, at ends in the gaps of the values found
    order = sorted(range(nconv), key=lambda i: values[i])
    t2 = time.perf_counter()
    ends = choose_ends(req, [values[i] for i in order])
    counts = [None if s is None else count_below(k, m, s) for s in ends]
    t_count = time.perf_counter() - t2
    if RANK == 0:
        import numpy as np

        with open(os.path.join(directory, "vectors.bin.part"), "wb") as f:
            for i in order:
                np.asarray(vectors[i], dtype="<f8").tofile(f)
        os.replace(
            os.path.join(directory, "vectors.bin.part"), os.path.join(directory, "vectors.bin")
        )
    write_json(
        os.path.join(directory, "result.json"),
        {
            "values": [values[i] for i in order],
            "ends": ends,
            "counts": [None if c is None else list(c) for c in counts],
            "iterations": its,
            "solved": solved,
            "factor_entries": factor_entries,
            "converged": nconv,
            "ranks": COMM.getSize(),
            "seconds": {"load": t_load, "solve": t_solve, "count": t_count},
            "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
            "slepc": ".".join(map(str, SLEPc.Sys.getVersion())),
        },
    )


def choose_ends(req, values):
    """The interval to count: below the lowest or around the nearest `count` values, with ends in
    the gaps to the next values found (femu checks the same choice on its side)."""
    kind = req["kind"]
    if kind == "band":
        return [req["lo"], req["hi"]]
    count = req["count"]
    sigma = req["sigma"]
    if kind == "lowest":
        sel = values[:count]
        rest = values[count:]
        top = sel[-1]
        above = [v for v in rest if v > top * (1 + 1e-8) + 1e-300]
        upper = 0.5 * (top + above[0]) if above else top + max(1e-6 * abs(top), 1e-12)
        return [None, upper]
    by_distance = sorted(values, key=lambda v: abs(v - sigma))
    sel = sorted(by_distance[:count])
    rest = by_distance[count:]
    lo, hi = sel[0], sel[-1]
    above = [v for v in rest if v > hi]
    below = [v for v in rest if v < lo]
    upper = 0.5 * (hi + min(above)) if above else hi + max(1e-6 * abs(hi), 1e-12)
    lower = 0.5 * (lo + max(below)) if below else lo - max(1e-6 * abs(lo), 1e-12)
    return [lower, upper]


if __name__ == "__main__":
    directory = sys.argv[1]
    try:
        main(directory)
    except Exception as e:  # every failure reaches femu as a message
        write_json(
            os.path.join(directory, "error.json"),
            {"error": f"{type(e).__name__}: {e}", "trace": traceback.format_exc()},
        )
        COMM.Barrier()
        sys.exit(3)
