#!/usr/bin/env bash
# Installs the peers (CalculiX, SLEPc/PETSc/MUMPS and SuiteSparse from Debian; scipy, pypardiso
# (MKL PARDISO), scikit-sparse (CHOLMOD) and threadpoolctl from PyPI into target/peers-venv),
# builds femu's benchmark example and runs the side-by-side comparison of benches/peers/run.py.
#   bash benches/peers/run.sh [SIZES...]   e.g. "hex8:20 tet10:10" (default: the clamped hex8 block
#   and the free-free hex8 plate at 50k and 200k DOF; 600k (hex8:46, tet10:23) takes about an hour
#   with CalculiX: time-box it with PEER_TIMEOUT=1800; PEERS selects peers and PEER_ROUNDS=R runs
#   every tool R times in rounds (medians and the per-round ratios), PEER_FACTOR=R times the
#   numeric factorizations alone, femu's and PARDISO's on femu's ordering, see run.py; the
#   exported matrices are removed after each model unless PEERS_KEEP=1)
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v ccx >/dev/null || ! dpkg -s libsuitesparse-dev >/dev/null 2>&1; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq calculix-ccx time libsuitesparse-dev
fi
bash scripts/setup-slepc.sh
venv=target/peers-venv
[ -x $venv/bin/python ] || python3 -m venv $venv
$venv/bin/python -c "import scipy, pypardiso, sksparse, threadpoolctl" 2>/dev/null ||
  $venv/bin/pip install -q scipy pypardiso "scikit-sparse==0.4.16" threadpoolctl  # 0.5 needs SuiteSparse 7, Debian 12 has 5.12
export PEERS_PYTHON=$PWD/$venv/bin/python
cargo build --release --example peer_modes
sizes=("$@")
# default: the 50k and 200k DOF cases of the clamped block and the free-free plate
[ ${#sizes[@]} -gt 0 ] || sizes=(hex8:20 plate:16 hex8:32 plate:33)
for s in "${sizes[@]}"; do
  python3 benches/peers/run.py "${s%%:*}" "${s##*:}" 20
done
