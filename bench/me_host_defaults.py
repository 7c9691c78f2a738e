"""Model Exchange at hosts' defaults, before and after the host-aware cutoff, side by side in
one run. "Before" is each example rebuilt with the cutoff the builder chose before (every kept
normal mode dynamic: reduction.dynamic_cutoff at the scene's own cutoff, as report.json names
it), with today's nominals and default experiment; "after" is the default build. Each runs FMPy's simulate_fmu (ME, CVode, a force step from
t = 0, nothing but start values) over a 1 s run (2 s for the L-beam) at the FMU's tolerance and
at rtol 1e-4, and SciPy's BDF at rtol 1e-4 through FMPy's low-level API for 0.2 s, each against
the Co-Simulation of the same FMU. Prints states, wall time, derivative calls and the worst
output error relative to its swing; exits non-zero when an "after" run fails or misses 1e-3
(1e-2 at rtol 1e-4; the undamped L-beam 2e-2), or when "after" costs BDF more derivative calls
than "before" on the bracket.

Run from the repository root after `bash tests/run.sh` has made tests/.venv:
    tests/.venv/bin/python bench/me_host_defaults.py
"""

import json
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402
from fmpy import read_model_description  # noqa: E402

import me_hosts as mh  # noqa: E402


def fmpy_case(path, name, rtol):
    md = read_model_description(path)
    outs = mh.outputs_of(md, mh.EXAMPLES_ME[name][1])
    start, _ = mh.loads(name, md)["force step"]
    stop = 2.0 if name == "l-beam" else 1.0
    try:
        res, wall, _ = mh.fmpy_me(path, start, None, outs, stop_time=stop, relative_tolerance=rtol)
    except Exception as e:  # the host's own failure (mxstep, error test) is the figure
        return None, None, str(e).split("\n")[0][:60]
    t = res["time"]
    dt = float(np.min(np.diff(t)[np.diff(t) > 0]))
    grid = np.arange(0.0, t[-1] + 0.5 * dt, dt)
    cs = mh.cs_reference(path, start, None, outs, grid, dt)
    me = np.column_stack([np.interp(grid, t, res[o]) for o in outs])
    err = mh.relative_errors(outs, me, cs)
    return wall, max(err.values()), ""


def bdf_case(path, name):
    md = read_model_description(path)
    outs = mh.outputs_of(md, mh.EXAMPLES_ME[name][1])
    start, _ = mh.loads(name, md)["force step"]
    grid = np.linspace(0.0, 0.2, 201)
    try:
        me, nfev, wall = mh.scipy_me(path, start, None, outs, grid, 1e-4, "BDF")
    except Exception as e:
        return None, None, None, str(e)[:60]
    cs = mh.cs_reference(path, start, None, outs, grid, 1e-3)
    return nfev, wall, max(mh.relative_errors(outs, me, cs).values()), ""


def main():
    failures = []
    tmp = Path(tempfile.mkdtemp())
    print(f"{'example':13s} {'build':7s} {'states':>6s} | {'FMPy tol':>8s} {'wall s':>7s} {'error':>9s} | "
          f"{'FMPy 1e-4':>9s} {'wall s':>7s} {'error':>9s} | {'BDF 1e-4 calls':>14s} {'wall s':>7s} {'error':>9s}")
    bdf_calls = {}
    for name in mh.EXAMPLES_ME:
        after = mh.build(name, tmp)
        report = json.loads(zipfile.ZipFile(after).read("documentation/report.json"))
        scene = report["scene_cutoff_hz"] or 1e9
        before = mh.build(name, tmp, dynamic_cutoff=scene)
        for label, path in (("before", before), ("after", after)):
            md = read_model_description(path)
            tol = float(md.defaultExperiment.tolerance)
            w1, e1, f1 = fmpy_case(path, name, tol)
            w2, e2, f2 = fmpy_case(path, name, 1e-4)
            n3, w3, e3, f3 = bdf_case(path, name)
            bdf_calls[(name, label)] = n3

            def cell(w, e, f):
                return f"{'failed':>8s} {'':>7s} {f[:9]:>9s}" if w is None else f"{'ok':>8s} {w:7.2f} {e:9.2e}"

            print(f"{name:13s} {label:7s} {len(md.derivatives):6d} | {cell(w1, e1, f1)} | {cell(w2, e2, f2)} | "
                  + (f"{'failed':>14s} {'':>7s} {f3[:9]:>9s}" if n3 is None else f"{n3:14d} {w3:7.2f} {e3:9.2e}"),
                  flush=True)
            if label == "after":
                loose = 2e-2 if name == "l-beam" else 1e-2
                if w1 is None or e1 > 1e-3 or w2 is None or e2 > loose or n3 is None or e3 > 1e-2:
                    failures.append(f"{name}: after misses its target")
    for name in ("bracket", "bracket-band", "bracket-inp"):
        b, a = bdf_calls[(name, "before")], bdf_calls[(name, "after")]
        if a is None or (b is not None and a > b):
            failures.append(f"{name}: BDF needs {a} derivative calls after, {b} before")
    for f in failures:
        print("TARGET MISSED:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
