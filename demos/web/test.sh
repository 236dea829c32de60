#!/usr/bin/env bash
# The page in a real headless Chromium: for each scene (default: the reference scenes
# mixed, bullets and tower), load index.html?scene=<scene>&steps=<steps>&test=1 with the
# steps of its line in tests/golden/checksums.txt, wait (up to $WAIT seconds of wall time)
# for the page to POST its outcome to the server (serve.mjs prints `result <scene> <steps>
# <checksum> <ms>`), and compare the checksum with the golden line; then save a screenshot
# of the final frame to demos/web/out/<scene>.png (gitignored, best effort). Exits non-zero
# on a mismatch, a page that did not report in time, or a missing tool.
#
# Why not `--dump-dom`: Chromium dumps when it judges the page loaded, and the module's
# asynchronous compile does not hold that back, so on a slow or cold machine the dump can
# come before the run (CI once read '-' for the first scene that way).
#
# Usage: bash demos/web/test.sh [SCENE ...]
# Needs: Node >= 18 (serves the page), Chromium (Debian: apt-get install chromium; or set
# CHROMIUM=/path/to/chrome), rustup's wasm32-unknown-unknown target (added if missing).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
golden=../../tests/golden/checksums.txt
scenes=("$@")
WAIT="${WAIT:-120}"
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
# Stop every process whose command line names PATH (a Chromium and the helpers it forks,
# such as its crash handler, which outlive the `timeout` that started the browser and go on
# writing into the profile).
stop_named() { # PATH
    if command -v pkill >/dev/null; then
        pkill -f -- "$1" 2>/dev/null || true
    fi
}
# Never fails: a profile directory a late Chromium helper still writes into must not turn a
# passing check red (CI once failed on `rm: cannot remove ...: Directory not empty`).
cleanup() {
    if [[ -n $server_pid ]]; then
        kill "$server_pid" 2>/dev/null || true
        wait "$server_pid" 2>/dev/null || true
    fi
    stop_named "$tmp/profile-"
    for _ in $(seq 20); do
        rm -rf "$tmp" 2>/dev/null && break
        sleep 0.25
    done
    [[ ! -e $tmp ]] || echo "test.sh: left $tmp behind (a Chromium helper still writes there)" >&2
    return 0
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

# One headless Chromium run of PAGE with extra flags, bounded by `timeout` in wall time.
chrome() { # SECONDS PAGE PROFILE FLAGS...
    local seconds="$1" page="$2" profile="$3"
    shift 3
    timeout "$seconds" "$chromium" --headless=new --no-sandbox --disable-gpu --no-first-run \
        --disable-extensions --mute-audio --hide-scrollbars --user-data-dir="$profile" \
        --window-size=1024,768 "$@" "$page" 2>>"$tmp/chromium.log"
}

# Wait until the server has printed, after its first SKIP lines, a result line for SCENE
# (or an error line); print it.
wait_result() { # SCENE SKIP
    local line=""
    for _ in $(seq $((WAIT * 10))); do
        line="$(tail -n +$(($2 + 1)) "$tmp/server.log" | grep -m1 -a -E "^result ($1 |error)" || true)"
        [[ -n $line ]] && break
        sleep 0.1
    done
    echo "$line"
}

mkdir -p out
failed=0
run=0
for scene in "${scenes[@]}"; do
    run=$((run + 1)) # a fresh Chromium profile per run: a killed browser leaves its lock
    line="$(grep -m1 "^$scene " "$golden" || true)"
    if [[ -z $line ]]; then
        echo "FAIL $scene: no line in tests/golden/checksums.txt"
        failed=1
        continue
    fi
    read -r _ steps want <<<"$line"
    page="${url}index.html?scene=$scene&steps=$steps&test=1"
    start=$(date +%s.%N)
    seen="$(wc -l <"$tmp/server.log")"
    chrome "$WAIT" "$page" "$tmp/profile-$run" >/dev/null &
    chrome_pid=$!
    result="$(wait_result "$scene" "$seen")"
    kill "$chrome_pid" 2>/dev/null || true
    stop_named "$tmp/profile-$run"
    wait "$chrome_pid" 2>/dev/null || true
    seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    read -r _ _ _ got ms <<<"$result"
    shot="$PWD/out/$scene.png"
    rm -f "$shot"
    chrome 90 "$page" "$tmp/profile-$run-shot" --virtual-time-budget=60000 \
        --screenshot="$shot" >/dev/null || true
    stop_named "$tmp/profile-$run-shot"
    [[ -s $shot ]] || shot="(no screenshot)"
    if [[ $got == "$want" ]]; then
        echo "PASS $scene $steps $got = golden, page run ${ms} ms (${seconds} s with Chromium's start), screenshot $shot"
    else
        echo "FAIL $scene $steps: page said '${result:-nothing in ${WAIT} s}', golden $want" \
            "(screenshot $shot)"
        failed=1
    fi
done
if [[ $failed -ne 0 ]]; then
    echo "--- chromium's log (last 20 lines)"
    grep -v dbus "$tmp/chromium.log" | tail -n 20 || true
    exit 1
fi
echo "web page in headless chromium: ${#scenes[@]} scene(s) match tests/golden/checksums.txt"
