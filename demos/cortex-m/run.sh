#!/usr/bin/env bash
# Build the Cortex-M firmwares (release) and run one under QEMU with semihosting.
# Usage: run.sh [BIN]   BIN: carom-demo-cortex-m (default), minimal, stack_queries or
# panic_never (the panic-never check: prints nothing, exits 0).
# Environment:
#   CORE=m4f (default)  thumbv7em-none-eabihf on -machine mps2-an386 -cpu cortex-m4
#                       (hardware single-precision FPU)
#   CORE=m3             thumbv7m-none-eabi on -machine mps2-an385 -cpu cortex-m3 (no FPU:
#                       every float operation is compiler-builtins' soft-float)
#   FEATURES=micromath  build carom with the micromath backend (the firmware then prints
#                       tests/golden/checksums_micromath.txt's lines)
#   QEMU_ARGS="..."     extra QEMU arguments (measure.sh passes -icount shift=0)
#   TIMEOUT=600         seconds before the run is killed and fails
#   CARGO_TARGET_DIR    honoured, as cargo does (default demos/cortex-m/target)
# Prints what the firmware prints (carom-demo-cortex-m: the golden lines, the restored
# line, the peak stack, the step ticks; minimal: the ball line, the peak stack, the step
# ticks) and exits with the firmware's semihosting exit status. The full run takes about
# 100 s on the M4F and several minutes on the soft-float M3 under QEMU on a busy 2-core
# machine. Needs the rustup target and qemu-system-arm (Debian: qemu-system-arm).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
bin="${1:-carom-demo-cortex-m}"
case "${CORE:-m4f}" in
    m4f) target=thumbv7em-none-eabihf machine=mps2-an386 cpu=cortex-m4 ;;
    m3) target=thumbv7m-none-eabi machine=mps2-an385 cpu=cortex-m3 ;;
    *)
        echo "run.sh: CORE must be m4f or m3, not '$CORE'" >&2
        exit 2
        ;;
esac
features=()
if [[ -n "${FEATURES:-}" ]]; then
    features=(--features "$FEATURES")
fi
cargo build --release --quiet --bins --target "$target" ${features[@]+"${features[@]}"}
target_dir="${CARGO_TARGET_DIR:-$here/target}"
elf="$target_dir/$target/release/$bin"
# shellcheck disable=SC2086 # QEMU_ARGS is a list of words
timeout --kill-after=5 "${TIMEOUT:-600}" \
    qemu-system-arm -machine "$machine" -cpu "$cpu" -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native ${QEMU_ARGS:-} -kernel "$elf" </dev/null
