"""Exact derivatives through the FMI 2.0 C API (FMPy): fmi2GetDirectionalDerivative in Model
Exchange and Co-Simulation, fmi2GetRealOutputDerivatives in Co-Simulation.

References, none of them the derivative code: central finite differences of the FMU's own
fmi2GetReal / fmi2GetDerivatives (Richardson-extrapolated, error O(h^4)); the time slope of the
outputs over short fmi2DoStep steps; kinematics (d/dt of a flange's position is its velocity
output, and so on). Tolerance 5e-7 of each entry (ten times the measured worst, 5.2e-8, which is
the differences' rounding), with a floor of 1e-9 of the unknown's largest
response to a natural-size change of any known, below which a finite difference is noise."""

import json

import numpy as np
import pytest
from conftest import EXAMPLES, run_builder
from fmu_access import Fmu
from test_large_motion import FREE_BLOCK, build


def natural_scale(name, value):
    """What it takes to move the body noticeably: the finite-difference step is 1e-2 of it."""
    if ".R[" in name:
        return 0.1  # the runtime accepts rotation inputs up to 1e-2 off orthonormal
    if name.startswith("frame.Q["):
        return 0.1  # a unit quaternion: orientation is far from linear in it
    if name.startswith("q["):
        base = 1e-4
    elif name.startswith("qd["):
        base = 1e-2
    elif ".f[" in name:
        base = 100.0
    elif ".t[" in name or ".a[" in name or ".z[" in name:
        base = 10.0
    else:
        base = 1.0
    return max(base, abs(value))


def tilt(phi, axis):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(phi) * k + (1 - np.cos(phi)) * k @ k


@pytest.fixture(scope="module")
def tsquare(tmp_path_factory):
    """The T-square with stress outputs at two points and three hot spots: the Jacobians cover
    stresses and von Mises stresses as they cover the flanges' motion."""
    spec = json.loads((EXAMPLES / "t-square.json").read_text())
    spec["outputs"] = {"stress": {"points": [[0.18, 0.0, 0.02], [0.06, 0.02, 0.0]], "hot_spots": 3}}
    return build(tmp_path_factory.mktemp("derivatives"), spec, "t-square")


@pytest.fixture(scope="module")
def soft_tsquare(tmp_path_factory):
    """The T-square in a soft material and lightly damped (modes up to 8 kHz instead of 100 kHz,
    beta w^2 up to 3e3/s instead of 4e8/s), so that a step short against its fastest motion is
    still long against rounding."""
    spec = json.loads((EXAMPLES / "t-square.json").read_text())
    spec["material"] = {"E": 2e8, "nu": 0.3, "rho": 1200.0}
    spec["damping"] = {"alpha": 1.0, "beta": 1e-6}
    spec["reduction"]["modes"] = 6
    # every mode dynamic, as when the slope test's figure was measured: with the default cutoff
    # (2 kHz) the modes above it start in equilibrium and the outputs' third derivative grows,
    # and with it the finite differences' own O(h^3) truncation (7.1e-8 at h = 1e-7, 3.7e-7 at
    # 2e-7, 3.0e-6 at 4e-7), not the output derivatives' error
    spec["reduction"]["dynamic_cutoff"] = 1e5
    return build(tmp_path_factory.mktemp("derivatives-soft"), spec, "soft-t-square")


@pytest.fixture(scope="module")
def free_block(tmp_path_factory):
    return build(tmp_path_factory.mktemp("derivatives-free"), FREE_BLOCK, "free")


TSQUARE_INPUTS = {"base.r[1]": 0.2, "base.v[2]": 1.5, "base.w[1]": 3.0, "base.w[2]": -5.0, "base.w[3]": 20.0,
                  "base.a[1]": 4.0, "base.a[3]": -2.0, "base.z[2]": 30.0, "base.z[3]": -10.0,
                  "left.f[3]": 40.0, "left.f[1]": -15.0, "right.f[2]": 25.0, "right.t[1]": 2.0, "g[3]": -9.81}


def start_tsquare(path, kind):
    fmu = Fmu(str(path), kind)
    fmu.set(**TSQUARE_INPUTS)
    rot = tilt(0.7, [1, 1, 1])
    for i in range(3):
        for j in range(3):
            fmu.set_named(f"base.R[{i + 1},{j + 1}]", rot[i, j])
    fmu.initialize()
    return fmu


def start_free(path, kind):
    fmu = Fmu(str(path), kind)
    fmu.set(**{"initial.r[1]": 0.3, "initial.phi[1]": 0.4, "initial.phi[3]": -1.1, "initial.v[2]": 0.5,
               "initial.w[1]": 0.5, "initial.w[2]": -2.0, "initial.w[3]": 3.0, "g[3]": -9.81,
               "end.f[1]": 2.0, "end.f[3]": -1.5, "end.t[2]": 0.05})
    fmu.initialize()
    return fmu


def excite(fmu, scale):
    """Every dynamic mode displaced and moving, every relaxing one displaced (Model Exchange:
    through the state vector; the algebraic modes follow from them and the inputs)."""
    x = fmu.states()
    names = [d.variable.derivative.name for d in fmu.md.derivatives]
    # state order: q, qd of the dynamic modes, then q of the relaxing ones
    n = sum(1 for s in names if s.startswith("qd["))
    nr = sum(1 for s in names if s.startswith("q[")) - n
    j = np.arange(n)
    x[:n] += scale * np.sin(0.7 * j + 0.3)
    x[n:2 * n] += 30 * scale * np.cos(1.3 * j + 0.1)
    x[2 * n:2 * n + nr] += scale * np.sin(0.9 * np.arange(nr) + 0.2)
    fmu.set_states(x)


def names_by(fmu, causality):
    return [v.name for v in fmu.md.modelVariables if v.causality == causality and v.type == "Real"]


def state_names(fmu):
    return [d.variable.derivative.name for d in fmu.md.derivatives]


def derivative_names(fmu):
    return [d.variable.name for d in fmu.md.derivatives]


def check_jacobian(fmu, unknowns, knowns, what):
    """Every column of d unknowns / d knowns by fmi2GetDirectionalDerivative against finite
    differences; returns (worst relative error, entries compared relatively)."""
    states = state_names(fmu) if fmu.kind == "ModelExchange" else []
    vu = [fmu.vr[u] for u in unknowns]

    def read():
        return np.array(fmu.fmu.getReal(vu))

    def value(k):
        return fmu.states()[states.index(k)] if k in states else fmu.get(k)[0]

    def put(k, x):
        if k in states:
            xs = fmu.states()
            xs[states.index(k)] = x
            fmu.set_states(xs)
        else:
            fmu.set_named(k, x)

    exact, fd, scales = [], [], []
    for k in knowns:
        exact.append(np.array(fmu.fmu.getDirectionalDerivative(vu, [fmu.vr[k]], [1.0])))
        x = value(k)
        s = natural_scale(k, x)

        def central(h):
            put(k, x + h)
            plus = read()
            put(k, x - h)
            minus = read()
            put(k, x)
            return (plus - minus) / (2 * h)

        h = 1e-2 * s
        d1, d2 = central(h), central(h / 2)
        fd.append((4 * d2 - d1) / 3)
        scales.append(s)
    exact, fd, scales = np.array(exact), np.array(fd), np.array(scales)
    response = np.max(np.abs(exact) * scales[:, None], axis=0)
    floor = 1e-9 * response[None, :] / scales[:, None]
    err = np.abs(exact - fd)
    bad = err > 5e-7 * np.abs(exact) + floor
    if bad.any():
        k, u = np.argwhere(bad)[0]
        raise AssertionError(f"{what}: d {unknowns[u]} / d {knowns[k]}: exact {exact[k, u]:e}, "
                             f"finite differences {fd[k, u]:e} ({bad.sum()} entries off)")
    big = np.abs(exact) > 1e3 * floor
    worst = float(np.max(err[big] / np.abs(exact[big])))
    print(f"\n{what}: {len(knowns)} knowns x {len(unknowns)} unknowns, {big.sum()} entries compared "
          f"relatively, worst {worst:.1e}")
    assert big.sum() > 50
    return worst


def test_model_exchange_jacobian_of_a_spinning_tsquare(tsquare):
    """State matrix, input matrix and output matrices of the spinning, tilted, accelerating,
    loaded T-square: all four blocks in one Jacobian, exact against finite differences."""
    fmu = start_tsquare(tsquare, "ModelExchange")
    excite(fmu, 1e-4)
    inputs = names_by(fmu, "input")
    unknowns = names_by(fmu, "output") + derivative_names(fmu)
    check_jacobian(fmu, unknowns, inputs + state_names(fmu), "T-square, Model Exchange")
    fmu.close()


def test_model_exchange_jacobian_of_a_free_block(free_block):
    fmu = start_free(free_block, "ModelExchange")
    excite(fmu, 1e-3)
    unknowns = names_by(fmu, "output") + derivative_names(fmu)
    check_jacobian(fmu, unknowns, names_by(fmu, "input") + state_names(fmu), "free block, Model Exchange")
    fmu.close()


def test_co_simulation_output_input_jacobian(tsquare):
    """Co-Simulation: outputs with respect to inputs at a communication point, mid-run."""
    fmu = start_tsquare(tsquare, "CoSimulation")
    t = 0.0
    for k in range(20):
        fmu.set_named("left.f[3]", 40.0 + 10 * np.sin(k))
        fmu.fmu.doStep(t, 1e-3)
        t += 1e-3
    check_jacobian(fmu, names_by(fmu, "output"), names_by(fmu, "input"), "T-square, Co-Simulation")
    fmu.close()


def test_directional_derivative_is_linear_in_the_seed(tsquare):
    """A combined seed gives the combination of the columns (the call takes a direction, not
    one variable at a time)."""
    fmu = start_tsquare(tsquare, "CoSimulation")
    outputs = [fmu.vr[n] for n in names_by(fmu, "output")]
    knowns = [fmu.vr[n] for n in ["base.w[3]", "left.f[3]", "base.R[1,2]"]]
    seed = [0.3, -2.0, 0.05]
    combined = np.array(fmu.fmu.getDirectionalDerivative(outputs, knowns, seed))
    columns = sum(s * np.array(fmu.fmu.getDirectionalDerivative(outputs, [k], [1.0])) for k, s in zip(knowns, seed))
    print(f"\nseed linearity: {np.abs(combined - columns).max() / np.max(np.abs(columns)):.1e}")
    # measured 1.2e-16: round-off of one combination
    assert np.allclose(combined, columns, rtol=2e-15, atol=2e-15 * np.max(np.abs(columns)))
    fmu.close()


def flange_names(fmu, flange, q):
    return [f"{flange}.{q}[{i}]" for i in range(1, 4)]


def test_output_derivatives_follow_the_kinematics(tsquare, free_block):
    """d/dt of a flange's position, velocity and angular velocity are its velocity, acceleration
    and angular acceleration outputs, for a spinning mount and a tumbling free body."""
    cases = [(start_tsquare(tsquare, "CoSimulation"), ["left", "right"], "left.f[3]"),
             (start_free(free_block, "CoSimulation"), ["end"], "end.f[3]")]
    for fmu, flanges, load in cases:
        t = 0.0
        for k in range(30):
            fmu.set_named(load, 3.0 * np.cos(0.3 * k))
            fmu.fmu.doStep(t, 2e-3)
            t += 2e-3
        for flange in flanges:
            for of, rate in [("r", "v"), ("v", "a"), ("w", "z")]:
                names = flange_names(fmu, flange, of)
                d = np.array(fmu.fmu.getRealOutputDerivatives([fmu.vr[n] for n in names], [1, 1, 1]))
                expected = fmu.get(*flange_names(fmu, flange, rate))
                print(f"\n{flange} d{of}/dt vs {rate}: {np.abs(d - expected).max() / np.max(np.abs(expected)):.1e}")
                # the same quantity by two routes: measured 3.1e-16 at most
                assert np.allclose(d, expected, rtol=3e-15, atol=3e-15 * np.max(np.abs(expected))), (flange, of, d, expected)
        fmu.close()


def test_output_derivatives_are_the_slope_of_the_steps(soft_tsquare, free_block):
    """Against the outputs' own trajectory: with input derivatives set (the mount's consistent
    with its motion, a, z and the loads ramping), forward differences of the outputs over steps
    of h, h/2, h/4 from one saved FMU state, extrapolated twice (error O(h^3)), equal
    fmi2GetRealOutputDerivatives for every output, reactions and accelerations included. Any
    first-order consistent step has the exact slope at h -> 0; h = 1e-7 s is short against the
    fastest mode (h w_max = 5e-3) and long against rounding."""
    for start, path, rates in [
        (start_tsquare, soft_tsquare, {"base.a[1]": 50.0, "base.z[3]": -200.0, "left.f[3]": 4000.0, "right.t[1]": -300.0}),
        (start_free, free_block, {"end.f[3]": 40.0, "end.t[2]": -3.0}),
    ]:
        fmu = start(path, "CoSimulation")
        t = 0.0
        for _ in range(10):
            fmu.fmu.doStep(t, 1e-3)
            t += 1e-3
        outputs = names_by(fmu, "output")
        vo = [fmu.vr[n] for n in outputs]
        names, values = list(rates), list(rates.values())
        if start is start_tsquare:
            # the mount moves as its inputs say: r' = v, R' = w~ R, v' = a, w' = z
            rot = np.array([[fmu.get(f"base.R[{i},{j}]")[0] for j in range(1, 4)] for i in range(1, 4)])
            w = fmu.get(*flange_names(fmu, "base", "w"))
            rdot = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]) @ rot
            names += [f"base.R[{i + 1},{j + 1}]" for i in range(3) for j in range(3)]
            values += [rdot[i, j] for i in range(3) for j in range(3)]
            for i in range(1, 4):
                names += [f"base.r[{i}]", f"base.v[{i}]", f"base.w[{i}]"]
                values += [fmu.get(f"base.v[{i}]")[0], fmu.get(f"base.a[{i}]")[0], fmu.get(f"base.z[{i}]")[0]]
        fmu.fmu.setRealInputDerivatives([fmu.vr[n] for n in names], [1] * len(names), values)
        exact = np.array(fmu.fmu.getRealOutputDerivatives(vo, [1] * len(vo)))
        y0 = np.array(fmu.fmu.getReal(vo))
        state = fmu.fmu.getFMUstate()

        def slope(h):
            fmu.fmu.setFMUstate(state)
            fmu.fmu.doStep(t, h)
            return (np.array(fmu.fmu.getReal(vo)) - y0) / h

        h = 1e-7
        d = [slope(h), slope(h / 2), slope(h / 4)]
        r1 = [2 * d[1] - d[0], 2 * d[2] - d[1]]
        fd = (4 * r1[1] - r1[0]) / 3
        fmu.fmu.freeFMUstate(state)
        scale = np.maximum(np.abs(exact), 1e-6 * np.max(np.abs(exact)))
        err = np.abs(exact - fd) / scale
        worst = int(np.argmax(err))
        print(f"\n{start.__name__}: {len(outputs)} output derivatives vs the steps' slope, worst {err[worst]:.1e} "
              f"({outputs[worst]}: {exact[worst]:e} vs {fd[worst]:e})")
        # ten times the measured worst (3.3e-9, the steps' slope's own truncation)
        assert err[worst] < 3e-8, (outputs[worst], exact[worst], fd[worst])
        fmu.close()


def in_initialization_mode(path, kind, inputs):
    """The T-square between fmi2EnterInitializationMode and fmi2ExitInitializationMode, its
    inputs at `inputs` and its mount tilted as in `start_tsquare` when any are given."""
    fmu = Fmu(str(path), kind)
    fmu.set(**inputs)
    if inputs:
        rot = tilt(0.7, [1, 1, 1])
        for i in range(3):
            for j in range(3):
                fmu.set_named(f"base.R[{i + 1},{j + 1}]", rot[i, j])
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()
    return fmu


def jacobian(fmu, unknowns, knowns):
    vu = [fmu.vr[u] for u in unknowns]
    return np.array([fmu.fmu.getDirectionalDerivative(vu, [fmu.vr[k]], [1.0]) for k in knowns])


def mode_names(fmu):
    return [v.name for v in fmu.md.modelVariables if v.name.startswith(("q[", "qd["))]


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_directional_derivatives_in_initialization_mode(tsquare, kind):
    """fmi2GetDirectionalDerivative in Initialization Mode (FMI 2.0 allows it there; hosts that
    solve an algebraic loop through the body's feedthrough call it before the loop is solved):
    d outputs (and, Model Exchange, d derivatives) / d inputs at the inputs set there, against
    central finite differences of fmi2GetReal in the same mode, and equal to round-off to the same
    call after initialisation at the same inputs and state."""
    fmu = in_initialization_mode(tsquare, kind, TSQUARE_INPUTS)
    me = kind == "ModelExchange"
    inputs = names_by(fmu, "input")
    unknowns = names_by(fmu, "output") + (derivative_names(fmu) if me else [])
    worst = check_jacobian(fmu, unknowns, inputs, f"T-square, {kind}, Initialization Mode")
    assert worst < 1e-6
    fmu.close(terminate=False)

    # the same call before and after initialisation, at the same inputs and state: Model Exchange
    # puts the state it had in Initialization Mode back (the initialisation settles the modes);
    # Co-Simulation cannot set its state, so it starts from rest with no loads, where the
    # initialisation leaves the modes where they are (checked)
    fmu = in_initialization_mode(tsquare, kind, TSQUARE_INPUTS if me else {})
    knowns = inputs + (state_names(fmu) if me else [])
    before = jacobian(fmu, unknowns, knowns)
    modes = mode_names(fmu)
    x = fmu.states() if me else fmu.get(*modes)
    fmu.fmu.exitInitializationMode()
    if me:
        fmu.fmu.newDiscreteStates()
        fmu.fmu.enterContinuousTimeMode()
        fmu.set_states(x)
    else:
        assert np.array_equal(fmu.get(*modes), x)
    after = jacobian(fmu, unknowns, knowns)
    scale = np.max(np.abs(after), axis=0)
    deviation = float(np.max(np.abs(before - after) / np.where(scale > 0, scale, 1.0)))
    print(f"\n{kind}: Initialization Mode against after it, {before.size} entries, deviation {deviation:.1e}")
    assert np.count_nonzero(after) > 50
    assert deviation <= 1e-14
    fmu.close()


FREE_START = {"initial.r[1]": 0.3, "initial.phi[1]": 0.4, "initial.phi[3]": -1.1, "initial.v[2]": 0.5,
              "initial.w[1]": 0.5, "initial.w[2]": -2.0, "initial.w[3]": 3.0}
FREE_LOADS = {"g[3]": -9.81, "end.f[1]": 2.0, "end.f[3]": -1.5, "end.t[2]": 0.05}


def test_free_body_in_initialization_mode_starts_from_the_parameters_set_there(free_block):
    """A free body's initial pose and velocity may be set in Initialization Mode (they are
    parameters with initial="exact"): the values, derivatives and Jacobian read there are those of
    the frame they give, the same as after initialisation (Model Exchange, whose frame states a
    host reads in that mode)."""
    fmu = Fmu(str(free_block), "ModelExchange")
    fmu.set(**FREE_LOADS)
    fmu.fmu.setupExperiment(startTime=0.0)
    fmu.fmu.enterInitializationMode()
    fmu.set(**FREE_START)
    unknowns = names_by(fmu, "output") + derivative_names(fmu)
    knowns = names_by(fmu, "input") + state_names(fmu)
    x, values, before = fmu.states(), fmu.get(*unknowns), jacobian(fmu, unknowns, knowns)
    fmu.fmu.exitInitializationMode()
    fmu.fmu.newDiscreteStates()
    fmu.fmu.enterContinuousTimeMode()
    assert np.array_equal(fmu.states(), x), "the initialisation starts the frame where it was read"
    assert np.array_equal(fmu.get(*unknowns), values)
    assert np.array_equal(jacobian(fmu, unknowns, knowns), before)
    fmu.close()
