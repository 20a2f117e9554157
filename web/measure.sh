#!/usr/bin/env bash
# The figures of docs/results/web.md: the core's µs per frame natively (the native_frame
# example, built with the .wasm builds' profile: LTO, one codegen unit, panic=abort) and in
# headless Chromium (web/test/browser-test.mjs, scalar and SIMD), in ROUNDS interleaved
# rounds (default 5) so a busy machine disturbs all three alike; prints each round and the
# medians with their ratios. Needs what the browser test needs (see trainer/tests/browser.rs).
set -euo pipefail
web="$(cd "$(dirname "$0")" && pwd)"
root="$(dirname "$web")"
cd "$root"
rounds="${ROUNDS:-5}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_LTO=true \
  CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1 CARGO_PROFILE_RELEASE_PANIC=abort \
  cargo build -q --release --target-dir target/web-native -p aprt-wasm --example native_frame
cargo build -q --release -p aprt-trainer --bin aprt
target/release/aprt eval web/data/model.aprt --builtin --clip wave --npy "$tmp/eval.npy"
for _ in $(seq "$rounds"); do
  target/web-native/release/examples/native_frame | tee -a "$tmp/log"
  node web/test/browser-test.mjs --reference "$tmp/eval.npy" | grep -E '^(scalar|simd):' | tee -a "$tmp/log"
done
awk '
  /^native:/ { n[++a] = $6 }
  /^(scalar|simd):/ { v = $0; sub(/.* relative \([^)]*\), /, "", v); v += 0 }
  /^scalar:/ { s[++b] = v }
  /^simd:/   { d[++c] = v }
  function sort(x, k,   i, j, t) {
    for (i = 1; i <= k; i++) for (j = i + 1; j <= k; j++) if (x[j] < x[i]) { t = x[i]; x[i] = x[j]; x[j] = t }
  }
  function median(x, k) { sort(x, k); return k % 2 ? x[(k + 1) / 2] : (x[k / 2] + x[k / 2 + 1]) / 2 }
  function row(what, m, lo) { printf "%-12s median %6.1f µs (%.2fx native)  fastest %6.1f µs (%.2fx native)\n", what, m, m / N, lo, lo / L }
  END {
    N = median(n, a); L = n[1]; S = median(s, b); D = median(d, c)
    printf "%d rounds, µs per frame (set_pose + light + shade of every vertex):\n", a
    row("native", N, L); row("wasm scalar", S, s[1]); row("wasm SIMD", D, d[1])
    printf "SIMD over scalar: %.2fx (medians)\n", S / D
  }' "$tmp/log"
