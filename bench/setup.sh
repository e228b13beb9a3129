#!/usr/bin/env bash
# Idempotently create the Python venv used by bench/compare_vlmaps.py:
# numpy, opencv-python-headless, pyvisgraph 0.2.1 (and tqdm, which it imports) (VLMaps' planner dependencies).
set -euo pipefail
VENV="${IVLMAP_BENCH_VENV:-$HOME/.cache/ivlmap/venv-bench}"
if [ ! -x "$VENV/bin/python" ]; then
    mkdir -p "$(dirname "$VENV")"
    python3 -m venv "$VENV"
fi
if ! "$VENV/bin/python" -c 'import numpy, cv2, pyvisgraph, importlib.metadata as m; assert m.version("pyvisgraph") == "0.2.1"' 2>/dev/null; then
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet numpy opencv-python-headless "pyvisgraph==0.2.1" tqdm  # pyvisgraph imports tqdm without declaring it
fi
echo "$VENV/bin/python"
