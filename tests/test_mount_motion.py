"""The mount in motion (fixed orientation, translating) and the FMU's conventions: inertial
loads of a translating mount, gravity, and vectors resolved in the world frame.

References: Euler-Bernoulli cantilever under a uniform load q = rho A a (tip deflection
q l^4 / (8 EI), 1 %: shear and 3D effects are ~1e-3 for l/h = 50, and Craig-Bampton without
inertial static modes converges on this load to better than 1e-3 with 12 modes), Newton's
second law for the mount reaction (m a, to round-off of the modal sums), and the frame
transformation for a rotated mount."""

import ctypes

import numpy as np
import pytest
from scipy.linalg import expm

from conftest import ROOT
from fmpy.fmi1 import FMICallException
from fmu_access import Fmu
from test_fmi_robustness import Recorder, restore_default_logger  # noqa: F401 (autouse fixture)

E, RHO, L, B, H = 2e11, 7850.0, 1.0, 0.01, 0.02
TIP_U = ["tip.u[1]", "tip.u[2]", "tip.u[3]"]
TIP_PHI = ["tip.phi[1]", "tip.phi[2]", "tip.phi[3]"]
REACTION = ["base.f[1]", "base.f[2]", "base.f[3]"]


def static(path, **inputs):
    fmu = Fmu(path, "ModelExchange")
    try:
        fmu.set(static_start=True, **inputs)
        fmu.initialize()
        return {n: fmu.get(n)[0] for n in fmu.vr if fmu.var[n].type == "Real"}
    finally:
        fmu.close()


def test_accelerating_mount_bends_the_beam_like_a_uniform_load(beam):
    a = 50.0  # m/s^2 upwards: the beam lags behind, tip deflects down (body frame)
    out = static(beam[0], **{"base.a[3]": a})
    ei = E * B * H**3 / 12
    w = RHO * B * H * a * L**4 / (8 * ei)
    mass = RHO * B * H * L
    print(f"\naccelerating mount: tip {out['tip.u[3]'] / -w - 1:+.2e} vs Euler-Bernoulli, reaction {out['base.f[3]'] / (mass * a) - 1:+.1e} vs m a")
    assert out["tip.u[3]"] == pytest.approx(-w, rel=0.01, abs=0)  # measured -3.0e-3
    assert out["base.f[3]"] == pytest.approx(mass * a, rel=2e-12, abs=0)  # measured 1.6e-13


def test_gravity_is_an_acceleration_of_the_mount(beam):
    g = -9.81
    by_gravity = static(beam[0], **{"g[3]": g})
    by_acceleration = static(beam[0], **{"base.a[3]": -g})
    scale = max(abs(by_acceleration[n]) for n in TIP_U + TIP_PHI)
    print(f"\ngravity vs acceleration: tip {max(abs(by_gravity[n] - by_acceleration[n]) for n in TIP_U + TIP_PHI) / scale:.1e}, "
          f"reaction {max(abs(by_gravity[n] - by_acceleration[n]) for n in REACTION):.1e} N, "
          f"m g {by_gravity['base.f[3]'] / (-RHO * B * H * L * g) - 1:+.1e}")
    # measured 0 (the same numbers enter the same equations): an eps of reordering allowed
    weight = RHO * B * H * L * abs(g)
    for name in TIP_U + TIP_PHI:
        assert by_gravity[name] == pytest.approx(by_acceleration[name], rel=1e-15, abs=1e-15 * scale)
    for name in REACTION:
        assert by_gravity[name] == pytest.approx(by_acceleration[name], rel=1e-15, abs=1e-15 * weight)
    assert by_gravity["base.f[3]"] == pytest.approx(-RHO * B * H * L * g, rel=2e-12, abs=0)  # measured 1.6e-13


def rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def test_rotated_mount_resolves_loads_and_outputs_in_the_world_frame(beam):
    r0 = np.array([0.3, -0.2, 1.5])
    rot = rot_x(np.pi / 2)  # body z is world -y
    f_world = np.array([0.0, -2.0, 0.0])  # = +2 N along body z
    inputs = {f"base.r[{i + 1}]": r0[i] for i in range(3)}
    inputs.update({f"base.R[{i + 1},{j + 1}]": rot[i, j] for i in range(3) for j in range(3)})
    inputs.update({f"tip.f[{i + 1}]": f_world[i] for i in range(3)})
    rotated = static(beam[0], **inputs)
    upright = static(beam[0], **{"tip.f[3]": 2.0})
    scale = max(abs(upright[n]) for n in TIP_U + TIP_PHI)
    print(f"\nrotated vs upright: {max(abs(rotated[n] - upright[n]) for n in TIP_U + TIP_PHI) / scale:.1e} of the largest")
    for name in TIP_U + TIP_PHI:  # deformation in the body frame is the same (cos(pi/2) ~ 6e-17)
        assert rotated[name] == pytest.approx(upright[name], rel=3e-15, abs=3e-15 * scale)  # measured 2.4e-16
    u = np.array([upright[n] for n in TIP_U])
    r_tip = np.array([rotated[f"tip.r[{i + 1}]"] for i in range(3)])
    tip_rot0 = np.array([[rotated[f"tip.R[{i + 1},{j + 1}]"] for j in range(3)] for i in range(3)])
    phi0 = np.array([upright[n] for n in TIP_PHI])
    sk0 = np.array([[0, -phi0[2], phi0[1]], [phi0[2], 0, -phi0[0]], [-phi0[1], phi0[0], 0]])
    print(f"r_tip {np.abs(r_tip - r0 - rot @ (np.array([L, 0, 0]) + u)).max():.1e} m, R^T R - I {np.abs(tip_rot0.T @ tip_rot0 - np.eye(3)).max():.1e}, "
          f"R - R0 exp {np.abs(tip_rot0 - rot @ expm(sk0)).max():.1e}, reaction {np.abs(np.array([rotated[n] for n in REACTION]) + f_world).max():.1e} N")
    # round-off of positions ~1.5 m, rotations ~1 and reactions ~2 N (measured 4.4e-16 m, 1.1e-16,
    # 1.8e-19, 9.4e-28 N)
    np.testing.assert_allclose(r_tip, r0 + rot @ (np.array([L, 0, 0]) + u), rtol=0, atol=5e-15)
    tip_rot = np.array([[rotated[f"tip.R[{i + 1},{j + 1}]"] for j in range(3)] for i in range(3)])
    np.testing.assert_allclose(tip_rot.T @ tip_rot, np.eye(3), rtol=0, atol=1e-15)
    phi = np.array([upright[n] for n in TIP_PHI])
    skew = np.array([[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]])
    np.testing.assert_allclose(tip_rot, rot @ expm(skew), rtol=0, atol=1e-15)  # flange frame = R exp(phi~)
    reaction = np.array([rotated[n] for n in REACTION])
    np.testing.assert_allclose(reaction, -f_world, rtol=0, atol=1e-15)


def test_a_non_rotation_base_R_is_refused(beam):
    rec = Recorder()
    fmu = Fmu(beam[0], "ModelExchange", callbacks=rec.callbacks)
    try:
        with pytest.raises(FMICallException):
            fmu.set(**{"base.R[1,1]": 2.0})  # no entry of any rotation: refused at once
        assert "base.R[1,1]" in rec.text() and "rotation matrix" in rec.text(), rec.text()
        fmu.set(**{"base.R[1,1]": 0.5})  # possible entries, but no rotation: refused at initialisation
        with pytest.raises(FMICallException):
            fmu.initialize()
    finally:
        fmu.close(terminate=False)
    assert "base.R is not a proper rotation matrix" in rec.text(), rec.text()


FMI2_FUNCTIONS = """GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean
GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate
SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative
EnterEventMode NewDiscreteStates EnterContinuousTimeMode CompletedIntegratorStep SetTime
SetContinuousStates GetDerivatives GetEventIndicators GetContinuousStates
GetNominalsOfContinuousStates SetRealInputDerivatives GetRealOutputDerivatives DoStep CancelStep
GetStatus GetRealStatus GetIntegerStatus GetBooleanStatus GetStringStatus""".split()


def test_binary_exports_all_44_fmi2_functions(beam):
    fmu = Fmu(beam[0], "CoSimulation")
    try:
        lib = ctypes.CDLL(f"{fmu.dir}/binaries/linux64/Beam.so")
        assert len(FMI2_FUNCTIONS) == 44
        missing = [f for f in FMI2_FUNCTIONS if not hasattr(lib, "fmi2" + f)]
        assert missing == []
        lib.fmi2GetVersion.restype = ctypes.c_char_p
        lib.fmi2GetTypesPlatform.restype = ctypes.c_char_p
        assert lib.fmi2GetVersion() == b"2.0" and lib.fmi2GetTypesPlatform() == b"default"
    finally:
        fmu.close(terminate=False)
