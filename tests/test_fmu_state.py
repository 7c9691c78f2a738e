"""Serialized FMU states (canSerializeFMUstate): with FMPy, a state taken mid-run, serialized
and deserialized into a FRESH instance continues bit-identically to the original (Co-Simulation
outputs step by step; Model Exchange states, derivatives and outputs), for a mounted beam, the
T-square on a spinning mount and a free-floating block. Damaged or foreign bytes return
fmi2Error with a logged reason, and the instance keeps working."""

import numpy as np
import pytest
from fmpy import read_model_description

from conftest import EXAMPLES, run_builder
from fmu_access import Fmu
from test_fmi_robustness import Recorder, refused, restore_default_logger  # noqa: F401 (autouse fixture)
from test_large_motion import FREE_BLOCK, build

H = 1e-3


def beam_inputs(t):
    return {"base.a[3]": 30.0 * np.sin(40.0 * t), "tip.f[2]": 200.0 * (1.0 + t), "tip.t[1]": 5.0 * np.cos(70.0 * t)}


def tsquare_inputs(t):
    # spinning up about z (w = 2 + 50 t, z = 50) with a tilt rate about x and a load on the head
    theta = 2.0 * t + 25.0 * t * t
    c, s = np.cos(theta), np.sin(theta)
    return {"base.R[1,1]": c, "base.R[1,2]": -s, "base.R[2,1]": s, "base.R[2,2]": c,
            "base.w[3]": 2.0 + 50.0 * t, "base.z[3]": 50.0, "base.w[1]": 0.3,
            "left.f[3]": 20.0 * np.sin(90.0 * t)}


def free_inputs(t):
    return {"end.f[3]": 0.5 * np.sin(30.0 * t), "end.t[2]": 0.01}


@pytest.fixture(scope="module")
def cases(beam, tmp_path_factory):
    d = tmp_path_factory.mktemp("state")
    tsquare = d / "t-square.fmu"
    run_builder([EXAMPLES / "t-square.json", "-o", tsquare])
    free = build(d, FREE_BLOCK, "free")
    return {
        "beam": (beam[0], beam_inputs, {"g[3]": -9.81, "static_start": True}),
        "t-square": (tsquare, tsquare_inputs, {"g[3]": -9.81, "damping.alpha": 0.5}),
        "free": (free, free_inputs, {"initial.w[1]": 0.5, "initial.w[3]": 3.0, "initial.v[1]": 0.2,
                                      "g[3]": -1.0, "q[1]": 1e-4}),
    }


def recorded(fmu):
    """Every Real output and local (states, accelerations) of the FMU."""
    return [v.name for v in fmu.md.modelVariables
            if v.type == "Real" and v.causality in ("output", "local")]


def bits(rows):
    return np.ascontiguousarray(np.array(rows, dtype=float)).view(np.uint64)


def run_cs(fmu, inputs, t, n):
    names = recorded(fmu)
    rows = []
    for _ in range(n):
        fmu.set(**inputs(t))
        fmu.fmu.doStep(t, H)
        t += H
        rows.append(fmu.get(*names))
    return t, rows


def serialize(fmu):
    state = fmu.fmu.getFMUstate()
    blob = fmu.fmu.serializeFMUstate(state)
    fmu.fmu.freeFMUstate(state)
    return blob


def restore(fmu, blob):
    state = fmu.fmu.deSerializeFMUstate(blob)
    fmu.fmu.setFMUstate(state)
    fmu.fmu.freeFMUstate(state)


def test_capability_flags(cases):
    md = read_model_description(str(cases["beam"][0]))
    for iface in (md.modelExchange, md.coSimulation):
        assert iface.canGetAndSetFMUstate and iface.canSerializeFMUstate


@pytest.mark.parametrize("name", ["beam", "t-square", "free"])
def test_co_simulation_state_continues_bit_identically_in_a_fresh_instance(cases, name):
    path, inputs, start = cases[name]
    a = Fmu(path, "CoSimulation")
    b = Fmu(path, "CoSimulation")
    try:
        a.set(**start)
        a.initialize()
        t, _ = run_cs(a, inputs, 0.0, 20)
        blob = serialize(a)
        assert blob[:8] == b"FLEXSTAT"
        _, expected = run_cs(a, inputs, t, 50)
        # b was instantiated only: deserialize and set bring it to a's state and mode
        restore(b, blob)
        assert b.fmu.getRealStatus(2) == t  # fmi2LastSuccessfulTime
        _, got = run_cs(b, inputs, t, 50)
        assert np.array_equal(bits(got), bits(expected))
        assert np.abs(np.array(expected)).max() > 0  # it moved
        # the same bytes once more, into the handle FMPy hands back for reuse
        state = b.fmu.getFMUstate()
        state = b.fmu.deSerializeFMUstate(blob, state)
        b.fmu.setFMUstate(state)
        b.fmu.freeFMUstate(state)
        _, again = run_cs(b, inputs, t, 50)
        assert np.array_equal(bits(again), bits(expected))
        print(f"\n{name}: {len(blob)} bytes, {len(expected)} steps x {len(expected[0])} values bit-identical")
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("name", ["beam", "t-square", "free"])
def test_model_exchange_states_and_derivatives_identical_after_restore(cases, name):
    path, inputs, start = cases[name]
    a = Fmu(path, "ModelExchange")
    b = Fmu(path, "ModelExchange")
    names = recorded(a)
    h = 1e-7  # explicit Euler below the stiffest mode's stability limit

    def euler(fmu, t, n):
        rows = []
        for _ in range(n):
            fmu.fmu.setTime(t)
            fmu.set(**inputs(t))
            x, dx = fmu.states(), fmu.derivatives()
            rows.append(np.concatenate([x, dx, fmu.get(*names)]))
            fmu.set_states(x + h * dx)
            t += h
        return t, rows

    try:
        a.set(**start)
        a.initialize()
        t, _ = euler(a, 0.0, 10)
        blob = serialize(a)
        _, expected = euler(a, t, 20)
        restore(b, blob)
        _, got = euler(b, t, 20)
        assert np.array_equal(bits(got), bits(expected))
    finally:
        a.close()
        b.close()


def test_bad_bytes_are_refused_and_the_instance_keeps_working(cases):
    path, inputs, start = cases["beam"]
    other_path, other_inputs, _ = cases["t-square"]
    rec = Recorder()
    a = Fmu(path, "CoSimulation", callbacks=rec.callbacks)
    other = Fmu(other_path, "CoSimulation")
    me = Fmu(path, "ModelExchange")
    try:
        a.set(**start)
        a.initialize()
        t, _ = run_cs(a, inputs, 0.0, 5)
        blob = serialize(a)
        other.initialize()
        foreign = serialize(other)
        me.initialize()
        me_blob = serialize(me)
        flipped = bytearray(blob)
        flipped[len(blob) // 2] ^= 0x01
        for bad, reason in [
            (blob[:-1], "truncated"),
            (blob[: len(blob) // 2], "truncated"),
            (blob[:10], "truncated"),
            (b"", "truncated"),
            (blob + b"\0", "header says"),
            (bytes(flipped), "CRC-32"),
            (b"PK\x03\x04 not an FMU state at all", "not a serialized FMU state"),
            (foreign, "GUID"),
            (me_blob, "ModelExchange instance"),
        ]:
            n = len(rec.messages)
            with refused("fmi2DeSerializeFMUstate"):
                a.fmu.deSerializeFMUstate(bad)
            assert len(rec.messages) > n, reason
            assert "fmi2DeSerializeFMUstate" in rec.messages[-1] and reason in rec.messages[-1], rec.messages[-1]
        # a refused state is a bad argument, nothing was changed: the run goes on
        t_blob = t
        t, after_refusals = run_cs(a, inputs, t_blob, 5)
        # and a good state still restores, also out of the Error state a failed step leaves
        with refused("fmi2SetReal"):
            a.set(**{"base.R[1,1]": 2.0})  # no entry of a rotation: refused at once
        assert "base.R[1,1]" in rec.messages[-1] and "rotation" in rec.messages[-1], rec.messages[-1]
        a.set(**{"base.R[1,1]": 0.5})  # each entry possible, the matrix no rotation: the step fails
        with refused("fmi2DoStep"):
            a.fmu.doStep(t, H)
        assert "base.R" in rec.messages[-1]
        with refused("fmi2DoStep"):
            a.fmu.doStep(t, H)  # Error state: only restore, reset or free help
        print(f"\ndoStep in the Error state: {rec.messages[-1]}")
        assert "fmi2DoStep" in rec.messages[-1] and "Error" in rec.messages[-1], rec.messages[-1]
        restore(a, blob)
        _, again = run_cs(a, inputs, t_blob, 5)
        assert np.array_equal(bits(again), bits(after_refusals))
    finally:
        a.close()
        other.close()
        me.close()


@pytest.mark.parametrize("name", ["beam", "t-square"])
def test_pending_input_derivatives_travel_with_the_state(cases, name):
    """Input derivatives set for the next step are part of the state: saved between
    fmi2SetRealInputDerivatives and fmi2DoStep, restored in a fresh instance, the step is the same."""
    path, inputs, start = cases[name]
    a = Fmu(path, "CoSimulation")
    b = Fmu(path, "CoSimulation")
    try:
        a.set(**start)
        a.initialize()
        t, _ = run_cs(a, inputs, 0.0, 5)
        flange = [v.name for v in a.md.modelVariables if v.causality == "input" and v.name.endswith(".f[3]")][0]
        a.fmu.setRealInputDerivatives([a.vr[flange]], [1], [250.0])
        blob = serialize(a)
        a.fmu.doStep(t, H)
        expected = a.get(*recorded(a))
        restore(b, blob)
        b.fmu.doStep(t, H)
        got = b.get(*recorded(b))
        assert np.array_equal(bits([got]), bits([expected]))
        assert b.get(flange)[0] == a.get(flange)[0] != inputs(t - H).get(flange, 0.0)  # ended interpolated
    finally:
        a.close()
        b.close()
