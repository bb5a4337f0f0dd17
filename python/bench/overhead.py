"""Python's overhead on a scenario run and the cost of one Twin.step from Python.

    python python/bench/overhead.py [HOST_SIM]

For each scenario: the best of 5 wall times of structomat.run (the whole call: options,
the run, the numpy arrays) against the best of 5 of the run inside `host-sim run --out
FILE` (its summary's wall line: the run and its CSV, without the process start), and
the run's own wall inside the Python call (summary["wall"]). Then Twin.step()'s cost
per call from Python against the core's ns/step of the same steps in host-sim.
"""

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import structomat

ROOT = Path(__file__).resolve().parents[2]
HOST_SIM = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "target" / "release" / "host-sim")
REPEATS = 5


def cli_wall(source, args):
    with tempfile.TemporaryDirectory() as d:
        p = subprocess.run([HOST_SIM, "run", source, *args, "--out", f"{d}/r.csv"],
                           capture_output=True, text=True, check=False)
    m = re.search(r"^wall\s+([0-9.]+) s", p.stdout, re.M)
    if not m:
        raise SystemExit(f"no wall line from host-sim: {p.stdout}{p.stderr}")
    return float(m.group(1))


def measure(source, kw, args):
    py, inner, cli = [], [], []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        r = structomat.run(source, **kw)
        py.append(time.perf_counter() - t0)
        inner.append(r.summary["wall"])
        cli.append(cli_wall(source, args))
    return min(py), min(inner), min(cli)


def main():
    cases = [("ccc-s2", {"t_end": 1.0}, ["--t-end", "1.0"]),
             ("five-bar", {}, [])]
    print("scenario   python run   its run inside   host-sim run (CSV)   python vs host-sim   outside the run")
    for source, kw, args in cases:
        py, inner, cli = measure(source, kw, args)
        print(f"{source:10} {py:9.4f} s   {inner:9.4f} s      {cli:9.4f} s        "
              f"{100 * (py - cli) / cli:+6.2f} %            {100 * (py - inner) / inner:+6.2f} %")
    # Twin.step() against the run of the same steps, interleaved, best of each.
    n = 10000
    step, step_io, core, getter = [], [], [], []
    for _ in range(REPEATS):
        twin = structomat.Twin("ccc-s2")
        t0 = time.perf_counter()
        for _ in range(n):
            twin.step()
        step.append((time.perf_counter() - t0) / n)
        twin = structomat.Twin("ccc-s2")
        t0 = time.perf_counter()
        for _ in range(n):
            twin.step(12.0, 800.0)
            twin.mode, twin.crank_speed, twin.shaft_speed, twin.c6, twin.c8
        step_io.append((time.perf_counter() - t0) / n)
        t0 = time.perf_counter()
        for _ in range(n):
            twin.steps
        getter.append((time.perf_counter() - t0) / n)
        r = structomat.run("ccc-s2", t_end=n * 1e-4)
        core.append(r.summary["ns_per_step"] * 1e-9)
    ns = lambda v: min(v) * 1e9
    print(f"Twin.step() from Python, S2's first {n} steps at h = 1e-4: {ns(step):.0f} ns a call; "
          f"the core's Twin::step in the same steps (host-sim's pipeline): {ns(core):.0f} ns")
    print(f"a Python call into the twin (the getter Twin.steps): {ns(getter):.0f} ns")
    print(f"Twin.step(12.0, 800.0) then reading mode, crank and shaft speeds, c6, c8: "
          f"{ns(step_io):.0f} ns a step")

if __name__ == "__main__":
    main()
