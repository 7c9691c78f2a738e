"""Model Exchange as hosts run it at their defaults, for the tests and the benchmark: the
examples' scenes (a force from t = 0, gravity, the T-square's mount spinning from an R(t), w(t)
table plus a force), the hosts (FMPy's `simulate_fmu` with nothing but start values, at the
FMU's DefaultExperiment or a given stop time and tolerance; SciPy's BDF and Radau through FMPy's
low-level API; a fixed-step explicit Euler loop as the FMI Compliance Checker runs it), and
their reference: the Co-Simulation of the same FMU, whose step is exact for held inputs.

Errors are max |ME - CS| over the run relative to the swing of the output's vector (the largest
swing of the three components of tip.u, base.f, ...)."""

import ctypes
import json
import time
from pathlib import Path

import numpy as np
from fmpy import read_model_description, simulate_fmu
from scipy.integrate import solve_ivp

from conftest import EXAMPLES, run_builder
from fmu_access import Fmu

# example: (input file, force flange, force input, magnitude [N])
EXAMPLES_ME = {
    "beam": ("beam.json", "tip", "tip.f[3]", 100.0),
    "l-beam": ("l-beam.json", "tip", "tip.f[3]", 1.0),
    "t-square": ("t-square.json", "left", "left.f[3]", 10.0),
    "bracket": ("bracket/bracket.json", "arm", "arm.f[1]", 200.0),
    "bracket-band": ("bracket/bracket-band.json", "arm", "arm.f[1]", 200.0),
    "bracket-inp": ("bracket/bracket-inp.json", "arm", "arm.f[1]", 200.0),
}

# the spinning mount: 20 rad/s about z, from a table FMPy interpolates linearly (between its
# rows R(t) is no rotation), at the rows' spacing
SPIN = 20.0
SPIN_TABLE_STEP = 1e-3


def build(name, out_dir, **reduction):
    """The example's FMU; `reduction` fields (dynamic_cutoff, ...) override the input's."""
    source = EXAMPLES / EXAMPLES_ME[name][0]
    spec = json.loads(source.read_text())
    spec.pop("$schema", None)
    if "mesh" in spec["geometry"]:
        spec["geometry"]["mesh"] = str(source.parent / spec["geometry"]["mesh"])
    spec["reduction"].update(reduction)
    tag = name + "".join(f"-{k}{v}" for k, v in reduction.items())
    path = Path(out_dir) / f"{tag}.json"
    path.write_text(json.dumps(spec))
    fmu = Path(out_dir) / f"{tag}.fmu"
    run_builder([path, "-o", fmu])
    return fmu


def loads(name, md):
    """The scenes of an example: {scene: (start values, input table or None)}. Gravity where the
    mount is fixed (the spinning T-square turns it); the T-square spinning with a force."""
    _, flange, force, magnitude = EXAMPLES_ME[name]
    names = {v.name for v in md.modelVariables}
    out = {"force step": ({force: magnitude}, None)}
    if "g[3]" in names:
        out["gravity"] = ({"g[3]": -9.81}, None)
    if name == "t-square":
        out["spinning mount and force"] = ({force: magnitude}, "spin")
    return out


def spin_table(stop, md, start):
    """Rows of (time, every real input): the mount turning at SPIN about z from t = 0, the
    other inputs held at their start values (FMPy warns of inputs a table leaves out)."""
    t = np.arange(0.0, stop + SPIN_TABLE_STEP, SPIN_TABLE_STEP)
    names = [v.name for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    rows = np.zeros(len(t), dtype=[("time", float)] + [(n, float) for n in names])
    rows["time"] = t
    for v in md.modelVariables:
        if v.name in names:
            rows[v.name] = start.get(v.name, float(v.start or 0.0))
    c, s = np.cos(SPIN * t), np.sin(SPIN * t)
    rows["base.R[1,1]"], rows["base.R[1,2]"] = c, -s
    rows["base.R[2,1]"], rows["base.R[2,2]"] = s, c
    rows["base.R[3,3]"] = 1.0
    rows["base.w[3]"] = SPIN
    return rows


def spin_inputs(t):
    c, s = np.cos(SPIN * t), np.sin(SPIN * t)
    return {"base.R[1,1]": c, "base.R[1,2]": -s, "base.R[2,1]": s, "base.R[2,2]": c, "base.R[3,3]": 1.0,
            "base.w[3]": SPIN}


def outputs_of(md, flange):
    """The outputs that carry the deformation and the motion: the force flange's u, phi, v, w,
    and where the body has a mount its reaction f, t."""
    names = {v.name for v in md.modelVariables if v.causality == "output"}
    wanted = [f"{flange}.{q}[{i}]" for q in ("u", "phi", "r", "v", "w") for i in (1, 2, 3)]
    wanted += [f"base.{q}[{i}]" for q in ("f", "t") for i in (1, 2, 3)]
    return [n for n in wanted if n in names]


def relative_errors(outputs, me, cs):
    """{output: max |ME - CS| / swing of its vector}, for the vectors that move."""
    assert me.shape == cs.shape and me.shape[1] == len(outputs), (me.shape, cs.shape, len(outputs))
    swing = np.max(cs, axis=0) - np.min(cs, axis=0)
    groups = {}
    for j, name in enumerate(outputs):
        groups.setdefault(name.split("[")[0], []).append(j)
    errors = {}
    for cols in groups.values():
        peak = swing[cols].max()
        if peak <= 1e-14:
            continue
        for j in cols:
            errors[outputs[j]] = float(np.max(np.abs(me[:, j] - cs[:, j])) / peak)
    return errors


def initialized(f, start, table):
    """Fmu `f` with its start values (and the spinning mount's pose at t = 0), initialised."""
    f.set(**start)
    if table is not None:
        f.set(**spin_inputs(0.0))
    f.fmu.setupExperiment(startTime=0.0)
    f.fmu.enterInitializationMode()
    f.fmu.exitInitializationMode()
    return f


def cs_reference(path, start, table, outputs, grid, h):
    """Co-Simulation of the same FMU on `grid` (multiples of h): exact for held inputs; the
    spinning mount's pose and rate are given with their derivatives over each step."""
    f = Fmu(path, "CoSimulation")
    try:
        initialized(f, start, table)
        out = [f.get(*outputs)]
        n = int(round(grid[-1] / h))
        every = int(round((grid[1] - grid[0]) / h))
        for k in range(n):
            t = k * h
            if table is not None:
                now = spin_inputs(t)
                f.set(**now)
                rates = {"base.R[1,1]": -SPIN * now["base.R[2,1]"], "base.R[1,2]": -SPIN * now["base.R[1,1]"],
                         "base.R[2,1]": SPIN * now["base.R[1,1]"], "base.R[2,2]": -SPIN * now["base.R[2,1]"]}
                f.fmu.setRealInputDerivatives([f.vr[n] for n in rates], [1] * len(rates), list(rates.values()))
            f.fmu.doStep(t, h)
            if (k + 1) % every == 0:
                out.append(f.get(*outputs))
        return np.array(out)
    finally:
        f.close()


class Messages:
    """The FMU's log, as a host shows it."""

    def __init__(self):
        self.lines = []

    def __call__(self, component, instance, status, category, message):
        self.lines.append((status, category.decode(), message.decode()))


def fmpy_me(path, start, table, outputs, stop_time=None, relative_tolerance=None, solver="CVode",
            output_interval=None):
    """FMPy's simulate_fmu, Model Exchange, nothing but start values (and the spin table)."""
    log = Messages()
    t0 = time.perf_counter()
    kwargs = {}
    if table is not None:
        md = read_model_description(path)
        stop = stop_time if stop_time is not None else float(md.defaultExperiment.stopTime)
        kwargs["input"] = spin_table(stop, md, start)
    result = simulate_fmu(path, fmi_type="ModelExchange", start_values=start, output=outputs,
                          stop_time=stop_time, relative_tolerance=relative_tolerance, solver=solver,
                          output_interval=output_interval, logger=log, debug_logging=False, **kwargs)
    wall = time.perf_counter() - t0
    return result, wall, log


def _ptr(x):
    return x.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def scipy_me(path, start, table, outputs, grid, rtol, method):
    """SciPy's BDF or Radau on the FMU through FMPy's low-level API, atol = rtol x nominal, the
    inputs applied at every right-hand side; returns outputs on `grid` and derivative calls."""
    f = Fmu(path, "ModelExchange")
    try:
        initialized(f, start, table)
        f.fmu.newDiscreteStates()
        f.fmu.enterContinuousTimeMode()
        x0 = f.states()
        nom = np.zeros(f.nx)
        f.fmu.getNominalsOfContinuousStates(_ptr(nom), f.nx)

        def rhs(t, x):
            f.fmu.setTime(t)
            if table is not None:
                f.set(**spin_inputs(t))
            f.set_states(x)
            return f.derivatives()

        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (grid[0], grid[-1]), x0, method=method, rtol=rtol, atol=rtol * nom, t_eval=grid,
                        max_step=(grid[-1] - grid[0]) / 50)
        wall = time.perf_counter() - t0
        if not sol.success:
            raise RuntimeError(sol.message)
        out = []
        for k, t in enumerate(sol.t):
            f.fmu.setTime(t)
            if table is not None:
                f.set(**spin_inputs(t))
            f.set_states(sol.y[:, k])
            out.append(f.get(*outputs))
        return np.array(out), sol.nfev, wall
    finally:
        f.close()


def cvode_oscillator_floor(frequency, stop, rtol, intervals=500):
    """The error FMPy's own CVode makes on the best-posed undamped mode there is: one exact
    two-state oscillator x'' = w^2 (1 - x) from rest (a unit step load), nominals 1e-3 and
    1e-3 w as the FMU's, output every stop/500 as `simulate_fmu` samples; returns the worst
    velocity error over the run / its swing 2w, against the closed form w sin(wt). Nothing of
    the FMU is in it: it is the host's floor for an undamped mode at that frequency."""
    from fmpy.sundials import CVodeSolver
    w = 2.0 * np.pi * frequency
    state = {"x": np.zeros(2)}

    def view(p, n):
        return np.ctypeslib.as_array(p, (n,))

    def get_x(p, n):
        view(p, n)[:] = state["x"]

    def set_x(p, n):
        state["x"] = view(p, n).copy()

    def get_dx(p, n):
        x, v = state["x"]
        view(p, n)[:] = (v, w * w * (1.0 - x))

    def nominals(p, n):
        view(p, n)[:] = (1e-3, 1e-3 * w)

    class NoInputs:
        def apply(self, t):
            pass

    solver = CVodeSolver(2, 0, get_x, set_x, get_dx, lambda p, n: None, nominals, lambda t: None, NoInputs(),
                         0.0, maxStep=stop / 50.0, relativeTolerance=rtol)
    worst = 0.0
    for k in range(1, intervals + 1):
        _, _, t = solver.step(0.0, k * stop / intervals)
        worst = max(worst, abs(state["x"][1] - w * np.sin(w * t)))
    return worst / (2.0 * w)
