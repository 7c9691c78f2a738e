"""How each build phase scales with threads: the same build at 1 thread and at 2 (or the counts
given), side by side in one run, from the builder's own phase profile (`--timings`).

The mesh and spec are builder_vs_calculix.py's: the example bracket meshed by Gmsh at about
2.4e5 DoF (cached in the work directory), Craig-Bampton with 20 modes. The builder runs
`--repeats` times per thread count (RAYON_NUM_THREADS and OMP_NUM_THREADS), the counts
interleaved, each a child process, and each phase keeps its fastest run. Printed per phase: that
wall time at each count, the speed-up from the first count to each other, and the process's CPU
time over the wall time at each count (the cores the phase kept busy: 1.0 is a serial phase,
whatever the thread count).

Target, PASS or MISS, exit code 1 on a miss: every phase that takes at least 1 s at the first
count runs at least 1.5 times faster at the second (the issue asks for 1.7 and for the
benchmark to fail below 1.5).

Run from the repository root with the tests' environment (bash tests/run.sh makes tests/.venv
with gmsh):

    tests/.venv/bin/python bench/thread_scaling.py                      # 2.4e5 DoF, 1 and 2 threads
    tests/.venv/bin/python bench/thread_scaling.py --size 2e4 --no-targets
    tests/.venv/bin/python bench/thread_scaling.py --threads 1,2,4,8,16 # a larger machine

A benchmark, not a timed test: the figures depend on the machine and what else runs on it.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import builder_vs_calculix as bvc  # noqa: E402

#: a phase this long at the first thread count is held to the speed-up target [s]
TARGET_FROM_S = 1.0
TARGET_SPEEDUP = 1.5


@dataclass
class PhaseTime:
    path: str  # the phase's name under its parents' names ("reduction basis / eigen-solve ...")
    depth: int
    wall_s: float
    cpu_s: float | None


def parse_profile(table: str) -> list[PhaseTime]:
    """The rows of a --timings table; a phase is named by its path, and a name that repeats under
    one parent is numbered (#2, #3) so every row keeps its own key."""
    lines = table.splitlines()
    if not lines or not lines[0].startswith("phase") or "cpu/wall" not in lines[0]:
        raise bvc.BenchError(f"not a --timings table with CPU times:\n{table[:500]}")
    rows, parents, seen = [], [], {}
    row = re.compile(r"^( *)(\S.*?)\s+(\d+\.\d{3})\s+(\d+|-)\s+(\d+\.\d{3}|-)\s+(\d+\.\d{2}|-)(?:\s+.*)?$")
    for line in lines[1:]:
        m = row.match(line)
        if not m:
            raise bvc.BenchError(f"unexpected line in the --timings table: {line!r}")
        depth, name = len(m.group(1)) // 2, m.group(2)
        key = " / ".join(parents[:depth] + [name])
        seen[key] = seen.get(key, 0) + 1
        if seen[key] > 1:
            name = f"{name} #{seen[key]}"
        parents = parents[:depth] + [name]
        path = " / ".join(parents)
        cpu = None if m.group(5) == "-" else float(m.group(5))
        rows.append(PhaseTime(path, depth, float(m.group(3)), cpu))
    return rows


def run_at(threads: int, spec: Path, mesh_dir: Path, builder: Path) -> tuple[float, list[PhaseTime]]:
    env = dict(os.environ, **bvc.thread_env(threads))
    fmu = mesh_dir / f"Bracket-{threads}t.fmu"
    fmu.unlink(missing_ok=True)
    log = mesh_dir / f"builder-{threads}t.log"
    run = bvc.run_measured([builder, spec, "-o", fmu, "--force", "--timings", "-q"], mesh_dir, env, log)
    if run.returncode != 0:
        raise bvc.BenchError(f"fmu-builder at {threads} threads failed (exit {run.returncode}), log {log}:\n"
                             + run.output[-3000:])
    return run.wall_s, parse_profile(bvc.profile_table(run.output))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=float, default=2.4e5, help="nominal DoF count (default %(default)g)")
    parser.add_argument("--threads", default="1,2", help="thread counts, the first the baseline (default 1,2)")
    parser.add_argument("--repeats", type=int, default=2,
                        help="builds per thread count, interleaved; each phase keeps its fastest (default %(default)s)")
    parser.add_argument("--no-targets", action="store_true", help="report only: exit 0 whatever the figures")
    parser.add_argument("--work", type=Path, default=bvc.TARGET_DIR / "builder-bench",
                        help="meshes (cached per element size), FMUs and logs (default %(default)s)")
    args = parser.parse_args(argv)
    try:
        counts = [int(t) for t in args.threads.split(",") if t.strip()]
    except ValueError:
        raise SystemExit(f"--threads: expected counts like 1,2, got {args.threads!r}")
    if len(counts) < 2 or min(counts) < 1:
        raise SystemExit(f"--threads: at least two counts of 1 or more, got {args.threads!r}")
    if args.repeats < 1:
        raise SystemExit(f"--repeats: at least 1, got {args.repeats}")
    args.work = args.work.resolve()
    builder = bvc.snapshot_builder(args.work)
    lc = bvc.element_size(args.size)
    inp, how = bvc.make_mesh(lc, args.work)
    spec = bvc.write_spec(inp.parent)
    print(f"{bvc.label(args.size)} DoF: Gmsh lc {lc:g} m ({inp}, {how}); builder {builder}; "
          f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.1f}", flush=True)

    # the counts interleaved, round after round, and each phase's fastest run kept: on a shared
    # virtual machine a neighbour's load can slow one whole build by a fifth (one-thread builds
    # of 33.6 s and 38.5 s on the same day), which a single run per count would report as scaling
    walls = [float("inf")] * len(counts)
    profiles = [{} for _ in counts]
    for r in range(args.repeats):
        for k, t in enumerate(counts):
            wall, phases = run_at(t, spec, inp.parent, builder)
            walls[k] = min(walls[k], wall)
            for p in phases:
                if p.path not in profiles[k] or p.wall_s < profiles[k][p.path].wall_s:
                    profiles[k][p.path] = p
            print(f"  round {r + 1}, {t} thread(s): {wall:.1f} s", flush=True)

    base = profiles[0]
    head = ["phase", *[f"{t}t [s]" for t in counts], *[f"x{t}t" for t in counts[1:]],
            *[f"cpu/wall {t}t" for t in counts]]
    print("\n| " + " | ".join(head) + " |")
    print("|---|" + "---:|" * (len(head) - 1))
    results = []
    for path, p in base.items():
        times = [prof.get(path) for prof in profiles]
        cells = ["&nbsp;&nbsp;" * p.depth + path.rsplit(" / ", 1)[-1]]
        cells += [f"{q.wall_s:.2f}" if q else "-" for q in times]
        speedups = [p.wall_s / q.wall_s if q and q.wall_s > 0 else None for q in times[1:]]
        cells += [f"{s:.2f}" if s else "-" for s in speedups]
        cells += [f"{q.cpu_s / q.wall_s:.2f}" if q and q.cpu_s is not None and q.wall_s >= 0.01 else "-"
                  for q in times]
        print("| " + " | ".join(cells) + " |")
        if p.wall_s >= TARGET_FROM_S and speedups[0] is not None:
            results.append((speedups[0] >= TARGET_SPEEDUP,
                            f"{path}: {p.wall_s:.2f} s at {counts[0]} thread(s), x{speedups[0]:.2f} at {counts[1]} "
                            f"(target x{TARGET_SPEEDUP})"))
    total = [f"{w:.1f} s" for w in walls]
    print(f"\nwhole build: {', '.join(f'{t}t {w}' for t, w in zip(counts, total))}; "
          f"x{walls[0] / walls[1]:.2f} from {counts[0]} to {counts[1]} thread(s)")
    print(f"\ntargets (phases of at least {TARGET_FROM_S:g} s at {counts[0]} thread(s)):"
          + ("  (--no-targets: reported, not enforced)" if args.no_targets else ""))
    for ok, text in results:
        print(f"  {'PASS' if ok else 'MISS'}  {text}")
    missed = sum(not ok for ok, _ in results)
    print(f"{missed} of {len(results)} targets missed" if missed else f"all {len(results)} targets met", flush=True)
    return 1 if missed and not args.no_targets else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except bvc.BenchError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
