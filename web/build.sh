#!/usr/bin/env bash
# Builds the core for the page twice, scalar and with wasm SIMD (+simd128), into
# web/aprt-scalar.wasm and web/aprt-simd.wasm, shrinks both with `wasm-opt -Oz` when binaryen
# is installed, and prints their bytes; copies the WebGPU path's kernel, aprt-gpu's WGSL, into
# web/wgsl/. Run from anywhere; needs the wasm32 target
# (`rustup target add wasm32-unknown-unknown`).
set -euo pipefail
web="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$web")"
cd "$root"

# Speed first (opt-level 3: the page times the core against native), then strip what a page
# never needs: debug info, symbol names, unwinding.
export CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true
export CARGO_PROFILE_RELEASE_LTO=true CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1
export CARGO_PROFILE_RELEASE_PANIC=abort

build() { # flavour, extra rustflags
  local dir="$root/target/web-$1"
  RUSTFLAGS="${2:-}" cargo build -q -p aprt-wasm --release --target wasm32-unknown-unknown \
    --target-dir "$dir"
  cp "$dir/wasm32-unknown-unknown/release/aprt_wasm.wasm" "$web/aprt-$1.wasm"
  local raw
  raw=$(wc -c <"$web/aprt-$1.wasm")
  if command -v wasm-opt >/dev/null; then
    # Rust enables these post-MVP features by default (binaryen 108 does not).
    local features=(--enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext
      --enable-mutable-globals --enable-reference-types --enable-multivalue)
    [ "$1" = simd ] && features+=(--enable-simd)
    wasm-opt -Oz "${features[@]}" "$web/aprt-$1.wasm" -o "$web/aprt-$1.wasm"
    echo "aprt-$1.wasm: $raw bytes from cargo, $(wc -c <"$web/aprt-$1.wasm") after wasm-opt -Oz"
  else
    echo "aprt-$1.wasm: $raw bytes (wasm-opt not installed: apt-get install binaryen)"
  fi
}

build scalar ""
build simd "-C target-feature=+simd128"

# The page is served from web/ alone (`python3 -m http.server` there, or any static host), so
# it cannot fetch gpu/src/shaders/: it gets a copy, byte for byte, which trainer/tests/browser.rs
# checks against the source (a stale copy fails `cargo test`, not the page).
mkdir -p "$web/wgsl"
cp gpu/src/shaders/rows.wgsl gpu/src/shaders/shade.wgsl "$web/wgsl/"
