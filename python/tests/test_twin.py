"""structomat.Twin stepped from Python against the Rust twin of host-sim run (its CSV,
every step): the same state, step for step, bit for bit."""

import math

import numpy as np
import pytest

import structomat
from conftest import run_cli, same_bits


def compare_steps(twin, csv, steps, step):
    names = list(csv)
    for k in range(steps + 1):
        if k > 0:
            step(twin, k)
        row = twin.state()
        assert list(row) == names
        for name in names:
            want = csv[name][k]
            got = row[name]
            if isinstance(want, str):
                assert got == want, (k, name)
            else:
                assert same_bits([got], [want]), (k, name, got, want)


@pytest.mark.parametrize("f32", [False, True])
def test_twin_under_the_scenarios_law_equals_host_sim(host_sim, tmp_path, f32):
    n = 600  # 0.06 s at h = 1e-4: the start, the first catch and release of S2
    args = ["--t-end", str(n * 1e-4)] + (["--f32"] if f32 else [])
    p, csv, logs = run_cli(host_sim, tmp_path, "ccc-s2", *args)
    assert p.returncode == 0, p.stderr
    twin = structomat.Twin("ccc-s2", f32=f32)
    assert twin.precision == ("f32" if f32 else "f64")
    events = []
    def step(t, k):
        t.step()
        events.extend(e["time"] for e in t.events)
    compare_steps(twin, csv, n, step)
    assert events == list(logs["events"]["time"][1:])  # the first is the start's


def test_twin_with_per_step_torques_equals_the_constant_law(host_sim, tmp_path):
    # S2's motor law is a constant 12 N·m and its load 800 N·m: given as per-step
    # inputs they must step the twin exactly as the law does.
    n = 400
    p, csv, _ = run_cli(host_sim, tmp_path, "ccc-s2", "--t-end", str(n * 1e-4))
    twin = structomat.Twin("ccc-s2")
    compare_steps(twin, csv, n, lambda t, k: t.step(12.0, 800.0))


def test_twin_with_overrides_equals_host_sim(host_sim, tmp_path):
    n = 300
    args = ["--h", "2e-4", "--t-end", str(n * 2e-4), "--motor", "20", "--load", "300", "--ccw"]
    p, csv, _ = run_cli(host_sim, tmp_path, "ccc-s2", *args)
    twin = structomat.Twin("ccc-s2", h=2e-4, motor=20, load=300, ccw=True)
    compare_steps(twin, csv, n, lambda t, k: t.step())


def test_twin_spreading_its_events_equals_host_sim(host_sim, tmp_path):
    # S2 at the 1 kHz loop's step with its events spread, as firmware on a Cortex-M4F
    # runs it: host-sim's rows bit for bit, and the twin's lag is its clock's steps * h
    # minus its time (behind after the first release at 0.0288 s, caught up by 0.06 s).
    n = 60
    args = ["--h", "1e-3", "--t-end", str(n * 1e-3), "--spread-events"]
    p, csv, _ = run_cli(host_sim, tmp_path, "ccc-s2", *args)
    assert p.returncode == 0, p.stderr
    twin = structomat.Twin("ccc-s2", h=1e-3, spread_events=True)
    lags = []
    def step(t, k):
        t.step()
        lags.append(t.lag)
        assert t.lag == t.steps * t.h - t.time
    compare_steps(twin, csv, n, step)
    assert max(lags) > 1e-3 and lags[-1] == 0.0, lags
    # structomat.run's summary gives the largest lag, as host-sim's does.
    r = structomat.run("ccc-s2", h=1e-3, t_end=n * 1e-3, spread_events=True)
    assert r.summary["lag"] == max(lags)
    assert structomat.run("ccc-s2", h=1e-3, t_end=n * 1e-3).summary["lag"] is None


def test_twin_outputs_are_the_states_cells():
    twin = structomat.Twin("ccc-s2")
    for _ in range(300):
        twin.step()
    row = twin.state()
    assert twin.steps == 300 and twin.time == row["t"]
    assert twin.mode == row["mode"] and twin.mode_code == row["mode_code"]
    assert twin.coordinates == row["coords"]
    assert twin.c6 == row["c6"] and twin.c8 == row["c8"]
    assert twin.shaft_angle == row["shaft_angle"] and twin.shaft_speed == row["shaft_speed"]
    assert twin.crank_angle == row["theta1"] and twin.crank_speed == row["omega1"]
    assert list(twin.theta) == [row[f"theta{p}"] for p in range(1, 9)]
    assert twin.audit["residual"] == row["audit_residual"]
    q = twin.q
    assert q[0] == row["q1"] and len(q) in (0, 1, 2)
    # The energy audit closes (an independent check of the state: SPEC's tolerance).
    a = twin.audit
    assert abs(a["residual"]) < 1e-6 * max(1.0, abs(a["motor_work"]))


def test_a_refused_step_raises_and_keeps_the_last_good_state():
    twin = structomat.Twin("ccc-s2")
    for _ in range(10):
        twin.step(12.0, 800.0)
    before = twin.state()
    # A load past 1e6 N·m is beyond the clutches' torque tolerance: the core refuses it
    # (host-sim refuses it in options, run files and logs).
    for bad in [dict(motor=math.nan), dict(motor=12.0, load=-1.0), dict(motor=math.inf),
                dict(motor=12.0, load=1e7)]:
        with pytest.raises(structomat.TwinError) as e:
            twin.step(**bad)
        assert isinstance(e.value, structomat.Error)
        assert "step 11" in str(e.value)
        after = twin.state()
        assert all(same_bits([after[k]], [before[k]]) if not isinstance(before[k], str)
                   else after[k] == before[k] for k in before)
    twin.step(12.0, 800.0)
    assert twin.steps == 11


def test_the_nan_message_names_the_input():
    twin = structomat.Twin("ccc-s2")
    with pytest.raises(structomat.TwinError, match="(?i)motor"):
        twin.step(math.nan)


def test_a_mechanism_is_no_twin():
    with pytest.raises(structomat.Error, match="not a converter"):
        structomat.Twin("five-bar")
    with pytest.raises(TypeError, match="'speed'"):
        structomat.Twin("ccc-s2", speed=3)
    # A run's keywords that a twin has no use for are refused, not ignored.
    for kw in [dict(t_end=0.5), dict(every=10)]:
        with pytest.raises(TypeError, match="a twin has no run"):
            structomat.Twin("ccc-s2", **kw)
