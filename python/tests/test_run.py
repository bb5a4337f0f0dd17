"""structomat.run against host-sim run: the same values bit for bit, the same errors."""

import subprocess

import numpy as np
import pytest

import structomat
from conftest import assert_table, run_cli

CASES = [
    ("ccc-s2", {"t_end": 0.2}, ["--t-end", "0.2"]),
    ("ccc-s2", {"t_end": 0.1, "f32": True, "every": 3}, ["--t-end", "0.1", "--f32", "--every", "3"]),
    ("ccc-s2", {"t_end": 0.1, "load": 500, "motor": 15.5, "ccw": True},
     ["--t-end", "0.1", "--load", "500", "--motor", "15.5", "--ccw"]),
    ("ccc-s1", {}, []),
    ("five-bar", {}, []),
    ("slider-crank", {"h": 0.002, "t_end": 1.0}, ["--h", "0.002", "--t-end", "1.0"]),
]


@pytest.mark.parametrize("source,kw,args", CASES, ids=[f"{c[0]}-{k}" for k, c in enumerate(CASES)])
def test_run_equals_host_sim_csv(host_sim, tmp_path, source, kw, args):
    p, csv, logs = run_cli(host_sim, tmp_path, source, *args)
    assert p.returncode == 0, p.stderr
    r = structomat.run(source, **kw)
    assert_table(r.columns, csv, f"{source} state")
    assert len(r) == r.summary["rows"] == len(next(iter(csv.values())))
    if source.startswith("ccc"):
        assert_table(r.events, logs["events"], f"{source} events")
        assert_table(r.switches, logs["switches"], f"{source} switches")
        assert r.summary["kind"] == "converter"
    else:
        assert r.events == {} and r.switches == {}
        assert r.summary["kind"] == "mechanism"


def test_summary_figures_match_the_tables():
    r = structomat.run("ccc-s2", t_end=0.2)
    s = r.summary
    assert s["end"] == "completed" and s["exit_code"] == 0
    assert s["steps"] == 2000 and s["precision"] == "f64"
    # The audit's figures are the last row's (an independent path: the row's cells).
    assert s["audit"]["motor_work"] == r.columns["motor_work"][-1]
    assert s["audit"]["residual"] == r.columns["audit_residual"][-1]
    assert s["mode"] == r.columns["mode"][-1]
    assert s["event_count"] == len(r.events["time"])
    assert "scenario  ccc-s2" in s["text"]


def test_s1_ends_at_its_singularity_without_an_error():
    r = structomat.run("ccc-s1")
    assert r.summary["end"] == "singularity" and r.summary["exit_code"] == 0
    assert "singular" in r.summary["error"]


def test_a_run_file_path_runs(host_sim, tmp_path):
    from conftest import ROOT
    f = ROOT / "host-sim" / "mechanisms" / "ccc-free.toml"
    p, csv, _ = run_cli(host_sim, tmp_path, f, "--t-end", "0.05")
    r = structomat.run(f, t_end=0.05)
    assert (p.returncode == 0) == (r.summary["exit_code"] == 0)
    assert_table(r.columns, csv, "ccc-free")


def test_unknown_keyword_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="'tt_end'"):
        structomat.run("ccc-s2", tt_end=1.0)
    with pytest.raises(TypeError, match="load: a number expected"):
        structomat.run("ccc-s2", load="800")
    with pytest.raises(TypeError, match="f32: True or False"):
        structomat.run("ccc-s2", f32=1)


def cli_message(host_sim, *args):
    p = subprocess.run([str(host_sim), "run", *args, "--out", "/dev/null", "--quiet"],
                       capture_output=True, text=True)
    assert p.returncode != 0
    return p.stderr.splitlines()[0].removeprefix("host-sim: ")


def test_bad_values_raise_host_sims_message(host_sim):
    for kw, args in [({"h": -1.0}, ["--h", "-1.0"]), ({"load": -5}, ["--load", "-5"]),
                     ({"h": 1.0, "t_end": 0.1}, ["--h", "1.0", "--t-end", "0.1"])]:
        want = cli_message(host_sim, "ccc-s2", *args)
        with pytest.raises(structomat.Error) as e:
            structomat.run("ccc-s2", **kw)
        assert str(e.value) == want
        assert isinstance(e.value, RuntimeError)


BAD_FILES = {
    "syntax.toml": "name = \"x\"\n[converter\nmass = 6.0\n",
    "negative_mass.toml": None,  # made from ccc-s2 below
    "unknown_key.toml": None,
}


def test_a_bad_run_file_raises_the_files_own_message(host_sim, tmp_path):
    from conftest import ROOT
    s2 = (ROOT / "host-sim" / "scenarios" / "ccc-s2.toml").read_text()
    files = {
        "syntax.toml": "name = \"x\"\n[converter\nmass = 6.0\n",
        "negative_mass.toml": s2.replace("mass = 6.0 ", "mass = -6.0 "),
        "unknown_key.toml": s2.replace("mass = 6.0 ", "mas = 6.0 "),
    }
    for name, text in files.items():
        assert text != s2
        f = tmp_path / name
        f.write_text(text)
        want = cli_message(host_sim, str(f))
        with pytest.raises(structomat.Error) as e:
            structomat.run(f)
        assert str(e.value) == want, name
        assert str(f) in str(e.value) or name in str(e.value)


def test_a_missing_file_raises():
    with pytest.raises(structomat.Error, match="no-such-file.toml"):
        structomat.run("no-such-file.toml")


def test_scenarios_lists_the_builtins():
    names = [n for n, _ in structomat.scenarios()]
    assert names == ["slider-crank", "five-bar", "ccc-s1", "ccc-s2"]


def test_the_gil_is_released_during_a_run():
    import threading
    import time
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.005)

    t = threading.Thread(target=tick)
    t.start()
    t0 = time.monotonic()
    # At 150 N·m S2 never jams (at 800 N·m it does at 0.82 s and the run is over in
    # ~0.08 s): 5 s of simulated time, 50,000 steps, take ~0.5-1 s here, long enough
    # for the count of ticks below to tell a released GIL from a held one.
    r = structomat.run("ccc-s2", t_end=5.0, load=150.0)
    t1 = time.monotonic()
    stop.set()
    t.join()
    during = [x for x in ticks if t0 < x < t1]
    # The other thread kept running: a tick every ~5 ms of the run's wall time.
    assert r.summary["wall"] > 0.1
    assert len(during) >= 0.25 * (t1 - t0) / 0.005


def test_numpy_numbers_are_numbers():
    """A numpy float or integer (a loop over np.linspace, a load from an array) is its
    value: the run equals the one given the plain Python number, bit for bit."""
    import numpy as np
    plain = structomat.run("ccc-s2", t_end=0.05, load=500.0, every=5)
    for load, every in [(np.float64(500.0), np.int64(5)), (np.float32(500.0), 5),
                        (500, np.int32(5))]:
        r = structomat.run("ccc-s2", t_end=0.05, load=load, every=every)
        assert r.summary["rows"] == plain.summary["rows"]
        for name, col in plain.columns.items():
            if isinstance(col, np.ndarray):
                assert col.tobytes() == r.columns[name].tobytes(), name
    with pytest.raises(TypeError, match="load: a number expected"):
        structomat.run("ccc-s2", t_end=0.05, load="500")
    with pytest.raises(TypeError, match="load: a number expected"):
        structomat.run("ccc-s2", t_end=0.05, load=True)
