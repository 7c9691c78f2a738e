"""Nothing non-finite leaves the FMU with fmi2OK, in FMPy as users call it: a non-finite or
absurd value from the host is refused with the variable named and the instance stays usable; a
state of another FMU or forged bytes are refused; a resource file changed after the build, a
FIFO or a device in its place is refused at fmi2Instantiate. The issue's minimal reproducers."""

import ctypes
import math
import os
import shutil
import struct
import zlib

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave

from conftest import _build
from test_fmi_robustness import RESOURCE, Recorder, not_instantiated, refused, restore_default_logger  # noqa: F401


@pytest.fixture(scope="module")
def tsquare(build_dir):
    return _build("t-square.json", build_dir)


def instance(fmu_path, kind, name="nonfinite", rec=None):
    md = read_model_description(str(fmu_path))
    directory = extract(str(fmu_path))
    # FMPy's logger proxy has one global target: instances logging together share a recorder
    rec = rec or Recorder()
    cls, ident = (FMU2Model, md.modelExchange) if kind == "me" else (FMU2Slave, md.coSimulation)
    fmu = cls(guid=md.guid, unzipDirectory=directory, modelIdentifier=ident.modelIdentifier, instanceName=name)
    fmu.instantiate(callbacks=rec.callbacks)
    return fmu, rec, md, directory


def outputs(md):
    return [v.valueReference for v in md.modelVariables if v.causality == "output" and v.type == "Real"]


def doubles(values):
    return (ctypes.c_double * len(values))(*values)


def states(fmu, n):
    x = doubles([0.0] * n)
    fmu.getContinuousStates(x, n)
    return list(x)


def derivatives(fmu, n):
    dx = doubles([0.0] * n)
    fmu.getDerivatives(dx, n)
    return list(dx)


def initialized(fmu):
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()


def test_model_exchange_refuses_a_nan_state_and_outputs_stay_finite(beam):
    fmu, rec, md, directory = instance(beam[0], "me")
    try:
        initialized(fmu)
        fmu.enterContinuousTimeMode()
        n = md.numberOfContinuousStates
        x = states(fmu, n)
        bad = list(x)
        bad[0] = float("nan")
        with refused("fmi2SetContinuousStates"):
            fmu.setContinuousStates(doubles(bad), n)
        assert "x[0] = NaN is not a finite number" in rec.messages[-1], rec.text()
        with refused("fmi2SetTime"):
            fmu.setTime(float("nan"))
        assert "not a finite number" in rec.messages[-1], rec.text()
        assert states(fmu, n) == x, "a refused call sets no state"
        values = fmu.getReal(outputs(md))
        assert len(values) == len(outputs(md)) and all(math.isfinite(v) for v in values)
        # absurd but finite states: the derivatives are refused with fmi2Discard, never NaN with fmi2OK
        fmu.setContinuousStates(doubles([1e308] * n), n)
        with pytest.raises(FMICallException, match=r"status 2 \(discard\)"):
            derivatives(fmu, n)
        assert "evaluates to" in rec.messages[-1], rec.text()
        # the instance goes on from finite states
        fmu.setContinuousStates(doubles(x), n)
        assert all(math.isfinite(v) for v in derivatives(fmu, n))
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def test_co_simulation_refuses_absurd_inputs_with_the_variable_named(beam):
    fmu, rec, md, directory = instance(beam[0], "cs")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    try:
        for name, value in [("tip.f[3]", -1e308), ("tip.f[3]", float("inf")), ("g[3]", 1e200),
                            ("tip.f[1]", float("nan")), ("damping.alpha", -1000.0)]:
            with refused("fmi2SetReal"):
                fmu.setReal([vr[name]], [value])
            assert name in rec.messages[-1], (name, rec.messages[-1])
        initialized(fmu)
        values = fmu.getReal(outputs(md))
        assert all(math.isfinite(v) for v in values)
        fmu.doStep(0.0, 1e-3)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def test_a_state_of_another_fmu_is_refused(beam, tsquare):
    beam_fmu, rec, _, d1 = instance(beam[0], "cs", name="beam")
    other, _, _, d2 = instance(tsquare[0], "cs", name="tsquare", rec=rec)
    try:
        initialized(beam_fmu)
        initialized(other)
        foreign = other.getFMUstate()
        with refused("fmi2SetFMUstate"):
            beam_fmu.setFMUstate(foreign)
        assert "GUID" in rec.messages[-1], rec.text()
        with refused("fmi2DeSerializeFMUstate"):
            beam_fmu.deSerializeFMUstate(other.serializeFMUstate(foreign))
        assert "GUID" in rec.messages[-1], rec.text()
        beam_fmu.doStep(0.0, 1e-3)  # still the beam, still usable
        other.freeFMUstate(foreign)
        for f in (beam_fmu, other):
            f.terminate()
            f.freeInstance()
    finally:
        shutil.rmtree(d1, ignore_errors=True)
        shutil.rmtree(d2, ignore_errors=True)


def reseal(data):
    return data[:-4] + struct.pack("<I", zlib.crc32(data[:-4]) & 0xFFFFFFFF)


def array_offset(data, name):
    """Offset of the first value of the container's array `name` (name, kind 0, rank, dims)."""
    key = struct.pack("<H", len(name)) + name.encode() + b"\x00"
    at = data.index(key) + len(key)
    rank = data[at]
    return at + 1 + 8 * rank


def test_a_forged_state_with_a_nan_or_a_negative_damping_is_refused(beam):
    fmu, rec, md, directory = instance(beam[0], "cs")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    try:
        fmu.setReal([vr["damping.alpha"]], [1.25])
        initialized(fmu)
        good = bytes(fmu.serializeFMUstate(fmu.getFMUstate()))
        at = good.index(struct.pack("<d", 1.25))
        for forged, reason in [(float("nan"), "not a finite number"), (-1000.0, "negative")]:
            bad = reseal(good[:at] + struct.pack("<d", forged) + good[at + 8:])
            with refused("fmi2DeSerializeFMUstate"):
                fmu.deSerializeFMUstate(bad)
            assert reason in rec.messages[-1], rec.text()
        fmu.doStep(0.0, 1e-3)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


@pytest.mark.parametrize("damage,reason", [
    ("nan", "not a finite number"),
    ("edited", "changed after the build"),
    ("fifo", "not a regular file"),
    ("device", "not a regular file"),
])
def test_a_resource_file_changed_after_the_build_or_not_a_file_is_refused(beam, tmp_path, damage, reason):
    directory = extract(str(beam[0]), unzipdir=str(tmp_path / damage))
    path = f"{directory}/{RESOURCE}"
    data = open(path, "rb").read()
    os.remove(path)
    if damage == "nan":
        at = array_offset(data, "mass")
        open(path, "wb").write(reseal(data[:at] + struct.pack("<d", float("nan")) + data[at + 8:]))
    elif damage == "edited":
        # a consistent but different model under the old GUID: the CRC is valid, the content is not the GUID's
        at = array_offset(data, "mass")
        mass = struct.unpack("<d", data[at:at + 8])[0]
        open(path, "wb").write(reseal(data[:at] + struct.pack("<d", 2 * mass) + data[at + 8:]))
    elif damage == "fifo":
        os.mkfifo(path)  # reading it would block fmi2Instantiate forever
    else:
        os.symlink("/dev/zero", path)  # reading it would never end
    md = read_model_description(str(beam[0]))
    rec = Recorder()
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=directory, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="tampered")
    with not_instantiated():
        fmu.instantiate(callbacks=rec.callbacks)
    assert reason in rec.text() and "reduced_body.bin" in rec.text(), rec.text()
