#!/usr/bin/env bash
# The page in a real headless Chromium: for each scene (default: the reference scenes
# mixed, bullets and tower), load index.html?scene=<scene>&steps=<steps>&test=1 with the
# steps of its line in tests/golden/checksums.txt, read the checksum the page wrote into
# #checksum and its title (`done 0x...`) from the DOM after the run, and compare them with
# the golden line; then save a screenshot of the final frame to demos/web/out/<scene>.png
# (gitignored). Exits non-zero on a mismatch, a page that did not finish, or a missing
# tool.
#
# Usage: bash demos/web/test.sh [SCENE ...]
# Needs: Node >= 18 (serves the page), Chromium (Debian: apt-get install chromium; or set
# CHROMIUM=/path/to/chrome), rustup's wasm32-unknown-unknown target (added if missing).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
golden=../../tests/golden/checksums.txt
scenes=("$@")
[[ ${#scenes[@]} -gt 0 ]] || scenes=(mixed bullets tower)

chromium="${CHROMIUM:-}"
if [[ -z $chromium ]]; then
    for c in chromium chromium-browser google-chrome; do
        if command -v "$c" >/dev/null; then
            chromium="$c"
            break
        fi
    done
fi
[[ -n $chromium ]] || { echo "test.sh: no chromium found (apt-get install chromium)" >&2; exit 1; }
command -v node >/dev/null || { echo "test.sh: node not found" >&2; exit 1; }

bash build.sh

tmp="$(mktemp -d)"
server_pid=""
cleanup() {
    if [[ -n $server_pid ]]; then
        kill "$server_pid" 2>/dev/null || true
        wait "$server_pid" 2>/dev/null || true
    fi
    rm -rf "$tmp"
}
trap cleanup EXIT

# Any free port: the server prints the one it got.
node serve.mjs 0 >"$tmp/server.log" 2>&1 &
server_pid=$!
url=""
for _ in $(seq 100); do
    url="$(grep -o 'http://127\.0\.0\.1:[0-9]*/' "$tmp/server.log" || true)"
    [[ -n $url ]] && break
    kill -0 "$server_pid" 2>/dev/null || break
    sleep 0.1
done
[[ -n $url ]] || { echo "test.sh: the server did not start" >&2; cat "$tmp/server.log" >&2; exit 1; }
echo "serving $url ($chromium: $("$chromium" --version 2>/dev/null || echo '?'))"

# One headless Chromium run of PAGE with extra flags; virtual time lets the page finish
# (the run is synchronous), `timeout` bounds the wall time.
chrome() { # PAGE PROFILE FLAGS...
    local page="$1" profile="$2"
    shift 2
    timeout 90 "$chromium" --headless=new --no-sandbox --disable-gpu --no-first-run \
        --disable-extensions --mute-audio --hide-scrollbars --user-data-dir="$profile" \
        --window-size=1024,768 --virtual-time-budget=60000 "$@" "$page" \
        2>>"$tmp/chromium.log"
}

mkdir -p out
failed=0
for scene in "${scenes[@]}"; do
    line="$(grep -m1 "^$scene " "$golden" || true)"
    if [[ -z $line ]]; then
        echo "FAIL $scene: no line in tests/golden/checksums.txt"
        failed=1
        continue
    fi
    read -r _ steps want <<<"$line"
    page="${url}index.html?scene=$scene&steps=$steps&test=1"
    start=$(date +%s.%N)
    dom="$(chrome "$page" "$tmp/profile-$scene-dom" --dump-dom || true)"
    seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    title="$(grep -o '<title>[^<]*' <<<"$dom" | head -n1 | sed 's/^<title>//' || true)"
    got="$(grep -o 'id="checksum">[^<]*' <<<"$dom" | head -n1 | sed 's/^.*>//' || true)"
    shot="$PWD/out/$scene.png"
    rm -f "$shot"
    chrome "$page" "$tmp/profile-$scene-shot" --screenshot="$shot" >/dev/null || true
    [[ -s $shot ]] || shot="(no screenshot)"
    if [[ $title == "done $want" && $got == "$want" ]]; then
        echo "PASS $scene $steps $got = golden, page run ${seconds} s, screenshot $shot"
    else
        echo "FAIL $scene $steps: page title '${title:-none}', #checksum '${got:-none}'," \
            "golden $want (page run ${seconds} s, screenshot $shot)"
        failed=1
    fi
done
if [[ $failed -ne 0 ]]; then
    echo "--- chromium's log (last 20 lines)"
    grep -v dbus "$tmp/chromium.log" | tail -n 20 || true
    exit 1
fi
echo "web page in headless chromium: ${#scenes[@]} scene(s) match tests/golden/checksums.txt"
