"""Python's overhead on a scenario run: what structomat.run costs beyond the run itself
(options, the twin's set-up, the numpy arrays, the summary's dict) is under 5 % of the
run's own wall time (its summary's `wall`, measured by host-sim's pipeline).

The issue asks for the figure, so it is asserted on time; what keeps it small is
asserted on structure first, where no machine's load can blur it: no number column is
copied into numpy and no row makes a Python object (a row costs a list slot, about 16 ns
on the AMD EPYC against a run's 2 µs a row). Measured there: 1.2 % of S2's first second
with a row every step, 0.4 % of the five-bar's. The best of up to 15 runs is taken: the
machine's other load only ever adds time."""

import time

import numpy as np
import pytest

import structomat


def test_a_run_hands_its_columns_over_without_a_copy_or_an_object_a_row():
    r = structomat.run("ccc-s2", t_end=0.2)
    rows = len(r.columns["t"])
    assert rows == 2001
    for name, col in r.columns.items():
        if isinstance(col, np.ndarray):
            # numpy owns no data: the array views the Vec the run filled.
            assert col.dtype == np.float64 and not col.flags.owndata, name
            assert type(col.base).__name__ == "PySliceContainer", name
        else:
            # A name column: one str object per distinct name, shared by its rows.
            assert len(col) == rows, name
            assert len({id(s) for s in col}) == len(set(col)), name
    modes = {"free", "I0", "I6", "I8", "jam", "A6", "A8", "A68", "coast"}
    assert set(r.columns["mode"]) <= modes
    assert len(set(r.columns["mode"])) >= 2


@pytest.mark.parametrize("source,kw", [("ccc-s2", {"t_end": 1.0}), ("five-bar", {"t_end": 2.0})])
def test_python_overhead_under_five_percent(source, kw):
    shares = []
    for _ in range(15):
        t0 = time.perf_counter()
        r = structomat.run(source, **kw)
        total = time.perf_counter() - t0
        shares.append((total - r.summary["wall"]) / r.summary["wall"])
        if len(shares) >= 7 and min(shares) < 0.05:
            break
    assert min(shares) < 0.05, shares
