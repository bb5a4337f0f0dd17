"""structomat.design against host-sim's own search: the same best design bit for bit,
in-process and with each generation's designs as tasks on a Dask LocalCluster of 2
worker processes."""

from pathlib import Path

import pytest

import structomat
from structomat import _core

# S2 against 150 N·m for 0.15 s, two free parameters, 3 generations of 5 designs.
DESIGN = '''
base = "ccc-s2"
[[free]]
key = "converter.mass"
min = 4.0
max = 8.0
[[free]]
key = "converter.rocker_d"
min = 0.3
max = 0.4
[[point]]
load = 150.0
motor = 12.0
horizon = 0.15
[search]
population = 5
generations = 2
seed = 3
'''


@pytest.fixture(scope="module")
def design_file(tmp_path_factory):
    f = tmp_path_factory.mktemp("design") / "d.toml"
    f.write_text(DESIGN)
    return f


@pytest.fixture(scope="module")
def reference(design_file):
    # host-sim's search on its own pool of 2 threads.
    x, violation, objective = _core.design_search(str(design_file), 2)
    return x, violation, objective


def test_in_process_design_equals_host_sim(design_file, reference):
    r = structomat.design(design_file)
    assert r["tasks"] == 15
    assert (r["best"], r["violation"], r["objective"]) == reference
    assert r["feasible"] and reference[2] < 0.0


def test_dask_design_equals_host_sim(design_file, reference):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        r = structomat.design(design_file, client=client)
    # Python floats carry f64 exactly: equality is bit for bit.
    assert (r["best"], r["violation"], r["objective"]) == reference


def test_a_bad_design_file_raises_before_anything_runs(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(DESIGN.replace("horizon = 0.15", "horizon = -1.0"))
    with pytest.raises(structomat.Error, match="point 1: horizon = -1"):
        structomat.design(f)
