"""structomat.sweep against host-sim sweep: the same sweep.csv and heat-maps byte for
byte, in-process and on a Dask LocalCluster of 1 and 2 worker processes."""

import subprocess
from pathlib import Path

import pytest

import structomat
from conftest import ROOT

SWEEP = ROOT / "host-sim" / "sweeps" / "mass-motor.toml"


def files(d: Path):
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


@pytest.fixture(scope="module")
def reference(host_sim, tmp_path_factory):
    out = tmp_path_factory.mktemp("host-sim-sweep")
    p = subprocess.run([str(host_sim), "sweep", str(SWEEP), "--out-dir", str(out), "--quiet"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    got = files(out)
    assert "sweep.csv" in got and len(got) == 5
    return got


def test_in_process_sweep_equals_host_sim(reference, tmp_path):
    r = structomat.sweep(SWEEP, tmp_path / "out", batch=7)
    assert r["variants"] == 30 and r["tasks"] == 5
    assert files(tmp_path / "out") == reference


@pytest.mark.parametrize("workers", [1, 2])
def test_dask_sweep_equals_host_sim(reference, tmp_path, workers):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        r = structomat.sweep(SWEEP, tmp_path / "out", client=client)
    # About four tasks a worker: the 30 variants in batches of ceil(30 / 4w).
    batch = -(-30 // (4 * workers))
    assert r["tasks"] == -(-30 // batch)
    assert files(tmp_path / "out") == reference


def test_a_failing_variant_is_a_row(host_sim, tmp_path):
    # A step so long the twin's energy check fails (h = 0.2 s; at 0.05 s its sub-steps
    # keep the first 0.2 s): a row saying so, not a lost task.
    f = tmp_path / "bad.toml"
    f.write_text('base = "ccc-s2"\n[set]\n"run.t_end" = 0.2\n'
                 '[[axis]]\nkey = "run.h"\nvalues = [1e-4, 0.2]\n')
    ref = tmp_path / "ref"
    p = subprocess.run([str(host_sim), "sweep", str(f), "--out-dir", str(ref), "--quiet"],
                       capture_output=True, text=True)
    assert p.returncode == 0 and "variant 1 (run.h = 0.2)" in p.stderr, p.stderr
    structomat.sweep(f, tmp_path / "py")
    assert files(tmp_path / "py") == files(ref)
    rows = (ref / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3


def test_a_bad_sweep_file_raises_host_sims_message(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('base = "ccc-s2"\n[[axis]]\nkey = "converter.nope"\nvalues = [1.0]\n')
    with pytest.raises(structomat.Error, match="converter"):
        structomat.sweep(f, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_a_worker_killed_mid_sweep_loses_and_duplicates_no_row(host_sim, tmp_path):
    # One variant a task, each a few tenths of a second, on 2 worker processes; once the
    # first task has finished, the process of a worker that is running one is killed
    # (SIGKILL: no clean shutdown). Dask runs its lost tasks again on the worker its
    # nanny restarts or on the other; the files must still be host-sim's, byte for byte.
    distributed = pytest.importorskip("distributed")
    import os
    import signal
    import threading
    import time

    f = tmp_path / "long.toml"
    f.write_text('base = "ccc-s2"\n[set]\n"run.t_end" = 0.6\n'
                 '[[axis]]\nkey = "converter.mass"\nvalues = [4.0, 6.0, 8.0, 10.0]\n'
                 '[[axis]]\nkey = "run.motor"\nvalues = [10.0, 12.0, 14.0]\n')
    ref = tmp_path / "ref"
    p = subprocess.run([str(host_sim), "sweep", str(f), "--out-dir", str(ref), "--quiet"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        done = {}

        def go():
            try:
                done["result"] = structomat.sweep(f, tmp_path / "out", client=client, batch=1)
            except BaseException as e:  # reported below, in the test's own thread
                done["error"] = e

        t = threading.Thread(target=go)
        t.start()
        killed = None
        deadline = time.monotonic() + 60
        while killed is None and time.monotonic() < deadline and t.is_alive():
            info = client.run_on_scheduler(
                lambda dask_scheduler: (
                    sum(ts.state == "memory" for ts in dask_scheduler.tasks.values()),
                    {w: len(ws.processing) for w, ws in dask_scheduler.workers.items()}))
            finished, processing = info
            busy = [w for w, n in processing.items() if n > 0 and w in pids]
            if finished >= 1 and busy:
                killed = busy[0]
                os.kill(pids[killed], signal.SIGKILL)
            else:
                time.sleep(0.02)
        t.join(timeout=300)
        assert not t.is_alive(), "the sweep did not finish after a worker was killed"
    assert killed is not None, "the sweep ended before a worker could be killed mid-way"
    assert "error" not in done, done.get("error")
    assert done["result"]["variants"] == 12 and done["result"]["tasks"] == 12
    assert files(tmp_path / "out") == files(ref)
