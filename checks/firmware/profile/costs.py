#!/usr/bin/env python3
"""Where a run's mean step goes: the `cost` records of the harness's `costs<K>` command
(each step's Thumb-2 instructions, the mode and coordinates it started in, `event` if
it had an event, a coordinate switch or a mode change) grouped by what the step was.

    costs.py LOG

A row per mode and coordinates for the steps without an event (their median, mean and
largest step, and their share of the run's mean: their instructions over all the
run's steps), the steps of each row over 1.5 times its median apart (a step redone in
sub-steps after its energy balance broke, or one that looked at other coordinates),
and the event steps in one row.
"""
import collections
import re
import signal
import statistics
import sys

# Quietly cut off when piped into `head`.
signal.signal(signal.SIGPIPE, signal.SIG_DFL)

steps = []
for line in open(sys.argv[1], errors="replace"):
    m = re.match(r"(\S+) cost (\d+) (\d+) (\S+)( event)?$", line.strip())
    if m:
        steps.append((int(m.group(2)), int(m.group(3)), m.group(4), bool(m.group(5))))
if not steps:
    sys.exit("no cost records in " + sys.argv[1])
n = len(steps)
total = sum(c for _, c, _, _ in steps)
rows = collections.defaultdict(list)
for _, c, kind, event in steps:
    rows["events" if event else kind].append(c)
table = []
for kind, counts in rows.items():
    if kind == "events":
        table.append((kind, counts))
        continue
    median = statistics.median(counts)
    plain = [c for c in counts if c <= 1.5 * median]
    dear = [c for c in counts if c > 1.5 * median]
    table.append((kind, plain))
    if dear:
        table.append((kind + ", over 1.5x its median", dear))
print(f"{n} steps, mean {total / n:,.0f} instructions")
print(f"{'steps of':<40} {'steps':>6} {'median':>9} {'mean':>9} {'largest':>9} {'share of the mean':>18}")
for kind, counts in sorted(table, key=lambda r: -sum(r[1])):
    print(
        f"{kind:<40} {len(counts):>6} {statistics.median(counts):>9,.0f} "
        f"{sum(counts) / len(counts):>9,.0f} {max(counts):>9,} {sum(counts) / n:>18,.0f}"
    )
