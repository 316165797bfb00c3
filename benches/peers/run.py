"""Side-by-side eigensolver comparison on one model: femu, CalculiX (*FREQUENCY), scipy's eigsh
(ARPACK shift-invert) with SuperLU, MKL PARDISO or CHOLMOD factors, and SLEPc (Krylov-Schur with
MUMPS) on one and two MPI ranks, each in its own process under /usr/bin/time for wall time and
peak memory, on the same K and M (femu's export).

    python3 benches/peers/run.py KIND N [COUNT]     (KIND: hex8 | hex20 | tet10 | plate)

Prints a JSON line per tool and a table: wall time of the whole command (femu assembles its
model; the peers read K and M from MatrixMarket files, which at 200k DOF takes seconds), the time
of the eigensolve alone (factorizations included, as each tool reports it), peak memory, the
ratios to femu's, and the largest relative frequency difference against femu. `run.sh` installs the peers first. Environment: PEER_TIMEOUT (seconds,
default 3600) stops a peer and reports a lower bound; PEER_ROUNDS (default 1) runs femu and every
peer that many times, one after the other in rounds, and reports each tool's median time, its
range, its largest peak, and the fastest peer's ratio to femu within each round (median and
range): on a machine whose times move by tens of per cent from run to run, one round's ratio
is good to about 0.1-0.2; PEERS selects peers (default
"calculix,eigsh+pardiso,eigsh+cholmod,slepc+mumps:1,slepc+mumps:2"; "eigsh+superlu" is scipy's
default factorization). PEERS_PYTHON: the Python with scipy, pypardiso, scikit-sparse and
threadpoolctl (run.sh makes a venv). After femu's solve in every round, `peer_modes gemm` measures
faer's dense GEMM on all threads, and femu's factorization rate is reported against it (the goal
"within 3x of the dense GEMM limit"). PEER_FACTOR=R (default 0: off) also times the numeric
factorization alone in every round, R times each: femu's stored factorization and Sturm count
(`peer_modes factor`) and PARDISO's with its own ordering and with femu's
(`pardiso_factor.py`), and prints their rates at one flop count, femu's, on the same factor.
"""
import glob, json, os, re, shutil, statistics, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.path.join(ROOT, "target", "release", "examples", "peer_modes")


# The peers' shift: 10 Hz below zero, below every wanted eigenvalue and away from the rigid-body
# zeros of a free-free deck (femu places its own shift).
SIGMA = -(2 * 3.141592653589793 * 10.0) ** 2


def timed(cmd, cwd, timeout, env=None):
    """Runs cmd under /usr/bin/time -v; a run past `timeout` seconds is killed and reported with
    code None and its wall time as a lower bound."""
    p = subprocess.Popen(["/usr/bin/time", "-v"] + cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        out, err = p.communicate(timeout=timeout)
        code = p.returncode
    except subprocess.TimeoutExpired:
        subprocess.run(["pkill", "-TERM", "-P", str(p.pid)])
        out, err = p.communicate()
        code = None
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", err)
    seconds = sum(float(v) * 60 ** i for i, v in enumerate(reversed(wall.group(1).split(":")))) if wall else float(timeout)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", err)
    return code, out, seconds, int(rss.group(1)) / 1024.0 if rss else float("nan")


def ccx_frequencies(dat):
    text = open(dat).read()
    block = text.split("E I G E N V A L U E   O U T P U T")[1]
    f = []
    for line in block.splitlines():
        m = re.match(r"\s+(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", line)
        if m:
            f.append(float(m.group(4)))
        elif f:
            break
    return f


def json_of(cmd, cwd, env=None):
    """The last line of cmd's output as JSON; a failure stops the run with the command's error."""
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed (exit {p.returncode}): {p.stderr.strip()[-500:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def factor_table(kind, dofs, factor_runs):
    """The numeric factorizations of every round: the first of each kind and the median of the
    others, pooled over the rounds; rates at femu's flop count of its factor, which PARDISO
    factors too when given femu's ordering (its own ordering's factor is about as large; its rate
    there is at its own count scaled by the ratio of the two counts on femu's ordering)."""
    femu_flops = factor_runs[0][0]["factor_flops"]
    rest = lambda lists: statistics.median([t for ts in lists for t in ts[1:]] or [t for ts in lists for t in ts])
    firsts = lambda lists: f"{min(ts[0] for ts in lists):.3f}-{max(ts[0] for ts in lists):.3f}"
    p0 = factor_runs[0][1]
    scale = femu_flops * 1e-9 / p0["femu_ordering"]["factor_gflop"]
    dense = p0["dense"]
    print(f"\n{kind}, {dofs} DOF: the numeric factorization of K - sigma M alone, {len(factor_runs)} round(s) of "
          f"{len(factor_runs[0][0]['factor_s'])}; rates at femu's count of its factor ({femu_flops * 1e-9:.3f} GFLOP). "
          f"PARDISO counts {p0['femu_ordering']['factor_gflop']:.3f} GFLOP for the same factor ({1 / scale:.3f}x) and "
          f"{dense['pardiso_gflop']:.3f} for a dense {dense['n']} x {dense['n']} matrix whose classical count is {dense['classical_gflop']:.3f}\n")
    print("| factorization | entries | its flop count (GFLOP) | first (s) | the others, median (s) | GFLOP/s at femu's count |")
    print("|---|---|---|---|---|---|")
    for name, times, entries, gflop, flops in (
        ("femu, stored", [f["factor_s"] for f, _ in factor_runs], factor_runs[0][0]["factor_len"], femu_flops * 1e-9, femu_flops * 1e-9),
        ("femu, Sturm count (no factor kept)", [f["count_s"] for f, _ in factor_runs], factor_runs[0][0]["factor_len"], femu_flops * 1e-9, femu_flops * 1e-9),
        ("PARDISO, femu's ordering", [p["femu_ordering"]["factor_s"] for _, p in factor_runs], p0["femu_ordering"]["factor_nnz"], p0["femu_ordering"]["factor_gflop"], femu_flops * 1e-9),
        ("PARDISO, its own ordering", [p["own"]["factor_s"] for _, p in factor_runs], p0["own"]["factor_nnz"], p0["own"]["factor_gflop"], p0["own"]["factor_gflop"] * scale),
    ):
        t = rest(times)
        print(f"| {name} | {entries / 1e6:.2f}M | {gflop:.3f} | {firsts(times)} | {t:.3f} | {flops / t:.1f} |")
    print(flush=True)


def main():
    kind, n = sys.argv[1], int(sys.argv[2])
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    limit = float(os.environ.get("PEER_TIMEOUT", "3600"))
    d = tempfile.mkdtemp(prefix=f"femu-peers-{kind}-{n}-")
    info = json.loads(subprocess.run([EXE, "export", kind, str(n), str(count), d], capture_output=True, text=True, check=True).stdout)
    dofs = info["dofs"]
    rounds = max(1, int(os.environ.get("PEER_ROUNDS", "1")))
    script = lambda name: os.path.join(ROOT, "benches", "peers", name)
    # absolute: the tools run in the export directory
    venv = os.path.abspath(os.environ.get("PEERS_PYTHON", sys.executable))
    debian = "/usr/bin/python3"  # petsc4py and slepc4py from Debian's packages
    sigma = str(SIGMA)
    peers = [
        ("calculix", ["ccx", "model"]),
        ("eigsh+superlu", [venv, script("scipy_eigsh.py"), d, str(count), sigma, "superlu"]),
        ("eigsh+pardiso", [venv, script("scipy_eigsh.py"), d, str(count), sigma, "pardiso"]),
        ("eigsh+cholmod", [venv, script("scipy_eigsh.py"), d, str(count), sigma, "cholmod"]),
        ("slepc+mumps:1", ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", "1", debian, script("slepc_eigs.py"), "solve", d, str(count), sigma]),
        ("slepc+mumps:2", ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", "2", debian, script("slepc_eigs.py"), "solve", d, str(count), sigma]),
    ]
    wanted = os.environ.get("PEERS", "calculix,eigsh+pardiso,eigsh+cholmod,slepc+mumps:1,slepc+mumps:2").split(",")
    # Debian's petsc4py and slepc4py find PETSc and SLEPc through these (as femu's SLEPc engine)
    petsc_env = {}
    for var, root in (("PETSC_DIR", "/usr/lib/petscdir"), ("SLEPC_DIR", "/usr/lib/slepcdir")):
        versions = sorted(glob.glob(os.path.join(root, "*", "*-real")))
        if versions:
            petsc_env[var] = versions[-1]
    if any(t.startswith("slepc") for t in wanted):
        subprocess.run([debian, script("slepc_eigs.py"), "convert", d], check=True, env=dict(os.environ, **petsc_env))
    # runs[tool] = [(wall, rss, eigensolve, note)], one per round; femu first in every round
    runs = {}
    ref = None
    factor_reps = int(os.environ.get("PEER_FACTOR", "0"))
    factor_runs = []
    # the GEMM limit over femu's factorization rate, one per round
    gemm_gaps = []
    for r in range(rounds):
        code, out, femu_wall, rss = timed([EXE, "solve", kind, str(n), str(count)], d, limit)
        femu = json.loads(out)
        # the factorizations' rate: the symbolic flop count of one, times their number, over their time
        femu_rate = femu["factorizations"] * femu["factor_flops"] / femu["factor_s"] * 1e-9
        # the dense GEMM limit of this minute (faer's, on all threads): the goal sets the
        # factorization's rate against it, and this machine's limit moves by up to 2x
        gemm = json_of([EXE, "gemm"], d)["gflops_best"]
        gemm_gaps.append(gemm / femu_rate)
        print(json.dumps({"kind": kind, "dofs": dofs, "tool": "femu", "round": r + 1, "wall_s": femu_wall, "rss_mb": rss, "gemm_gflops": gemm, **femu}), flush=True)
        print(f"{kind} {dofs} DOF: femu     wall {femu_wall:8.2f} s, peak {rss:8.0f} MB "
              f"(assembly {femu['assembly_s']} s with the ordering+symbolic analysis beside it ({femu.get('analysis_s', 0)} s), input checks {femu.get('check_s', 0)} s, "
              f"ordering+symbolic in the solve {femu['symbolic_s']} s, factor {femu['factor_s']} s x{femu['factorizations']} "
              f"({femu_rate:.1f} GFLOP/s of {femu['factor_flops'] * 1e-9:.1f} GFLOP each, {gemm_gaps[-1]:.1f}x below "
              f"the GEMM limit of {gemm:.0f} GFLOP/s measured after it), "
              f"solves {femu['solve_s']} s for {femu['solved_vectors']} vectors, orthogonalisation {femu['orth_s']} s, "
              f"Rayleigh-Ritz and checks {femu['ritz_s']} s, other {femu['other_s']} s), "
              f"Sturm verified {femu['sturm_verified']}", flush=True)
        if ref is None:
            ref = femu["frequencies_hz"]
        else:
            moved = max(abs(a - b) / b for a, b in zip(femu["frequencies_hz"], ref) if b > 1e-3 * ref[-1])
            if moved > 1e-12:
                print(f"femu's frequencies in round {r + 1} differ from round 1's by {moved:.1e}", flush=True)
        runs.setdefault("femu", []).append((femu_wall, rss, femu["eigen_s"], f"{femu['factorizations']} factorizations, {femu['solved_vectors']} solved vectors, Sturm verified {femu['sturm_verified']}"))
        for tool, cmd in peers:
            if tool not in wanted:
                continue
            # one BLAS thread per MPI rank, two threads otherwise (the machine has two cores)
            threads = "1" if tool == "slepc+mumps:2" else "2"
            env = dict(os.environ, OMP_NUM_THREADS=threads, OPENBLAS_NUM_THREADS=threads, MKL_NUM_THREADS=threads)
            if tool.startswith("slepc"):
                env.update(petsc_env)
            code, out, wall, rss = timed(cmd, d, limit, env)
            if code is None:
                print(f"{kind} {dofs} DOF: {tool:14s} stopped after {wall:.0f} s at {rss:.0f} MB without finishing", flush=True)
                runs.setdefault(tool, []).append((wall, rss, None, f"failed (stopped after {wall:.0f} s, a lower bound)"))
                continue
            info = {}
            if tool == "calculix":
                f = ccx_frequencies(os.path.join(d, "model.dat")) if code == 0 else []
            else:
                info = json.loads(out.strip().splitlines()[-1]) if code == 0 else {}
                f = info.get("frequencies_hz", [])
            diff = max((abs(a - b) / b for a, b in zip(f, ref) if b > 1e-3 * ref[-1]), default=float("nan"))
            note = f"max rel. frequency difference to femu {diff:.1e}"
            if info.get("factor_s"):
                note += f", factorization {info['factor_s']:.2f} s"
            if info.get("factor_gflop"):
                # PARDISO's numeric factorization alone, at its own flop count, beside femu's rate
                note += (f" (numeric, {info['factor_gflop'] / info['factor_s']:.1f} GFLOP/s of its {info['factor_gflop']:.1f} GFLOP, "
                         f"{info['factor_nnz'] / 1e6:.1f}M entries; femu {femu_rate:.1f} GFLOP/s of {femu['factor_flops'] * 1e-9:.1f}, "
                         f"{femu['factor_len'] / 1e6:.1f}M; analysis {info['analysis_s']:.2f} s)")
            if info.get("applications"):
                note += f", {info['applications']} solves"
            if info.get("blas"):
                note += f", BLAS: {'; '.join(info['blas'])}"
            if code != 0 or len(f) < len(ref):
                note = f"failed (exit {code}): {out.strip()[-300:]}"
            print(json.dumps({"kind": kind, "dofs": dofs, "tool": tool, "round": r + 1, "wall_s": wall, "rss_mb": rss, "ok": code == 0, "max_rel_diff": diff, **{k: v for k, v in info.items() if k != "frequencies_hz"}}), flush=True)
            runs.setdefault(tool, []).append((wall, rss, info.get("eigen_s"), note))
        if factor_reps:
            env = dict(os.environ, OMP_NUM_THREADS="2", MKL_NUM_THREADS="2")
            femu_f = json_of([EXE, "factor", kind, str(n), str(factor_reps)], d)
            pardiso_f = json_of([venv, script("pardiso_factor.py"), d, sigma, str(factor_reps)], d, env)
            print(json.dumps({"kind": kind, "dofs": dofs, "tool": "factorization", "round": r + 1, "femu": femu_f, "pardiso": pardiso_f}), flush=True)
            factor_runs.append((femu_f, pardiso_f))
    if factor_runs:
        factor_table(kind, dofs, factor_runs)
    good = {t: [x for x in v if not x[3].startswith("failed")] for t, v in runs.items()}
    # the fastest peer over femu within each round (a peer that failed or stopped in a round is
    # left out of that round)
    ratios, solve_ratios = [], []
    for r in range(rounds):
        femu_r = runs["femu"][r]
        peer_r = [v[r] for t, v in runs.items() if t != "femu" and len(v) > r and not v[r][3].startswith("failed")]
        if peer_r:
            ratios.append(min(x[0] for x in peer_r) / femu_r[0])
            solves = [x[2] for x in peer_r if x[2]]
            if solves:
                solve_ratios.append(min(solves) / femu_r[2])
    spread = lambda xs: f" (median of {len(xs)} rounds, {min(xs):.2f}-{max(xs):.2f})" if len(xs) > 1 else ""
    fmt = lambda xs: f"{statistics.median(xs):.2f}x{spread(xs)}" if xs else "nan"
    against = f"fastest peer / femu: {fmt(ratios)} in wall time, {fmt(solve_ratios)} in eigensolve time" if ratios else "no peer ran"
    print(f"\n{kind}, {dofs} DOF, {count} lowest modes (sigma {SIGMA:g} s^-2 for the peers); {against}\n")
    print("| tool | wall (s) | eigensolve (s) | peak RSS (MB) | wall / femu's | eigensolve / femu's | notes |")
    print("|---|---|---|---|---|---|---|")
    femu_wall = statistics.median([x[0] for x in good["femu"]])
    femu_solve = statistics.median([x[2] for x in good["femu"]])
    for tool, all_runs in runs.items():
        ok_runs = good[tool]
        if not ok_runs:
            print(f"| {tool} | - | - | - | - | - | {all_runs[0][3]} |")
            continue
        wall = statistics.median([x[0] for x in ok_runs])
        mb = max(x[1] for x in ok_runs)
        solves = [x[2] for x in ok_runs if x[2]]
        solve = statistics.median(solves) if solves else None
        note = ok_runs[0][3]
        if tool == "femu" and gemm_gaps:
            note += f", factorization {min(gemm_gaps):.1f}-{max(gemm_gaps):.1f}x below the GEMM limit"
        if len(ok_runs) > 1:
            walls = [x[0] for x in ok_runs]
            note += f"; wall {min(walls):.{2 if max(walls) < 10 else 1}f}-{max(walls):.{2 if max(walls) < 10 else 1}f} s over {len(ok_runs)} rounds"
        if len(ok_runs) < len(all_runs):
            note += f"; {len(all_runs) - len(ok_runs)} round(s) failed"
        sr = f"{solve / femu_solve:.2f}" if solve else "-"
        st = f"{solve:.1f}" if solve else "-"
        print(f"| {tool} | {wall:.1f} | {st} | {mb:.0f} | {wall / femu_wall:.2f} | {sr} | {note} |")
    print(flush=True)
    # the exported decks and matrices (about 1 GB at 200k DOF); PEERS_KEEP=1 keeps them
    if not os.environ.get("PEERS_KEEP"):
        shutil.rmtree(d, ignore_errors=True)


if __name__ == "__main__":
    main()
