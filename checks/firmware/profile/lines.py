#!/usr/bin/env python3
"""A line-level profile of a firmware run: the TCG plugin's blocks (`<first hex> <last
hex> <instructions> <executions>`) spread over their instructions (the disassembly's
addresses), each instruction given to the innermost source line of the project's own
code that it was inlined from (`addr2line -i`: a `core::` iterator or an `f64` `Add`
inlined into a pass is counted on the pass's line), and the memory helpers' call sites
with the bytes each call's immediate gives.

    lines.py ELF DISASSEMBLY BLOCKS TOP [PREFIX]

PREFIX: the source paths counted as the project's (default: this checkout's root).
"""
import bisect
import collections
import re
import subprocess
import sys
from pathlib import Path

from calls import helper_calls

elf, dis_path, blocks_path, top = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
prefix = sys.argv[5] if len(sys.argv) > 5 else str(Path(__file__).resolve().parents[3]) + "/"

insn = re.compile(r"^\s*([0-9a-f]+):\s")
addrs = sorted(int(m.group(1), 16) for m in map(insn.match, open(dis_path)) if m)

# Executions of each instruction: its blocks' (a block retranslated is counted under
# both translations).
count = collections.Counter()
runs_to = collections.Counter()
for line in open(blocks_path):
    first, last, _, runs = line.split()
    a, b, runs = int(first, 16), int(last, 16), int(runs)
    runs_to[b] += runs
    i = bisect.bisect_left(addrs, a)
    while i < len(addrs) and addrs[i] <= b:
        count[addrs[i]] += runs
        i += 1


def frames(addresses):
    """Each address's inlined source locations, innermost first (`addr2line -a -f -i`:
    the address, then a function and a location per frame)."""
    out = subprocess.run(
        ["addr2line", "-e", elf, "-a", "-f", "-C", "-i"],
        input="".join(f"{a:#x}\n" for a in addresses),
        capture_output=True, text=True, check=True,
    ).stdout.splitlines()
    result, cur = {}, None
    for line in out:
        if re.fullmatch(r"0x[0-9a-f]+", line):
            cur = int(line, 16)
            result[cur] = []
        elif cur is not None:
            result[cur].append(line)
    return {a: fr[1::2] for a, fr in result.items()}


def ours(locations):
    """The innermost location in the project's code, else the innermost one."""
    pick = next((x for x in locations if x.startswith(prefix)), locations[0] if locations else "?")
    return re.sub(r" \(discriminator \d+\)", "", pick).replace(prefix, "")


located = frames(list(count))
lines = collections.Counter()
for a, n in count.items():
    lines[ours(located.get(a, []))] += n
total = sum(count.values())
print(f"instructions executed (plugin): {total:,}")
print(f"{'own':>12} {'share':>6}  innermost line of the project's code")
for loc, n in lines.most_common(top):
    print(f"{n:12,} {100 * n / total:5.1f}%  {loc}")

# The memory helpers' calls by site.
sites = [(n * nbytes, n, nbytes, addr, helper)
         for addr, helper, n, nbytes in helper_calls(dis_path, runs_to)]
sites.sort(reverse=True)
located = frames([s[3] for s in sites[:top]])
print()
print(f"{'bytes':>13} {'calls':>9} {'size':>6}  helper  <- site (innermost line of the project's code)")
for b, n, nbytes, addr, helper in sites[:top]:
    print(f"{b:13,} {n:9,} {nbytes:6}  {helper} <- {ours(located.get(addr, []))}")
