"""A slider-crank with a flexible connecting rod: a crank of radius r on the ground, driven
about the world y axis and spun up smoothly from rest to a constant speed, carries the rod's
mount at its pin through a revolute joint about y; the rod's tip flange runs on a frictionless,
massless slider along the world x axis through the crank's centre. The rod is an FMU of this
builder (its mount `base`, its force flange `tip`), co-simulated by chain_master.py's iterating
master: the rod's angle at the pin (a revolute joint on a moving ground frame, the crank pin's)
and the slider's normal load are solved at every step, so that the pin carries no torque about
its axis and the rod's tip stays on the line. The mechanism starts at rest in static equilibrium
(the rod sagging between pin and slider).

Run: python examples/chain/slider_crank.py Link.fmu --length 1 --radius 0.2 --stop 6
(see docs/CONNECTING.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import chain_master as cm  # noqa: E402

Y = np.array([0.0, 1.0, 0.0])


class Crank:
    """The crank's angle about y from rest: speed (1 - cos(pi t / spin_up)) / 2 of `speed`
    over the spin-up (no jerk at its start), then constant."""

    def __init__(self, radius: float, speed: float, spin_up: float):
        if not radius > 0 or not spin_up > 0:
            raise ValueError("the crank's radius and spin-up time must be positive")
        self.radius, self.speed, self.spin_up = radius, speed, spin_up

    def angle(self, t):
        """Angle, rate and acceleration at times `t` (arrays or floats)."""
        t = np.asarray(t, dtype=float)
        w, tr = self.speed, self.spin_up
        ramp = t < tr
        phi = np.where(ramp, w / 2 * (t - tr / np.pi * np.sin(np.pi * t / tr)), w / 2 * tr + w * (t - tr))
        rate = np.where(ramp, w / 2 * (1 - np.cos(np.pi * t / tr)), w)
        acceleration = np.where(ramp, w * np.pi / (2 * tr) * np.sin(np.pi * t / tr), 0.0)
        return phi, rate, acceleration

    def pin(self, t: float) -> np.ndarray:
        """The crank pin's frame (the crank's axes) at time t, 24 values in chain_master's
        MOTION order."""
        phi, rate, acceleration = (float(v) for v in self.angle(t))
        rotation = cm.rotation(Y, phi)
        p = rotation @ np.array([self.radius, 0.0, 0.0])
        v = rate * np.cross(Y, p)
        a = acceleration * np.cross(Y, p) - rate ** 2 * p
        return np.concatenate([p, rotation.ravel(), v, rate * Y, a, acceleration * Y])


def slider_crank(rod_fmu: str, crank: Crank, step: float = 1e-3, start: dict | None = None):
    """The rod's body, the master and the slider, initialised at rest in static equilibrium."""
    rod = cm.Body(rod_fmu, "rod", {"g[3]": -9.81, **(start or {})})
    pin = cm.Joint(None, 0, "base", axis=Y, angle=0.0, rate=0.0, ground=crank.pin)
    slider = cm.Slider(0, "tip", [0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    chain = cm.Chain([rod], [pin], step, sliders=[slider])
    chain.initialize(static=True)
    return chain, rod, slider


def run(rod_fmu: str, crank: Crank, seconds: float, step: float = 1e-3, start: dict | None = None):
    """Times, slider position (the rod tip's x, z) and the slider's normal load on the rod (z)
    at every communication point after t = 0; the load is held over each step, so it is the
    step's mean (compare it with a reference at the step's midpoint)."""
    chain, rod, slider = slider_crank(rod_fmu, crank, step, start)
    tip = rod.refs("tip", ["r[1]", "r[3]"])
    rows = []
    for _ in range(int(round(seconds / step))):
        chain.step()
        rows.append([chain.t, *rod.get(tip), slider.load[2]])
    return np.array(rows), chain


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("rod", help="the connecting rod's FMU (mount `base` at the crank pin, force flange `tip` on the slider)")
    p.add_argument("--length", type=float, required=True, help="the rod's length between its flanges [m]")
    p.add_argument("--radius", type=float, default=0.2, help="crank radius [m]")
    p.add_argument("--speed", type=float, default=1.0, help="crank speed after the spin-up [rev/s]")
    p.add_argument("--spin-up", type=float, default=1.0, help="spin-up time [s]")
    p.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    p.add_argument("--stop", type=float, default=6.0, help="stop time [s]")
    p.add_argument("--csv", help="write time, slider x, rod tip z and the slider's load at every step")
    args = p.parse_args(argv)
    if not args.radius < args.length:
        raise SystemExit(f"the crank radius ({args.radius} m) must be shorter than the rod ({args.length} m)")
    rows, chain = run(args.rod, Crank(args.radius, 2 * np.pi * args.speed, args.spin_up), args.stop, args.step)
    print(f"{len(rows)} steps: {chain.evaluations / len(rows):.2f} retaken steps per step, {chain.jacobians} Jacobians")
    print(f"slider x in [{rows[:, 1].min():.6g}, {rows[:, 1].max():.6g}] m, rod tip off the line by at most "
          f"{np.abs(rows[:, 2]).max():.3g} m, slider load in [{rows[:, 3].min():.6g}, {rows[:, 3].max():.6g}] N")
    if args.csv:
        np.savetxt(args.csv, rows, delimiter=",", header="time,slider_x,tip_z,slider_load_z", comments="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
