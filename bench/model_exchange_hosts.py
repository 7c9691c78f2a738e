"""Model Exchange before and after the quasi-static split, side by side in one run: the same
example built with every mode a state (`reduction.dynamic_cutoff` 1e9 Hz) and with the default
cutoff, driven by SciPy's BDF (atol = rtol x nominal, the FMU's default tolerance) and by
FMPy's CVode at its defaults; each against the exact Co-Simulation of the same FMU. Prints derivative calls, wall
time and the worst flange output error; exits non-zero when the split does not at least halve
the BDF host's derivative calls on the bracket, or misses the acceptance figure 1e-3 of the
swing (the split costs some accuracy under a ramped force: its quasi-static modes have no
velocity in Model Exchange).

Run from the repository root after `bash tests/run.sh` has made tests/.venv:
    tests/.venv/bin/python bench/model_exchange_hosts.py
"""

import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402
from fmpy import simulate_fmu  # noqa: E402

import test_me_generic_host as host  # noqa: E402
from conftest import EXAMPLES, run_builder  # noqa: E402
from fmu_access import Fmu  # noqa: E402


def build(example, tmp, all_dynamic):
    spec = json.loads((EXAMPLES / example).read_text())
    spec.pop("$schema", None)
    if "mesh" in spec["geometry"]:
        spec["geometry"]["mesh"] = str((EXAMPLES / example).parent / spec["geometry"]["mesh"])
    if all_dynamic:
        spec["reduction"]["dynamic_cutoff"] = 1e9
    tag = f"{Path(example).stem}-{'all' if all_dynamic else 'split'}"
    spec_path = tmp / f"{tag}.json"
    spec_path.write_text(json.dumps(spec))
    out = tmp / f"{tag}.fmu"
    run_builder([spec_path, "-o", out])
    return out


def bdf(path, case):
    _, start, inputs, flange, t_end, h = host.CASES[case]
    f = Fmu(path)
    outs = host.flange_outputs(f.md, flange)
    f.close(terminate=False)
    every = int(round(1e-3 / h))
    cs = host.run_cs(path, t_end, inputs, start, outs, h, ramps=True)[::every]
    grid = np.arange(len(cs)) * 1e-3
    t0 = time.perf_counter()
    me, nfev, rtol = host.run_me(path, t_end, inputs, start, outs, grid)
    wall = time.perf_counter() - t0
    return nfev, wall, max(host.relative_errors(outs, me, cs).values()), rtol


def fmpy_defaults(path, flange, force, magnitude, t_end, h, start):
    f = Fmu(path)
    outs = host.flange_outputs(f.md, flange)
    f.close(terminate=False)
    cs = host.run_cs(path, t_end, lambda t: {force: magnitude}, start, outs, h)
    t0 = time.perf_counter()
    res = simulate_fmu(str(path), fmi_type="ModelExchange", stop_time=t_end,
                       start_values={**start, force: magnitude}, output=outs)
    wall = time.perf_counter() - t0
    me = np.array([res[n] for n in outs]).T
    cs = cs[np.round(res["time"] / h).astype(int)]
    return wall, max(host.relative_errors(outs, me, cs).values())


def main():
    ok = True
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        print("host            example   states  calls    wall [s]  worst error   (every mode a state -> split)")
        rows = {}
        for all_dynamic in (True, False):
            path = build("bracket/bracket.json", tmp, all_dynamic)
            f = Fmu(path)
            nx = f.nx
            f.close(terminate=False)
            rows[all_dynamic] = (nx, *bdf(path, "bracket under gravity, force ramp"))
        for all_dynamic in (True, False):
            nx, calls, wall, err, rtol = rows[all_dynamic]
            print(f"SciPy BDF {rtol:.0e} bracket {nx:6d} {calls:6d} {wall:10.2f}  {err:.2e}")
        if not (rows[True][1] >= 2 * rows[False][1] and rows[False][3] <= 1e-3):
            print("target missed: the split must halve the derivative calls within 1e-3 of the swing")
            ok = False
        for example, args in [
            ("bracket/bracket.json", ("arm", "arm.f[1]", 200.0, 0.02, 1e-5, {})),
            ("t-square.json", ("left", "left.f[3]", 10.0, 0.05, 1e-5, {"base.w[3]": 20.0})),
        ]:
            for all_dynamic in (True, False):
                path = build(example, tmp, all_dynamic)
                f = Fmu(path)
                nx = f.nx
                f.close(terminate=False)
                wall, err = fmpy_defaults(path, *args)
                print(f"FMPy CVode dflt {Path(example).stem:9s} {nx:6d}      - {wall:10.2f}  {err:.2e}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
