#!/usr/bin/env bash
# Build the WASM demo for wasm32-wasip1 (release) and run it under Node's WASI. Prints the
# golden lines of tests/golden/checksums.txt, then `restored mixed 1000 0x...`; the
# module's size goes to stderr. Needs Node >= 20 and the wasm32-wasip1 target.
#
# SIMD=1 builds it with `-C target-feature=+simd128` (WebAssembly's 128-bit SIMD, in
# every current browser and in Node): the solver's four lanes then run as vector
# instructions, and the lines must not change. That build goes to target/simd128, so the
# two builds do not rebuild each other.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
target_dir="$here/target"
if [[ ${SIMD:-0} == 1 ]]; then
    export RUSTFLAGS="${RUSTFLAGS:-} -C target-feature=+simd128"
    target_dir="$here/target/simd128"
fi
cargo build --release --target wasm32-wasip1 --quiet --target-dir "$target_dir"
wasm="$target_dir/wasm32-wasip1/release/carom-demo-wasm.wasm"
echo "wasm size: $(wc -c < "$wasm") bytes" >&2
exec node --no-warnings "$here/run.mjs" "$wasm"
