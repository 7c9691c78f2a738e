"""Why Co-Simulation keeps the modes above the dynamic cutoff quasi-static, measured against
the full FE model: the L-beam (examples/l-beam.json, undamped, 4 reduced modes above its cutoff
at 4.3 kHz) under a force step at the tip from rest, Co-Simulation of the default FMU (split) and
of the same body with every mode dynamic (`reduction.dynamic_cutoff` 1e9 Hz: the exact step
propagates all of them), each against CalculiX *DYNAMIC (direct integration of the full mesh,
alpha 0: no numerical damping) on the mesh the builder exports. Prints the error of every tip
output over the run, as the largest error and the RMS error relative to the output's swing, and
exits non-zero when the split is less accurate than all modes dynamic.

Run from the repository root after `bash tests/run.sh` has made tests/.venv:
    tests/.venv/bin/python bench/cosim_split_vs_calculix.py
"""

import json
import re
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import calculix as ccx  # noqa: E402
from conftest import EXAMPLES, run_builder  # noqa: E402
from fmu_access import Fmu  # noqa: E402

FORCE = 1.0  # N along z (out of the L's plane) at the tip flange
T_END = 2e-3  # s: 8.7 periods of the highest dynamic mode, 2.5 to 24 of those above the cutoff
H_CCX = 5e-6  # s: 4.3 kHz at omega h 0.14, the trapezoidal rule period error 1.5e-3
H_FMU = 5e-6


def build(tmp, all_dynamic):
    spec = json.loads((EXAMPLES / "l-beam.json").read_text())
    spec.pop("$schema", None)
    if all_dynamic:
        spec["reduction"]["dynamic_cutoff"] = 1e9
    tag = "all" if all_dynamic else "split"
    path = tmp / f"{tag}.json"
    path.write_text(json.dumps(spec))
    fmu, inp = tmp / f"{tag}.fmu", tmp / f"{tag}.inp"
    run_builder([path, "-o", fmu, "--export-inp", inp, "-q"])
    report = json.loads(zipfile.ZipFile(fmu).read("documentation/report.json"))
    return fmu, report, inp.read_text()


def fmu_history(fmu_path, outputs):
    """Co-Simulation from rest, the force switched on for the first step."""
    f = Fmu(fmu_path, "CoSimulation")
    try:
        f.fmu.setupExperiment(startTime=0.0)
        f.fmu.enterInitializationMode()
        f.fmu.exitInitializationMode()
        out = [f.get(*outputs)]
        f.set(**{"tip.f[3]": FORCE})
        n = int(round(T_END / H_FMU))
        for k in range(n):
            f.fmu.doStep(k * H_FMU, H_FMU)
            out.append(f.get(*outputs))
        return np.array(out)
    finally:
        f.close()


def calculix_history(deck, workdir):
    ref, rot = ccx.set_node(deck, "TIP_REF"), ccx.set_node(deck, "TIP_ROT")
    step = (ccx.rigid_body(deck, "base") + ccx.rigid_body(deck, "tip") + ccx.clamp(deck, "base")
            + "*AMPLITUDE, NAME=HELD\n0., 1., 1., 1.\n"
            + f"*STEP, INC=1000000\n*DYNAMIC, DIRECT, ALPHA=0.0\n{H_CCX}, {T_END}\n"
            + f"*CLOAD, AMPLITUDE=HELD\n{ref}, 3, {FORCE}\n"
            + "*NSET, NSET=TIPOUT\n" + f"{ref}, {rot}\n"
            + "*NODE PRINT, NSET=TIPOUT\nU, V\n*END STEP\n")
    result = ccx.run_ccx(deck, step, workdir, timeout=3000)
    text = (Path(workdir) / "job.dat").read_text()
    # blocks "displacements (vx,vy,vz) for set TIPOUT and time  0.25E-05", then "node x y z"
    series = {"displacements": {}, "velocities": {}}
    kind, t = None, None
    for line in text.splitlines():
        m = re.match(r"\s*(displacements|velocities) .* and time\s+(\S+)", line)
        if m:
            kind, t = m.group(1), float(m.group(2))
            continue
        tok = line.split()
        if kind and len(tok) == 4 and tok[0].isdigit():
            series[kind].setdefault(t, {})[int(tok[0])] = np.array([float(x) for x in tok[1:]])
    del result
    times = sorted(series["displacements"])
    u = np.array([series["displacements"][t][ref] for t in times])
    phi = np.array([series["displacements"][t][rot] for t in times])
    v = np.array([series["velocities"][t][ref] for t in times])
    w = np.array([series["velocities"][t][rot] for t in times])
    return np.array(times), {"u": u, "phi": phi, "v": v, "w": w}


def main():
    names = {g: [f"tip.{g}[{i}]" for i in (1, 2, 3)] for g in ("u", "phi", "v", "w")}
    outputs = [n for g in names.values() for n in g]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        split_fmu, split_report, deck = build(tmp, all_dynamic=False)
        all_fmu, all_report, _ = build(tmp, all_dynamic=True)
        print(f"L-beam: {split_report['dynamic_modes']} of {split_report['order']} modes dynamic, cutoff "
              f"{split_report['dynamic_cutoff_hz']:.1f} Hz; reduced modes above it "
              f"{[round(f) for f in split_report['accuracy']['reduced_hz'][split_report['dynamic_modes']:]]} Hz")
        times, ref = calculix_history(deck, tmp / "ccx")
        assert len(times) == int(round(T_END / H_CCX)), f"{len(times)} CalculiX increments"
        k = np.round(times / H_FMU).astype(int)
        runs = {"split (default)": fmu_history(split_fmu, outputs),
                "all modes dynamic": fmu_history(all_fmu, outputs)}
        worst = {}
        print(f"force step {FORCE} N along z at the tip, {T_END * 1e3:g} ms; error relative to the "
              "swing of each output vector, largest / RMS over the run, vs CalculiX *DYNAMIC")
        for label, hist in runs.items():
            cells, rms_all = [], []
            for j, (g, cols) in enumerate(names.items()):
                ours = hist[k][:, 3 * j:3 * j + 3]
                theirs = ref[g]
                assert ours.shape == theirs.shape, (ours.shape, theirs.shape)
                swing = np.abs(theirs).max()
                err = np.linalg.norm(ours - theirs, axis=1) / swing
                cells.append(f"{g} {err.max():.2e}/{np.sqrt(np.mean(err**2)):.2e}")
                rms_all.append(np.sqrt(np.mean(err**2)))
            worst[label] = rms_all
            print(f"  {label:18s} " + "   ".join(cells))
        split, every = worst["split (default)"], worst["all modes dynamic"]
        ok = all(s <= 1.05 * a for s, a in zip(split, every))
        print("the split is " + ("at least as accurate" if ok else "LESS accurate")
              + " as every mode dynamic in every output's RMS error")
        return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
