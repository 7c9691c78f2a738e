"""FMI robustness of the runtime: a corrupt or foreign reduced-model file, a wrong GUID and calls
in the wrong state return errors with a logged reason, never a crash."""

import ctypes
import shutil
import zipfile

import fmpy.fmi2
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
from fmpy.logging import addLoggerProxy

RESOURCE = "resources/reduced_body.bin"

# FMPy's native logger proxy keeps ONE global target: keep every recorder alive and hand the
# proxy back to FMPy's default logger after each test, or a later log call jumps into freed memory.
_RECORDERS = []


@pytest.fixture(autouse=True)
def restore_default_logger():
    yield
    addLoggerProxy(ctypes.byref(fmpy.fmi2.defaultCallbacks))


class Recorder:
    def __init__(self):
        self.messages = []
        # (status, category, message) of each, for the tests that check how a message came
        self.entries = []

        def log(env, name, status, category, message):
            text = message.decode(errors="replace") if message else ""
            self.messages.append(text)
            self.entries.append((status, category.decode(errors="replace") if category else "", text))

        self.logger = fmi2CallbackLoggerTYPE(log)
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = self.logger
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(0)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(0)
        # FMPy's native proxy formats the variadic message ("%s" + text) as a C host would
        addLoggerProxy(ctypes.byref(self.callbacks))
        _RECORDERS.append(self)

    def text(self):
        return " | ".join(self.messages)


def refused(function):
    """The call fails the way FMPy reports fmi2Error from `function` (status 3), not with any
    exception; callers check the logged reason as well."""
    return pytest.raises(FMICallException, match=rf"^{function} failed with status 3 \(error\)")


def not_instantiated():
    """fmi2Instantiate returned NULL (FMPy raises a plain Exception with this text)."""
    return pytest.raises(Exception, match="^Failed to instantiate model$")


def slave(directory, md, guid=None):
    rec = Recorder()
    fmu = FMU2Slave(guid=guid or md.guid, unzipDirectory=directory,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="robust")
    return fmu, rec


def test_corrupt_truncated_and_foreign_resources_are_refused(beam, tmp_path):
    md = read_model_description(str(beam[0]))
    for name, damage in [
        ("corrupt", lambda b: b[:100] + bytes([b[100] ^ 0x55]) + b[101:]),
        ("truncated", lambda b: b[: len(b) // 2]),
        ("foreign", lambda b: b"PK\x03\x04 this is not a reduced body"),
    ]:
        directory = extract(str(beam[0]), unzipdir=str(tmp_path / name))
        path = f"{directory}/{RESOURCE}"
        data = open(path, "rb").read()
        open(path, "wb").write(damage(data))
        fmu, rec = slave(directory, md)
        with not_instantiated():
            fmu.instantiate(callbacks=rec.callbacks)
        assert "reduced" in rec.text() and RESOURCE.split("/")[1] in rec.text(), rec.text()
        expected = {"corrupt": "CRC", "truncated": "truncated", "foreign": "not a reduced-model file"}[name]
        assert expected in rec.text(), rec.text()


def test_wrong_guid_is_refused(beam):
    md = read_model_description(str(beam[0]))
    directory = extract(str(beam[0]))
    try:
        fmu, rec = slave(directory, md, guid="{00000000-0000-0000-0000-000000000000}")
        with not_instantiated():
            fmu.instantiate(callbacks=rec.callbacks)
        assert "GUID" in rec.text()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def test_calls_in_the_wrong_state_are_errors(beam):
    md = read_model_description(str(beam[0]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    directory = extract(str(beam[0]))
    try:
        fmu, rec = slave(directory, md)
        fmu.instantiate(callbacks=rec.callbacks)
        with refused("fmi2DoStep"):
            fmu.doStep(0.0, 0.01)  # before initialisation
        assert "fmi2DoStep" in rec.text()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.01)
        n = len(rec.messages)
        with refused("fmi2SetReal"):
            fmu.setReal([vr["g[3]"]], [-9.81])  # fixed parameter after initialisation
        assert len(rec.messages) > n and "g[3]" in rec.messages[-1] and "Fixed" in rec.messages[-1]
        with refused("fmi2GetReal"):
            fmu.getReal([999999])
        assert "999999" in rec.messages[-1], rec.messages[-1]
        with refused("fmi2SetReal"):
            fmu.setReal([vr["tip.u[1]"]], [1.0])  # an output
        print(f"\nsetReal of an output: {rec.messages[-1]}")
        assert "tip.u[1]" in rec.messages[-1], rec.messages[-1]
        with refused("fmi2SetRealInputDerivatives"):
            fmu.setRealInputDerivatives([vr["tip.f[3]"]], [2], [1.0])  # second order
        assert "order 2" in rec.messages[-1]
        with refused("fmi2SetRealInputDerivatives"):
            fmu.setRealInputDerivatives([vr["tip.u[3]"]], [1], [1.0])  # not an input
        assert "inputs only" in rec.messages[-1]
        fmu.doStep(0.01, 0.01)  # still usable after refused calls
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(directory, ignore_errors=True)


def test_derivative_requests_out_of_bounds_are_errors(beam):
    """fmi2GetRealOutputDerivatives of order 2 or of an input, fmi2GetDirectionalDerivative of an
    input or with respect to an output or (Co-Simulation) a state, and either before
    initialisation has begun (Instantiated; Initialization Mode answers directional derivatives,
    as the standard allows): fmi2Error with the reason logged; the instance keeps working."""
    md = read_model_description(str(beam[0]))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    directory = extract(str(beam[0]))
    try:
        fmu, rec = slave(directory, md)
        fmu.instantiate(callbacks=rec.callbacks)
        with refused("fmi2GetDirectionalDerivative"):
            fmu.getDirectionalDerivative([vr["tip.r[1]"]], [vr["tip.f[1]"]], [1.0])
        assert "called in state Instantiated; allowed in: InitializationMode" in rec.messages[-1], rec.text()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        assert fmu.getDirectionalDerivative([vr["tip.a[3]"]], [vr["tip.f[3]"]], [1.0])[0] > 0  # feedthrough
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 0.01)
        for call, reason in [
            (lambda: fmu.getRealOutputDerivatives([vr["tip.r[1]"]], [2]), "maxOutputDerivativeOrder"),
            (lambda: fmu.getRealOutputDerivatives([vr["tip.f[1]"]], [1]), "tip.f[1]"),
            (lambda: fmu.getDirectionalDerivative([vr["tip.f[1]"]], [vr["tip.f[2]"]], [1.0]), "tip.f[1]"),
            (lambda: fmu.getDirectionalDerivative([vr["tip.r[1]"]], [vr["tip.v[1]"]], [1.0]), "tip.v[1]"),
            (lambda: fmu.getDirectionalDerivative([vr["tip.r[1]"]], [vr["q[1]"]], [1.0]), "Model Exchange"),
            (lambda: fmu.getDirectionalDerivative([vr["tip.r[1]"]], [vr["tip.f[1]"]], [float("nan")]), "finite"),
        ]:
            n = len(rec.messages)
            with pytest.raises(FMICallException, match=r"^fmi2Get\w+Derivatives? failed with status 3 \(error\)"):
                call()
            assert len(rec.messages) > n and reason in rec.messages[-1], (reason, rec.messages[n:])
            # still usable
            assert fmu.getDirectionalDerivative([vr["tip.a[3]"]], [vr["tip.f[3]"]], [1.0])[0] > 0  # feedthrough
            fmu.getRealOutputDerivatives([vr["tip.r[1]"]], [1])
        fmu.doStep(0.01, 0.01)
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(directory, ignore_errors=True)
