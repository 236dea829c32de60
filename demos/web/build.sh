#!/usr/bin/env bash
# Build the page's module: carom for wasm32-unknown-unknown (release), copied to
# demos/web/pkg/carom_demo_web.wasm next to index.html (pkg/ is gitignored).
# CARGO_TARGET_DIR is honoured.
#
# Built with WebAssembly's SIMD (`-C target-feature=+simd128`, in every current browser:
# Chrome and Edge 91, Firefox 89, Safari 16.4): the solver's four lanes then run as
# vector instructions, with the same bits (test.sh checks the golden lines in Chromium).
# SIMD=0 builds the scalar module instead, for an older browser; it goes to its own
# target directory, so the two builds do not rebuild each other.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
fi
target_dir="${CARGO_TARGET_DIR:-target}"
if [[ ${SIMD:-1} == 1 ]]; then
    export RUSTFLAGS="${RUSTFLAGS:-} -C target-feature=+simd128"
else
    target_dir="$target_dir/scalar"
fi
cargo build --release --target wasm32-unknown-unknown --target-dir "$target_dir"
mkdir -p pkg
cp "$target_dir/wasm32-unknown-unknown/release/carom_demo_web.wasm" pkg/
echo "built demos/web/pkg/carom_demo_web.wasm ($(wc -c <pkg/carom_demo_web.wasm) bytes)" >&2
