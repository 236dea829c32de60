#!/usr/bin/env bash
# What carom costs on a Cortex-M, libm against micromath, on the Cortex-M4F (hardware
# single-precision FPU) and on the soft-float Cortex-M3: flash, static RAM, peak stack and
# instructions per step of the two firmwares, measured under QEMU.
#
# Usage: bash demos/cortex-m/measure.sh [CORE ...]      CORE: m4f, m3 (default: both)
# Environment: BACKENDS (default "libm micromath"), FIRMWARES (default "minimal full"),
# CARGO_TARGET_DIR (honoured), TIMEOUT per QEMU run (default 3000 s).
#
# For each core and backend it builds the firmwares (run.sh: release, opt-level "s", LTO)
# and runs them under `qemu-system-arm -icount shift=0`, where QEMU's virtual clock
# advances 1 ns per executed instruction; the firmwares time every World::step with
# SysTick at the MPS2 boards' 25 MHz, so one tick is 40 instructions (src/ticks.rs). The
# figures:
#   flash        text + data of the ELF (llvm-size; text includes .rodata and the vectors)
#   static RAM   data + bss
#   stack        the peak stack of the whole run (painted, src/stack.rs)
#   instr/step   mean and largest over the timed steps: `minimal`'s 120 steps (one ball
#                on the ground: World<4, 8, 8>) and, in the full firmware, the 1000 steps
#                of the `mixed` scene (125 bodies of every shape in a
#                scenes::ReferenceWorld); then the same for `tower` (11 bodies), whose run
#                gives the same bits with both backends, so both do the same work
# Then, per core, the stack each query needs (src/bin/stack_queries.rs, libm): the painted
# peak of one call of each stateless query and of the steps of a 13-body world.
# The full firmware's golden lines are checked against tests/golden/checksums.txt
# (libm) or checksums_micromath.txt (micromath) on the way: a wrong line fails the run.
# QEMU counts instructions, not cycles: a real M3 or M4 takes 1 to ~12 cycles per
# instruction (more for flash wait states), so compare the figures with each other.
# Takes about 25 minutes for both cores and both backends on a busy 2-core machine (the
# full firmware on the M3 is the slow part). Needs the rustup targets
# thumbv7em-none-eabihf and thumbv7m-none-eabi, qemu-system-arm and llvm-size (or size).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
cores=("$@")
[[ ${#cores[@]} -gt 0 ]] || cores=(m4f m3)
read -r -a backends <<<"${BACKENDS:-libm micromath}"
read -r -a firmwares <<<"${FIRMWARES:-minimal full}"
target_dir="${CARGO_TARGET_DIR:-$here/target}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

elf_size() { # ELF -> "text data bss"
    (llvm-size "$1" 2>/dev/null || size "$1") | tail -n 1 | awk '{print $1, $2, $3}'
}

# check_golden OUTPUT GOLDEN: the golden lines, then `restored <the mixed line>`.
check_golden() {
    local n
    n="$(wc -l <"$2")"
    head -n "$n" "$1" | diff "$2" - >&2
    [[ "$(sed -n "$((n + 1))p" "$1")" == "restored $(grep '^mixed ' "$2")" ]]
}

printf '| core | math | firmware | flash (B) | static RAM (B) | peak stack (B) | instructions per step: mean | max |\n'
printf '| --- | --- | --- | ---: | ---: | ---: | ---: | ---: |\n'
for core in "${cores[@]}"; do
    case "$core" in
        m4f) target=thumbv7em-none-eabihf ;;
        m3) target=thumbv7m-none-eabi ;;
        *)
            echo "measure.sh: unknown core '$core' (m4f or m3)" >&2
            exit 2
            ;;
    esac
    for backend in "${backends[@]}"; do
        features=""
        golden="$root/tests/golden/checksums.txt"
        if [[ $backend == micromath ]]; then
            features=micromath
            golden="$root/tests/golden/checksums_micromath.txt"
        fi
        for fw in "${firmwares[@]}"; do
            bin=minimal
            [[ $fw == full ]] && bin=carom-demo-cortex-m
            log="$out/$core-$backend-$fw"
            CORE="$core" FEATURES="$features" QEMU_ARGS="-icount shift=0" \
                TIMEOUT="${TIMEOUT:-3000}" bash "$here/run.sh" "$bin" >"$log"
            if [[ $fw == full ]]; then
                check_golden "$log" "$golden" ||
                    { echo "measure.sh: $core $backend: golden lines differ" >&2; exit 1; }
            fi
            read -r text data bss <<<"$(elf_size "$target_dir/$target/release/$bin")"
            stack="$(sed -nE 's/^stack ([0-9]+) bytes$/\1/p' "$log")"
            scene=ball
            [[ $fw == full ]] && scene=mixed
            read -r steps total max <<<"$(sed -nE \
                "s/^ticks $scene ([0-9]+) steps total ([0-9]+) max ([0-9]+)\$/\\1 \\2 \\3/p" \
                "$log")"
            printf '| %s | %s | %s | %d | %d | %d | %d | %d |\n' "$core" "$backend" \
                "$fw" $((text + data)) $((data + bss)) "$stack" \
                $((total * 40 / steps)) $((max * 40))
            if [[ $fw == full ]]; then
                read -r steps total max <<<"$(sed -nE \
                    's/^ticks tower ([0-9]+) steps total ([0-9]+) max ([0-9]+)$/\1 \2 \3/p' \
                    "$log")"
                printf '| %s | %s | full: tower | | | | %d | %d |\n' "$core" "$backend" \
                    $((total * 40 / steps)) $((max * 40))
            fi
        done
    done
done

printf '\n| query | %s |\n| --- |%s\n' "$(printf '%s stack (B) | ' "${cores[@]}" | sed 's/ | $//')" \
    "$(printf ' ---: |%.0s' "${cores[@]}")"
for core in "${cores[@]}"; do
    CORE="$core" TIMEOUT="${TIMEOUT:-3000}" bash "$here/run.sh" stack_queries >"$out/stack-$core"
done
while read -r _ query _; do
    row="| $query |"
    for core in "${cores[@]}"; do
        row="$row $(sed -nE "s/^stack $query ([0-9]+) bytes\$/\\1/p" "$out/stack-$core") |"
    done
    echo "$row"
done <"$out/stack-${cores[0]}"
