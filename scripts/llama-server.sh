#!/usr/bin/env bash
# Builds llama.cpp's llama-server once, for the openai backend's real-server test
# (llm/tests/openai_llama_server.rs) and for running `--backend openai` locally.
# Prints the binary's path as the last line of stdout; a second run with the binary
# present builds nothing and only prints it.
#
# usage: scripts/llama-server.sh [--rebuild]
#   the binary: ${IVLMAP_LLAMA_SERVER:-~/.cache/ivlmap/llama-server}/bin/llama-server
#
# Source: the llama.cpp vendored in the llama-cpp-python 0.3.36 sdist (PyPI, checked by
# SHA-256; the same sdist bench/llama_bench.sh takes llama-bench from, reused from its
# cache when present). llama-cpp-sys-2 ships no tools/server source, so unlike
# llama-bench the whole server comes from the sdist: library, common and server of one
# llama.cpp version.
# Build: CPU only, Release, only the llama-server target (ggml, llama, common, mtmd,
# cpp-httplib, the server), -j2; static libraries, no curl, no OpenSSL (the tests talk
# plain HTTP on 127.0.0.1), no web UI (the UI's prebuilt assets would be downloaded from
# Hugging Face, which is not a package registry: the server is built with an empty UI
# table and answers the API only). GGML_NATIVE=OFF and OpenMP as bench/llama_bench.sh,
# so the binary runs on any x86-64 machine that shares the cache.
# Cost, cold: 14 CPU-minutes of compiling (192 files; about 7-8 minutes on 2 idle cores,
# 12 on a loaded machine) and the 76 MB sdist download (pip prepares its metadata too:
# about 2 minutes); then 88 MB in the cache (the binary and the sdist).
# Concurrent runs (CI and a test) wait for each other on a lock file.
set -euo pipefail

CACHE="${IVLMAP_LLAMA_SERVER:-$HOME/.cache/ivlmap/llama-server}"
PY_SDIST_VERSION=0.3.36
PY_SDIST_SHA256=832db0699007f1be95a7e41ef12e88926b02ba836461e36a36372db2760c1a2e
JOBS=2 # a 2-core machine shared with other builds

bin="$CACHE/bin/llama-server"
# What the binary was built from and how: a binary with another stamp is rebuilt.
stamp_text="llama-cpp-python $PY_SDIST_VERSION sdist $PY_SDIST_SHA256; native=off openmp=on curl=off openssl=off ui=none"

rebuild=0
while [ $# -gt 0 ]; do
  case "$1" in
    --rebuild) rebuild=1; shift ;;
    -h|--help) sed -n '2,24p' "$0"; exit 0 ;;
    *) echo "llama-server.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done

log() { echo "llama-server.sh: $*" >&2; }
die() { log "$*"; exit 1; }

built() { [ -x "$bin" ] && [ "$(cat "$bin.stamp" 2>/dev/null)" = "$stamp_text" ]; }

if [ "$rebuild" = 0 ] && built; then
  echo "$bin"
  exit 0
fi

mkdir -p "$CACHE/bin" "$CACHE/sdist"
exec 9>"$CACHE/.lock"
if ! flock -n 9; then
  log "another build holds $CACHE/.lock; waiting for it"
  flock 9
fi
# The other build may have finished it.
if [ "$rebuild" = 0 ] && built; then
  echo "$bin"
  exit 0
fi

for tool in cmake c++ tar sha256sum; do
  command -v "$tool" >/dev/null 2>&1 || die "$tool is missing (scripts/setup.sh installs cmake and a C++ compiler)"
done

sdist="$CACHE/sdist/llama_cpp_python-$PY_SDIST_VERSION.tar.gz"
sha_ok() { echo "$PY_SDIST_SHA256  $1" | sha256sum -c --status 2>/dev/null; }
if ! sha_ok "$sdist"; then
  bench_sdist="${IVLMAP_LLAMA_BENCH:-$HOME/.cache/ivlmap/llama-bench}/sdist/llama_cpp_python-$PY_SDIST_VERSION.tar.gz"
  if sha_ok "$bench_sdist"; then
    log "reusing $bench_sdist"
    cp "$bench_sdist" "$sdist.tmp"
    mv "$sdist.tmp" "$sdist"
  else
    log "downloading the llama-cpp-python $PY_SDIST_VERSION sdist from PyPI (76 MB)"
    python3 -m pip --version >/dev/null 2>&1 || die "pip is missing (apt-get install python3-pip)"
    rm -f "$sdist" # pip keeps a file of that name without checking it
    python3 -m pip download --quiet --no-deps --no-binary :all: -d "$CACHE/sdist" \
      "llama-cpp-python==$PY_SDIST_VERSION" >&2
  fi
  sha_ok "$sdist" || die "$sdist: SHA-256 is not $PY_SDIST_SHA256"
fi

src="$CACHE/src"
build="$CACHE/build"
rm -rf "$src" "$build"
mkdir -p "$src"
log "unpacking llama.cpp from $(basename "$sdist")"
tar -xzf "$sdist" -C "$src" --strip-components=3 \
  --exclude="llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/models" \
  --exclude="llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/docs" \
  --exclude="llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/media" \
  "llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp"
[ -f "$src/tools/server/server.cpp" ] || die "the sdist has no tools/server/server.cpp"
# No prebuilt UI in tools/ui/dist and no download: an empty UI table (see above).
rm -rf "$src/tools/ui/dist"

log "configuring llama-server in $build"
started=$(date +%s)
cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release \
  -DLLAMA_BUILD_SERVER=ON -DLLAMA_BUILD_TOOLS=ON -DLLAMA_BUILD_COMMON=ON \
  -DLLAMA_BUILD_TESTS=OFF -DLLAMA_BUILD_EXAMPLES=OFF -DLLAMA_BUILD_APP=OFF \
  -DLLAMA_BUILD_UI=OFF -DLLAMA_USE_PREBUILT_UI=OFF \
  -DLLAMA_CURL=OFF -DLLAMA_OPENSSL=OFF \
  -DGGML_NATIVE=OFF -DGGML_OPENMP=ON -DGGML_WEBGPU=OFF -DGGML_CUDA=OFF -DGGML_VULKAN=OFF \
  -DGGML_METAL=OFF -DBUILD_SHARED_LIBS=OFF >&2
log "building llama-server (-j$JOBS; several minutes on 2 cores)"
cmake --build "$build" --target llama-server -j "$JOBS" >&2
[ -x "$build/bin/llama-server" ] || die "the build left no $build/bin/llama-server"
"$build/bin/llama-server" --version >&2 || die "the built llama-server does not start"
cp "$build/bin/llama-server" "$bin.tmp"
mv "$bin.tmp" "$bin"
echo "$stamp_text" > "$bin.stamp"
rm -rf "$src" "$build"
log "built in $(( $(date +%s) - started )) s (configure and compile)"
echo "$bin"
