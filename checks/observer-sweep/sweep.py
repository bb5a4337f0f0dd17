#!/usr/bin/env python3
"""The observer across operating points: the known machine (`known-machine.toml`,
bench1's identified one) run at each load and motor torque of OPERATING_POINTS, its
logs written in bench1's format with three seeds of the torque sensor's noise
(`make_known_logs.py`), each replayed three ways:

- `open`: open loop with the machine's own parameters (the control: no model error,
  so the twin should make the machine's events and counts);
- `identified`: the observer tuned for an identified twin (`--observer identified`)
  with the machine's own parameters, from its start angle;
- `exact-nom`: the same twin with the observer tuned for nominal parameters (the
  mismatch the tunings are for);
- `nominal`: the observer tuned for nominal parameters with SPEC's parameters
  (`ccc-s2.toml`), from a crank angle 5° off (issue 19's case for bench1).

For each replay: whether the twin makes the machine's clutch events in the same order
(and if not, the first pair that differs), the crank residual's RMS after 20 ms,
counts, and the events within 1 ms. A measurement, not a test: it exits 0 whenever
every replay ran, whatever the numbers.

    python3 sweep.py HOST_SIM WORK_DIR
"""
import os, re, subprocess, sys

OPERATING_POINTS = [(1000, 14), (800, 10), (800, 16), (600, 12), (400, 12)]
SEEDS = [1, 2, 3]

host_sim, work = sys.argv[1], sys.argv[2]
root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
data = os.path.join(root, "host-sim", "tests", "data")
spec = open(os.path.join(root, "host-sim", "scenarios", "ccc-s2.toml")).read()
nominal = os.path.join(work, "nominal-110deg.toml")
assert "crank_deg = 105.0" in spec
open(nominal, "w").write(spec.replace("crank_deg = 105.0", "crank_deg = 110.0"))
exact = os.path.join(data, "known-machine.toml")


def replay(log, clutch, params, tuning, out):
    args = [host_sim, "replay", log, "--params", params, "--clutch-log", clutch, "--out", out]
    if tuning:
        args += ["--observer", tuning]
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"replay of {log} failed ({r.returncode}): {r.stderr}")
    text = r.stdout + r.stderr
    # The crank's residual after 20 ms (observed), else over the whole log (open loop).
    m = re.search(r"after 0\.02 s:.*?residual \(measured - twin\) RMS ([0-9.]+) counts", text, re.S)
    if not m:
        m = re.search(r"crank\s+residual \(measured - twin\) RMS ([0-9.]+) counts", text)
    rms = float(m.group(1))
    pairs = re.search(r"the machine (\d+) events, the twin (\d+)", text)
    mismatch = re.search(r"the first mismatch is pair (\d+) \(t = ([0-9.]+) s\)", text)
    dts = [float(x) for x in re.findall(r"([-+][0-9.]+) ms", text)]
    return {
        "same": mismatch is None and pairs.group(1) == pairs.group(2),
        "mismatch": mismatch.group(2) if mismatch else "",
        "events": int(pairs.group(1)),
        "within": sum(abs(d) <= 1.0 for d in dts),
        "rms": rms,
    }


rows = []
for load, motor in OPERATING_POINTS:
    for seed in SEEDS:
        d = os.path.join(work, f"{load}Nm-{motor}Nm-{seed}")
        os.makedirs(d, exist_ok=True)
        subprocess.run([sys.executable, os.path.join(data, "make_known_logs.py"), host_sim,
                        str(load), str(motor), str(seed), d], check=True)
        log = os.path.join(d, f"known-{load}Nm-{motor}Nm.csv")
        clutch = os.path.join(d, f"known-{load}Nm-{motor}Nm_clutch_log.csv")
        for name, params, tuning in [("open", exact, None), ("identified", exact, "identified"),
                                     ("exact-nom", exact, "nominal"),
                                     ("nominal", nominal, "nominal")]:
            r = replay(log, clutch, params, tuning, os.path.join(d, f"{name}.csv"))
            rows.append((load, motor, seed, name, r))

print(f"{'T_r':>5} {'motor':>5} {'seed':>4} {'replay':10} {'sequence':>22} {'RMS':>8} {'in 1 ms':>8}")
for load, motor, seed, name, r in rows:
    seq = "same" if r["same"] else f"parts at {r['mismatch']} s"
    print(f"{load:>5} {motor:>5} {seed:>4} {name:10} {seq:>22} {r['rms']:>8.2f} "
          f"{r['within']:>3}/{r['events']:<4}")
for name in ("open", "identified", "exact-nom", "nominal"):
    mine = [r for *_, n, r in rows if n == name]
    kept = sum(r["same"] for r in mine)
    good = sum(r["same"] and r["rms"] <= 1.0 for r in mine)
    print(f"{name}: the machine's sequence kept in {kept} of {len(mine)} logs; "
          f"kept with crank RMS <= 1 count in {good}")
