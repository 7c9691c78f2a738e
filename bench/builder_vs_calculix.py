"""The builder's speed and memory against CalculiX on the same mesh, side by side in one run.

The example bracket (examples/bracket/bracket-inp.json: mount `base` on the bolt hole BOLT_BASE,
force flange `arm` on BOLT_ARM; without its scene, Craig-Bampton with 20 fixed-interface modes)
is meshed by Gmsh at about 2e4, 1e5 and 2.4e5 DoF (and 1e6 with --long). At each size the
builder makes the FMU (`fmu-builder --timings`) and CalculiX 2.20 solves `*FREQUENCY` for 20
modes on the same .inp, as the builder's mounted problem: the mount's hole nodes fixed (the
builder ties them rigidly to a held reference point, which fixes them all), the arm's hole nodes
a `*RIGID BODY` whose reference node, at the builder's reference point, is free. Each program is
a child process: wall time and its own peak resident memory (wait4's ru_maxrss) are measured
around it.

Printed per size, as soon as it is done: wall time, peak memory and their ratios builder /
CalculiX, the first five frequencies of both (CalculiX against the builder's full FE model,
report.json accuracy.full_hz; the reduced model's beside them) and the builder's phase profile.
At the end the targets, PASS or MISS, and the exit code 1 on any miss:

- time builder / CalculiX <= 0.2 at 2.4e5 DoF;
- peak memory builder <= CalculiX at every size from 1e5 DoF on (at 2e4 both are mostly fixed
  overheads: reported only);
- the first five frequencies of CalculiX and of the builder's full model within 1e-6 (relative)
  at every size (CalculiX prints 7 digits: its rounding alone is up to 5e-7);
- with --long, the builder within 24 GiB at 1e6 DoF (CalculiX runs there only if its memory,
  extrapolated from the smaller sizes of the same run, fits into what the machine has free).

Run from the repository root with the tests' environment (bash tests/run.sh makes tests/.venv
with gmsh):

    tests/.venv/bin/python bench/builder_vs_calculix.py                 # 2e4, 1e5, 2.4e5 DoF
    tests/.venv/bin/python bench/builder_vs_calculix.py --long          # and 1e6 DoF
    tests/.venv/bin/python bench/builder_vs_calculix.py --sizes 2e4 --no-targets   # the smoke test's run

A benchmark, not a timed test: the figures depend on the machine and what else runs on it; the
ratios of one run are what to compare.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))  # the CalculiX harness
sys.path.insert(0, str(ROOT / "bench"))  # bracket_mesh

import bracket_mesh  # noqa: E402
import calculix as ccx  # noqa: E402

TARGET_DIR = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))  # as cargo and tests/conftest.py
BUILDER = TARGET_DIR / "release" / "fmu-builder"
SPEC = ROOT / "examples" / "bracket" / "bracket-inp.json"

MODES = 20
FREQS = 5  # frequencies compared and printed
FREQ_TOL = 1e-6
TIME_RATIO_MAX = 0.2
TIME_RATIO_AT = 2.4e5  # nominal size where the time ratio is a target
MEMORY_FROM = 1e5  # nominal sizes from which the builder's peak must not exceed CalculiX's
LONG_SIZE = 1e6
LONG_MEMORY_MIB = 24 * 1024

#: Gmsh global element size [m] -> DoF (3 x nodes) of the bracket, measured with gmsh 4.15.2;
#: the nominal sizes are these points, others are interpolated log-log between them.
CALIBRATION = [(0.0048, 20_550), (0.0023, 106_389), (0.0016, 253_473), (0.00098, 1_016_826)]


# --------------------------------------------------------------------------------------------
# Sizes


def element_size(dof: float) -> float:
    """Gmsh size for about `dof` DoF: a calibration point within 15 %, else log-log between the
    two nearest points (DoF ~ lc^-2.5 here: the holes keep their finer size)."""
    for lc, n in CALIBRATION:
        if abs(n / dof - 1) < 0.15:
            return lc
    pts = sorted(CALIBRATION, key=lambda p: p[1])
    lo, hi = (pts[0], pts[1]) if dof < pts[1][1] else (pts[-2], pts[-1])
    for a, b in zip(pts, pts[1:]):
        if a[1] <= dof <= b[1]:
            lo, hi = a, b
    slope = math.log(hi[0] / lo[0]) / math.log(hi[1] / lo[1])
    return round(lo[0] * (dof / lo[1]) ** slope, 6)


def label(dof: float) -> str:
    """A nominal size as the issue writes it: 2e4, 2.4e5, 1e6."""
    exponent = math.floor(math.log10(dof))
    return f"{dof / 10**exponent:.3g}e{exponent}"


def parse_sizes(text: str) -> list[float]:
    try:
        sizes = [float(s) for s in text.split(",") if s.strip()]
    except ValueError:
        raise SystemExit(f"--sizes: expected numbers like 2e4,1e5,2.4e5, got {text!r}")
    if not sizes or min(sizes) < 1e3:
        raise SystemExit(f"--sizes: DoF counts of at least 1e3 expected, got {text!r}")
    return sizes


# --------------------------------------------------------------------------------------------
# Children: wall time and their own peak memory


@dataclass
class Run:
    wall_s: float
    maxrss_mib: float
    returncode: int
    output: str
    load: float  # 1-minute load average at the start: other work on the machine slows the child
    cpu_s: float  # user + system: far above wall x threads' share when threads wait on busy cores


def run_measured(cmd, cwd: Path, env: dict, log: Path) -> Run:
    """Run `cmd` as a child; wall time and its peak RSS from wait4 (its own rusage, not the
    sum over every child this process ever had, as getrusage(RUSAGE_CHILDREN) would be)."""
    load = os.getloadavg()[0]
    with open(log, "w") as out:
        start = time.perf_counter()
        proc = subprocess.Popen([str(c) for c in cmd], cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT)
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        except BaseException:
            proc.kill()  # Ctrl-C: do not leave a 20 GiB child behind
            proc.wait()
            raise
        wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped by wait4: tell Popen
    return Run(wall, usage.ru_maxrss / 1024.0, proc.returncode, log.read_text(errors="replace"), load,
               usage.ru_utime + usage.ru_stime)


def thread_env(threads: int) -> dict:
    """Both programs get every core: CalculiX reads OMP_NUM_THREADS and its CCX_NPROC_* (SPOOLES,
    stiffness, results); the builder's libraries RAYON_NUM_THREADS / OMP_NUM_THREADS."""
    n = str(threads)
    names = ["OMP_NUM_THREADS", "CCX_NPROC_EQUATION_SOLVER", "CCX_NPROC_STIFFNESS", "CCX_NPROC_RESULTS",
             "NUMBER_OF_CPUS", "RAYON_NUM_THREADS"]
    return {name: n for name in names}


# --------------------------------------------------------------------------------------------
# The builder


@dataclass
class BuilderResult:
    run: Run
    peak_mib: float  # max(ru_maxrss, the builder's own printed peak)
    printed_peak_mib: float | None
    nodes: int
    full_hz: list
    reduced_hz: list
    profile: str


def builder_binary() -> Path:
    """The release builder (CARGO_TARGET_DIR respected), built if missing."""
    if not BUILDER.exists():
        print(f"{BUILDER} missing: cargo xtask build", flush=True)
        subprocess.run(["cargo", "build", "--release", "-p", "fmu-builder"], cwd=ROOT, check=True)
    return BUILDER


def snapshot_builder(work: Path) -> Path:
    """A copy of the release builder in the work directory: a cargo build during the run (the
    builder is being worked on) must not give the sizes of one run different builders."""
    work.mkdir(parents=True, exist_ok=True)
    copy = work / "fmu-builder"
    copy.unlink(missing_ok=True)
    shutil.copy2(builder_binary(), copy)
    return copy


def write_spec(mesh_dir: Path) -> Path:
    """bracket-inp.json without its scene, Craig-Bampton with MODES modes, on this mesh."""
    spec = json.loads(SPEC.read_text())
    spec.pop("$schema", None)
    spec.pop("scene", None)
    spec["reduction"] = {"method": "craig_bampton", "modes": MODES}
    spec["geometry"] = {"mesh": "bracket.inp"}  # relative to the spec, which lies next to it
    path = mesh_dir / "bracket-bench.json"
    path.write_text(json.dumps(spec, indent=2))
    return path


def profile_table(output: str) -> str:
    """The --timings table: from its header line to the end of the output."""
    m = re.search(r"^phase\s+wall \[s\].*", output, flags=re.M | re.S)
    return m.group(0).rstrip() if m else "(no phase profile in the builder's output)"


def run_builder(builder: Path, mesh_dir: Path, env: dict) -> BuilderResult:
    spec = write_spec(mesh_dir)
    fmu = mesh_dir / "Bracket.fmu"
    fmu.unlink(missing_ok=True)
    run = run_measured([builder, spec, "-o", fmu, "--force", "--timings"], mesh_dir, env, mesh_dir / "builder.log")
    if run.returncode != 0:
        # a negative code is a signal: 9 is what the kernel's out-of-memory killer sends
        how = f"killed by signal {-run.returncode}" if run.returncode < 0 else f"exit {run.returncode}"
        raise BenchError(f"fmu-builder failed ({how}), log {mesh_dir / 'builder.log'}:\n"
                         + run.output[-3000:])
    # --timings resets the kernel's high-water mark per phase, so ru_maxrss can miss the true peak;
    # the builder folds every phase's mark into its own and prints it
    m = re.search(r"^peak memory (\d+(?:\.\d+)?) MiB", run.output, flags=re.M)
    printed = float(m.group(1)) if m else None
    report = json.loads(zipfile.ZipFile(fmu).read("documentation/report.json"))
    acc = report["accuracy"]
    return BuilderResult(run, max(run.maxrss_mib, printed or 0.0), printed, report["nodes"],
                         acc["full_hz"], acc["reduced_hz"], profile_table(run.output))


# --------------------------------------------------------------------------------------------
# CalculiX


@dataclass
class CcxResult:
    run: Run
    frequencies_hz: list
    threads: list = field(default_factory=list)  # what ccx says it uses ("Using up to 2 cpu(s) ...")


class BenchError(RuntimeError):
    pass


def max_node_id(inp_text: str) -> int:
    """Largest node id of the deck's *NODE blocks (not *NODE PRINT), read without parsing every
    coordinate."""
    top = 0
    for block in re.finditer(r"^\*NODE[ \t]*(?:,[^\n]*)?\n(.*?)(?=^\*)", inp_text, flags=re.M | re.S | re.I):
        ids = re.findall(r"^\s*(\d+)\s*,", block.group(1), flags=re.M)
        if ids:
            top = max(top, max(map(int, ids)))
    if top == 0:
        raise BenchError("no *NODE block in the mesh deck")
    return top


def calculix_deck(inp_text: str) -> str:
    """Gmsh's deck plus material, the mounted problem's constraints and the frequency step.

    The builder's mount ties BOLT_BASE rigidly to a reference point it holds fixed: every slave
    node is then fixed, so *BOUNDARY on the set is the same constraint (and cheaper than a rigid
    body with fixed nodes). The arm's RBE2 with a free reference point is a *RIGID BODY whose
    reference and rotation nodes sit at the builder's reference point (bracket-inp.json)."""
    spec = json.loads(SPEC.read_text())
    mat = spec["material"]
    arm = next(f for f in spec["flanges"] if f["name"] == "arm")
    if arm["nodes"] != {"node_set": "BOLT_ARM"}:
        raise BenchError(f"{SPEC}: flange arm is expected on node set BOLT_ARM")
    ref = max_node_id(inp_text) + 1
    point = ", ".join(ccx.fit_field(repr(float(c))) for c in arm["reference_point"])
    # one-node sets BOLT_ARM_REF, BOLT_ARM_ROT next to the slave set BOLT_ARM, as the harness's
    # rigid_body expects them (it names the slave set after the flange)
    sets = f"*NSET, NSET=BOLT_ARM_REF\n{ref}\n*NSET, NSET=BOLT_ARM_ROT\n{ref + 1}\n"
    return (inp_text.rstrip("\n") + "\n"
            + f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{ccx.fit_field(repr(float(mat['E'])))}, "
            + f"{ccx.fit_field(repr(float(mat['nu'])))}\n*DENSITY\n{ccx.fit_field(repr(float(mat['rho'])))}\n"
            + "*SOLID SECTION, ELSET=BRACKET, MATERIAL=STEEL\n"
            + f"*NODE\n{ref}, {point}\n{ref + 1}, {point}\n" + sets
            + "*BOUNDARY\nBOLT_BASE, 1, 3\n"
            + ccx.rigid_body(sets, "bolt_arm")
            + ccx.frequency_step(MODES))


def run_calculix(inp: Path, env: dict) -> CcxResult:
    exe = ccx.ccx_executable()  # CcxError with the install hint when missing
    work = inp.parent / "ccx"
    work.mkdir(exist_ok=True)
    (work / "job.inp").write_text(calculix_deck(inp.read_text()))
    dat = work / "job.dat"
    dat.unlink(missing_ok=True)
    run = run_measured([exe, "-i", "job"], work, env, work / "ccx.log")
    # a card CalculiX could not read is only a *WARNING to it (a *RIGID BODY on a missing set
    # leaves the flange free and the frequencies 5 % low): for a comparison it is an error
    errors = [line.strip() for line in run.output.splitlines() if "*ERROR" in line or "*WARNING reading" in line]
    if run.returncode != 0 or errors or not dat.exists():
        raise BenchError(f"ccx failed (exit {run.returncode}) on {work / 'job.inp'}:\n"
                         + "\n".join(errors[:20]) + "\n" + run.output[-3000:])
    freqs = ccx.parse_dat(dat.read_text()).frequencies_hz
    if len(freqs) < FREQS:
        raise BenchError(f"CalculiX printed {len(freqs)} frequencies in {dat}, expected {MODES}")
    threads = sorted({line.strip() for line in run.output.splitlines() if line.strip().startswith("Using up to")})
    (work / "job.frd").unlink(missing_ok=True)  # mode shapes nobody reads: up to GiBs at 1e6 DoF
    return CcxResult(run, freqs, threads)


def mem_available_mib() -> float:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) / 1024.0
    return float("inf")


def ccx_memory_estimate(done: list, dof: int) -> float | None:
    """CalculiX's peak at `dof`, extrapolated from this run's sizes (power law through the two
    largest; SPOOLES's fill grows faster than the DoF count), None without two of them."""
    pts = sorted((r["dof"], r["ccx_peak_mib"]) for r in done if r.get("ccx_peak_mib"))
    if len(pts) < 2:
        return None
    (n1, m1), (n2, m2) = pts[-2], pts[-1]
    exponent = math.log(m2 / m1) / math.log(n2 / n1) if n2 > n1 and m2 > m1 else 1.0
    return m2 * (dof / n2) ** exponent


# --------------------------------------------------------------------------------------------
# One size


def make_mesh(lc: float, work: Path) -> tuple[Path, str]:
    """The cached or new Gmsh mesh, in a child process (Gmsh's memory is gone before the builder
    runs, which matters at 1e6 DoF); with what was done ("cached" or Gmsh's time)."""
    if (bracket_mesh.mesh_dir(work, lc) / bracket_mesh.DONE).exists():
        return bracket_mesh.mesh_dir(work, lc) / "bracket.inp", "cached"
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "bracket_mesh.py"), repr(lc), str(work)],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise BenchError(f"meshing at lc = {lc} failed:\n{proc.stdout}{proc.stderr}")
    return Path(proc.stdout.strip().splitlines()[-1]), f"meshed by Gmsh in {time.perf_counter() - start:.1f} s"


def relative_diffs(ours, theirs) -> list:
    return [abs(a / b - 1) for a, b in zip(ours[:FREQS], theirs[:FREQS])]


def bench_size(nominal: float, args, env: dict, done: list) -> dict:
    lc = element_size(nominal)
    inp, how = make_mesh(lc, args.work)
    row = {"nominal": nominal, "lc": lc, "mesh": str(inp)}
    print(f"\n== {label(nominal)} DoF: Gmsh lc {lc:g} m ({inp}, {how}) ==", flush=True)
    b = run_builder(args.builder, inp.parent, env)
    row.update(builder_fields(b))
    print_builder(b)
    skip = calculix_skip_reason(row["dof"], done)
    if skip:
        row["ccx_skipped"] = skip
        print(f"CalculiX  not run: {skip}", flush=True)
    else:
        c = run_calculix(inp, env)
        row.update(calculix_fields(b, c))
        print_calculix(c, row)
    print_frequencies(row)
    print("builder phase profile (--timings):\n" + "\n".join("  " + line for line in b.profile.splitlines()),
          flush=True)
    return row


def builder_fields(b: BuilderResult) -> dict:
    return dict(dof=3 * b.nodes, nodes=b.nodes, builder_wall_s=b.run.wall_s, builder_cpu_s=b.run.cpu_s,
                builder_peak_mib=b.peak_mib, builder_maxrss_mib=b.run.maxrss_mib,
                builder_printed_peak_mib=b.printed_peak_mib, builder_load=b.run.load,
                full_hz=b.full_hz[:FREQS], reduced_hz=b.reduced_hz[:FREQS], profile=b.profile)


def calculix_fields(b: BuilderResult, c: CcxResult) -> dict:
    return dict(ccx_wall_s=c.run.wall_s, ccx_cpu_s=c.run.cpu_s, ccx_peak_mib=c.run.maxrss_mib,
                ccx_load=c.run.load, ccx_threads=c.threads, ccx_hz=c.frequencies_hz[:FREQS],
                max_rel_diff=max(relative_diffs(b.full_hz, c.frequencies_hz)),
                time_ratio=b.run.wall_s / c.run.wall_s, memory_ratio=b.peak_mib / c.run.maxrss_mib)


def print_builder(b: BuilderResult):
    printed = f"{b.printed_peak_mib:.0f}" if b.printed_peak_mib is not None else "-"
    print(f"builder   {b.run.wall_s:9.1f} s (cpu {b.run.cpu_s:.1f} s)  peak {b.peak_mib:8.0f} MiB  "
          f"(ru_maxrss {b.run.maxrss_mib:.0f}, printed {printed}); {b.nodes} nodes, {3 * b.nodes} DoF; "
          f"load average {b.run.load:.1f} at its start", flush=True)


def print_calculix(c: CcxResult, row: dict):
    print(f"CalculiX  {c.run.wall_s:9.1f} s (cpu {c.run.cpu_s:.1f} s)  peak {c.run.maxrss_mib:8.0f} MiB  "
          f"(load average {c.run.load:.1f} at its start; {' '.join(c.threads)})", flush=True)
    print(f"ratio builder/CalculiX: time {row['time_ratio']:.3f}, peak memory {row['memory_ratio']:.3f}",
          flush=True)


def calculix_skip_reason(dof: int, done: list) -> str | None:
    """Why CalculiX is not run at this size (it would not fit), or None."""
    estimate = ccx_memory_estimate(done, dof)
    available = mem_available_mib()
    if estimate is not None and estimate > 0.9 * available:
        return (f"its peak memory, extrapolated from this run's smaller sizes, is about {estimate / 1024:.1f} GiB "
                f"and {available / 1024:.1f} GiB are available")
    return None


def print_frequencies(row: dict):
    ccx_hz = row.get("ccx_hz")
    print(f"  mode  {'CalculiX [Hz]':>16}  {'builder full [Hz]':>18}  {'rel. diff':>9}  {'builder reduced [Hz]':>20}")
    for k in range(FREQS):
        theirs = f"{ccx_hz[k]:16.7g}" if ccx_hz else f"{'-':>16}"
        diff = f"{abs(row['full_hz'][k] / ccx_hz[k] - 1):9.1e}" if ccx_hz else f"{'-':>9}"
        print(f"  {k + 1:4d}  {theirs}  {row['full_hz'][k]:18.10g}  {diff}  {row['reduced_hz'][k]:20.10g}")
    if ccx_hz:
        print(f"  largest relative difference, CalculiX vs builder full model: {row['max_rel_diff']:.1e} "
              f"(tolerance {FREQ_TOL:g})", flush=True)


# --------------------------------------------------------------------------------------------
# Summary and targets


def fmt(row: dict, key: str, spec: str) -> str:
    value = row.get(key)
    return "-" if value is None else format(value, spec)


def summary(rows: list) -> str:
    head = ("| size | DoF | builder [s] | CalculiX [s] | time ratio | builder peak [MiB] | CalculiX peak [MiB] "
            "| memory ratio | max freq. diff |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    lines = [head]
    for r in rows:
        if "error" in r:
            lines.append(f"| {label(r['nominal'])} | - | failed: {r['error'].splitlines()[0]} | | | | | | |")
            continue
        lines.append(f"| {label(r['nominal'])} | {r['dof']} | {fmt(r, 'builder_wall_s', '.1f')} | {fmt(r, 'ccx_wall_s', '.1f')} "
                     f"| {fmt(r, 'time_ratio', '.3f')} | {fmt(r, 'builder_peak_mib', '.0f')} "
                     f"| {fmt(r, 'ccx_peak_mib', '.0f')} | {fmt(r, 'memory_ratio', '.3f')} "
                     f"| {fmt(r, 'max_rel_diff', '.1e')} |")
    return "\n".join(lines)


def targets(rows: list) -> list:
    """(passed, text) for every target that applies to the sizes run."""
    out = []
    for r in rows:
        size = f"{label(r['nominal'])} DoF"
        if "error" in r:
            out.append((False, f"{size}: the run failed ({r['error'].splitlines()[0]})"))
            continue
        if "max_rel_diff" in r:
            out.append((r["max_rel_diff"] <= FREQ_TOL, f"{size}: first {FREQS} frequencies CalculiX vs builder "
                        f"within {FREQ_TOL:g}: {r['max_rel_diff']:.1e}"))
        if math.isclose(r["nominal"], TIME_RATIO_AT) and "time_ratio" in r:
            out.append((r["time_ratio"] <= TIME_RATIO_MAX, f"{size}: time builder/CalculiX <= {TIME_RATIO_MAX}: "
                        f"{r['time_ratio']:.3f} ({r['builder_wall_s']:.1f} s / {r['ccx_wall_s']:.1f} s)"))
        if r["nominal"] >= MEMORY_FROM and "memory_ratio" in r:
            out.append((r["memory_ratio"] <= 1.0, f"{size}: peak memory builder <= CalculiX: "
                        f"{r['builder_peak_mib']:.0f} MiB vs {r['ccx_peak_mib']:.0f} MiB"))
        if r["nominal"] >= LONG_SIZE:
            out.append((r["builder_peak_mib"] <= LONG_MEMORY_MIB, f"{size}: builder within 24 GiB: "
                        f"{r['builder_peak_mib'] / 1024:.1f} GiB"))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="2e4,1e5,2.4e5", help="nominal DoF counts (default 2e4,1e5,2.4e5)")
    parser.add_argument("--long", action="store_true", help=f"add {LONG_SIZE:g} DoF")
    parser.add_argument("--no-targets", action="store_true", help="report only: exit 0 whatever the figures")
    parser.add_argument("--work", type=Path, default=TARGET_DIR / "builder-bench",
                        help="meshes (cached per element size), FMUs, CalculiX decks and logs (default %(default)s)")
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                        help="threads for both programs (default: the core count, %(default)s)")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON here")
    args = parser.parse_args(argv)
    sizes = parse_sizes(args.sizes) + ([LONG_SIZE] if args.long else [])
    args.work = args.work.resolve()

    try:
        ccx_exe = ccx.ccx_executable()
    except ccx.CcxError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    env = dict(os.environ, **thread_env(args.threads))
    args.builder = snapshot_builder(args.work)
    print(f"builder {BUILDER} (built {time.ctime(BUILDER.stat().st_mtime)}, run as its copy {args.builder}); "
          f"CalculiX {ccx_exe}\n"
          f"threads: {' '.join(f'{k}={v}' for k, v in thread_env(args.threads).items())} "
          f"({os.cpu_count()} cores); work directory {args.work}", flush=True)

    rows = []
    for nominal in sizes:
        try:
            rows.append(bench_size(nominal, args, env, rows))
        except (BenchError, ccx.CcxError) as e:
            print(f"error at {label(nominal)} DoF: {e}", flush=True)
            rows.append({"nominal": nominal, "error": str(e)})
    print("\n" + summary(rows), flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))

    results = targets(rows)
    print("\ntargets:" + ("  (--no-targets: reported, not enforced)" if args.no_targets else ""))
    for ok, text in results:
        print(f"  {'PASS' if ok else 'MISS'}  {text}")
    missed = sum(not ok for ok, _ in results)
    print(f"{missed} of {len(results)} targets missed" if missed else f"all {len(results)} targets met", flush=True)
    failed = any("error" in r for r in rows)  # a run that failed is never only a report
    return 1 if failed or (missed and not args.no_targets) else 0


if __name__ == "__main__":
    sys.exit(main())
