#!/usr/bin/env bash
# Build the page and serve it on http://127.0.0.1:PORT/ (PORT default 8000), with Node
# (serve.mjs) or, without Node, python3's http.server. Ctrl-C stops it.
# Usage: bash demos/web/serve.sh [PORT]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
port="${1:-${PORT:-8000}}"
bash build.sh
echo "open http://127.0.0.1:$port/ (scene picker, reset, play/pause, step, throw, fire)"
echo "test mode: http://127.0.0.1:$port/index.html?scene=mixed&steps=1000&test=1"
if command -v node >/dev/null; then
    exec node serve.mjs "$port"
else
    exec python3 -m http.server "$port" --bind 127.0.0.1
fi
