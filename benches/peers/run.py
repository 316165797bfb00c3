"""Side-by-side eigensolver comparison on one model: femu, CalculiX (*FREQUENCY) and scipy eigsh
(shift-invert), each in its own process under /usr/bin/time for wall time and peak memory.

    python3 benches/peers/run.py KIND N [COUNT]     (KIND: hex8 | hex20 | tet10)

Prints a JSON line per tool and a summary with the ratios and the largest relative frequency
difference against femu. `run.sh` installs the peers first. Environment: PEER_TIMEOUT (seconds,
default 3600) stops a peer and reports a lower bound; PEERS selects peers (default
"calculix,scipy").
"""
import json, os, re, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.path.join(ROOT, "target", "release", "examples", "peer_modes")


def timed(cmd, cwd, timeout):
    """Runs cmd under /usr/bin/time -v; a run past `timeout` seconds is killed and reported with
    code None and its wall time as a lower bound."""
    p = subprocess.Popen(["/usr/bin/time", "-v"] + cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
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


def main():
    kind, n = sys.argv[1], int(sys.argv[2])
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    limit = float(os.environ.get("PEER_TIMEOUT", "3600"))
    d = tempfile.mkdtemp(prefix=f"femu-peers-{kind}-{n}-")
    info = json.loads(subprocess.run([EXE, "export", kind, str(n), str(count), d], capture_output=True, text=True, check=True).stdout)
    dofs = info["dofs"]
    code, out, femu_wall, rss = timed([EXE, "solve", kind, str(n), str(count)], d, limit)
    femu = json.loads(out)
    print(json.dumps({"kind": kind, "dofs": dofs, "tool": "femu", "wall_s": femu_wall, "rss_mb": rss, **femu}), flush=True)
    print(f"{kind} {dofs} DOF: femu     wall {femu_wall:8.2f} s, peak {rss:8.0f} MB "
          f"(assembly {femu['assembly_s']} s, ordering+symbolic {femu['symbolic_s']} s, factor {femu['factor_s']} s x{femu['factorizations']}, "
          f"solves {femu['solve_s']} s for {femu['solved_vectors']} vectors, orthogonalisation {femu['orth_s']} s), "
          f"Sturm verified {femu['sturm_verified']}", flush=True)
    ref = femu["frequencies_hz"]
    peers = [("calculix", ["ccx", "model"]), ("scipy", [sys.executable, os.path.join(ROOT, "benches", "peers", "scipy_eigsh.py"), d, str(count)])]
    wanted = os.environ.get("PEERS", "calculix,scipy").split(",")
    for tool, cmd in peers:
        if tool not in wanted:
            continue
        code, out, wall, rss = timed(cmd, d, limit)
        if code is None:
            print(f"{kind} {dofs} DOF: {tool:8s} stopped after {wall:.0f} s at {rss:.0f} MB without finishing: "
                  f"femu is more than {wall / femu_wall:.2f}x faster", flush=True)
            continue
        if tool == "calculix":
            f = ccx_frequencies(os.path.join(d, "model.dat")) if code == 0 else []
        else:
            f = json.loads(out)["frequencies_hz"] if code == 0 else []
        diff = max((abs(a - b) / b for a, b in zip(f, ref)), default=float("nan"))
        print(json.dumps({"kind": kind, "dofs": dofs, "tool": tool, "wall_s": wall, "rss_mb": rss, "ok": code == 0}), flush=True)
        print(f"{kind} {dofs} DOF: {tool:8s} wall {wall:8.2f} s, peak {rss:8.0f} MB, femu is {wall / femu_wall:.2f}x faster, "
              f"max rel. freq. difference to femu {diff:.2e}", flush=True)


if __name__ == "__main__":
    main()
