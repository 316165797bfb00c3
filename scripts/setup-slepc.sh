#!/usr/bin/env bash
# Installs SLEPc and PETSc with MUMPS (Python bindings) and Open MPI from Debian's packages, for
# femu's `--engine slepc` (docs/SCALING.md), with OpenBLAS for MUMPS's dense kernels (Debian's
# default reference BLAS makes its factorization about 10x slower). Idempotent; sudo when not root.
set -euo pipefail
if dpkg -s python3-slepc4py-real python3-petsc4py-real python3-numpy openmpi-bin libopenblas0-pthread >/dev/null 2>&1; then
  exit 0
fi
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq \
  python3-slepc4py-real python3-petsc4py-real python3-numpy openmpi-bin libopenblas0-pthread >/dev/null
