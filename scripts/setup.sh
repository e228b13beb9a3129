#!/usr/bin/env bash
# One-time setup for a fresh machine; safe to run again (every step checks first).
#  - apt packages llama.cpp's build needs (cmake, clang, libclang-dev)
#  - chromium, chromium-driver and a font for the browser test of `ivlmap serve`
#  - python3 numpy (tests check that numpy reads our .npy layers)
#  - the local models of design.md into ~/.cache/ivlmap/models (SHA-256 checked)
# usage: scripts/setup.sh [model ...]   (models as scripts/fetch-models.sh takes them)
set -euo pipefail
cd "$(dirname "$0")/.."

log() { printf '[setup] %s\n' "$*" >&2; }

need_apt=()
command -v cmake >/dev/null 2>&1 || need_apt+=(cmake)
command -v clang >/dev/null 2>&1 || need_apt+=(clang)
if ! ls /usr/lib/llvm-*/lib/libclang*.so* >/dev/null 2>&1 && ! ls /usr/lib/x86_64-linux-gnu/libclang*.so* >/dev/null 2>&1; then
  need_apt+=(libclang-dev)
fi
command -v unzip >/dev/null 2>&1 || need_apt+=(unzip)
# the browser test of `ivlmap serve` (server/tests/browser.rs): Debian's chromium, its
# WebDriver, and a font for the page's text
command -v chromium >/dev/null 2>&1 || need_apt+=(chromium)
command -v chromedriver >/dev/null 2>&1 || need_apt+=(chromium-driver)
[ -d /usr/share/fonts/truetype/dejavu ] || need_apt+=(fonts-dejavu-core)
if [ "${#need_apt[@]}" -gt 0 ]; then
  log "installing ${need_apt[*]}"
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

if ! python3 -c 'import numpy' >/dev/null 2>&1; then
  log "installing numpy"
  python3 -m pip install -q numpy || log "numpy could not be installed; .npy interop tests will say so"
fi

scripts/fetch-models.sh "$@"
log "ready"
