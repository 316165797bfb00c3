#!/usr/bin/env python3
"""Reading another solver's matrices: CalculiX stores K and M of a clamped steel hex8 bar
(`*FREQUENCY, SOLVER=MATRIXSTORAGE`); `femu modes job.sti` reads them with the deck's nodes. Prints
the files' size, the time to read their bytes into memory (Python, warm cache), femu's read phase
(`load.read_seconds` of `femu modes --json`: parse, sort into columns, renumber) and the ratio,
and the modes' agreement with femu's own assembly of the same deck. Needs `ccx` and a release
`femu` (cargo build --release -p femu-cli).

    python3 benches/external/run.py [NX NY NZ]     (default 80 20 20: 105,840 DOF)
"""
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FEMU = os.path.join(ROOT, "target", "release", "femu")


def deck(nx, ny, nz, step):
    lx, ly, lz = 1.0, 0.25, 0.25
    nid = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    out = ["*NODE"]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                out.append(f"{nid(i, j, k)}, {lx * i / nx}, {ly * j / ny}, {lz * k / nz}")
    out.append("*ELEMENT, TYPE=C3D8, ELSET=E")
    e = 1
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                n = [nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k),
                     nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1),
                     nid(i, j + 1, k + 1)]
                out.append(", ".join(map(str, [e] + n)))
                e += 1
    out.append("*NSET, NSET=ROOT")
    out += [str(nid(0, j, k)) for k in range(nz + 1) for j in range(ny + 1)]
    out += ["*MATERIAL, NAME=STEEL", "*ELASTIC", "2.1e11, 0.3", "*DENSITY", "7850.",
            "*SOLID SECTION, ELSET=E, MATERIAL=STEEL", "*BOUNDARY", "ROOT, 1, 3", "*STEP",
            step, "10", "*END STEP"]
    return "\n".join(out) + "\n"


def modes(path, cwd):
    json_path = os.path.join(cwd, "modes.json")
    subprocess.run([FEMU, "modes", path, "--count", "10", "--json", json_path, "--quiet"],
                   check=True, cwd=cwd)
    with open(json_path) as f:
        return json.load(f)


def main():
    nx, ny, nz = (int(a) for a in sys.argv[1:4]) if len(sys.argv) > 3 else (80, 20, 20)
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "job.inp"), "w") as f:
            f.write(deck(nx, ny, nz, "*FREQUENCY, SOLVER=MATRIXSTORAGE"))
        subprocess.run(["ccx", "-i", "job"], check=True, cwd=d, capture_output=True)
        files = [os.path.join(d, f"job.{e}") for e in ("sti", "mas", "dof", "inp")]
        size = sum(os.path.getsize(f) for f in files)
        for f in files:  # warm the cache
            open(f, "rb").read()
        start = time.perf_counter()
        for f in files:
            open(f, "rb").read()
        raw = time.perf_counter() - start
        external = modes("job.sti", d)
        own = modes("job.inp", d)
        read = external["load"]["read_seconds"]
        worst = max(abs(a / b - 1) for a, b in zip(external["eigenvalues"], own["eigenvalues"]))
        print(f"| DOF | files (MB) | bytes read (s) | femu's read (s) | ratio | eigenvalues against femu's assembly |")
        print("|---|---|---|---|---|---|")
        print(f"| {external['dofs']} | {size / 1e6:.0f} | {raw:.2f} | {read:.2f} | {read / raw:.1f} | {worst:.1e} |")


if __name__ == "__main__":
    main()
