#!/usr/bin/env bash
# Eq. 2 labelling, Rust (map_build::perception::label_masks) against numpy (bench/eq2_numpy.py), on
# the same generated inputs: a 1000 x 1000 label map and 200 SAM masks (COCO RLE).
# Prints both medians and the ratio, and fails if any mask's result differs.
#   bash bench/eq2_compare.sh [DIR] [--reps N]     (CARGO_TARGET_DIR is honoured)
set -euo pipefail
cd "$(dirname "$0")/.."
DIR="${1:-$(mktemp -d -t eq2-bench.XXXXXX)}"
REPS="${REPS:-21}"
PY="$(bash bench/setup.sh)"
cargo build --quiet --release -p map_build --example eq2_bench
BIN="${CARGO_TARGET_DIR:-target}/release/examples/eq2_bench"
"$BIN" gen "$DIR"
"$PY" bench/eq2_numpy.py "$DIR" --reps "${NUMPY_REPS:-5}"
"$BIN" run "$DIR" --reps "$REPS" --numpy "$DIR/numpy_result.json"
