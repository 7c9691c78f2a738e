"""The flexible double pendulum (examples/assemblies/double_pendulum.json) as the other masters
and solvers of the repository's tests run it, timed, for fmu-bench's assembly section
(bench/src/assembly.rs runs this script when it finds the tests' Python, or is given one).

- chain_master: examples/chain/chain_master.py, the Python master that co-simulates two
  separate body FMUs of examples/chain/link.json and iterates on the joints (retaking every
  step), driven as tests/test_chain.py's `double_pendulum(link, seconds)` drives it. Every
  `Chain.step` is timed (per step p50/p99/max and the loop's wall time per simulated second).
- Exudyn (optional, --deck): tests/exudyn_reference.py's `double_pendulum`, the same mesh's
  CalculiX matrices, Exudyn's own Craig-Bampton modes, floating-frame bodies, joints and
  generalised alpha at h = 1 ms. Only `SolveDynamic` is timed (not the matrices, the modes or the
  assembly of the system); Exudyn steps inside C++, so only its mean per step is known.

Accuracy: each trajectory's elbow and tip (x, z) against the rigid double pendulum of two uniform
bars of the links' size (tests/test_chain.py `rigid_double_pendulum`), max over the window as a
fraction of the rigid swing per column; the assembly FMU's own trajectory (--assembly, a CSV of
t, elbow x, z, tip x, z from t = 0 that fmu-bench writes) is measured the same way, over its
whole window and over chain_master's and Exudyn's.

Prints one JSON object on stdout (progress on stderr). Run from anywhere with the tests' Python:

    tests/.venv/bin/python bench/assembly_masters.py --link Link.fmu --seconds 1 \
        [--deck link.inp --exudyn-seconds 2] [--assembly positions.csv]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "examples" / "chain"))

H = 1e-3
PIVOT = np.pi / 4


def against_rigid(positions: np.ndarray) -> list[float]:
    """Max |positions - rigid| per column over the rows (t = 0, H, ...), / the rigid swing."""
    from test_chain import rigid_double_pendulum

    t = np.arange(len(positions)) * H
    rigid = rigid_double_pendulum([PIVOT, PIVOT], t, length=1.0)
    swing = np.ptp(rigid, axis=0)
    return (np.abs(positions - rigid).max(axis=0) / swing).tolist()


def per_step(durations: list[float]) -> dict:
    d = np.asarray(durations) * 1e6
    p50 = float(np.percentile(d, 50))
    return {"p50_us": p50, "p99_us": float(np.percentile(d, 99)), "max_us": float(d.max()),
            "mean_us": float(d.mean()), "slow": int(np.count_nonzero(d > 4.0 * p50))}


def against_reference(positions: np.ndarray, reference: Path) -> float:
    """Max |positions - reference| at the positions' times (every H from 0; the reference's step
    divides H) within the reference's window, / the reference's swing, worst column."""
    ref = np.loadtxt(reference, delimiter=",", ndmin=2)
    swing = np.ptp(ref[:, 1:5], axis=0)
    every = int(round(H / (ref[1, 0] - ref[0, 0])))
    ref = ref[::every, 1:5]
    n = min(len(ref), len(positions))
    return float((np.abs(positions[:n] - ref[:n]).max(axis=0) / swing).max())


def chain_master(link: Path, seconds: float, reference: Path | None = None) -> dict:
    import chain_master as cm
    from test_chain import double_pendulum

    durations: list[float] = []
    step = cm.Chain.step

    def timed(self, *args, **kwargs):
        start = time.perf_counter()
        out = step(self, *args, **kwargs)
        durations.append(time.perf_counter() - start)
        return out

    cm.Chain.step = timed
    try:
        start = time.perf_counter()
        ours, retakes = double_pendulum(link, seconds)
        total = time.perf_counter() - start
    finally:
        cm.Chain.step = step
    loop = float(np.sum(durations))
    return {"seconds": seconds, "steps": len(durations), "wall_s": total, "loop_s": loop,
            "loop_s_per_sim_s": loop / seconds, "evaluations_per_step": float(retakes),
            **per_step(durations), "error_vs_rigid": against_rigid(ours),
            **({"error_vs_reference": against_reference(ours, reference)} if reference else {})}


def exudyn(deck: Path, seconds: float) -> dict:
    import exudyn as exu
    from exudyn_reference import double_pendulum

    solve = exu.MainSystem.SolveDynamic
    timing: dict[str, float] = {}

    def timed(mbs, *args, **kwargs):
        start = time.perf_counter()
        out = solve(mbs, *args, **kwargs)
        timing["solve_s"] = time.perf_counter() - start
        return out

    exu.MainSystem.SolveDynamic = timed
    try:
        with tempfile.TemporaryDirectory(prefix="exudyn-bench-") as work:
            start = time.perf_counter()
            _, positions = double_pendulum(deck.read_text(), Path(work), seconds=seconds)
            total = time.perf_counter() - start
    finally:
        exu.MainSystem.SolveDynamic = solve
    steps = int(round(seconds / H))
    return {"seconds": seconds, "steps": steps, "wall_s": total, "solve_s": timing["solve_s"],
            "solve_s_per_sim_s": timing["solve_s"] / seconds, "mean_us": timing["solve_s"] / steps * 1e6,
            "error_vs_rigid": against_rigid(positions)}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--link", type=Path, required=True, help="the FMU of examples/chain/link.json")
    p.add_argument("--seconds", type=float, default=1.0, help="chain_master's simulated time [s]")
    p.add_argument("--deck", type=Path, help="the link's CalculiX deck (fmu-builder --export-inp): runs Exudyn")
    p.add_argument("--exudyn-seconds", type=float, default=2.0, help="Exudyn's simulated time [s]")
    p.add_argument("--assembly", type=Path, help="CSV of the assembly FMU's t, elbow x, z, tip x, z")
    p.add_argument("--reference", type=Path,
                   help="CSV of a converged run's t, elbow x, z, tip x, z every few steps from t = 0: "
                        "chain_master's error against it (error_vs_reference)")
    a = p.parse_args()
    out: dict = {}
    print(f"chain_master: double pendulum, {a.seconds} s ...", file=sys.stderr, flush=True)
    out["chain_master"] = chain_master(a.link, a.seconds, a.reference)
    if a.deck is not None:
        print(f"Exudyn: double pendulum, {a.exudyn_seconds} s ...", file=sys.stderr, flush=True)
        try:
            out["exudyn"] = exudyn(a.deck, a.exudyn_seconds)
        except Exception as e:  # noqa: BLE001 - reported, the rest stands
            out["exudyn"] = {"error": f"{type(e).__name__}: {e}"}
    if a.assembly is not None:
        rows = np.loadtxt(a.assembly, delimiter=",", ndmin=2)
        positions = rows[:, 1:5]
        n = out["chain_master"]["steps"] + 1
        out["assembly"] = {"seconds": (len(rows) - 1) * H, "error_vs_rigid": against_rigid(positions),
                           "error_vs_rigid_chain_window": against_rigid(positions[:n])}
        if "steps" in out.get("exudyn", {}):
            n = out["exudyn"]["steps"] + 1
            out["assembly"]["error_vs_rigid_exudyn_window"] = against_rigid(positions[:n])
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
