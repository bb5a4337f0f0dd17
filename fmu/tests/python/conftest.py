"""Where fmu/run-tests put the FMU and host-sim's S2 CSV (environment variables set by
the script; the defaults are its paths under target/)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def fmu_path():
    path = pathlib.Path(os.environ.get("STRUCTOMAT_FMU", ROOT / "target/fmu/ccc.fmu"))
    if not path.is_file():
        pytest.fail(f"no FMU at {path}: run fmu/run-tests (it builds it with host-sim fmu)")
    return str(path)


@pytest.fixture(scope="session")
def s2_csv():
    path = pathlib.Path(os.environ.get("STRUCTOMAT_S2_CSV", ROOT / "target/fmu/s2.csv"))
    if not path.is_file():
        pytest.fail(f"no host-sim S2 CSV at {path}: run fmu/run-tests")
    return str(path)


@pytest.fixture(scope="session")
def variant():
    """The FMU of S2 with --h 2e-4 --t-end 0.3 --load 0 --ccw, and host-sim's run of it."""
    fmu = pathlib.Path(os.environ.get("STRUCTOMAT_VARIANT_FMU", ROOT / "target/fmu/ccc-variant.fmu"))
    csv = pathlib.Path(os.environ.get("STRUCTOMAT_VARIANT_CSV", ROOT / "target/fmu/s2-variant.csv"))
    for p in (fmu, csv):
        if not p.is_file():
            pytest.fail(f"no {p}: run fmu/run-tests")
    return str(fmu), str(csv)
