#!/usr/bin/env bash
# Long random fuzzing runs (not part of CI): every target for SECONDS (default 1800, the
# 30 minutes FUZZING.md reports), one after the other, each from its seeds and findings
# plus a corpus kept in fuzz/corpus/<target> (ignored by git). Prints one summary line
# per target: executions, seconds, corpus size, crashes. A crash leaves its input in
# fuzz/artifacts/<target>/: copy it to fuzz/findings/<target>/, make it a named test in
# tests/ (see tests/world_fuzz.rs, tests/fuzz_regressions.rs), fix, and record it in
# FUZZING.md.
#
# Usage: bash fuzz/long.sh [SECONDS] [TARGET...]
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds="${1:-1800}"
shift || true
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=(narrow_phase hull toi world snapshot mesh)
mkdir -p fuzz/logs
cargo +nightly fuzz build --debug-assertions --sanitizer none || exit 1
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t" "fuzz/seeds/$t" "fuzz/findings/$t"
    log="fuzz/logs/$t.log"
    cargo +nightly fuzz run --debug-assertions --sanitizer none "$t" "fuzz/corpus/$t" \
        "fuzz/seeds/$t" "fuzz/findings/$t" -- -max_total_time="$seconds" -timeout=10 \
        -rss_limit_mb=2048 >"$log" 2>&1
    rc=$?
    done_line="$(grep -o 'Done [0-9]* runs in [0-9]* second(s)' "$log" | tail -n 1)"
    corpus="$(find "fuzz/corpus/$t" -type f | wc -l)"
    crashes="$(find "fuzz/artifacts/$t" -type f 2>/dev/null | wc -l)"
    echo "$t: exit $rc; ${done_line:-no summary}; corpus $corpus; artifacts $crashes"
done
