#!/usr/bin/env bash
# Installs the peers (CalculiX from Debian, scipy from PyPI), builds femu's benchmark example and
# runs the side-by-side comparison of benches/peers/run.py at the sizes of issue 3.
#   bash benches/peers/run.sh [SIZES...]   e.g. "hex8:20 tet10:10" (default: the 50k, 200k and
#   600k DOF cases of issue 3; the 600k ones take about an hour each with CalculiX: time-box it with
#   PEER_TIMEOUT=1800, and skip scipy there with PEERS=calculix, whose LU does not fit in 23 GB)
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v ccx >/dev/null; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq calculix-ccx time; fi
python3 -c "import scipy" 2>/dev/null || pip install -q scipy
cargo build --release --example peer_modes
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(hex8:20 tet10:10 hex8:32 tet10:16 hex8:46 tet10:23)
for s in "${sizes[@]}"; do
  python3 benches/peers/run.py "${s%%:*}" "${s##*:}" 20
done
