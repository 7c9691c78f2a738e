"""ModelStructure/InitialUnknowns lists every known an initial value depends on, parameters
included (FMI 2.0: the knowns of Initialization Mode are the inputs and the variables with
initial="exact", parameters among them). Checked the way a host uses the list: change one
parameter before initialization, and every initial unknown whose value moves must list it."""

import json

from fmpy import read_model_description

from conftest import _build, run_builder
from fmu_access import Fmu
from test_large_motion import FREE_BLOCK


def initial_values(path, start):
    f = Fmu(path, "ModelExchange")
    try:
        f.set(**start)
        f.fmu.setupExperiment(startTime=0.0)
        f.fmu.enterInitializationMode()
        f.fmu.exitInitializationMode()
        md = f.md
        names = [u.variable.name for u in md.initialUnknowns]
        reals = [n for n in names if f.var[n].type == "Real"]
        return dict(zip(reals, f.get(*reals)))
    finally:
        f.close()


def declared(md):
    return {u.variable.name: {d.name for d in (u.dependencies or [])} for u in md.initialUnknowns}


def check(path, base, perturbations):
    md = read_model_description(str(path))
    deps = declared(md)
    before = initial_values(path, base)
    moved_total = 0
    for name, value in perturbations.items():
        after = initial_values(path, {**base, name: value})
        assert after.keys() == before.keys()
        moved = [u for u in before if abs(after[u] - before[u]) > 1e-12 * max(1.0, abs(before[u]))]
        moved_total += len(moved)
        undeclared = [u for u in moved if name not in deps[u]]
        print(f"\n{name}: {len(moved)} initial unknowns move")
        assert not undeclared, f"{name} moves {undeclared} but they do not list it"
    # the perturbations must move something, or the check proves nothing
    assert moved_total > 0


def test_mounted_beam_initial_unknowns_list_their_parameters(build_dir):
    path, _, _ = _build("beam.json", build_dir)
    base = {"tip.f[3]": 100.0, "base.a[1]": 1.0, "static_start": True}
    check(path, base, {"g[3]": -9.81, "g[1]": 3.0, "damping.alpha": 5.0, "damping.beta": 0.01,
                       "static_start": False})


def test_free_body_initial_unknowns_list_their_parameters(build_dir):
    spec = build_dir / "FreeBlockInit.json"
    spec.write_text(json.dumps({**FREE_BLOCK, "name": "FreeBlockInit"}))
    path = build_dir / "FreeBlockInit.fmu"
    run_builder([spec, "-o", path])
    base = {"end.f[2]": 1.0}
    check(path, base, {"g[3]": -9.81, "initial.r[1]": 0.5, "initial.v[2]": 1.0, "initial.w[3]": 2.0,
                       "damping.alpha": 5.0})
