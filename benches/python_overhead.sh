#!/usr/bin/env bash
# The Python module's overhead: the 20 lowest modes of the clamped steel block with 52,920 DOF
# (hex8, 40 x 20 x 20 cells, written by examples/export_inp.rs), read, assembled and solved by
# `femu modes` and by `femu.read_model(...).modes(20)` from Python, alternately, REPEAT times
# each (default 3); prints the wall times, their medians and the ratio Python / CLI.
#   bash benches/python_overhead.sh
set -euo pipefail
cd "$(dirname "$0")/.."
repeat="${REPEAT:-3}"
venv="${FEMU_VENV:-target/python-venv}"
cargo build --release -q -p femu-cli && cargo build --release -q -p femu --example export_inp
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q numpy scipy ./crates/femu-python
deck="$(mktemp -d)/block.inp"
target/release/examples/export_inp hex8 40 20 20 20 "$deck"
"$venv/bin/python" - "$deck" "$repeat" <<'PY'
import statistics, subprocess, sys, time
deck, repeat = sys.argv[1], int(sys.argv[2])
py = [sys.executable, "-c", "import femu, sys; m = femu.read_model(sys.argv[1]); print(m.free_count, m.modes(20).sturm['verified'])", deck]
cli = ["target/release/femu", "modes", deck, "--count", "20"]
times = {"cli": [], "python": []}
for _ in range(repeat):
    for name, cmd in (("cli", cli), ("python", py)):
        t = time.perf_counter()
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
        times[name].append(time.perf_counter() - t)
        if name == "python":
            dofs, verified = out.split()
            assert verified == "True"
c, p = statistics.median(times["cli"]), statistics.median(times["python"])
print(f"| {dofs} DOF, 20 modes | femu modes (CLI) | Python femu.read_model().modes(20) |")
print("|---|---|---|")
print("| runs (s) | " + ", ".join(f"{t:.2f}" for t in times["cli"]) + " | " + ", ".join(f"{t:.2f}" for t in times["python"]) + " |")
print(f"| median (s) | {c:.2f} | {p:.2f} |")
print(f"| Python / CLI | | {p / c:.3f} |")
PY
