#!/usr/bin/env python3
"""Maps the TCG plugin's blocks (`<first hex> <last hex> <instructions> <executions>`) to the
firmware's functions (`nm -C -n`'s text symbols) and prints the functions by their own
instructions (those of their blocks), with the run's per-step records for scale.

    aggregate.py SYMBOLS BLOCKS LOG TOP
"""
import bisect
import collections
import re
import sys

from calls import helper_calls

symbols_path, blocks_path, log_path, top = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
disassembly = sys.argv[5] if len(sys.argv) > 5 else None

starts, names = [], []
for line in open(symbols_path):
    parts = line.split(None, 2)
    # Mapping symbols ($t, $d: where Thumb code and data begin) are no functions.
    if len(parts) == 3 and parts[1] in "tTWw" and not parts[2].startswith("$"):
        # Thumb functions' symbols carry the Thumb bit; blocks start at even addresses.
        starts.append(int(parts[0], 16) & ~1)
        names.append(parts[2].strip())
order = sorted(range(len(starts)), key=lambda i: starts[i])
starts = [starts[i] for i in order]
names = [names[i] for i in order]

own = collections.Counter()
total = 0
# Executions of each instruction address that ends a block (a call ends its block;
# a block retranslated is counted under both translations).
runs_to = collections.Counter()
for line in open(blocks_path):
    start, last, insns, runs = line.split()
    n = int(insns) * int(runs)
    total += n
    runs_to[int(last, 16)] += int(runs)
    i = bisect.bisect_right(starts, int(start, 16)) - 1
    own[names[i] if i >= 0 else "?"] += n


def function_of(addr):
    """The index of the function `addr` lies in (names repeat: two instances of a
    generic function demangle alike), -1 before the first."""
    return bisect.bisect_right(starts, addr) - 1


def short(name, width=110):
    # Drop generic arguments and the crate paths' prefixes: the function's own name.
    name = re.sub(r"<[^<>]*>", "", re.sub(r"<[^<>]*>", "", re.sub(r"<[^<>]*>", "", name)))
    return name if len(name) <= width else name[: width - 1] + "…"


log = open(log_path).read()
count = re.search(r"^(\S+) count new (\d+) mean (\d+) median (\d+) p99 (\d+) worst (\d+)", log, re.M)
if count:
    name, new, mean, median, p99, worst = count.groups()
    print(f"{name}: Twin::new_in {new}, a step mean {mean} median {median} p99 {p99} worst {worst} (-icount)")
print(f"instructions executed (plugin): {total:,}")
print(f"{'own':>12} {'share':>6}  function")
for name, n in own.most_common(top):
    print(f"{n:12,} {100 * n / total:5.1f}%  {short(name)}")

if disassembly:
    sites = collections.Counter()
    by_bytes = collections.Counter()
    for addr, helper, n, nbytes in helper_calls(disassembly, runs_to):
        caller = names[function_of(addr)] if function_of(addr) >= 0 else "?"
        key = (short(caller, 70), helper)
        sites[key] += n
        by_bytes[key] += n * nbytes
    print()
    print(f"{'calls':>10} {'bytes':>13}  helper  <- caller (bytes: the size's immediate, 0 if none)")
    for key, b in sorted(by_bytes.items(), key=lambda kv: (-kv[1], -sites[kv[0]]))[:top]:
        print(f"{sites[key]:10,} {b:13,}  {key[1]} <- {key[0]}")
