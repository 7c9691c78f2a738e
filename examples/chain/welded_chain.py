"""A chain of flexible bodies, each an FMU of this builder, welded flange to mount and
co-simulated by a master that iterates on the joints.

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

Run: python examples/chain/welded_chain.py Link.fmu Link.fmu --step 1e-3 --stop 2
(see docs/CONNECTING.md)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field

import numpy as np
from fmpy import extract, read_model_description
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
    """Body `upper`'s force flange `flange` welded to body `upper + 1`'s mount `mount`."""

    upper: int
    flange: str
    mount: str
    # the flange's motion at the last communication point, and the mean accelerations of the
    # last step (the next step's slope is their change)
    motion: np.ndarray = field(default_factory=lambda: np.zeros(24))
    mean_acceleration: np.ndarray = field(default_factory=lambda: np.zeros(6))


class WeldedChain:
    """Bodies 0..n-1, body i's flange `flanges[i]` welded to body i+1's mount `mounts[i+1]`."""

    def __init__(self, bodies: list[Body], flanges: list[str], mounts: list[str], step: float):
        if len(bodies) < 2 or len(flanges) != len(bodies) - 1 or len(mounts) != len(bodies) - 1:
            raise ValueError("a chain needs n >= 2 bodies, n - 1 flanges and n - 1 mounts")
        if not step > 0:
            raise ValueError(f"the step must be positive, not {step}")
        self.bodies, self.h, self.t = bodies, float(step), 0.0
        self.joints = [Joint(i, f, m) for i, (f, m) in enumerate(zip(flanges, mounts))]
        self.evaluations = 0
        self.jacobians = 0
        self._jacobian: np.ndarray | None = None
        self._x: np.ndarray | None = None

    # -- references of each joint's variables
    def _flange_motion(self, j: Joint):
        return self.bodies[j.upper].refs(j.flange, MOTION)

    def _flange_load(self, j: Joint):
        return self.bodies[j.upper].refs(j.flange, WRENCH)

    def _mount_motion(self, j: Joint):
        return self.bodies[j.upper + 1].refs(j.mount, MOTION)

    def _mount_reaction(self, j: Joint):
        return self.bodies[j.upper + 1].refs(j.mount, WRENCH)

    def initialize(self, static: bool = False, static_rounds: int = 6):
        """Instantiate the bodies with each mount where its flange is, and solve the joints'
        algebraic loop at t = 0. `static`: every body starts in static equilibrium (its
        `static_start`) under the loads of the bodies below it, by `static_rounds` rounds of
        fixed point (the lower bodies' weight on the upper, the upper's deflection tilting the
        lower), 1e-12 apart after 6 on the examples."""
        loads = [np.zeros(6) for _ in self.joints]
        rounds = static_rounds if static else 1
        for _ in range(rounds):
            self._instantiate_all(loads, static)
            loads = [-self.bodies[j.upper + 1].get(self._mount_reaction(j)) for j in self.joints]
        if static:
            self._instantiate_all(loads, static)
        self._consistent_loads()
        for j in self.joints:
            j.motion = self.bodies[j.upper].get(self._flange_motion(j))
            j.mean_acceleration = j.motion[ACCELERATIONS].copy()
            self.bodies[j.upper + 1].set(self._mount_motion(j), j.motion)
        w = np.concatenate([self.bodies[j.upper].get(self._flange_load(j)) for j in self.joints])
        self._x = np.concatenate([np.concatenate([w[6 * k:6 * k + 6]] * 2) for k in range(len(self.joints))])

    def _instantiate_all(self, loads, static):
        for i, body in enumerate(self.bodies):
            inputs = {"static_start": True} if static else {}
            if i > 0:
                j = self.joints[i - 1]
                motion = self.bodies[j.upper].get(self._flange_motion(j))
                inputs.update({f"{j.mount}.{n}": v for n, v in zip(MOTION, motion)})
            if i < len(self.joints):
                j = self.joints[i]
                inputs.update({f"{j.flange}.{n}": v for n, v in zip(WRENCH, loads[i])})
            body.instantiate(inputs)

    def _consistent_loads(self):
        """Newton on W + reaction(W) = 0 at t = 0 through the feedthroughs (no step)."""
        def residual(w):
            r = np.zeros_like(w)
            for k, j in enumerate(self.joints):
                self.bodies[j.upper].set(self._flange_load(j), w[6 * k:6 * k + 6])
                motion = self.bodies[j.upper].get(self._flange_motion(j))
                self.bodies[j.upper + 1].set(self._mount_motion(j), motion)
            for k, j in enumerate(self.joints):
                r[6 * k:6 * k + 6] = w[6 * k:6 * k + 6] + self.bodies[j.upper + 1].get(self._mount_reaction(j))
            return r
        w = np.concatenate([self.bodies[j.upper].get(self._flange_load(j)) for j in self.joints])
        w = self._newton(residual, w, jacobian=None)[0]
        residual(w)

    def _newton(self, residual, x, jacobian):
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
                jacobian = self._finite_difference_jacobian(residual, x, r)
            last = size
            dx = -np.linalg.solve(jacobian, r)
            x = x + dx
            r_new = residual(x)
            jacobian = jacobian + np.outer(r_new - r - jacobian @ dx, dx) / (dx @ dx)
            r = r_new
        raise RuntimeError(f"t = {self.t:.6g} s: the joints did not converge in {MAX_ITERATIONS} "
                           f"iterations (largest force residual {np.abs(r).max():.3g})")

    def _finite_difference_jacobian(self, residual, x, r):
        self.jacobians += 1
        d = 1e-3 * max(1.0, np.abs(x).max())
        jac = np.zeros((len(r), len(x)))
        for c in range(len(x)):
            e = np.zeros(len(x))
            e[c] = d
            jac[:, c] = (residual(x + e) - r) / d
        return jac

    def step(self):
        """One communication step of h: every body retaken until the joints agree."""
        states = [b.fmu.getFMUstate() for b in self.bodies]
        try:
            # Newton's last residual is the step at the solution: the bodies are there already
            self._x, self._jacobian = self._newton(lambda x: self._retake(states, x), self._x, self._jacobian)
            for j, (motion, mean) in zip(self.joints, self._pending):
                j.motion, j.mean_acceleration = motion, mean
        finally:
            for b, s in zip(self.bodies, states):
                b.fmu.freeFMUstate(s)
        self.t += self.h
        # the next step's start wrench is this one's end; its end extrapolated
        x = self._x.reshape(-1, 2, 6)
        self._x = np.stack([x[:, 1], 2 * x[:, 1] - x[:, 0]], axis=1).reshape(-1)

    def _retake(self, states, x) -> np.ndarray:
        """The step from `states` with the joint wrenches `x` (per joint: start, end): the
        residuals W + reaction at both ends."""
        self.evaluations += 1
        h = self.h
        residual = np.zeros_like(x)
        end_motion = [None] * len(self.joints)
        means = [None] * len(self.joints)
        for i, body in enumerate(self.bodies):
            body.fmu.setFMUstate(states[i])
            if i > 0:
                k = i - 1
                j = self.joints[k]
                refs = self._mount_motion(j)
                start, rates, means[k] = mount_motion(j.motion, end_motion[k], j.mean_acceleration, h)
                body.set(refs, start)
                body.set_rates(refs, rates)
            if i < len(self.joints):
                w = x[12 * i:12 * i + 12]
                refs = self._flange_load(self.joints[i])
                body.set(refs, w[:6])
                body.set_rates(refs, (w[6:] - w[:6]) / h)
            if i > 0:
                residual[12 * (i - 1):12 * (i - 1) + 6] = x[12 * (i - 1):12 * (i - 1) + 6] + \
                    body.get(self._mount_reaction(self.joints[i - 1]))
            body.fmu.doStep(self.t, h)
            if i > 0:
                residual[12 * (i - 1) + 6:12 * i] = x[12 * (i - 1) + 6:12 * i] + \
                    body.get(self._mount_reaction(self.joints[i - 1]))
            if i < len(self.joints):
                end_motion[i] = body.get(self._flange_motion(self.joints[i]))
        self._pending = list(zip(end_motion, means))
        return residual


def mount_motion(start: np.ndarray, end: np.ndarray, last_mean: np.ndarray, h: float):
    """A mount's inputs at the step's start and their rates over the step, from its flange's
    motion at both ends: pose and velocities linear; accelerations linear with mean
    (v1 - v0) / h, (w1 - w0) / h and slope the change of that mean since the last step.
    Returns (start values, rates, mean accelerations)."""
    mean = np.concatenate([(end[VELOCITY] - start[VELOCITY]) / h, (end[SPIN] - start[SPIN]) / h])
    slope = (mean - last_mean) / h
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("fmus", nargs="+", help="the bodies' FMUs, top of the chain first")
    p.add_argument("--flange", default="tip", help="the force flange that carries the next body")
    p.add_argument("--mount", default="base", help="the mount that hangs from the flange above")
    p.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    p.add_argument("--stop", type=float, default=1.0, help="stop time [s]")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="a start value for every body (e.g. g[3]=-9.81)")
    p.add_argument("--static", action="store_true", help="start in static equilibrium")
    p.add_argument("--output", default="tip.r[3]", help="the last body's output to print")
    p.add_argument("--csv", help="write time and the output at every step to this file")
    args = p.parse_args(argv)
    start = parse_start(args.set)
    bodies = [Body(f, f"body{i}", start) for i, f in enumerate(args.fmus)]
    n = len(bodies)
    chain = WeldedChain(bodies, [args.flange] * (n - 1), [args.mount] * (n - 1), args.step)
    chain.initialize(static=args.static)
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
