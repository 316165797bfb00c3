#!/usr/bin/env python3
"""How much the 8-node brick's formulation matters: the fully integrated brick (CalculiX C3D8,
femu C3D8) against the brick with incompatible modes (CalculiX C3D8I, femu C3D8I, the family of
MSC Nastran's default CHEXA8 with bubble functions), on a clamped steel cantilever with 1, 2 and 4
elements through the thickness. The reference is CalculiX's converged C3D8I solution (8 through
the thickness, 80 along). Prints a Markdown table; needs `ccx` and a built `femu` (target/debug
or target/release).

    python3 benches/formulation/run.py
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

L, B, H = 1.0, 0.1, 0.05
E, NU, RHO = 210e9, 0.3, 7850.0
MODES = 4


def deck(nx, ny, nz, etype):
    nodes, els = [], []
    nid = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                nodes.append((nid(i, j, k), L * i / nx, B * j / ny, H * k / nz))
    e = 0
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                e += 1
                c = [nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k),
                     nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1), nid(i, j + 1, k + 1)]
                els.append((e, c))
    s = ["*HEADING", "cantilever", "*NODE, NSET=NALL"]
    s += [f"{n}, {x:.10g}, {y:.10g}, {z:.10g}" for n, x, y, z in nodes]
    s.append(f"*ELEMENT, TYPE={etype}, ELSET=EALL")
    s += [f"{e}, " + ", ".join(map(str, c)) for e, c in els]
    s.append("*NSET, NSET=ROOT")
    s += [str(n) for n, x, _, _ in nodes if x == 0.0]
    s += ["*BOUNDARY", "ROOT, 1, 3", "*MATERIAL, NAME=STEEL", "*ELASTIC", f"{E:g}, {NU}",
          "*DENSITY", f"{RHO}", "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
          "*STEP", "*FREQUENCY", f"{MODES}", "*END STEP"]
    return "\n".join(s) + "\n"


def ccx(text, work, name):
    with open(os.path.join(work, name + ".inp"), "w") as f:
        f.write(text)
    subprocess.run(["ccx", name], cwd=work, check=True, capture_output=True)
    dat = open(os.path.join(work, name + ".dat")).read()
    rows = re.findall(r"^\s+\d+\s+(\S+)\s+\S+\s+(\S+)\s+\S+\s*$", dat, re.M)
    return [float(r[1]) for r in rows][:MODES]


def femu(text, work, name, exe):
    path = os.path.join(work, name + "_femu.inp")
    with open(path, "w") as f:
        f.write(text)
    out = os.path.join(work, name + ".json")
    subprocess.run([exe, "modes", path, "--count", str(MODES), "--json", out],
                   check=True, capture_output=True)
    return json.load(open(out))["frequencies_hz"][:MODES]


def main():
    if shutil.which("ccx") is None:
        sys.exit("ccx is not on PATH (apt install calculix-ccx)")
    exe = next((p for p in ["target/debug/femu", "target/release/femu"] if os.path.exists(p)), None)
    if exe is None:
        sys.exit("build femu first: cargo build --release -p femu-cli")
    work = tempfile.mkdtemp()
    ref = ccx(deck(80, 4, 8, "C3D8I"), work, "ref")
    print(f"reference: C3D8I 80 x 4 x 8: " + ", ".join(f"{f:.3f}" for f in ref) + " Hz\n")
    print("| through the thickness | along | mode | reference | ccx C3D8 | femu C3D8 | ccx C3D8I | femu C3D8I |")
    print("|---|---|---|---|---|---|---|---|")
    err = lambda f, r: f"{f:.3f} ({100 * (f / r - 1):+.1f} %)"
    for nz, nx in [(1, 10), (1, 20), (2, 20), (4, 40)]:
        plain = ccx(deck(nx, 2, nz, "C3D8"), work, f"p{nz}_{nx}")
        inc = ccx(deck(nx, 2, nz, "C3D8I"), work, f"i{nz}_{nx}")
        ours = femu(deck(nx, 2, nz, "C3D8"), work, f"f{nz}_{nx}", exe)
        ours_inc = femu(deck(nx, 2, nz, "C3D8I"), work, f"fi{nz}_{nx}", exe)
        for k in range(MODES):
            r = ref[k]
            print(f"| {nz} | {nx} | {k + 1} | {r:.3f} | {err(plain[k], r)} | {err(ours[k], r)} "
                  f"| {err(inc[k], r)} | {err(ours_inc[k], r)} |")


if __name__ == "__main__":
    main()
