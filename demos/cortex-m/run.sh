#!/usr/bin/env bash
# Build the Cortex-M4F firmware (release) and run it under QEMU mps2-an386 with
# semihosting. Prints what the firmware prints (one line: narrow <count> 0x<hash>) and
# exits with the firmware's semihosting exit status; fails after TIMEOUT seconds (120).
# Needs the thumbv7em-none-eabihf target and qemu-system-arm (Debian: qemu-system-arm).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
cargo build --release --quiet
elf="$here/target/thumbv7em-none-eabihf/release/carom-demo-cortex-m"
timeout --kill-after=5 "${TIMEOUT:-120}" \
  qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel "$elf" </dev/null
