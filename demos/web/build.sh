#!/usr/bin/env bash
# Build the page's module: carom for wasm32-unknown-unknown (release), copied to
# demos/web/pkg/carom_demo_web.wasm next to index.html (pkg/ is gitignored).
# CARGO_TARGET_DIR is honoured.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
fi
cargo build --release --target wasm32-unknown-unknown
target_dir="${CARGO_TARGET_DIR:-target}"
mkdir -p pkg
cp "$target_dir/wasm32-unknown-unknown/release/carom_demo_web.wasm" pkg/
echo "built demos/web/pkg/carom_demo_web.wasm ($(wc -c <pkg/carom_demo_web.wasm) bytes)" >&2
