"""Shared helpers of the Python tests: the release host-sim (the oracle the package
must agree with bit for bit) and a CSV reader that parses host-sim's text as any CSV
reader would (Python's float(), correctly rounded)."""

import csv
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def host_sim_path() -> Path:
    p = Path(os.environ.get("STRUCTOMAT_HOST_SIM", ROOT / "target" / "release" / "host-sim"))
    if not p.exists():
        pytest.fail(f"no host-sim at {p}: python/run-tests builds it (or set STRUCTOMAT_HOST_SIM)")
    return p


@pytest.fixture(scope="session")
def host_sim():
    return host_sim_path()


def read_csv(path):
    """A CSV as a dict of column -> float64 array, or list of str when a column's
    first cell is not a number; an empty cell is NaN."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    out = {}
    for k, name in enumerate(header):
        cells = [r[k] for r in body]
        try:
            out[name] = np.array([math.nan if c == "" else float(c) for c in cells],
                                 dtype=np.float64)
        except ValueError:
            out[name] = cells
    return out


def run_cli(host_sim, tmp_path, source, *args):
    """host-sim run SOURCE ARGS --out tmp/run.csv: the state CSV and, for the
    converter, its two logs, read back."""
    out = tmp_path / "run.csv"
    p = subprocess.run([str(host_sim), "run", str(source), *args, "--out", str(out), "--quiet"],
                       capture_output=True, text=True)
    logs = {}
    for log in ("events", "switches"):
        q = out.with_suffix(f".{log}.csv")
        if q.exists():
            logs[log] = read_csv(q)
    return p, read_csv(out) if out.exists() else None, logs


def same_bits(a, b):
    """Two columns equal bit for bit (NaN at the same places), or equal lists of str."""
    texts = [isinstance(x, str) for c in (a, b) if isinstance(c, list) for x in c]
    if any(texts):
        return isinstance(a, list) and isinstance(b, list) and list(a) == list(b)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def assert_table(got, want, what):
    assert list(got) == list(want), f"{what}: columns differ"
    for name in want:
        assert same_bits(got[name], want[name]), f"{what}: column {name} differs"
