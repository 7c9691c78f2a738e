"""Co-Simulation of an undamped body on a steadily spinning mount: the gyroscopic (Coriolis)
coupling is energy-neutral, so a correct step keeps the energy and follows the exact solution at
any step size. The reference is the exact solution of the FMU's own linear Model Exchange
equations (state matrix and load taken through fmi2GetDirectionalDerivative and
fmi2GetDerivatives, propagated by scipy's matrix exponential): nothing computed by the
Co-Simulation step. Before the coupled modes were propagated by their exponential, the undamped
T-square at 300 rad/s reached max|q| = 0.245 after 10 s where the exact solution stays at 1e-4,
and a single 100 s step returned NaN with fmi2OK."""

import json

import numpy as np
import pytest
import scipy.linalg

from conftest import EXAMPLES, run_builder
from fmu_access import Fmu
from fmpy.fmi1 import FMICallException
from test_fmi_robustness import Recorder, restore_default_logger  # noqa: F401 (autouse fixture)

T_END = 20.0
SAMPLE = 1e-3


@pytest.fixture(scope="module")
def undamped(tmp_path_factory):
    """The T-square example without damping (the default of a spec that names none)."""
    spec = json.loads((EXAMPLES / "t-square.json").read_text())
    del spec["damping"]
    spec.pop("$schema", None)
    # every mode dynamic: these tests hold Co-Simulation's exact step to the matrix exponential of
    # the Model Exchange linearisation, which must then be the same model (with quasi-static
    # modes ME is the condensed model of the dynamic ones)
    spec["reduction"]["dynamic_cutoff"] = 1e9
    tmp = tmp_path_factory.mktemp("spin")
    path = tmp / "spec.json"
    path.write_text(json.dumps(spec))
    fmu_path = tmp / "TSquare.fmu"
    run_builder([path, "-o", fmu_path])
    return fmu_path


def spin_inputs(axis, w):
    return {f"base.w[{axis}]": w}


def linear_model(fmu_path, inputs):
    """x' = J x + f0 of the Model Exchange FMU at held inputs (exactly affine in the state):
    J by exact directional derivatives, f0 the derivatives at x = 0; the state names."""
    me = Fmu(fmu_path, "ModelExchange")
    try:
        me.set(**inputs)
        me.initialize()
        x0 = np.zeros(me.nx)
        me.set_states(x0)
        f0 = me.derivatives()
        states = [d.variable.derivative.valueReference for d in me.md.derivatives]
        ders = [d.variable.valueReference for d in me.md.derivatives]
        names = [d.variable.derivative.name for d in me.md.derivatives]
        jac = np.zeros((me.nx, me.nx))
        for j in range(me.nx):
            seed = np.zeros(me.nx)
            seed[j] = 1.0
            jac[:, j] = me.fmu.getDirectionalDerivative(ders, states, list(seed))
        return jac, f0, names
    finally:
        me.close()


def exact_samples(jac, f0, t_end, dt):
    """x(k dt) from rest, exactly: the exponential of the augmented matrix [[J, f0], [0, 0]]."""
    n = len(f0)
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = jac
    aug[:n, n] = f0
    step = scipy.linalg.expm(aug * dt)
    x = np.zeros(n)
    out = [x]
    for _ in range(int(round(t_end / dt))):
        x = step[:n, :n] @ x + step[:n, n]
        out.append(x)
    return np.array(out)


def cosim_samples(fmu_path, inputs, h, t_end, dt, names):
    fmu = Fmu(fmu_path, "CoSimulation")
    try:
        fmu.set(**inputs)
        fmu.initialize()
        every = int(round(dt / h))
        out = [fmu.get(*names)]
        t = 0.0
        for k in range(int(round(t_end / h))):
            fmu.fmu.doStep(t, h)
            t = (k + 1) * h
            if (k + 1) % every == 0:
                out.append(fmu.get(*names))
        return np.array(out)
    finally:
        fmu.close()


def energy(x, jac, f0, n):
    """H = 1/2 q'^T q' + 1/2 q^T K q - p^T q, the invariant of q'' + G q' + K q = p with G skew
    (K, G, p read off the linear model)."""
    k = -jac[n:, :n]
    k = 0.5 * (k + k.T)
    p = f0[n:]
    q, qd = x[:, :n], x[:, n:]
    return 0.5 * np.sum(qd * qd, axis=1) + 0.5 * np.einsum("ti,ij,tj->t", q, k, q) - q @ p, \
        0.5 * np.sum(qd * qd, axis=1) + 0.5 * np.einsum("ti,ij,tj->t", q, k, q)


def critical_speed(fmu_path, axis):
    """The lowest spin about `axis` at which K(w) = Lambda + w^2 C loses definiteness (no
    stiffening declared: centrifugal softening only), from the linear models at w = 0 and 1."""
    j0, _, names = linear_model(fmu_path, spin_inputs(axis, 0.0))
    j1, _, _ = linear_model(fmu_path, spin_inputs(axis, 1.0))
    n = len(names) // 2
    k0 = -j0[n:, :n]
    c = -j1[n:, :n] - k0
    c = 0.5 * (c + c.T)
    l = np.linalg.cholesky(0.5 * (k0 + k0.T))
    li = np.linalg.inv(l)
    softening = np.linalg.eigvalsh(-li @ c @ li.T).max()
    return 1.0 / np.sqrt(softening)


@pytest.mark.parametrize("axis", [3, 1])
def test_undamped_spin_follows_the_exact_solution(undamped, axis):
    w_c = critical_speed(undamped, axis)
    print(f"\naxis {axis}: first critical speed {w_c:.1f} rad/s")
    assert 500 < w_c < 1e4, w_c  # measured 2701 (z) and 1522 (x) rad/s; 0.8 w_c must exceed 300
    for w in (100.0, 300.0, 0.8 * w_c):
        inputs = spin_inputs(axis, w)
        jac, f0, names = linear_model(undamped, inputs)
        n = len(names) // 2
        assert len(names) == 2 * n and all(s.startswith("q[") for s in names[:n])
        exact = exact_samples(jac, f0, T_END, SAMPLE)
        h_exact, e_exact = energy(exact, jac, f0, n)
        q_max = np.abs(exact[:, :n]).max()
        for h in (1e-3, 1e-4):
            found = cosim_samples(undamped, inputs, h, T_END, SAMPLE, names)
            assert found.shape == exact.shape
            deviation = np.abs(found[:, :n] - exact[:, :n]).max() / q_max
            ratio = np.abs(found[:, :n]).max() / q_max
            h_found, _ = energy(found, jac, f0, n)
            drift = np.abs(h_found - h_found[0]).max() / e_exact.max()
            growth = (h_found[-1] - h_found[0]) / e_exact.max()
            print(f"  |max|q| / exact - 1| {abs(ratio - 1):.1e}")
            print(f"  w {w:7.1f} rad/s, h {h:g}: max|q| {np.abs(found[:, :n]).max():.4e} vs exact {q_max:.4e}, "
                  f"trajectory deviation {deviation:.1e} of max|q|, energy drift {drift:.1e}, end growth {growth:.1e}")
            # the issue asks max|q| within 1e-2 of the exact solution; the trajectory itself
            # agrees to the round-off of two exponentials (measured <= 5.9e-9 of max|q|), and
            # |max|found| - max|exact|| <= max|found - exact|, so both hold to 6e-8
            assert abs(ratio - 1) < 6e-8
            assert deviation < 6e-8
            # the energy of the rotating-frame system stays (measured drift <= 3.2e-9)
            assert drift < 3e-8 and growth < 3e-8


def test_one_long_step_stays_on_the_exact_solution(undamped):
    """A single 100 s step, undamped, at 300 rad/s about x: the exact transition, not NaN."""
    inputs = spin_inputs(1, 300.0)
    jac, f0, names = linear_model(undamped, inputs)
    n = len(names) // 2
    exact = exact_samples(jac, f0, 100.0, 100.0)[-1]
    fmu = Fmu(undamped, "CoSimulation")
    try:
        fmu.set(**inputs)
        fmu.initialize()
        fmu.fmu.doStep(0.0, 100.0)
        found = fmu.get(*names)
        outputs = fmu.get("left.u[1]", "left.u[2]", "left.u[3]", "right.u[1]")
    finally:
        fmu.close()
    assert found.shape == exact.shape and np.all(np.isfinite(outputs))
    scale = np.abs(exact[:n]).max()
    deviation = np.abs(found[:n] - exact[:n]).max() / scale
    print(f"\none 100 s step: max|q| {np.abs(found[:n]).max():.4e} vs exact {scale:.4e}, deviation {deviation:.1e}")
    # both sides are matrix exponentials over 1e5 periods of the stiffest mode: 1.3e-9 measured
    assert deviation < 1.3e-8


def test_spin_above_the_critical_speed_is_reported(undamped):
    """Above the critical speed without stiffening the body is unstable: the FMU logs why
    (logStatusWarning; the step was taken, so fmi2DoStep answers fmi2OK, which masters such as
    OMSimulator and fmusim require to go on), its outputs stay finite while it can, and the step
    that would make the deformation unrepresentable is refused with fmi2Discard and the reason,
    the state left as the last good step made it (a master may roll back or stop): never NaN with
    fmi2OK."""
    w = 1.2 * critical_speed(undamped, 3)
    rec = Recorder()
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(undamped))
    directory = extract(str(undamped))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=directory,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="spin")
    # warnings go to the logStatusWarning category, which the host switches on (errors are
    # logged regardless)
    slave.instantiate(callbacks=rec.callbacks, loggingOn=True)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave.setReal([vr["base.w[3]"]], [w])
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    # FMPy's doStep hides the status below fmi2Error: call the C function for it
    status = slave.fmi2DoStep(slave.component, 0.0, 1e-3, 1)
    assert status == 0, status  # fmi2OK: the step was taken
    assert "fmi2DoStep: " in rec.text() and "critical speed" in rec.text(), rec.text()
    outputs = [vr[n] for n in ("left.u[1]", "left.u[2]", "left.u[3]", "base.f[1]")]
    t, failed = 1e-3, False
    for _ in range(2000):
        try:
            slave.doStep(t, 1.0)
        except FMICallException as e:
            assert e.status == 2 and e.function == "fmi2DoStep", e  # fmi2Discard, with the reason below
            failed = True
            break
        t += 1.0
        assert np.all(np.isfinite(slave.getReal(outputs)))
    print(f"\nspin {w:.0f} rad/s: {rec.text()[:300]}")
    assert failed and "grew without bound" in rec.text(), rec.text()
    # the refused step changed nothing: the last good step's outputs, finite
    assert np.all(np.isfinite(slave.getReal(outputs)))
    slave.freeInstance()
