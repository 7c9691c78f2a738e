"""CalculiX (ccx) as an independent reference on exactly the builder's mesh.

`fmu-builder --export-inp deck.inp` writes the model data of the flanged mesh (nodes, C3D20 or
C3D8 elements in set EALL, per flange the slave set NAME and one-node sets NAME_REF and
NAME_ROT at the flange's reference point, material MAT). This module appends the analysis to
that deck, runs `ccx` and reads the printed results back:

    deck = Path("beam.inp").read_text()
    analysis = (rigid_body(deck, "base") + rigid_body(deck, "tip") + clamp(deck, "base")
                + static_step(cload(deck, "tip", force=(0, 0, 1e-4)), prints=["TIP_REF", "TIP_ROT"]))
    result = run_ccx(deck, analysis, workdir)
    u_tip = result.u(set_node(deck, "TIP_REF"))

Conventions (CalculiX 2.20, docs/REFERENCES.md section 3): `*RIGID BODY` ties a flange's slave nodes
rigidly to its reference node (translations = DoFs 1-3) and rotation node (small rotations =
DoFs 1-3), i.e. the same rigid coupling as the builder's flanges. Forces go on the reference
node, moments on the rotation node; `*NODE PRINT` with U prints both. Results in the .dat file
carry 7 significant digits (e13.6 / e14.7), so comparisons cannot be tighter than ~5e-7.

CalculiX is required, not optional: the project's tests install it (`apt-get install -y
calculix-ccx`), so a missing `ccx` is an error (CcxError), never a skip.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: CalculiX executable; override with the environment variable CCX.
CCX = os.environ.get("CCX", "ccx")

#: CalculiX reads every number of a data line from its first 20 characters (Fortran f20.0).
FIELD_WIDTH = 20


class CcxError(RuntimeError):
    """CalculiX is missing, failed, timed out, or printed something we cannot read."""


def ccx_executable() -> str:
    """Path of the ccx executable, or CcxError with how to install it."""
    path = shutil.which(CCX)
    if path is None:
        raise CcxError(
            f"CalculiX executable '{CCX}' not found on PATH. The CalculiX reference tests require it: "
            "install it with `apt-get install -y calculix-ccx` (Debian/Ubuntu, version 2.20), "
            "or point the environment variable CCX at a ccx binary.")
    return path


# --------------------------------------------------------------------------------------------
# The model deck


_REAL = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+)[eE][-+]?\d+(?![\w.])")


def fit_field(token: str) -> str:
    """`token` as a real of at most FIELD_WIDTH characters, exactly the same double if possible.

    Python's repr is the shortest string that reads back as the same double; only when even
    that is too long (it has 17 significant digits and a 3-character exponent) do we round, to
    the most digits that fit (>= 14 significant digits, relative change < 5e-15)."""
    if len(token) <= FIELD_WIDTH:
        return token
    x = float(token)
    text = repr(x)
    if len(text) <= FIELD_WIDTH:
        return text
    for digits in range(16, 0, -1):
        mantissa, exponent = f"{x:.{digits}e}".split("e")
        text = f"{mantissa}e{int(exponent)}"
        if len(text) <= FIELD_WIDTH:
            return text
    raise CcxError(f"cannot write {token} in {FIELD_WIDTH} characters")


def ccx_readable(deck: str) -> str:
    """The deck with every real number shortened to CalculiX's 20-character field width.

    The builder writes reals as `{:.17e}` (e.g. `-5.00000000000000010e-3`, 23 characters);
    CalculiX 2.20 reads only the first 20 characters of a field and stops with
    "*ERROR reading *NODE". The shortest round-trip form of the same double fits in almost
    every case, so the mesh CalculiX reads is bit-for-bit the builder's."""
    return _REAL.sub(lambda m: fit_field(m.group(0)), deck)


def _blocks(deck: str):
    """(keyword line, [data lines]) for every keyword of the deck, comments dropped."""
    blocks, current = [], None
    for line in deck.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("**"):
            continue
        if stripped.startswith("*"):
            current = (stripped, [])
            blocks.append(current)
        elif current is not None:
            current[1].append(stripped)
    return blocks


def _params(keyword_line: str) -> dict:
    parts = [p.strip() for p in keyword_line.split(",")]
    params = {"": parts[0].upper()}
    for p in parts[1:]:
        key, _, value = p.partition("=")
        params[key.strip().upper()] = value.strip()
    return params


def node_set(deck: str, name: str) -> list[int]:
    """Node ids of the set `name` (case-insensitive, as CalculiX) defined by *NSET in the deck."""
    ids = []
    found = False
    for keyword, lines in _blocks(deck):
        p = _params(keyword)
        if p[""] == "*NSET" and p.get("NSET", "").upper() == name.upper():
            found = True
            ids += [int(t) for line in lines for t in line.split(",") if t.strip()]
    if not found:
        raise CcxError(f"no node set {name.upper()} in the deck")
    return ids


def set_node(deck: str, name: str) -> int:
    """The single node of a one-node set (a flange's NAME_REF or NAME_ROT)."""
    ids = node_set(deck, name)
    if len(ids) != 1:
        raise CcxError(f"node set {name.upper()} has {len(ids)} nodes, expected one")
    return ids[0]


def node_coordinates(deck: str) -> dict[int, np.ndarray]:
    """{node id: (x, y, z)} of every *NODE block of the deck."""
    coords = {}
    for keyword, lines in _blocks(deck):
        if _params(keyword)[""] == "*NODE":
            for line in lines:
                t = [s for s in line.split(",") if s.strip()]
                coords[int(t[0])] = np.array([float(s) for s in t[1:4]])
    return coords


def reference_point(deck: str, flange: str) -> np.ndarray:
    """Coordinates of a flange's reference node (its reference point)."""
    return node_coordinates(deck)[set_node(deck, f"{flange}_REF")]


# --------------------------------------------------------------------------------------------
# Pieces of the analysis (each returns deck text ending in a newline)


def rigid_body(deck: str, flange: str) -> str:
    """`*RIGID BODY` tying the flange's slave set to its reference and rotation nodes."""
    name = flange.upper()
    ref, rot = set_node(deck, f"{name}_REF"), set_node(deck, f"{name}_ROT")
    return f"*RIGID BODY, NSET={name}, REF NODE={ref}, ROT NODE={rot}\n"


def clamp(deck: str, flange: str) -> str:
    """`*BOUNDARY` fixing the flange's reference and rotation nodes (DoFs 1-3 each): together with
    its rigid body, the flange is clamped (model data: put it before the step)."""
    name = flange.upper()
    ref, rot = set_node(deck, f"{name}_REF"), set_node(deck, f"{name}_ROT")
    return f"*BOUNDARY\n{ref}, 1, 3\n{rot}, 1, 3\n"


def cload(deck: str, flange: str, force=(0.0, 0.0, 0.0), moment=(0.0, 0.0, 0.0)) -> str:
    """`*CLOAD`: force [N] on the flange's reference node, moment [N m] (about its reference
    point) on its rotation node, global axes. Zero components are left out."""
    name = flange.upper()
    ref, rot = set_node(deck, f"{name}_REF"), set_node(deck, f"{name}_ROT")
    lines = [f"{ref}, {i + 1}, {fit_field(repr(float(v)))}" for i, v in enumerate(force) if v != 0.0]
    lines += [f"{rot}, {i + 1}, {fit_field(repr(float(v)))}" for i, v in enumerate(moment) if v != 0.0]
    if not lines:
        raise ValueError("cload without a non-zero component")
    return "*CLOAD\n" + "\n".join(lines) + "\n"


def _unit(direction) -> np.ndarray:
    n = np.asarray(direction, dtype=float)
    norm = np.linalg.norm(n)
    if not norm > 0:
        raise ValueError(f"direction {direction} has no length")
    return n / norm


def _short(v) -> str:
    """15 significant digits (relative change < 5e-16): keeps a *DLOAD line of seven reals well
    inside the 132 characters an input line may safely have."""
    return f"{float(v):.15g}"


def centrif(omega: float, point, axis, elset: str = "EALL") -> str:
    """`*DLOAD ..., CENTRIF`: centrifugal body force of a spin `omega` [rad/s] about the axis
    through `point` along `axis` (normalised here). Linear: no spin softening, no stress
    stiffening."""
    n = _unit(axis)
    values = [omega**2, *map(float, point), *n]
    return f"*DLOAD\n{elset}, CENTRIF, " + ", ".join(_short(v) for v in values) + "\n"


def gravity(g: float, direction, elset: str = "EALL") -> str:
    """`*DLOAD ..., GRAV`: acceleration of gravity of magnitude `g` [m/s^2] along `direction`
    (normalised here)."""
    n = _unit(direction)
    return f"*DLOAD\n{elset}, GRAV, {_short(g)}, " + ", ".join(_short(v) for v in n) + "\n"


def node_print(*sets: str, what: str = "U") -> str:
    """`*NODE PRINT` of `what` (U: displacements, RF: reaction forces) for each node set."""
    return "".join(f"*NODE PRINT, NSET={s.upper()}\n{what}\n" for s in sets)


def static_step(*loads: str, prints=(), reactions=()) -> str:
    """A linear `*STATIC` step with the given load cards, printing U of the sets in `prints`
    and RF of the sets in `reactions`."""
    return ("*STEP\n*STATIC\n" + "".join(loads) + node_print(*prints)
            + (node_print(*reactions, what="RF") if reactions else "") + "*END STEP\n")


def frequency_step(modes: int, shift_hz: float | None = None) -> str:
    """A `*FREQUENCY` step for the `modes` lowest eigenmodes (eigenvalue table in the .dat).

    `shift_hz`: CalculiX's lower frequency bound, also its shift (2 pi f)^2: a free-free part's
    stiffness is singular, and without a shift its elastic eigenvalues come out of ARPACK
    perturbed by the rigid-body ones (measured up to 2e-6)."""
    bound = "" if shift_hz is None else f", {float(shift_hz)!r}"
    return f"*STEP\n*FREQUENCY\n{int(modes)}{bound}\n*END STEP\n"


# --------------------------------------------------------------------------------------------
# Running and reading


@dataclass
class CcxResult:
    """What CalculiX printed into the .dat file, plus where to look when something is odd."""
    displacements: dict = field(default_factory=dict)  #: {node: array(ux, uy, uz)} (rot nodes: rotations)
    forces: dict = field(default_factory=dict)  #: {node: array(fx, fy, fz)} reaction forces (RF)
    frequencies_hz: list = field(default_factory=list)  #: CYCLES/TIME column of *FREQUENCY, ascending
    eigenvalues: list = field(default_factory=list)  #: omega^2 column of *FREQUENCY
    workdir: Path | None = None
    dat: str = ""
    log: str = ""

    def u(self, node: int) -> np.ndarray:
        """Printed displacement (or rotation, for a rotation node) of one node."""
        if node not in self.displacements:
            raise CcxError(f"node {node} has no printed displacement (missing *NODE PRINT?) in {self.workdir}")
        return self.displacements[node]


def _real(token: str) -> float:
    # Fortran drops the E of three-digit exponents: 0.1234567-100
    return float(re.sub(r"(\d)([-+]\d{3})$", r"\1E\2", token))


def parse_dat(text: str) -> CcxResult:
    """Node displacements, reaction forces and the eigenvalue table from a .dat file's text.
    A later block for the same node overrides an earlier one (last increment wins)."""
    result = CcxResult(dat=text)
    target = None
    in_eigen = False
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("displacements (vx,vy,vz)"):
            target, in_eigen = result.displacements, False
            continue
        if stripped.startswith("forces (fx,fy,fz)"):
            target, in_eigen = result.forces, False
            continue
        if stripped.replace(" ", "") == "EIGENVALUEOUTPUT":
            target, in_eigen = None, True
            result.frequencies_hz.clear()
            result.eigenvalues.clear()
            continue
        tokens = stripped.split()
        if in_eigen:
            if len(tokens) == 5 and tokens[0].isdigit():
                result.eigenvalues.append(_real(tokens[1]))
                result.frequencies_hz.append(_real(tokens[3]))
                continue
            if tokens[0] in ("MODE", "REAL", "(RAD/TIME)"):
                continue
            in_eigen = False
        if target is not None and len(tokens) == 4 and tokens[0].isdigit():
            target[int(tokens[0])] = np.array([_real(t) for t in tokens[1:]])
            continue
        target = None
    return result


def run_ccx(model_deck: str, step: str, workdir, job: str = "job", timeout: float = 300) -> CcxResult:
    """Append `step` (rigid bodies, boundaries and the *STEP ... *END STEP block) to the model
    deck, run `ccx -i job` in `workdir` and return the parsed .dat file.

    Raises CcxError if ccx is missing, exits non-zero, reports an *ERROR, times out or writes no
    .dat file; the message carries the tail of ccx's output and the path of the input deck.
    One thread (OMP_NUM_THREADS=1) keeps results reproducible to the last digit."""
    exe = ccx_executable()
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    inp = workdir / f"{job}.inp"
    inp.write_text(ccx_readable(model_deck).rstrip("\n") + "\n" + step)
    dat = workdir / f"{job}.dat"
    if dat.exists():
        dat.unlink()
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_EQUATION_SOLVER="1")
    try:
        proc = subprocess.run([exe, "-i", job], cwd=workdir, capture_output=True, text=True,
                              timeout=timeout, env=env)
    except subprocess.TimeoutExpired as e:
        raise CcxError(f"ccx timed out after {timeout} s on {inp}:\n{(e.stdout or '')[-3000:]}") from e
    log = proc.stdout + proc.stderr
    errors = [line.strip() for line in log.splitlines() if "*ERROR" in line]
    if proc.returncode != 0 or errors or not dat.exists():
        raise CcxError(f"ccx failed (exit code {proc.returncode}) on {inp}:\n"
                       + ("\n".join(errors[:20]) + "\n...\n" if errors else "") + log[-3000:])
    result = parse_dat(dat.read_text())
    result.workdir, result.log = workdir, log
    return result


# --------------------------------------------------------------------------------------------
# Reference solutions used by several tests


TSQUARE_OMEGA = 2 * math.pi * math.sqrt(3)  # sqrt(3) * 60 rpm [rad/s]
TSQUARE_AXIS = np.ones(3) / math.sqrt(3)


def tsquare_centrifugal_reference(tmpdir, axis=TSQUARE_AXIS, omega=TSQUARE_OMEGA) -> dict:
    """Paper example 3 in CalculiX: examples/t-square.json meshed by the builder, flange `base`
    clamped (rigid body with fixed reference and rotation nodes), flanges `left` and `right`
    rigid and free, linear static centrifugal load of a spin `omega` (default 2 pi sqrt(3)
    rad/s, i.e. omega = 2 pi (1, 1, 1)) about the axis through base's reference point along
    `axis` (default (1, 1, 1)/sqrt(3)).

    Returns a dict:
      "left", "right": {"u": displacement of the flange's reference node [m], "phi": its
          rotation (the rotation node's U) [rad]}, global axes = the FMU's body frame (axes of
          the undeformed part; origin at base's reference point, which does not move);
      "base_reaction": force the clamp exerts on the body (RF of BASE_REF) [N];
      "omega", "axis", "point": the spin; "deck": the exported deck; "fmu": path of the FMU the
          same builder run wrote (for comparisons against it).
    Linear statics: no spin softening and no stress stiffening (relative size (omega /
    omega_1)^2 ~ 5e-5 for this part, first clamped mode 242 Hz). Results carry CalculiX's 7
    printed digits."""
    from conftest import EXAMPLES, run_builder  # the tests' builder runner

    tmpdir = Path(tmpdir)
    tmpdir.mkdir(parents=True, exist_ok=True)
    inp = tmpdir / "t-square.inp"
    run_builder([EXAMPLES / "t-square.json", "-o", tmpdir / "t-square.fmu", "--export-inp", inp, "-q"])
    deck = inp.read_text()
    point = reference_point(deck, "base")
    analysis = (rigid_body(deck, "base") + rigid_body(deck, "left") + rigid_body(deck, "right")
                + clamp(deck, "base")
                + static_step(centrif(omega, point, axis),
                              prints=["LEFT_REF", "LEFT_ROT", "RIGHT_REF", "RIGHT_ROT"],
                              reactions=["BASE_REF"]))
    result = run_ccx(deck, analysis, tmpdir / "ccx")
    out = {"omega": omega, "axis": _unit(axis), "point": point, "deck": deck,
           "fmu": tmpdir / "t-square.fmu", "base_reaction": result.forces[set_node(deck, "BASE_REF")]}
    for flange in ["left", "right"]:
        out[flange] = {"u": result.u(set_node(deck, f"{flange}_REF")),
                       "phi": result.u(set_node(deck, f"{flange}_ROT"))}
    return out
