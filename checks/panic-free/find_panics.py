#!/usr/bin/env python3
"""Lists the panics still reachable in a `--features diagnose` build of the check.

When the panic-freedom check fails to link, the linker only names the panic handler.
Build the same binary with `--features diagnose` (its panic handler spins, so it links)
and run this script on it: it prints every call into `core::panicking` and friends with
its inlined source chain (innermost first), e.g.

    core::panicking::panic_bounds_check | twin.rs:866

Usage (host; for thumbv7em pass the toolchain's llvm-objdump, from
`rustup component add llvm-tools`, as the second argument):

    cargo build --release --manifest-path checks/panic-free/Cargo.toml --features diagnose
    python3 checks/panic-free/find_panics.py \\
        checks/panic-free/target/release/structomat-panic-free [objdump]

A developer's aid, not part of CI (CI needs only the Rust toolchain).
"""
import re
import subprocess
import sys

binary = sys.argv[1]
objdump = sys.argv[2] if len(sys.argv) > 2 else "objdump"
listing = subprocess.run(
    [objdump, "-d", "--no-show-raw-insn", "-C", binary], capture_output=True, text=True
).stdout
# x86 `call`, ARM `bl`/`b.w` into a panicking function.
call = re.compile(
    r"^\s*([0-9a-f]+):\s+(?:call|bl|b|b\.w)\s.*<(.*(?:panic|_fail|unwrap_failed"
    r"|expect_failed|rust_begin_unwind|assert_failed).*)>"
)
# Calls made inside the panic machinery itself are not sites.
machinery = ("core::panicking", "core::slice::index", "core::option::", "core::result::",
             "rust_begin_unwind", "core::fmt")
function = None
sites = []
for line in listing.splitlines():
    m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
    if m:
        function = m.group(1)
        continue
    m = call.search(line)
    if m and function and not any(x in function for x in machinery):
        sites.append((m.group(1), m.group(2)[:50]))
for address, target in sites:
    out = subprocess.run(["addr2line", "-f", "-i", "-C", "-e", binary, "0x" + address],
                         capture_output=True, text=True).stdout.strip().splitlines()
    chain = [out[i + 1].split("/")[-1] for i in range(0, len(out) - 1, 2)]
    print(target, "|", " <- ".join(chain))
print(len(sites), "call sites", file=sys.stderr)
