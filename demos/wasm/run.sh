#!/usr/bin/env bash
# Build the WASM demo for wasm32-wasip1 (release) and run it under Node's WASI. Prints the
# golden lines of tests/golden/checksums.txt, then `restored mixed 1000 0x...`; the
# module's size goes to stderr. Needs Node >= 20 and the wasm32-wasip1 target.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
cargo build --release --target wasm32-wasip1 --quiet
wasm="$here/target/wasm32-wasip1/release/carom-demo-wasm.wasm"
echo "wasm size: $(wc -c < "$wasm") bytes" >&2
exec node --no-warnings "$here/run.mjs" "$wasm"
