#!/usr/bin/env bash
# Time per step of the box, hull and sphere scenes on wasm32-wasip1 under Node, built
# without and with WebAssembly's SIMD (`-C target-feature=+simd128`), run one after the
# other REPS times (default 3; the first build goes first in odd repetitions); prints a
# Markdown table of the medians and fails if the two builds' checksums differ.
# Usage: bash demos/wasm/bench.sh [SCENE ...] (default: pyramid20 boxes hulls spheres;
# STEPS=N caps each scene's steps). Needs Node >= 20 and the wasm32-wasip1 target.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
reps="${REPS:-3}"
scenes=("$@")
[[ ${#scenes[@]} -gt 0 ]] || scenes=(pyramid20 boxes hulls spheres)
steps=()
[[ -z ${STEPS:-} ]] || steps=(--steps "$STEPS")
build() { # NAME RUSTFLAGS
    RUSTFLAGS="$2" cargo build --profile speed --target wasm32-wasip1 --quiet --bin bench \
        --target-dir "$here/target/bench-$1"
}
build scalar ""
build simd128 "-C target-feature=+simd128"
out="$(mktemp -d)"
run() { # NAME REP
    node --no-warnings "$here/run.mjs" "$here/target/bench-$1/wasm32-wasip1/speed/bench.wasm" \
        "${scenes[@]}" "${steps[@]}" >"$out/$1.$2"
}
for rep in $(seq 1 "$reps"); do
    if ((rep % 2)); then run scalar "$rep"; run simd128 "$rep"; else run simd128 "$rep"; run scalar "$rep"; fi
    echo "repetition $rep of $reps done" >&2
done
median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
echo "| scene | steps | scalar ms/step | simd128 ms/step | scalar/simd128 | checksum (both) |"
echo "| --- | ---: | ---: | ---: | ---: | --- |"
status=0
for s in "${scenes[@]}"; do
    a="$(cat "$out"/scalar.* | awk -v s="$s" '$1 == s {print $7}' | median)"
    b="$(cat "$out"/simd128.* | awk -v s="$s" '$1 == s {print $7}' | median)"
    n="$(awk -v s="$s" '$1 == s {print $3; exit}' "$out/scalar.1")"
    ca="$(awk -v s="$s" '$1 == s {print $5}' "$out"/scalar.* | sort -u)"
    cb="$(awk -v s="$s" '$1 == s {print $5}' "$out"/simd128.* | sort -u)"
    if [[ "$ca" != "$cb" || $(wc -l <<<"$ca") -ne 1 ]]; then
        echo "checksums differ for $s: scalar $ca, simd128 $cb" >&2
        status=1
    fi
    echo "| $s | $n | $a | $b | $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.2f", a / b}') | \`$ca\` |"
done
rm -rf "$out"
exit "$status"
