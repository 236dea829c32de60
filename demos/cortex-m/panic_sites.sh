#!/usr/bin/env bash
# List the panic call sites the panic-never firmware (src/bin/panic_never.rs) can reach:
# link it once with the missing symbol defined, disassemble, and name the carom source
# line of every call into core's panic functions. For when `.ci/run`'s panic-never step
# fails. Needs llvm-objdump, llvm-symbolizer (Debian: llvm) and python3.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
cargo rustc --release --quiet --bin panic_never -- \
    -C link-arg=--defsym=carom_panic_is_reachable=0
elf="$here/target/thumbv7em-none-eabihf/release/panic_never"
llvm-objdump -d --demangle --no-show-raw-insn "$elf" | python3 -c '
import re, subprocess, sys
elf = sys.argv[1]
panics = ("core::panicking", "slice_index_fail", "panic_on_ord_violation",
          "len_mismatch_fail", "unwrap_failed", "expect_failed")
fn, sites = None, []
for line in sys.stdin:
    m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
    if m:
        fn = fn if m.group(1).startswith("$") else m.group(1)
        continue
    m = re.match(r"^\s*([0-9a-f]+):\s+(bl|b|b\.w|blx)\s.*<(.*)>", line)
    if m and any(p in m.group(3) for p in panics) and not any(p in (fn or "") for p in panics):
        sites.append((m.group(1), m.group(3), fn))
for addr, target, fn in sites:
    out = subprocess.run(["llvm-symbolizer", "--obj=" + elf, "-i", "0x" + addr],
                         capture_output=True, text=True).stdout.split("\n")
    frames = [l for l in out if "/src/" in l and "rustc" not in l]
    name = target.split("::")[-1]
    print(name.ljust(24), fn)
    for f in frames[:4]:
        print("    " + f)
print(f"{len(sites)} panic call site(s)")
' "$elf"
