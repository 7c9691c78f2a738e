"""What external fuzzers found, on FMUs built from examples/ and driven through FMPy's low-level
classes (the C status of each call): a step or rate far beyond the body's range never answers
fmi2OK with a non-finite state and leaves the instance usable; seeds beyond the range are
refused with the variable named; a free body's unevaluable states are discarded and the
integrator recovers; a mount orientation that is no rotation is refused; a fast-spinning free
body's long step is bounded in time. The same cases on the runtime's fixtures, with the exact
reasons: fmu-runtime/tests/runtime_guards.rs."""

import ctypes
import json
import math
import time

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave

from conftest import EXAMPLES, run_builder
from test_fmi_robustness import Recorder

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3
R_NAMES = [f"base.R[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]


@pytest.fixture(scope="module")
def free_beam(build_dir):
    """The fuzzer's free-floating beam: examples/beam.json with its mount made a force flange."""
    spec = json.loads((EXAMPLES / "beam.json").read_text())
    spec.pop("$schema", None)
    spec["name"] = "FreeBeam"
    spec["flanges"][0]["role"] = "force"
    spec["reduction"] = {"method": "craig_bampton", "modes": 6}
    spec["scene"] = {"loads": ["gravity", "rotation"]}
    path = build_dir / "free_beam.json"
    path.write_text(json.dumps(spec))
    out = build_dir / "free_beam.fmu"
    run_builder([path, "-o", out])
    return out


class Instance:
    def __init__(self, path, kind):
        self.md = read_model_description(str(path))
        self.dir = extract(str(path))
        self.rec = Recorder()
        cls, ident = (FMU2Slave, self.md.coSimulation) if kind == "cs" else (FMU2Model, self.md.modelExchange)
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.dir, modelIdentifier=ident.modelIdentifier,
                       instanceName="guards")
        self.fmu.instantiate(callbacks=self.rec.callbacks, loggingOn=True)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.c = self.fmu.component

    def initialize(self):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def raw(self, function, *args):
        """The C function's status, whatever it is (FMPy raises on fmi2Error and above)."""
        f = getattr(self.fmu.dll, function)
        f.restype = ctypes.c_int
        return f(self.c, *args)

    def step(self, t, h):
        return self.raw("fmi2DoStep", ctypes.c_double(t), ctypes.c_double(h), ctypes.c_int(1))

    def get(self, names):
        vrs = (ctypes.c_uint * len(names))(*[self.vr[n] for n in names])
        out = (ctypes.c_double * len(names))()
        return self.raw("fmi2GetReal", vrs, ctypes.c_size_t(len(names)), out), list(out)

    def set(self, names, values):
        vrs = (ctypes.c_uint * len(names))(*[self.vr[n] for n in names])
        vals = (ctypes.c_double * len(names))(*values)
        return self.raw("fmi2SetReal", vrs, ctypes.c_size_t(len(names)), vals)

    def last_successful_time(self):
        t = ctypes.c_double(math.nan)
        assert self.raw("fmi2GetRealStatus", ctypes.c_int(2), ctypes.byref(t)) == OK
        return t.value

    def states(self):
        return [n for n in self.vr if n.startswith(("q[", "qd[", "frame."))]

    def close(self):
        self.fmu.freeInstance()


def test_a_step_of_1e306_s_from_rest_is_never_ok_with_a_non_finite_state(beam):
    for start in (None, {"g[3]": -9.81}):
        fmu = Instance(beam[0], "cs")
        if start:
            fmu.set(list(start), list(start.values()))
        fmu.initialize()
        saved = fmu.fmu.getFMUState()
        status = fmu.step(0.0, 1e306)
        read, x = fmu.get(fmu.states())
        assert read == OK and all(math.isfinite(v) for v in x), (status, fmu.rec.text())
        if status == DISCARD:
            assert fmu.last_successful_time() == 0.0
            assert "not taken" in fmu.rec.text(), fmu.rec.text()
            fmu.fmu.setFMUState(saved)
            assert fmu.step(0.0, 1e-3) == OK, fmu.rec.text()
        else:
            assert status in (OK, WARNING), fmu.rec.text()
        fmu.fmu.freeFMUState(saved)
        fmu.close()


def test_input_derivatives_and_seeds_of_1e300_are_refused_and_the_instance_goes_on(beam):
    fmu = Instance(beam[0], "cs")
    fmu.initialize()
    vr = (ctypes.c_uint * 1)(fmu.vr["tip.f[3]"])
    order = (ctypes.c_int * 1)(1)
    for rate in (1e200, 1e300, 1e308):
        value = (ctypes.c_double * 1)(rate)
        assert fmu.raw("fmi2SetRealInputDerivatives", vr, ctypes.c_size_t(1), order, value) == ERROR
        assert "tip.f[3]" in fmu.rec.messages[-1] and "beyond 1e100" in fmu.rec.messages[-1], fmu.rec.text()
    seed = (ctypes.c_double * 1)(1e308)
    unknown = (ctypes.c_uint * 1)(fmu.vr["tip.u[3]"])
    out = (ctypes.c_double * 1)()
    assert fmu.raw("fmi2GetDirectionalDerivative", unknown, ctypes.c_size_t(1), vr, ctypes.c_size_t(1), seed,
                   out) == ERROR
    assert "dvKnown[0] = 1e308" in fmu.rec.messages[-1] and "tip.f[3]" in fmu.rec.messages[-1], fmu.rec.text()
    assert fmu.step(0.0, 1e-3) == OK, fmu.rec.text()
    assert fmu.get(["tip.u[3]"])[0] == OK
    fmu.close()


def test_a_mount_orientation_that_is_no_rotation_is_refused(beam):
    fmu = Instance(beam[0], "cs")
    fmu.initialize()
    sheared = [1.0, 0.8, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    assert fmu.set(R_NAMES, sheared) == ERROR
    assert "base.R is not a proper rotation matrix" in fmu.rec.messages[-1], fmu.rec.text()
    # entry by entry: refused where used, the instance stays usable
    assert fmu.set(["base.R[1,2]"], [0.8]) == OK
    assert fmu.step(0.0, 1e-3) == ERROR
    assert "base.R is not a proper rotation matrix" in fmu.rec.messages[-1], fmu.rec.text()
    assert fmu.set(["base.R[1,2]"], [0.0]) == OK
    assert fmu.step(0.0, 1e-3) == OK, fmu.rec.text()
    fmu.close()


def test_a_free_body_discards_a_quaternion_that_is_no_orientation_and_recovers(free_beam):
    fmu = Instance(free_beam, "me")
    fmu.initialize()
    fmu.fmu.enterContinuousTimeMode()
    n = fmu.md.numberOfContinuousStates
    x = (ctypes.c_double * n)()
    dx = (ctypes.c_double * n)()
    assert fmu.raw("fmi2GetContinuousStates", x, ctypes.c_size_t(n)) == OK
    good = list(x)
    for quat in ([1e200, 0, 0, 0], [0, 0, 0, 0]):
        bad = (ctypes.c_double * n)(*good[:n - 10], *quat, *good[n - 6:])
        assert fmu.raw("fmi2SetContinuousStates", bad, ctypes.c_size_t(n)) == OK
        assert fmu.raw("fmi2GetDerivatives", dx, ctypes.c_size_t(n)) == DISCARD
        assert "frame.Q" in fmu.rec.messages[-1] and "no orientation" in fmu.rec.messages[-1], fmu.rec.text()
    assert fmu.raw("fmi2SetContinuousStates", (ctypes.c_double * n)(*good), ctypes.c_size_t(n)) == OK
    assert fmu.raw("fmi2GetDerivatives", dx, ctypes.c_size_t(n)) == OK, fmu.rec.text()
    assert all(math.isfinite(v) for v in dx)
    fmu.close()


def test_a_long_step_of_a_free_beam_spinning_at_300_rad_s_is_bounded(free_beam):
    """16 s at 300 rad/s would be 960 000 substeps of 0.005 rad (37 s before the bound): the
    step returns within 2 s, and if not taken the reason names the largest step, which a master
    restoring the state before the step then takes."""
    fmu = Instance(free_beam, "cs")
    assert fmu.set(["initial.w[3]"], [300.0]) == OK
    fmu.initialize()
    saved = fmu.fmu.getFMUState()
    start = time.perf_counter()
    status = fmu.step(0.0, 16.0)
    took = time.perf_counter() - start
    print(f"\nh = 16 s at 300 rad/s: status {status} in {took:.3f} s: {fmu.rec.messages[-1] if status else ''}")
    assert took < 2.0
    if status == DISCARD:
        reason = fmu.rec.messages[-1]
        assert "960000 substeps" in reason and "largest step at this spin is h = " in reason, reason
        largest = float(reason.split("largest step at this spin is h = ")[1].split(" ")[0])
        assert fmu.last_successful_time() == 0.0
        fmu.fmu.setFMUState(saved)
        start = time.perf_counter()
        assert fmu.step(0.0, largest) == OK, fmu.rec.text()
        took = time.perf_counter() - start
        print(f"the largest step, h = {largest} s: {took:.3f} s")
        assert took < 2.0
    else:
        assert status == OK
    fmu.fmu.freeFMUState(saved)
    fmu.close()
