#!/usr/bin/env bash
# Tokens per second of our llama backend (LlamaCppBackend, the product code path) against
# llama.cpp's own llama-bench, on the same GGUF, threads, prompt and generation lengths,
# in one run. Prints prompt-processing (pp) and generation (tg) tok/s for both, their
# medians and the ratios ours / llama.cpp.
#
# usage: bench/llama_bench.sh [GGUF] [-t THREADS] [-p N_PROMPT] [-n N_GEN] [-r REPS]
#                             [--rounds K] [--json FILE] [--build-only]
#   GGUF      default: $IVLMAP_MODELS/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf
#             (IVLMAP_MODELS defaults to ~/.cache/ivlmap/models, see scripts/fetch-models.sh)
#   -t 2 -p 512 -n 128 -r 3 --rounds 3 by default.
#   Each round runs llama-bench (-r REPS) and then ours (REPS repetitions): K rounds
#   interleave the two, so that load from other processes on a shared machine falls on
#   both; the figures are medians over all K*REPS samples of each side.
#
# llama-bench is built once into ${IVLMAP_LLAMA_BENCH:-~/.cache/ivlmap/llama-bench}:
# - the library (llama, ggml, common) from the llama.cpp source that our llama-cpp-sys-2
#   vendors (its version read from Cargo.lock; source in the cargo registry, `cargo fetch`
#   brings it), so both sides run the same kernels;
# - the llama-bench driver (tools/llama-bench/*.cpp, which the crate does not ship) from
#   the llama.cpp vendored in the llama-cpp-python 0.3.36 sdist (PyPI, checked by SHA-256);
#   its pp/tg timing loops are the ones of llama.cpp at that version, and it compiles
#   against the crate's slightly newer llama.h (same llama_process/common_batch API).
# - with the CMake options llama-cpp-sys-2's build.rs passes for x86_64 Linux with the
#   crate's default features: GGML_NATIVE=OFF (no target-cpu=native in RUSTFLAGS; ggml
#   then enables AVX, AVX2, FMA, F16C, BMI2, not AVX-512), GGML_OPENMP=ON (feature
#   "openmp"), BUILD_SHARED_LIBS=OFF, LLAMA_CURL=OFF, LLAMA_BUILD_COMMON=ON, and the C/C++
#   flags the cmake crate adds (-ffunction-sections -fdata-sections -fPIC -m64
#   -march=x86-64); CPU only, CMAKE_BUILD_TYPE=Release.
#
# Both sides run with OMP_WAIT_POLICY=passive unless it is already set: idle OpenMP
# threads then sleep instead of spinning, which on a shared 2-core machine is several times
# faster for both (spinning threads steal the cores the working ones need).
#
# What is measured (see agent/examples/tok_per_s.rs for ours):
# - pp: N_PROMPT tokens from an empty KV cache, timed around the decode calls only
#   (llama-bench: random tokens; ours: a chat prompt of exactly N_PROMPT tokens, prefix
#   cache off, tok/s = N_PROMPT / Completion::prompt_ms).
# - tg: N_GEN single-token decodes from (nearly) an empty cache (llama-bench: from
#   position 0, no sampling; ours: after a short prompt, greedy sampling, detokenisation and
#   stop checks included, EOS ignored, tok/s = decodes / Completion::generate_ms).
# Both warm up first (one pp and one 1-token tg), like llama-bench does.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODELS="${IVLMAP_MODELS:-$HOME/.cache/ivlmap/models}"
CACHE="${IVLMAP_LLAMA_BENCH:-$HOME/.cache/ivlmap/llama-bench}"
PY_SDIST_VERSION=0.3.36
PY_SDIST_SHA256=832db0699007f1be95a7e41ef12e88926b02ba836461e36a36372db2760c1a2e

model="$MODELS/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf"
threads=2 n_prompt=512 n_gen=128 reps=3 rounds=3 json_out="" build_only=0
while [ $# -gt 0 ]; do
  case "$1" in
    -t) threads="$2"; shift 2 ;;
    -p) n_prompt="$2"; shift 2 ;;
    -n) n_gen="$2"; shift 2 ;;
    -r) reps="$2"; shift 2 ;;
    --rounds) rounds="$2"; shift 2 ;;
    --json) json_out="$2"; shift 2 ;;
    --build-only) build_only=1; shift ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    -*) echo "llama_bench.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) model="$1"; shift ;;
  esac
done

log() { echo "llama_bench.sh: $*" >&2; }
die() { log "$*"; exit 1; }

# --- llama-bench, built once -------------------------------------------------------------

sys_version="$(awk '/^name = "llama-cpp-sys-2"$/ {getline; gsub(/version = |"/, ""); print; exit}' "$ROOT/Cargo.lock")"
[ -n "$sys_version" ] || die "no llama-cpp-sys-2 in $ROOT/Cargo.lock"
bench_bin="$CACHE/bin/llama-bench-sys-$sys_version"

find_vendored() {
  local d
  for d in "${CARGO_HOME:-$HOME/.cargo}"/registry/src/*/"llama-cpp-sys-2-$sys_version/llama.cpp"; do
    if [ -f "$d/CMakeLists.txt" ]; then echo "$d"; return 0; fi
  done
  return 1
}

build_llama_bench() {
  local vendored sdist_dir sdist src build
  if ! vendored="$(find_vendored)"; then
    log "llama-cpp-sys-2 $sys_version source not in the cargo registry: cargo fetch"
    (cd "$ROOT" && cargo fetch --locked >&2)
    vendored="$(find_vendored)" || die "cargo fetch did not bring llama-cpp-sys-2 $sys_version"
  fi
  sdist_dir="$CACHE/sdist"
  sdist="$sdist_dir/llama_cpp_python-$PY_SDIST_VERSION.tar.gz"
  mkdir -p "$sdist_dir" "$CACHE/bin"
  if ! echo "$PY_SDIST_SHA256  $sdist" | sha256sum -c --status 2>/dev/null; then
    log "downloading the llama-cpp-python $PY_SDIST_VERSION sdist (for tools/llama-bench)"
    pip download --quiet --no-deps --no-binary :all: -d "$sdist_dir" \
      "llama-cpp-python==$PY_SDIST_VERSION" >&2
    echo "$PY_SDIST_SHA256  $sdist" | sha256sum -c --status \
      || die "$sdist: SHA-256 is not $PY_SDIST_SHA256"
  fi
  src="$CACHE/src-sys-$sys_version"
  build="$CACHE/build-sys-$sys_version"
  rm -rf "$src" "$build"
  log "copying llama.cpp from $vendored"
  cp -a "$vendored" "$src"
  mkdir -p "$src/tools/llama-bench"
  tar -xzf "$sdist" -C "$src/tools/llama-bench" --strip-components=5 \
    "llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/tools/llama-bench/llama-bench.cpp" \
    "llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/tools/llama-bench/main.cpp" \
    "llama_cpp_python-$PY_SDIST_VERSION/vendor/llama.cpp/tools/llama-bench/CMakeLists.txt"
  # The crate ships no other tool's source: build llama-bench alone.
  cat > "$src/tools/CMakeLists.txt" <<'EOF'
find_package(Threads REQUIRED)
llama_add_compile_flags()
add_subdirectory(llama-bench)
EOF
  local flags="-ffunction-sections -fdata-sections -fPIC -m64 -march=x86-64"
  log "configuring llama-bench (llama.cpp of llama-cpp-sys-2 $sys_version) in $build"
  cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
    -DLLAMA_BUILD_TESTS=OFF -DLLAMA_BUILD_EXAMPLES=OFF -DLLAMA_BUILD_SERVER=OFF \
    -DLLAMA_BUILD_TOOLS=ON -DLLAMA_BUILD_APP=OFF -DLLAMA_BUILD_COMMON=ON -DLLAMA_CURL=OFF \
    -DGGML_NATIVE=OFF -DGGML_OPENMP=ON -DGGML_WEBGPU=OFF -DBUILD_SHARED_LIBS=OFF >&2
  log "building llama-bench (several minutes on 2 cores)"
  cmake --build "$build" --target llama-bench -j "$(nproc)" >&2
  cp "$build/bin/llama-bench" "$bench_bin.tmp"
  mv "$bench_bin.tmp" "$bench_bin"
  rm -rf "$src"
}

if [ ! -x "$bench_bin" ]; then
  build_llama_bench
fi
log "llama-bench: $bench_bin"

# --- ours: the tok_per_s example over LlamaCppBackend ---------------------------------------

target_dir="${CARGO_TARGET_DIR:-$ROOT/target}"
log "building agent example tok_per_s (release)"
(cd "$ROOT" && cargo build --release --quiet -p llm --example tok_per_s >&2)
ours_bin="$target_dir/release/examples/tok_per_s"
[ -x "$ours_bin" ] || die "no $ours_bin after the build"

[ "$build_only" = 1 ] && exit 0
[ -f "$model" ] || die "$model: no such model (scripts/fetch-models.sh fetches the default ones)"

export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
log "model $(basename "$model"), threads $threads, pp $n_prompt, tg $n_gen, $rounds rounds x $reps reps, OMP_WAIT_POLICY=$OMP_WAIT_POLICY"
for ((i = 1; i <= rounds; i++)); do
  log "round $i/$rounds: llama-bench"
  "$bench_bin" -m "$model" -t "$threads" -p "$n_prompt" -n "$n_gen" -r "$reps" -o json \
    > "$work/llama-$i.json" 2> "$work/llama-$i.log" \
    || { tail -20 "$work/llama-$i.log" >&2; die "llama-bench failed"; }
  log "round $i/$rounds: ours"
  "$ours_bin" --model "$model" --threads "$threads" --n-prompt "$n_prompt" --n-gen "$n_gen" \
    --reps "$reps" > "$work/ours-$i.jsonl" 2> "$work/ours-$i.log" \
    || { tail -20 "$work/ours-$i.log" >&2; die "tok_per_s failed"; }
done

python3 - "$work" "$rounds" "$json_out" "$model" "$threads" "$n_prompt" "$n_gen" <<'EOF'
import json, statistics, sys, os
work, rounds, json_out, model, threads, n_prompt, n_gen = sys.argv[1:8]
rounds = int(rounds)
llama = {"pp": [], "tg": []}
ours = {"pp": [], "tg": []}
for i in range(1, rounds + 1):
    for t in json.load(open(f"{work}/llama-{i}.json")):
        test = "pp" if t["n_gen"] == 0 else "tg"
        llama[test].extend(t["samples_ts"])
    for line in open(f"{work}/ours-{i}.jsonl"):
        r = json.loads(line)
        if r.get("test") in ours and "tok_s" in r:
            ours[r["test"]].append(r["tok_s"])
rows = {}
print(f"model {os.path.basename(model)}, threads {threads}, "
      f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY')}, medians of {rounds} interleaved rounds")
print(f"{'test':<8}{'llama-bench tok/s':>20}{'ours tok/s':>14}{'ours/llama':>12}  samples (llama | ours)")
for test, n in (("pp", n_prompt), ("tg", n_gen)):
    l, o = statistics.median(llama[test]), statistics.median(ours[test])
    rows[test] = {"n": int(n), "llama_bench_tok_s": l, "ours_tok_s": o, "ratio": o / l,
                  "llama_bench_samples": llama[test], "ours_samples": ours[test]}
    fmt = lambda xs: " ".join(f"{x:.1f}" for x in xs)
    print(f"{test + n:<8}{l:>20.2f}{o:>14.2f}{o / l:>12.3f}  {fmt(llama[test])} | {fmt(ours[test])}")
if json_out:
    with open(json_out, "w") as f:
        json.dump({"model": os.path.basename(model), "threads": int(threads),
                   "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY"), "rounds": rounds,
                   "tests": rows}, f, indent=2)
EOF
