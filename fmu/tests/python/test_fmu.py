"""The converter twin's FMU under FMPy: it validates; simulate_fmu of S2 at the
communication step h equals host-sim's S2 (an independent driver of the same core:
host-sim steps the twin with a constant motor law from its run file, the FMU with the
input torque FMPy holds) to 1e-12 in every output; a NaN input is an error status
whose log message names the input; fmi2Reset makes the instance usable again."""

import csv

import numpy as np
import pytest
from fmpy import read_model_description, extract
from fmpy.fmi1 import FMICallException
from ctypes import byref
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Error,
)
from fmpy import calloc, free
from fmpy.logging import addLoggerProxy
from fmpy.validation import validate_fmu
from fmpy import simulate_fmu

# The FMU's outputs and host-sim's CSV columns of the same quantity.
COLUMNS = {
    "crank_angle": "theta1",
    "crank_speed": "omega1",
    "shaft_angle": "shaft_angle",
    "shaft_speed": "shaft_speed",
    "c6": "c6",
    "c8": "c8",
    "audit.kinetic": "kinetic",
    "audit.potential": "potential",
    "audit.motor_work": "motor_work",
    "audit.load_work": "load_work",
    "audit.impact_loss": "impact_loss",
    "audit.residual": "audit_residual",
    "mode": "mode_code",
}

H = 1e-4


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in ["t", *COLUMNS.values()]}


def test_validate_fmu_finds_no_problem(fmu_path):
    assert validate_fmu(fmu_path) == []


def test_every_output_is_described(fmu_path):
    md = read_model_description(fmu_path)
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    assert outputs == set(COLUMNS)
    mode = next(v for v in md.modelVariables if v.name == "mode")
    assert mode.type == "Integer"
    for code, name in enumerate(["free", "I0", "I6", "I8", "jam", "A6", "A8", "A68", "coast"]):
        assert f"{code} {name}" in mode.description
    inputs = {v.name: float(v.start) for v in md.modelVariables if v.causality == "input"}
    assert inputs == {"motor_torque": 12.0, "load_torque": 800.0}
    assert md.defaultExperiment.stepSize == str(H) or float(md.defaultExperiment.stepSize) == H


def compare(fmu_path, csv_path, h):
    """simulate_fmu at the communication step h against host-sim's CSV: every output
    to 1e-12; returns the largest difference of each."""
    want = read_csv(csv_path)
    t_end = want["t"][-1]
    got = simulate_fmu(fmu_path, stop_time=t_end, output_interval=h, validate=True)
    assert len(got) == len(want["t"]), (len(got), len(want["t"]))
    np.testing.assert_allclose(got["time"], want["t"], rtol=0, atol=1e-12)
    worst = {}
    for out, col in COLUMNS.items():
        g, w = np.asarray(got[out], dtype=float), want[col]
        diff = float(np.max(np.abs(g - w)))
        worst[out] = diff
        assert diff <= 1e-12, f"{out} vs host-sim's {col}: {diff:.3e}"
    return want, worst


def test_simulate_s2_equals_host_sim(fmu_path, s2_csv):
    want, worst = compare(fmu_path, s2_csv, H)
    # S2 goes through its diode's modes: the comparison covers events, not only I0.
    assert len(set(want["mode_code"])) >= 3
    print("S2: largest |FMU - host-sim| by output:", worst)


def test_start_values_come_from_the_fmu(variant):
    # Not the binary's defaults: h, the load and the drive come from resources/start.txt.
    fmu_path, csv_path = variant
    md = read_model_description(fmu_path)
    start = {v.name: v.start for v in md.modelVariables}
    assert float(start["h"]) == 2e-4 and float(start["load_torque"]) == 0.0
    assert start["ccw"] in ("true", True)
    want, worst = compare(fmu_path, csv_path, 2e-4)
    # Counter-clockwise without load: the shaft turns the other way.
    assert want["shaft_angle"][-1] > 0
    print("variant: largest |FMU - host-sim| by output:", worst)


class Log:
    """The FMU's log messages, as FMPy's logger callback receives them."""

    def __init__(self):
        self.messages = []

    def __call__(self, component, instance, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))


def slave(fmu_path, log):
    md = read_model_description(fmu_path)
    unzipdir = extract(fmu_path)
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="twin",
    )
    # As simulate_fmu does with a logger: FMPy's C proxy formats the message (printf)
    # and hands it to the Python function.
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(log)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(byref(callbacks))
    log.callbacks = callbacks
    fmu.instantiate(loggingOn=False, callbacks=callbacks)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, refs


def test_nan_input_is_an_error_named_in_the_log_and_reset_recovers(fmu_path):
    log = Log()
    fmu, vr = slave(fmu_path, log)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=H)
    first = fmu.getReal([vr["crank_angle"]])[0]
    with pytest.raises(FMICallException) as e:
        fmu.setReal([vr["motor_torque"]], [float("nan")])
    assert e.value.status == fmi2Error
    status, category, message = log.messages[-1]
    assert status == fmi2Error and category == "logStatusError"
    assert "motor_torque" in message and "NaN" in message, message
    # No silent continuation: the next step is refused, with its reason.
    with pytest.raises(FMICallException) as e:
        fmu.doStep(currentCommunicationPoint=H, communicationStepSize=H)
    assert e.value.status == fmi2Error
    assert "not allowed in state error" in log.messages[-1][2]
    # fmi2Reset: a new run from the start values, the same first step.
    fmu.reset()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=H)
    assert fmu.getReal([vr["crank_angle"]])[0] == first
    fmu.terminate()
    fmu.freeInstance()


def test_a_step_off_the_grid_of_h_is_refused(fmu_path):
    log = Log()
    fmu, vr = slave(fmu_path, log)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.5 * H)
    assert "not a whole multiple" in log.messages[-1][2]
    fmu.freeInstance()


def test_a_saved_state_replays_the_same_steps(fmu_path):
    log = Log()
    fmu, vr = slave(fmu_path, log)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    outs = [vr[name] for name in COLUMNS if name != "mode"]
    for k in range(700):
        fmu.doStep(currentCommunicationPoint=k * H, communicationStepSize=H)
    state = fmu.getFMUstate()
    for k in range(700, 1000):
        fmu.doStep(currentCommunicationPoint=k * H, communicationStepSize=H)
    first = fmu.getReal(outs)
    fmu.setFMUstate(state)
    for k in range(700, 1000):
        fmu.doStep(currentCommunicationPoint=k * H, communicationStepSize=H)
    assert fmu.getReal(outs) == first
    fmu.freeFMUstate(state)
    fmu.terminate()
    fmu.freeInstance()
