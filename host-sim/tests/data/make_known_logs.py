#!/usr/bin/env python3
"""Writes `known-<T_r>Nm-<motor>Nm.csv` and `..._clutch_log.csv`: the converter of
`known-machine.toml` (bench1's identified machine, the truth) run by the twin at
another operating point, in bench1's format (see README.md beside this file).

    python3 make_known_logs.py HOST_SIM LOAD MOTOR SEED [OUT_DIR [MACHINE]]

HOST_SIM is a host-sim executable (`target/release/host-sim`); SEED seeds the torque
sensor's noise (Gaussian, σ 0.02 N·m, Python's `random`); OUT_DIR (this file's folder
if not given) is where the two files go; MACHINE, a converter run file with bench1's
operating point (`load = 800.0`, `motor = 12.0`, `h = 0.0001`, as `identify` writes
them), is the truth instead of `known-machine.toml`."""
import csv, math, os, random, subprocess, sys, tempfile


def run_converter(host_sim, text):
    """`host-sim run` of the converter run file `text`: its CSV rows and its event log's
    rows (dicts by column)."""
    with tempfile.TemporaryDirectory() as d:
        params, out = os.path.join(d, "m.toml"), os.path.join(d, "m.csv")
        open(params, "w").write(text)
        subprocess.run([host_sim, "run", params, "--out", out, "--quiet"], check=True)
        rows = list(csv.DictReader(open(out)))
        events = list(csv.DictReader(open(os.path.join(d, "m.events.csv"))))
    return rows, events


def main():
    host_sim, load, motor, seed = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    here = os.path.dirname(os.path.abspath(__file__))
    out_dir = sys.argv[5] if len(sys.argv) > 5 else here
    tag = os.path.join(out_dir, f"known-{load:g}Nm-{motor:g}Nm")
    machine_file = sys.argv[6] if len(sys.argv) > 6 else os.path.join(here, "known-machine.toml")
    machine = open(machine_file).read()
    for line in ("load = 800.0", "motor = 12.0", "h = 0.0001"):
        if line not in machine:
            sys.exit(f"{machine_file}: no line `{line}` (bench1's operating point) to replace")
    machine = (machine.replace("load = 800.0", f"load = {load}")
               .replace("motor = 12.0", f"motor = {motor}")
               .replace("h = 0.0001", "h = 0.001"))
    rows, events = run_converter(host_sim, machine)
    random.seed(seed)
    count = 2 * math.pi / 4096
    with open(tag + ".csv", "w") as f:
        f.write("t,motor_torque,load_torque,crank_counts,shaft_counts\n")
        for r in rows:
            # The crank's encoder: floor(θ1 / count); the shaft's: positive in the drive
            # direction (CW), the twin's shaft angle being CCW.
            f.write(f"{float(r['t']):.6f},{motor + random.gauss(0, 0.02):.4f},{load:.1f},"
                    f"{math.floor(float(r['theta1']) / count)},"
                    f"{math.floor(-float(r['shaft_angle']) / count)}\n")
    with open(tag + "_clutch_log.csv", "w") as f:
        f.write("t,event,from,to\n")
        for e in events:
            if e["event"] not in ("start", "switch"):
                f.write(f"{float(e['time']):.6f},{e['event']},{e['from']},{e['to']}\n")


if __name__ == "__main__":
    main()
