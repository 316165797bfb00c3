#!/usr/bin/env bash
# Runs every fuzz target for a bounded time (FUZZ_SECONDS, default 60) from the seed corpus of
# fixtures/, with the nightly toolchain and cargo-fuzz (installed if missing). Prints each target's
# executions and whether it found a crash (artifacts under fuzz/artifacts/<target>/).
set -euo pipefail
cd "$(dirname "$0")"
seconds="${FUZZ_SECONDS:-60}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
rustup toolchain list | grep -q nightly || rustup toolchain install nightly --profile minimal
for t in inp uff msh csv bdf; do
  mkdir -p "corpus/$t"
done
cp ../fixtures/inp/*.inp corpus/inp/ 2>/dev/null || true
cp ../fixtures/msh/*.msh corpus/msh/ 2>/dev/null || true
cp ../fixtures/uff/*.unv corpus/uff/ 2>/dev/null || true
cp ../fixtures/csv/*.csv corpus/csv/ 2>/dev/null || true
cp ../fixtures/nastran/*/*.bdf corpus/bdf/ 2>/dev/null || true
# inputs are capped at 16 KiB (-max_len): a large fixture would make every run slow without
# reaching more code, so larger seeds stay out of the corpus
find corpus -type f -size +16k -delete
for t in ${FUZZ_TARGETS:-inp uff msh csv bdf}; do
  echo "== $t ($seconds s)"
  cargo +nightly fuzz run "$t" "corpus/$t" -- -max_total_time="$seconds" -max_len=16384 -rss_limit_mb=2048 2>&1 \
    | grep -E "^#[0-9]+ *DONE|Done [0-9]+ runs|SUMMARY|panicked|ERROR" || true
done
