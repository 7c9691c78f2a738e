"""The distributed back-end (PETSc and MUMPS under MPI) against the in-process one, side by
side in one run, on the benchmark bracket of builder_vs_calculix.py (the same Gmsh meshes, cached
in target/builder-bench; Craig-Bampton with 20 fixed-interface modes).

At each size (default 2e4, 1e5 and 2.4e5 DoF) the builder makes the FMU three times: in
process, and with `--backend petsc` on 1 and on 2 MPI ranks. Printed per run: wall time, the
builder's own peak resident memory, each rank's peak (the driver's getrusage, report.json's
backend.peak_mib_per_rank), MUMPS's factor entries (all ranks), the driver's load / partition /
factor times, and the largest difference of the reduced frequencies from the in-process FMU's.

Then a projection to 1e7 DoF from the measured scaling: power laws fitted (log-log, least
squares) over the sizes of this run to MUMPS's factor entries, the ranks' summed peak memory
and the 2-rank wall time, extrapolated; with the number of ranks of 20 GiB each that
memory needs. A projection, not a measurement: the exponents hold while the mesh refines the
same part the same way.

Targets (exit 1 on a miss):
- at every size, 1 and 2 ranks: the reduced frequencies equal the in-process FMU's within 1e-9;
- at the largest size: with 2 ranks the larger rank's peak memory is at most 0.75 of the
  1-rank peak (the factor really is spread: measured about 0.6);
- at every size from 1e5 DoF: 1 rank takes at most 1.5 times the in-process build, and 2 ranks
  no longer than 1 rank (both cores work).

Both back-ends run the same block shift-invert Lanczos (the builder's, one Krylov space for the
whole and the held problem); on PETSc its block solves are MUMPS's, one request per block. What
remains of the difference on one machine: launching the ranks and importing petsc4py (about a
second), MUMPS's analysis and factorisation and its solves on one core per rank where faer's use
both cores. The distributed back-end is for parts whose factor one machine cannot hold, and its
figures here are what it costs where one could.

    tests/.venv/bin/python bench/petsc_backend.py                   # 2e4, 1e5, 2.4e5 DoF
    tests/.venv/bin/python bench/petsc_backend.py --sizes 2e4       # quick look

Needs Debian's python3-petsc4py-real, python3-mpi4py, openmpi-bin (and
libopenblas0-serial: MUMPS on the reference BLAS factors 4 times slower), as tests/run.sh
installs them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

import builder_vs_calculix as bvc  # noqa: E402

RANKS = [1, 2]
PROJECT_TO = 1e7
RANK_MEMORY_GIB = 20.0
EQUAL_FREQUENCIES = 1e-9
SPREAD_TARGET = 0.75
ONE_RANK_TIME_TARGET = 1.5
TWO_RANKS_TIME_TARGET = 1.0
TIME_TARGETS_FROM = 1e5


def launcher_env() -> dict:
    env = dict(os.environ)
    # mpirun refuses root without these (CI machines run as root)
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return env


def build(builder: Path, spec: Path, mesh_dir: Path, name: str, extra: list) -> dict:
    fmu = mesh_dir / f"{name}.fmu"
    fmu.unlink(missing_ok=True)
    log = mesh_dir / f"{name}.log"
    report_path = mesh_dir / f"{name}.report.json"
    run = bvc.run_measured([builder, spec, "-o", fmu, "--force", "--timings", "--report", report_path, *extra],
                           mesh_dir, launcher_env(), log)
    if run.returncode != 0:
        raise SystemExit(f"fmu-builder {name} failed, log {log}:\n{run.output[-3000:]}")
    # the full report: the FMU's copy leaves out the back-end's times, memory and factor size
    report = json.loads(report_path.read_text())
    printed = [float(line.split()[2]) for line in run.output.splitlines() if line.startswith("peak memory ")]
    backend = report["backend"]
    return {
        "name": name,
        "wall_s": run.wall_s,
        # the builder's own peak as it prints it: wait4's ru_maxrss would count the MPI ranks,
        # its waited-for descendants, too
        "builder_peak_mib": max(printed) if printed else run.maxrss_mib,
        "rank_peaks_mib": backend.get("peak_mib_per_rank", []),
        "rows_per_rank": backend.get("rows_per_rank", []),
        "factor_entries": backend["factor_entries"],
        "factor_s": backend.get("factor_seconds"),
        "partition_s": backend.get("partition_seconds"),
        "reduced_hz": report["accuracy"]["reduced_hz"],
        "dofs": report["dofs_constrained"],
        "profile": bvc.profile_table(run.output),
    }


def largest_difference(a: list, b: list) -> float:
    assert len(a) == len(b) > 0
    return max(abs(x / y - 1) for x, y in zip(a, b))


def fit(xs: list, ys: list) -> tuple[float, float]:
    """log y = a + b log x by least squares: (a, b)."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    b = sum((u - mx) * (v - my) for u, v in zip(lx, ly)) / sum((u - mx) ** 2 for u in lx)
    return my - b * mx, b


def print_run(row: dict, reference: dict):
    peaks = " / ".join(f"{p:.0f}" for p in row["rank_peaks_mib"]) or "-"
    factor = f"{row['factor_s']:.1f}" if row["factor_s"] is not None else "-"
    diff = largest_difference(row["reduced_hz"], reference["reduced_hz"])
    print(f"  {row['name']:<12} {row['wall_s']:8.1f} s  {row['wall_s'] / reference['wall_s']:5.2f}x  "
          f"builder {row['builder_peak_mib']:6.0f} MiB  ranks {peaks:>13} MiB  "
          f"factor {row['factor_entries']:.3e} entries, {factor} s  frequencies vs in-process {diff:.1e}", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="2e4,1e5,2.4e5", help="nominal DoF counts, comma-separated")
    parser.add_argument("--work", type=Path, default=bvc.TARGET_DIR / "builder-bench")
    parser.add_argument("--launcher", default="mpirun --oversubscribe")
    parser.add_argument("--python", default="/usr/bin/python3")
    parser.add_argument("--profiles", action="store_true", help="print each run's phase profile")
    args = parser.parse_args(argv)
    sizes = bvc.parse_sizes(args.sizes)
    args.work = args.work.resolve()
    builder = bvc.snapshot_builder(args.work)
    rows = []
    for nominal in sizes:
        lc = bvc.element_size(nominal)
        inp, how = bvc.make_mesh(lc, args.work)
        spec = bvc.write_spec(inp.parent)
        print(f"\n{bvc.label(nominal)} DoF (Gmsh size {lc}, mesh {how}):", flush=True)
        runs = [build(builder, spec, inp.parent, "in-process", [])]
        print_run(runs[0], runs[0])
        for ranks in RANKS:
            row = build(builder, spec, inp.parent, f"petsc-{ranks}",
                        ["--backend", "petsc", "--ranks", str(ranks), "--launcher", args.launcher,
                         "--python", args.python])
            print_run(row, runs[0])
            runs.append(row)
        if args.profiles:
            for row in runs:
                print(f"\n  {row['name']}:\n" + "\n".join("    " + line for line in row["profile"].splitlines()))
        rows.append((nominal, runs))

    print("\nProjection to 1e7 DoF from this run's sizes (2 ranks; power laws fitted log-log):")
    misses = []
    two = [(runs[0]["dofs"], runs[2]) for _, runs in rows]
    if len(two) >= 2:
        dofs = [d for d, _ in two]
        projected = {}
        for what, values, unit in [
            ("MUMPS factor entries", [r["factor_entries"] for _, r in two], ""),
            ("MUMPS factorisation time on 2 ranks", [r["factor_s"] for _, r in two], " s"),
            ("wall time on 2 ranks", [r["wall_s"] for _, r in two], " s"),
        ]:
            a, b = fit(dofs, values)
            projected[what] = math.exp(a) * PROJECT_TO ** b
            print(f"  {what}: ~ n^{b:.2f}, at 1e7 DoF {projected[what]:.3g}{unit}")
        # memory follows the factor: the ranks' summed peak per factor entry at the largest size
        # (at the small sizes each rank's fixed ~80 MiB of Python and PETSc hides the scaling)
        largest = two[-1][1]
        per_entry = sum(largest["rank_peaks_mib"]) * 2**20 / largest["factor_entries"]
        memory_gib = projected["MUMPS factor entries"] * per_entry / 2**30
        print(f"  ranks' memory: {per_entry:.1f} bytes per factor entry at {bvc.label(two[-1][0])} DoF, so at 1e7 DoF "
              f"about {memory_gib:.0f} GiB in all: at least {math.ceil(memory_gib / RANK_MEMORY_GIB)} ranks of "
              f"{RANK_MEMORY_GIB:.0f} GiB")
        print("  (the times are this machine's 2 ranks; more ranks divide the factorisation and the solves, not the "
              "builder's own stages)")
    else:
        print("  (needs two sizes or more)")

    print("\nTargets:")
    for nominal, runs in rows:
        for row in runs[1:]:
            diff = largest_difference(row["reduced_hz"], runs[0]["reduced_hz"])
            ok = diff <= EQUAL_FREQUENCIES
            print(f"  {'PASS' if ok else 'MISS'} {bvc.label(nominal)} {row['name']}: reduced frequencies vs in-process "
                  f"{diff:.1e} <= {EQUAL_FREQUENCIES:.0e}")
            if not ok:
                misses.append(row["name"])
    nominal, runs = rows[-1]
    one, two_ranks = runs[1], runs[2]
    spread = max(two_ranks["rank_peaks_mib"]) / max(one["rank_peaks_mib"])
    ok = spread <= SPREAD_TARGET
    print(f"  {'PASS' if ok else 'MISS'} {bvc.label(nominal)}: larger rank's peak on 2 ranks / the 1-rank peak "
          f"{spread:.2f} <= {SPREAD_TARGET}")
    if not ok:
        misses.append("spread")
    # the speed targets at every size of 1e5 DoF and more (below it the launch's fixed second
    # or two dominates)
    for nominal, runs in rows:
        if nominal < TIME_TARGETS_FROM:
            continue
        in_process, one, two_ranks = runs
        for what, ratio, target in [("1 rank / in process", one["wall_s"] / in_process["wall_s"], ONE_RANK_TIME_TARGET),
                                    ("2 ranks / 1 rank", two_ranks["wall_s"] / one["wall_s"], TWO_RANKS_TIME_TARGET)]:
            ok = ratio <= target
            print(f"  {'PASS' if ok else 'MISS'} {bvc.label(nominal)}: wall time {what} {ratio:.2f} <= {target}")
            if not ok:
                misses.append(f"{what} at {bvc.label(nominal)}")
    return 1 if misses else 0


if __name__ == "__main__":
    sys.exit(main())
