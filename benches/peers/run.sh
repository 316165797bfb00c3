#!/usr/bin/env bash
# Installs the peers (CalculiX from Debian, scipy from PyPI), builds femu's benchmark example and
# runs the side-by-side comparison of benches/peers/run.py at the sizes of issue 3.
#   bash benches/peers/run.sh [SIZES...]   e.g. "hex8:20 tet10:10" (default: 50k and 200k DOF cases)
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v ccx >/dev/null; then apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq calculix-ccx time; fi
python3 -c "import scipy" 2>/dev/null || pip install -q scipy
cargo build --release --example peer_modes
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(hex8:20 tet10:10 hex8:32 tet10:16)
for s in "${sizes[@]}"; do
  python3 benches/peers/run.py "${s%%:*}" "${s##*:}" 20
done
