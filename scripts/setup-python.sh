#!/usr/bin/env bash
# The Python side of femu for CI and benchmarks: a virtual environment (FEMU_VENV, default
# target/python-venv) with femu's package built from this repository by maturin (pip fetches
# maturin from PyPI) and what its tests use: numpy, scipy, pytest, mypy with scipy's stubs, pyuff,
# matplotlib. Prints the venv's python. Any failure fails the script.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${FEMU_VENV:-target/python-venv}"
if ! python3 -c "import venv, ensurepip" 2>/dev/null; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq python3-venv >/dev/null
fi
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q --upgrade pip >&2
"$venv/bin/pip" install -q numpy scipy pytest mypy scipy-stubs pyuff matplotlib >&2
if [ "${CI:-}" = true ]; then
  # CI builds the package from scratch for its tests only: less optimisation, no line tables
  # (205 s instead of 269 s on a 2-core machine); users' builds keep the release profile
  export CARGO_PROFILE_RELEASE_OPT_LEVEL=1 CARGO_PROFILE_RELEASE_DEBUG=false
fi
"$venv/bin/pip" install -q ./crates/femu-python >&2
echo "$venv/bin/python"
