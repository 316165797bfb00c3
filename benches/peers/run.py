"""Side-by-side eigensolver comparison on one model: femu, CalculiX (*FREQUENCY) and scipy eigsh
(shift-invert), each in its own process under /usr/bin/time for wall time and peak memory.

    python3 benches/peers/run.py KIND N [COUNT]     (KIND: hex8 | hex20 | tet10)

Prints a JSON line per tool and a summary with the ratios and the largest relative frequency
difference against femu. `run.sh` installs the peers first.
"""
import json, os, re, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXE = os.path.join(ROOT, "target", "release", "examples", "peer_modes")


def timed(cmd, cwd, timeout=3600):
    p = subprocess.run(["/usr/bin/time", "-v"] + cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    err = p.stderr
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", err).group(1)
    parts = [float(x) for x in wall.split(":")]
    seconds = sum(v * 60 ** i for i, v in enumerate(reversed(parts)))
    rss_kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", err).group(1))
    return p.returncode, p.stdout, seconds, rss_kb / 1024.0


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
    d = tempfile.mkdtemp(prefix=f"femu-peers-{kind}-{n}-")
    info = json.loads(subprocess.run([EXE, "export", kind, str(n), str(count), d], capture_output=True, text=True, check=True).stdout)
    rows = {}
    code, out, wall, rss = timed([EXE, "solve", kind, str(n), str(count)], d)
    femu = json.loads(out)
    rows["femu"] = {"wall_s": wall, "rss_mb": rss, **femu}
    code, out, wall, rss = timed(["ccx", "model"], d)
    rows["calculix"] = {"wall_s": wall, "rss_mb": rss, "ok": code == 0, "frequencies_hz": ccx_frequencies(os.path.join(d, "model.dat")) if code == 0 else []}
    code, out, wall, rss = timed([sys.executable, os.path.join(ROOT, "benches", "peers", "scipy_eigsh.py"), d, str(count)], d)
    rows["scipy"] = {"wall_s": wall, "rss_mb": rss, "ok": code == 0, **(json.loads(out) if code == 0 else {})}
    ref = femu["frequencies_hz"]
    print(json.dumps({"kind": kind, "n": n, "dofs": info["dofs"], "elements": info["elements"], **{k: {a: b for a, b in v.items() if a != "frequencies_hz"} for k, v in rows.items()}}))
    for tool in ("calculix", "scipy"):
        f = rows[tool].get("frequencies_hz", [])
        diff = max((abs(a - b) / b for a, b in zip(f, ref)), default=float("nan"))
        print(f"{kind} {info['dofs']} DOF: {tool:8s} wall {rows[tool]['wall_s']:8.2f} s, peak {rows[tool]['rss_mb']:8.0f} MB, "
              f"femu is {rows[tool]['wall_s'] / rows['femu']['wall_s']:5.2f}x faster, max rel. freq. difference {diff:.2e}")
    print(f"{kind} {info['dofs']} DOF: femu     wall {rows['femu']['wall_s']:8.2f} s, peak {rows['femu']['rss_mb']:8.0f} MB "
          f"(assembly {femu['assembly_s']} s, ordering+symbolic {femu['symbolic_s']} s, factor {femu['factor_s']} s x{femu['factorizations']}, "
          f"solves {femu['solve_s']} s, orthogonalisation {femu['orth_s']} s), Sturm verified {femu['sturm_verified']}")


if __name__ == "__main__":
    main()
