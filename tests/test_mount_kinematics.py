"""A mount that moves within a Co-Simulation step as its own inputs say. A host that samples the
mount's pose at step starts and gives no input derivatives (FMPy's default, most masters) used
to have the mount stand still within each step: gravity turned in the body frame in jumps, a
first-order error. The FMU now turns the mount by its own spin within the step (R' = w~ R,
w' = z) and the error is that of host-given derivatives.

The T-square spins about z at 10 rad/s under gravity along x: in the body frame gravity turns at
10 rad/s and drives the arms. Reference: the same FMU at h = 1e-5 s with the host giving dR/dt
(converged: the h = 2e-5 run agrees to the printed figure)."""

import numpy as np
import pytest

from conftest import _build
from fmu_access import Fmu

SPIN = 10.0
G = 9.81
T_END = 0.5
# halving steps that divide the 10 ms sampling; h = 1 ms is the second
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)


def rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


R_NAMES = [f"base.R[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]
OUTPUTS = [f"{f}.u[{i}]" for f in ("left", "right") for i in (1, 2, 3)]


def run(path, h, host_rates):
    """Deformation at the arms every 10 ms, the host setting the pose at each step start."""
    f = Fmu(path, "CoSimulation")
    try:
        f.set(**{"g[1]": G, "base.w[3]": SPIN})
        f.fmu.setupExperiment(startTime=0.0)
        f.fmu.enterInitializationMode()
        f.set(**dict(zip(R_NAMES, rz(0.0).ravel())))
        f.fmu.exitInitializationMode()
        n = int(round(T_END / h))
        every = int(round(0.01 / h))
        out = []
        w_tilde = np.array([[0.0, -SPIN, 0.0], [SPIN, 0.0, 0.0], [0.0, 0.0, 0.0]])
        for k in range(n):
            t = k * h
            rot = rz(SPIN * t)
            f.set(**dict(zip(R_NAMES, rot.ravel())))
            if host_rates:
                vrs = [f.vr[name] for name in R_NAMES]
                f.fmu.setRealInputDerivatives(vrs, [1] * 9, list((w_tilde @ rot).ravel()))
            f.fmu.doStep(t, h)
            if (k + 1) % every == 0:
                out.append(f.get(*OUTPUTS))
        return np.array(out)
    finally:
        f.close()


@pytest.fixture(scope="module")
def tsquare(build_dir):
    return _build("t-square.json", build_dir)[0]


def test_held_mount_moves_by_its_own_velocity_within_a_step(tsquare):
    reference = run(tsquare, 1e-5, host_rates=True)
    check = run(tsquare, 2e-5, host_rates=True)
    assert reference.shape == check.shape and reference.shape[0] == int(round(T_END / 0.01))
    scale = np.max(np.abs(reference))
    converged = np.max(np.abs(check - reference)) / scale
    errors = {}
    for host_rates in (False, True):
        errors[host_rates] = []
        for h in STEPS:
            found = run(tsquare, h, host_rates)
            assert found.shape == reference.shape
            errors[host_rates].append(np.max(np.abs(found - reference)) / scale)
    print(f"\nreference converged to {converged:.1e} of the peak deformation {scale:.3e} m")
    for host_rates, errs in errors.items():
        orders = [np.log2(a / b) for a, b in zip(errs, errs[1:])]
        label = "host dR/dt" if host_rates else "no derivatives (kinematic)"
        print(f"{label:28s} errors " + " ".join(f"{e:.2e}" for e in errs) + "  orders " + " ".join(f"{o:.2f}" for o in orders))
    # without derivatives the error at h = 1 ms equals the host-derivative one (measured: see
    # the print; both second order); held inputs used to be first order, 4e-3 at 1 ms
    assert errors[False][1] <= 1.5 * errors[True][1]
    assert errors[False][1] < 10 * max(errors[True][1], converged)
    orders = [np.log2(a / b) for a, b in zip(errors[False], errors[False][1:])]
    assert min(orders) > 1.7, orders
