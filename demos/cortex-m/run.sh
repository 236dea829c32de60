#!/usr/bin/env bash
# Build the Cortex-M4F firmwares (release) and run one under QEMU mps2-an386 with
# semihosting. Usage: run.sh [BIN]   BIN: carom-demo-cortex-m (default), minimal or
# panic_never (the panic-never check: prints nothing, exits 0).
# Prints what the firmware prints (carom-demo-cortex-m: the golden lines, the restored
# line, the peak stack; minimal: the ball line and the peak stack) and exits with the
# firmware's semihosting exit status; fails after TIMEOUT seconds (default 600: the full
# run takes about 100 s under QEMU on a busy 2-core machine).
# Needs the thumbv7em-none-eabihf target and qemu-system-arm (Debian: qemu-system-arm).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
bin="${1:-carom-demo-cortex-m}"
cargo build --release --quiet --bins
elf="$here/target/thumbv7em-none-eabihf/release/$bin"
timeout --kill-after=5 "${TIMEOUT:-600}" \
  qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel "$elf" </dev/null
