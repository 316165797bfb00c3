#!/usr/bin/env bash
# The two eigen engines side by side against model size (docs/SCALING.md): femu's own solver and
# SLEPc + MUMPS on 1 and 2 MPI ranks, 20 lowest modes of the models of examples/peer_modes.rs
# (hex8: the clamped steel block, 2n x n x n cells; plate: the free-free plate, 5n x 3n x 3
# cells), each run in its own process under /usr/bin/time -v (wall time, peak resident memory of
# the largest process: femu's or one rank's).
#   bash benches/scaling.sh [KIND:N...]   (default hex8:20 hex8:32 plate:33 plate:57: 53k, 209k,
#                                          199k and 590k DOF)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-slepc.sh
command -v /usr/bin/time >/dev/null || { apt-get update -qq && apt-get install -y -qq time; }
cargo build --release --example peer_modes
exe=target/release/examples/peer_modes
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(hex8:20 hex8:32 plate:33 plate:57)
printf '| DOF, model | engine | wall (s) | peak RSS per process (MB) | eigen solve (s) | max rel. diff. of elastic eigenvalues to femu | Sturm |\n|---|---|---|---|---|---|---|\n'
for size in "${sizes[@]}"; do
  kind=${size%%:*} n=${size##*:}
  ref=""
  for engine in femu slepc:1 slepc:2; do
    log=$(mktemp)
    if [ "$engine" = femu ]; then
      /usr/bin/time -v "$exe" solve "$kind" "$n" 20 >"$log.out" 2>"$log"
    else
      FEMU_ENGINE=$engine /usr/bin/time -v "$exe" solve "$kind" "$n" 20 >"$log.out" 2>"$log"
    fi
    python3 - "$log" "$log.out" "$engine" "$ref" "$kind" <<'PY'
import json, re, sys
err = open(sys.argv[1]).read()
out = json.loads(open(sys.argv[2]).read())
wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", err).group(1)
wall = sum(float(v) * 60 ** i for i, v in enumerate(reversed(wall.split(":"))))
rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", err).group(1)) / 1024
f = out["frequencies_hz"]
ref = [float(v) for v in sys.argv[4].split(",")] if sys.argv[4] else f
# eigenvalues of the elastic modes, relative; the rigid-body modes of a free model are zeros up
# to round-off (about 1e-16 of the largest eigenvalue of the pencil), rounded differently by each solver
lam = lambda x: (2 * 3.141592653589793 * x) ** 2
top = max(lam(v) for v in ref)
diff = max((abs(lam(a) - lam(b)) / lam(b) for a, b in zip(f, ref) if lam(b) > 1e-6 * top), default=0.0)
print(f"| {out['dofs']} {sys.argv[5]} | {sys.argv[3]} | {wall:.1f} | {rss:.0f} | {out['eigen_s']:.1f} | {diff:.1e} | {out['sturm_verified']} |")
open(sys.argv[2] + ".f", "w").write(",".join(repr(v) for v in f))
PY
    [ -n "$ref" ] || ref=$(cat "$log.out.f")
    rm -f "$log" "$log.out" "$log.out.f"
  done
done
