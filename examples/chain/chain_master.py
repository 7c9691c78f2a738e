"""A chain of flexible bodies, each an FMU of this builder, connected flange to mount by welds
or revolute joints and co-simulated by a master that iterates on the joints.

Body i's force flange carries body i+1's mount: body i+1 takes the flange's motion (r, R, v, w,
a, z) as its mount inputs, and body i takes minus body i+1's mount reaction (base.f, base.t) as
its flange load. That loop is algebraic (the reaction depends on the mount's acceleration, the
flange's acceleration on its load), and a master that breaks it with a one-step delay (libcosim,
Ecos, a plain FMPy loop) diverges within a few hundredths of a second at any step: the
delayed reaction carries the lower body's mass, larger than what the flange can carry in one
step. This master retakes every step (fmi2GetFMUstate / fmi2SetFMUstate) and solves, by Newton
on a Jacobian taken by finite differences of whole steps, for the joint wrenches at both ends
of the step that make the two sides agree:

- the upper body's flange load ramps over the step (fmi2SetRealInputDerivatives) between the
  lower body's mount reactions at the step's start and end, both taken after the inputs of this
  step are set (a reaction jumps with the mount's acceleration);
- the lower body's mount moves over the step as the flange did: pose and velocity ramp between
  the flange's values at the two ends, and the accelerations are linear in time with their mean
  equal to the velocities' change over the step (so the lower body gains exactly the momentum
  the flange did) and their slope the change of that mean since the last step.

Accelerations are not taken from the flange's outputs directly: modes above the step's Nyquist
frequency ring in them, and an interpolation through them feeds that ringing back; velocities'
changes are their average over the step.

A revolute joint turns the mount about an axis of its own axes by an angle the master
integrates: the mount's motion is the flange's composed with the joint's rotation, the joint
carries no torque about its axis, and the master solves for the joint's rate at the step's end
as one more unknown, with the mount's torque about the axis at the step's end as its equation.
A revolute joint on the ground (a pendulum's pivot) has only that unknown.

Run: python examples/chain/chain_master.py Link.fmu Link.fmu --step 1e-3 --stop 2
     python examples/chain/chain_master.py Link.fmu Link.fmu --pivot y:30 --joint y --stop 5
(see docs/CONNECTING.md)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

#: a flange's motion outputs and a mount's motion inputs, in this order
MOTION = ([f"r[{i}]" for i in (1, 2, 3)] + [f"R[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]
          + [f"{q}[{i}]" for q in "vwaz" for i in (1, 2, 3)])
POSE_AND_VELOCITY = slice(0, 18)
VELOCITY = slice(12, 15)
SPIN = slice(15, 18)
ACCELERATIONS = slice(18, 24)
#: a force flange's load inputs and a mount's reaction outputs
WRENCH = [f"{q}[{i}]" for q in "ft" for i in (1, 2, 3)]

#: Newton stops when every joint force and torque agrees to this fraction of the largest
#: (N, N.m): 1e-8, far below a step's coupling error (about 1e-4 of the swing at 1 ms,
#: docs/CONNECTING.md), and far above round-off
RELATIVE_TOLERANCE = 1e-8
MAX_ITERATIONS = 20
MAX_HALVINGS = 8


class Body:
    """One co-simulation FMU through FMPy's FMU2Slave, with named real variables."""

    def __init__(self, path: str, name: str, start: dict[str, float] | None = None):
        self.path, self.name = path, name
        self.md = read_model_description(path)
        self.dir = extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.kind = {v.name: v.type for v in self.md.modelVariables}
        self.start = dict(start or {})
        self.fmu: FMU2Slave | None = None

    def instantiate(self, inputs: dict[str, float] | None = None):
        """A fresh instance in initialisation mode's end state, its start values and `inputs` set."""
        if self.fmu is not None:
            self.fmu.terminate()
            self.fmu.freeInstance()
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=self.name)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in {**self.start, **(inputs or {})}.items():
            if name not in self.vr:
                raise KeyError(f"{self.path}: no variable {name!r}")
            if self.kind[name] == "Boolean":
                self.fmu.setBoolean([self.vr[name]], [bool(value)])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])
        self.fmu.exitInitializationMode()

    def refs(self, flange: str, names: list[str]) -> list[int]:
        missing = [f"{flange}.{n}" for n in names if f"{flange}.{n}" not in self.vr]
        if missing:
            raise KeyError(f"{self.path}: no variable {missing[0]!r} (is {flange!r} a flange of that role?)")
        return [self.vr[f"{flange}.{n}"] for n in names]

    def get(self, refs) -> np.ndarray:
        return np.array(self.fmu.getReal(refs))

    def set(self, refs, values):
        self.fmu.setReal(refs, [float(v) for v in values])

    def set_rates(self, refs, rates):
        self.fmu.setRealInputDerivatives(refs, [1] * len(refs), [float(v) for v in rates])


@dataclass
class Joint:
    """Body `lower`'s mount `mount` on body `upper`'s force flange `flange`, or on the ground
    (`upper` None) at the pose `ground`: welded (`axis` None) or revolute about `axis`, a unit
    vector in the mount's axes (the same in the flange's axes: the joint turns about it, the
    joint's point is the mount's origin)."""

    upper: int | None
    lower: int
    mount: str
    flange: str | None = None
    axis: np.ndarray | None = None
    #: the ground frame's motion where `upper` is None: 24 values in `MOTION`'s order, or a
    #: function of time giving them (a driven crank's pin)
    ground: np.ndarray | Callable[[float], np.ndarray] | None = None
    #: a revolute joint's angle from the flange's axes to the mount's [rad] and its rate [rad/s]
    angle: float = 0.0
    rate: float = 0.0
    # the mount's motion at the last communication point, and the mean accelerations of the
    # last step (the next step's slope is their change)
    motion: np.ndarray = field(default_factory=lambda: np.zeros(24))
    mean_acceleration: np.ndarray | None = None

    def __post_init__(self):
        if (self.upper is None) != (self.flange is None):
            raise ValueError(f"joint of body {self.lower}: a flange names the upper body's flange; "
                             "the ground has none")
        if self.upper is None and self.ground is None:
            self.ground = ground_motion()
        if self.axis is not None:
            axis = np.asarray(self.axis, dtype=float)
            if axis.shape != (3,) or not np.linalg.norm(axis) > 0:
                raise ValueError(f"joint of body {self.lower}: the axis must be a non-zero 3-vector, not {self.axis!r}")
            self.axis = axis / np.linalg.norm(axis)
            self._basis = axis_basis(self.axis)

    @property
    def revolute(self) -> bool:
        return self.axis is not None

    @property
    def load_size(self) -> int:
        """Parameters of the flange load: a weld's six components, a revolute joint's force and
        its two torques across the axis."""
        return 5 if self.revolute else 6

    @property
    def unknowns(self) -> int:
        """Per step: a weld's wrench at both ends (12); a revolute joint's force and its two
        torques across the axis at both ends and its rate at the end (11); on the ground only
        the rate (1), or nothing for a welded (fixed) mount."""
        if self.upper is None:
            return 1 if self.revolute else 0
        return 2 * self.load_size + (1 if self.revolute else 0)

    def wrench(self, p: np.ndarray, mount_rotation: np.ndarray) -> np.ndarray:
        """The flange load (world) from its parameters: a weld's six components; a revolute
        joint's force and its torques about the two axes across the joint axis."""
        if not self.revolute:
            return p
        across = mount_rotation @ self._basis[:, 1:]
        return np.concatenate([p[:3], across @ p[3:5]])

    def wrench_residual(self, w: np.ndarray, reaction: np.ndarray, mount_rotation: np.ndarray) -> np.ndarray:
        """Load plus reaction, with a revolute joint's torque only across its axis."""
        if not self.revolute:
            return w + reaction
        across = mount_rotation @ self._basis[:, 1:]
        return np.concatenate([w[:3] + reaction[:3], across.T @ (w[3:] + reaction[3:])])

    def axial_torque(self, reaction: np.ndarray, mount_rotation: np.ndarray) -> float:
        return float((mount_rotation @ self.axis) @ reaction[3:])


def ground_at(j: Joint, t: float) -> np.ndarray:
    return np.asarray(j.ground(t) if callable(j.ground) else j.ground, dtype=float)


def ground_motion(r=(0.0, 0.0, 0.0), rotation=None) -> np.ndarray:
    """A frame at rest: position `r`, orientation `rotation` (identity), no velocity."""
    rotation = np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)
    return np.concatenate([np.asarray(r, dtype=float), rotation.ravel(), np.zeros(12)])


def axis_basis(axis: np.ndarray) -> np.ndarray:
    """Columns: the axis and two unit vectors across it (right-handed)."""
    trial = np.eye(3)[int(np.argmin(np.abs(axis)))]
    p1 = np.cross(axis, trial)
    p1 /= np.linalg.norm(p1)
    return np.column_stack([axis, p1, np.cross(axis, p1)])


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by `angle` about the unit vector `axis` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def rotation_vector(phi: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(phi))
    return np.eye(3) if angle == 0.0 else rotation(phi / angle, angle)


def compose(flange: np.ndarray, axis, angle: float, rate: float, acceleration: float) -> np.ndarray:
    """The mount's motion on a flange moving as `flange` through a revolute joint about `axis`
    (mount axes) at `angle`, `rate`, `acceleration`; a weld (`axis` None) passes it on."""
    if axis is None:
        return flange.copy()
    flange_rotation = flange[3:12].reshape(3, 3)
    mount_rotation = flange_rotation @ rotation(axis, angle)
    spin_axis = flange_rotation @ axis
    w = flange[SPIN]
    out = flange.copy()
    out[3:12] = mount_rotation.ravel()
    out[SPIN] = w + spin_axis * rate
    out[21:24] = flange[21:24] + spin_axis * acceleration + np.cross(w, spin_axis * rate)
    return out


@dataclass
class Slider:
    """Body `body`'s force flange `flange` kept on a line of the ground (through `point` along
    `direction`, world) by a frictionless, massless slider: the slider's load on the flange is
    normal to the line and held over each step (two unknowns: its components along two
    normals), and the equations are the flange's distance from the line at the step's end.
    Held, not ramping from the last step's value: a ramp makes the load at the step's end
    answer for the whole step's error, and it grew by a factor of -2.3 per step (a position
    constraint's multiplier). With a revolute joint on the same body this closes a kinematic
    loop (a slider-crank's connecting rod)."""

    body: int
    flange: str
    point: np.ndarray
    direction: np.ndarray
    #: the slider's load on the flange over the last step (world); None until a static start
    #: or the first step solves it
    load: np.ndarray | None = None

    def __post_init__(self):
        self.point = np.asarray(self.point, dtype=float)
        u = np.asarray(self.direction, dtype=float)
        if u.shape != (3,) or not np.linalg.norm(u) > 0 or self.point.shape != (3,):
            raise ValueError(f"slider on body {self.body}: a point and a non-zero direction, 3-vectors each")
        self.direction = u / np.linalg.norm(u)
        self.normals = axis_basis(self.direction)[:, 1:]

    unknowns = 2


class Chain:
    """Bodies connected by joints, each joint a body's mount on an upper body's force flange or
    on the ground; every body's upper body comes before it (a chain, or a tree)."""

    def __init__(self, bodies: list[Body], joints: list[Joint], step: float, sliders: list[Slider] = ()):
        if not step > 0:
            raise ValueError(f"the step must be positive, not {step}")
        lowers = [j.lower for j in joints]
        if len(set(lowers)) != len(lowers):
            raise ValueError("a body hangs from one joint at most")
        for j in joints:
            if not 0 <= j.lower < len(bodies) or (j.upper is not None and not 0 <= j.upper < j.lower):
                raise ValueError(f"joint {j.upper} -> {j.lower}: each body's upper body must come before it")
        self.bodies, self.h, self.t = bodies, float(step), 0.0
        self.joints = sorted(joints, key=lambda j: j.lower)
        self.hung = {j.lower: j for j in self.joints}
        self._joint_index = {j.lower: k for k, j in enumerate(self.joints)}
        for sl in sliders:
            if not 0 <= sl.body < len(bodies):
                raise ValueError(f"slider on body {sl.body}: there are {len(bodies)} bodies")
        self.sliders = list(sliders)
        # the unknowns: every joint's, then every slider's
        self.offsets = np.cumsum([0] + [j.unknowns for j in self.joints] + [sl.unknowns for sl in self.sliders])
        # which unknowns are a revolute joint's rate (each joint's last)
        self._angular = np.zeros(self.offsets[-1], dtype=bool)
        for k, j in enumerate(self.joints):
            if j.revolute:
                self._angular[self.offsets[k + 1] - 1] = True
        self.evaluations = 0
        self.jacobians = 0
        self._jacobian: np.ndarray | None = None
        self._x: np.ndarray | None = None

    def _part(self, x: np.ndarray, owner: int) -> np.ndarray:
        """The unknowns (a view) of joint `owner`, or of slider `owner - len(joints)`."""
        return x[self.offsets[owner]:self.offsets[owner + 1]]

    @classmethod
    def welded(cls, bodies: list[Body], flanges: list[str], mounts: list[str], step: float) -> "Chain":
        """Body i's flange `flanges[i]` welded to body i+1's mount `mounts[i]`."""
        if len(bodies) < 2 or len(flanges) != len(bodies) - 1 or len(mounts) != len(bodies) - 1:
            raise ValueError("a chain needs n >= 2 bodies, n - 1 flanges and n - 1 mounts")
        return cls(bodies, [Joint(i, i + 1, m, f) for i, (f, m) in enumerate(zip(flanges, mounts))], step)

    # -- references of each joint's variables
    def _flange_motion(self, j: Joint):
        return self.bodies[j.upper].refs(j.flange, MOTION)

    def _flange_load(self, j: Joint):
        return self.bodies[j.upper].refs(j.flange, WRENCH)

    def _mount_motion(self, j: Joint):
        return self.bodies[j.lower].refs(j.mount, MOTION)

    def _mount_reaction(self, j: Joint):
        return self.bodies[j.lower].refs(j.mount, WRENCH)

    def _flange_now(self, j: Joint) -> np.ndarray:
        return ground_at(j, self.t) if j.upper is None else self.bodies[j.upper].get(self._flange_motion(j))

    def initialize(self, static: bool = False, static_rounds: int = 6):
        """Instantiate the bodies with each mount where its joint puts it, and solve the joints'
        algebraic loop at t = 0 (loads, and revolute joints' angular accelerations). `static`:
        every body starts in static equilibrium (its `static_start`) under the loads of the
        bodies below it, by `static_rounds` rounds of fixed point (the lower bodies' weight on
        the upper, the upper's deflection tilting the lower), 1e-12 apart after 6 on the
        examples. With revolute joints or sliders, `static` also solves, by Newton, for the
        revolute joints' angles and the sliders' loads of a mechanism at rest: no torque about
        any joint's axis, every slider's flange on its line (a slider-crank held still, its
        rod sagging between crank pin and slider). The joints' angles given are where Newton
        starts: a pendulum started at 45 degrees with `static` ends hanging down at rest."""
        if static and (self.sliders or any(j.revolute for j in self.joints)):
            self._static_mechanism(static_rounds)
        else:
            self._static_rounds(static, static_rounds if static else 1)
        accelerations = self._consistent_loads()
        for j in self.joints:
            j.motion = compose(self._flange_now(j), j.axis, j.angle, j.rate, accelerations[j.lower])
            # the first step's accelerations are constant: those at t = 0 through the
            # feedthroughs are the instant's, not the step's (a flexible body's modes take up a
            # sudden acceleration; the links' mount torque answers a joint's angular
            # acceleration with 3e-4 of their rigid inertia at that instant)
            j.mean_acceleration = None
            self.bodies[j.lower].set(self._mount_motion(j), j.motion)
        x = []
        for j in self.joints:
            if j.upper is not None:
                w = self.bodies[j.upper].get(self._flange_load(j))
                if j.revolute:
                    across = j.motion[3:12].reshape(3, 3) @ j._basis[:, 1:]
                    w = np.concatenate([w[:3], across.T @ w[3:]])
                x += [w, w]
            if j.revolute:
                x.append([j.rate])
        for sl in self.sliders:
            x.append(np.zeros(sl.unknowns) if sl.load is None else sl.normals.T @ sl.load)
        self._x = np.concatenate(x) if x else np.zeros(0)

    def _static_rounds(self, static: bool, rounds: int):
        loads = {j.lower: np.zeros(6) for j in self.joints}
        for _ in range(rounds):
            self._instantiate_all(loads, static)
            loads = {j.lower: -self.bodies[j.lower].get(self._mount_reaction(j)) for j in self.joints}
        if static:
            self._instantiate_all(loads, static)

    def _static_mechanism(self, rounds: int):
        """Newton on the revolute joints' angles and the sliders' normal loads, each evaluation
        a static start of every body (`_static_rounds`); the residuals are the joints' torques
        about their axes and the sliders' flanges' distances from their lines."""
        revolute = [j for j in self.joints if j.revolute]
        n_angles = len(revolute)

        def residual(z):
            for j, angle in zip(revolute, z[:n_angles]):
                j.angle = float(angle)
            for k, sl in enumerate(self.sliders):
                sl.load = sl.normals @ z[n_angles + 2 * k:n_angles + 2 * k + 2]
            self._static_rounds(True, rounds)
            out = []
            for j in revolute:
                reaction = self.bodies[j.lower].get(self._mount_reaction(j))
                rotation_now = compose(self._flange_now(j), j.axis, j.angle, j.rate, 0.0)[3:12].reshape(3, 3)
                out.append(j.axial_torque(reaction, rotation_now))
            for sl in self.sliders:
                at = self.bodies[sl.body].get(self.bodies[sl.body].refs(sl.flange, ["r[1]", "r[2]", "r[3]"]))
                out.extend(sl.normals.T @ (at - sl.point))
            return np.array(out)

        z = np.concatenate([[j.angle for j in revolute]] + [np.zeros(2) for _ in self.sliders])
        steps = np.array([1e-6] * n_angles + [1e-3] * (2 * len(self.sliders)))
        r = residual(z)
        for _ in range(MAX_ITERATIONS):
            scale = max(1.0, np.abs(z[n_angles:]).max() if len(z) > n_angles else 0.0)
            if np.abs(r).max() <= RELATIVE_TOLERANCE * scale:
                break
            jac = np.zeros((len(r), len(z)))
            for c in range(len(z)):
                e = np.zeros(len(z))
                e[c] = steps[c]
                jac[:, c] = (residual(z + e) - r) / steps[c]
            z = z - np.linalg.solve(jac, r)
            r = residual(z)
        else:
            raise RuntimeError(f"no static equilibrium of the mechanism found in {MAX_ITERATIONS} iterations "
                               f"(largest torque [N m] or distance [m] {np.abs(r).max():.3g}); start it without static")

    def _instantiate_all(self, loads, static):
        for i, body in enumerate(self.bodies):
            inputs = {"static_start": True} if static else {}
            if i in self.hung:
                j = self.hung[i]
                motion = compose(self._flange_now(j), j.axis, j.angle, j.rate, 0.0)
                inputs.update({f"{j.mount}.{n}": v for n, v in zip(MOTION, motion)})
            for j in self.joints:
                if j.upper == i:
                    inputs.update({f"{j.flange}.{n}": v for n, v in zip(WRENCH, loads[j.lower])})
            for sl in self.sliders:
                if sl.body == i and sl.load is not None:
                    inputs.update({f"{sl.flange}.{n}": v for n, v in zip(WRENCH[:3], sl.load)})
            body.instantiate(inputs)

    def _consistent_loads(self) -> dict[int, float]:
        """Newton at t = 0 through the feedthroughs (no step): per joint its load (a revolute
        joint's without torque about its axis) and a revolute joint's angular acceleration,
        such that loads and reactions balance. Returns the angular accelerations."""
        sizes = [(0 if j.upper is None else j.load_size) + (1 if j.revolute else 0) for j in self.joints]
        offsets = np.cumsum([0] + sizes)
        rotations = {j.lower: compose(self._flange_now(j), j.axis, j.angle, j.rate, 0.0)[3:12].reshape(3, 3)
                     for j in self.joints}

        def split(y, k, j):
            part = y[offsets[k]:offsets[k + 1]]
            return (part[:-1] if j.revolute else part), (part[-1] if j.revolute else 0.0)

        def residual(y):
            r = np.zeros_like(y)
            for k, j in enumerate(self.joints):
                if j.upper is not None:
                    self.bodies[j.upper].set(self._flange_load(j), j.wrench(split(y, k, j)[0], rotations[j.lower]))
            for k, j in enumerate(self.joints):
                motion = compose(self._flange_now(j), j.axis, j.angle, j.rate, split(y, k, j)[1])
                self.bodies[j.lower].set(self._mount_motion(j), motion)
            for k, j in enumerate(self.joints):
                reaction = self.bodies[j.lower].get(self._mount_reaction(j))
                out = []
                if j.upper is not None:
                    w = j.wrench(split(y, k, j)[0], rotations[j.lower])
                    out.append(j.wrench_residual(w, reaction, rotations[j.lower]))
                if j.revolute:
                    out.append([j.axial_torque(reaction, rotations[j.lower])])
                if out:
                    r[offsets[k]:offsets[k + 1]] = np.concatenate(out)
            return r

        y = np.zeros(offsets[-1])
        for k, j in enumerate(self.joints):
            if j.upper is not None and not j.revolute:
                y[offsets[k]:offsets[k + 1]] = self.bodies[j.upper].get(self._flange_load(j))
        if len(y):
            angular = np.zeros(len(y), dtype=bool)
            for k, j in enumerate(self.joints):
                if j.revolute:
                    angular[offsets[k + 1] - 1] = True
            y = self._newton(residual, y, jacobian=None, angular=angular)[0]
            residual(y)
        return {j.lower: split(y, k, j)[1] for k, j in enumerate(self.joints)}

    def _newton(self, residual, x, jacobian, angular):
        """Quasi-Newton: a Jacobian by finite differences where there is none or where an
        iteration gained less than half, Broyden's update after every iteration (the joints'
        Jacobian turns slowly with the bodies' poses)."""
        r = residual(x)
        tol = RELATIVE_TOLERANCE * max(1.0, np.abs(x).max())
        last = np.inf
        for _ in range(MAX_ITERATIONS):
            size = np.abs(r).max()
            if size <= tol:
                return x, jacobian
            # round-off: no further progress within a thousand times the tolerance
            if size < 1e3 * tol and size >= last:
                return x, jacobian
            if jacobian is None or size > 0.5 * last:
                jacobian = self._finite_difference_jacobian(residual, x, r, angular)
            last = size
            try:
                dx = -np.linalg.solve(jacobian, r)
            except np.linalg.LinAlgError:
                # a Broyden update can make the Jacobian singular: take it anew
                jacobian = self._finite_difference_jacobian(residual, x, r, angular)
                dx = -np.linalg.solve(jacobian, r)
            r_new = None
            # a trial far off (an FMU refusing the step, e.g. a body spun past its critical
            # speed by a stale Jacobian's guess) is halved back towards the last iterate
            for _ in range(MAX_HALVINGS):
                try:
                    r_new = residual(x + dx)
                    break
                except FMICallException:
                    dx = 0.5 * dx
            if r_new is None:
                raise RuntimeError(f"t = {self.t:.6g} s: every trial step of the joints was refused by a body")
            x = x + dx
            jacobian = jacobian + np.outer(r_new - r - jacobian @ dx, dx) / (dx @ dx)
            r = r_new
        raise RuntimeError(f"t = {self.t:.6g} s: the joints did not converge in {MAX_ITERATIONS} "
                           f"iterations (largest residual {np.abs(r).max():.3g})")

    def _finite_difference_jacobian(self, residual, x, r, angular):
        """Columns by forward differences: a load's by 1e-3 of the largest load (the residuals
        are nearly linear in the loads); a joint's rate or angular acceleration by 1e-5 rad/s
        (rad/s^2) relative, since a rate's step turns into an angular acceleration of step / h
        on the lower body, which a stiff body answers with large forces."""
        self.jacobians += 1
        loads = np.abs(x[~angular])
        d_load = 1e-3 * max(1.0, loads.max() if len(loads) else 0.0)
        jac = np.zeros((len(r), len(x)))
        for c in range(len(x)):
            d = 1e-5 * max(1.0, abs(x[c])) if angular[c] else d_load
            e = np.zeros(len(x))
            e[c] = d
            jac[:, c] = (residual(x + e) - r) / d
        return jac

    def step(self):
        """One communication step of h: every body retaken until the joints agree."""
        if self._x is None:
            raise RuntimeError("initialize() the chain before stepping it")
        states = [b.fmu.getFMUstate() for b in self.bodies]
        try:
            if len(self._x):
                # Newton's last residual is the step at the solution: the bodies are there already
                self._x, self._jacobian = self._newton(lambda x: self._retake(states, x), self._x, self._jacobian,
                                                       self._angular)
            else:
                self._retake(states, self._x)
            starts = [j.rate for j in self.joints]
            slider_starts = [sl.load for sl in self.sliders]
            for j, (angle, rate, motion, mean) in zip(self.joints, self._pending):
                j.angle, j.rate, j.motion, j.mean_acceleration = angle, rate, motion, mean
            for sl, load in zip(self.sliders, self._pending_sliders):
                sl.load = load
        finally:
            for b, s in zip(self.bodies, states):
                b.fmu.freeFMUstate(s)
        self.t += self.h
        # the next step's start wrench is this one's end, its end extrapolated; so the rates
        for k, j in enumerate(self.joints):
            part = self._part(self._x, k)
            if j.upper is not None:
                n = j.load_size
                start, end = part[:n].copy(), part[n:2 * n].copy()
                part[:n], part[n:2 * n] = end, 2 * end - start
            if j.revolute:
                part[-1] = 2 * j.rate - starts[k]
        for k, (sl, start) in enumerate(zip(self.sliders, slider_starts)):
            if start is not None:
                part = self._part(self._x, len(self.joints) + k)
                part[:] = 2 * part - sl.normals.T @ start

    def _retake(self, states, x) -> np.ndarray:
        """The step from `states` with the joints' unknowns `x`: per joint the residuals of
        load plus reaction at both ends (a revolute joint's torque only across its axis) and a
        revolute joint's torque about its axis at the step's end."""
        self.evaluations += 1
        h = self.h
        residual = np.zeros_like(x)
        end_flange: dict[int, np.ndarray] = {}
        pending: dict[int, tuple] = {}
        pending_sliders: list[np.ndarray | None] = [None] * len(self.sliders)
        # the mount's axes at the step's end, for a revolute joint's loads: turned from the start
        # by the flange's spin (an end-of-step basis the loads need before the upper body steps)
        end_rotation = {}
        for j in self.joints:
            start_rotation = j.motion[3:12].reshape(3, 3)
            turn = j.motion[SPIN] * h + 0.5 * h * h * j.motion[21:24]
            end_rotation[j.lower] = rotation_vector(turn) @ start_rotation
        for i, body in enumerate(self.bodies):
            body.fmu.setFMUstate(states[i])
            j = self.hung.get(i)
            if j is not None:
                part = self._part(x, self._joint_index[i])
                rate = part[-1] if j.revolute else 0.0
                angle = j.angle + 0.5 * h * (j.rate + rate) if j.revolute else 0.0
                flange = ground_at(j, self.t + h) if j.upper is None else end_flange[j.lower]
                end = compose(flange, j.axis, angle, rate, 0.0)
                refs = self._mount_motion(j)
                start, rates, mean = mount_motion(j.motion, end, j.mean_acceleration, h)
                body.set(refs, start)
                body.set_rates(refs, rates)
                pending[i] = (angle, rate, end, mean)
            carried = [jj for jj in self.joints if jj.upper == i]
            for jj in carried:
                part = self._part(x, self._joint_index[jj.lower])
                n = jj.load_size
                w0 = jj.wrench(part[:n], jj.motion[3:12].reshape(3, 3))
                w1 = jj.wrench(part[n:2 * n], end_rotation[jj.lower])
                refs = self._flange_load(jj)
                body.set(refs, w0)
                body.set_rates(refs, (w1 - w0) / h)
            held = [(k, sl) for k, sl in enumerate(self.sliders) if sl.body == i]
            for k, sl in held:
                part = self._part(x, len(self.joints) + k)
                w1 = np.concatenate([sl.normals @ part, np.zeros(3)])
                refs = body.refs(sl.flange, WRENCH)
                body.set(refs, w1)
                body.set_rates(refs, np.zeros(6))
                pending_sliders[k] = w1[:3]
            if j is not None:
                reaction0 = body.get(self._mount_reaction(j))
            body.fmu.doStep(self.t, h)
            for k, sl in held:
                at = body.get(body.refs(sl.flange, ["r[1]", "r[2]", "r[3]"]))
                self._part(residual, len(self.joints) + k)[:] = sl.normals.T @ (at - sl.point)
            if j is not None:
                reaction1 = body.get(self._mount_reaction(j))
                k = self._joint_index[i]
                part = self._part(x, k)
                out = []
                r0, r1 = j.motion[3:12].reshape(3, 3), end_rotation[j.lower]
                if j.upper is not None:
                    n = j.load_size
                    out.append(j.wrench_residual(j.wrench(part[:n], r0), reaction0, r0))
                    out.append(j.wrench_residual(j.wrench(part[n:2 * n], r1), reaction1, r1))
                if j.revolute:
                    # the torque about the axis at the step's end, not the mean of both ends: that
                    # leaves the split between the ends free, and it rang at the step's Nyquist
                    # frequency until a double pendulum of stiff links diverged (t = 1.2 s)
                    out.append([j.axial_torque(reaction1, r1)])
                if out:
                    self._part(residual, k)[:] = np.concatenate(out)
            for jj in carried:
                end_flange[jj.lower] = body.get(self._flange_motion(jj))
        self._pending = [pending[j.lower] for j in self.joints]
        self._pending_sliders = pending_sliders
        return residual


def mount_motion(start: np.ndarray, end: np.ndarray, last_mean: np.ndarray | None, h: float):
    """A mount's inputs at the step's start and their rates over the step, from its flange's
    motion at both ends: pose and velocities linear; accelerations linear with mean
    (v1 - v0) / h, (w1 - w0) / h and slope the change of that mean since the last step (none
    on the first step, `last_mean` None). Returns (start values, rates, mean accelerations)."""
    mean = np.concatenate([(end[VELOCITY] - start[VELOCITY]) / h, (end[SPIN] - start[SPIN]) / h])
    slope = np.zeros(6) if last_mean is None else (mean - last_mean) / h
    values = start.copy()
    values[ACCELERATIONS] = mean - 0.5 * h * slope
    rates = np.zeros(24)
    rates[POSE_AND_VELOCITY] = (end[POSE_AND_VELOCITY] - start[POSE_AND_VELOCITY]) / h
    rates[ACCELERATIONS] = slope
    return values, rates, mean


def parse_start(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise SystemExit(f"--set {item!r}: expected NAME=VALUE")
        out[name] = float(value) if value not in ("true", "false") else value == "true"
    return out


def parse_axis(text: str) -> np.ndarray:
    named = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
    if text in named:
        return np.array(named[text])
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise SystemExit(f"axis {text!r}: expected x, y, z or three comma-separated numbers")
    return np.array(values)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("fmus", nargs="+", help="the bodies' FMUs, top of the chain first")
    p.add_argument("--flange", default="tip", help="the force flange that carries the next body")
    p.add_argument("--mount", default="base", help="the mount that hangs from the flange above")
    p.add_argument("--joint", default="weld", metavar="weld|AXIS",
                   help="the joints between bodies: welds, or revolute about AXIS (x, y, z or a,b,c in the mount's axes)")
    p.add_argument("--pivot", metavar="AXIS:DEGREES",
                   help="hang the first body from the ground by a revolute joint about AXIS (world), "
                        "turned by DEGREES from the world's axes; without it the first body's mount stays at its start values")
    p.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    p.add_argument("--stop", type=float, default=1.0, help="stop time [s]")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a start value for every body (e.g. g[3]=-9.81)")
    p.add_argument("--static", action="store_true",
                   help="start in static equilibrium (revolute joints' angles included: a pendulum starts hanging at rest)")
    p.add_argument("--output", default="tip.r[3]", help="the last body's output to print")
    p.add_argument("--csv", help="write time and the output at every step to this file")
    args = p.parse_args(argv)
    start = parse_start(args.set)
    bodies = [Body(f, f"body{i}", start) for i, f in enumerate(args.fmus)]
    n = len(bodies)
    axis = None if args.joint == "weld" else parse_axis(args.joint)
    joints = [Joint(i, i + 1, args.mount, args.flange, axis=axis) for i in range(n - 1)]
    if args.pivot:
        name, _, degrees = args.pivot.partition(":")
        try:
            angle = np.radians(float(degrees or 0.0))
        except ValueError:
            raise SystemExit(f"--pivot {args.pivot!r}: expected AXIS:DEGREES") from None
        joints.insert(0, Joint(None, 0, args.mount, axis=parse_axis(name), angle=angle))
    if not joints:
        raise SystemExit("one body and no --pivot: nothing to connect")
    chain = Chain(bodies, joints, args.step)
    chain.initialize(static=args.static)
    if args.static and any(j.revolute for j in joints):
        print("static start: revolute joints at " + ", ".join(f"{np.degrees(j.angle):.6g}" for j in joints if j.revolute)
              + " degrees")
    out_ref = bodies[-1].vr[args.output]
    rows = [(0.0, bodies[-1].get([out_ref])[0])]
    for _ in range(int(round(args.stop / args.step))):
        chain.step()
        rows.append((chain.t, bodies[-1].get([out_ref])[0]))
    values = np.array(rows)
    print(f"{n} bodies, h = {args.step:g} s, {len(rows) - 1} steps: {chain.evaluations / (len(rows) - 1):.2f} "
          f"retaken steps per step, {chain.jacobians} Jacobians")
    print(f"{args.output} of the last body: final {values[-1, 1]:.6g}, range [{values[:, 1].min():.6g}, "
          f"{values[:, 1].max():.6g}]")
    if args.csv:
        np.savetxt(args.csv, values, delimiter=",", header=f"time,{args.output}", comments="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
