"""Bad input files: each gets a clear error naming the file and the field, a non-zero exit
status, and never a panic."""

import copy
import json
import re
import zipfile

import numpy as np

import pytest

from conftest import EXAMPLES, run_builder
from meshes import BoxMesh

BASE = json.loads((EXAMPLES / "beam.json").read_text())
BASE["geometry"]["boxes"][0]["elements"] = [10, 1, 1]  # small: these runs must fail fast anyway


def variant(change):
    spec = copy.deepcopy(BASE)
    change(spec)
    return spec


def set_path(spec, path, value):
    node = spec
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value


CASES = [
    ("malformed JSON", None, ["not valid JSON", "line"]),
    ("unknown field", lambda s: s["material"].update(colour="red"), ["material", "colour"]),
    ("E = 0", lambda s: set_path(s, ["material", "E"], 0.0), ["material.E"]),
    ("E < 0", lambda s: set_path(s, ["material", "E"], -2e11), ["material.E"]),
    ("nu = 0.5", lambda s: set_path(s, ["material", "nu"], 0.5), ["material.nu"]),
    ("nu = -1", lambda s: set_path(s, ["material", "nu"], -1.0), ["material.nu"]),
    ("degenerate box", lambda s: set_path(s, ["geometry", "boxes", 0, "max"], [1.0, -0.005, 0.01]),
     ["geometry.boxes[0]", "degenerate"]),
    ("flange selecting no node",
     lambda s: set_path(s, ["flanges", 1, "nodes"], {"plane": {"point": [2.0, 0, 0], "normal": [1, 0, 0]}}),
     ["flanges[1].nodes", "selects no node"]),
    ("collinear flange nodes",
     lambda s: set_path(s, ["flanges", 1, "nodes"], {"plane": {"point": [1.0, 0, 0.01], "normal": [1, 0, 1]}}),
     ["flanges[1].nodes", "non-collinear"]),
    ("flanges sharing nodes",
     lambda s: set_path(s, ["flanges", 1, "nodes"], {"plane": {"point": [0.0, 0, 0], "normal": [1, 0, 0]}}),
     ["flanges[1].nodes", "shares"]),
    ("two mounts", lambda s: set_path(s, ["flanges", 1, "role"], "motion"), ["flanges[1].role", "second"]),
    # distributing flanges
    ("weights on a rigid flange", lambda s: s["flanges"][1].update(weights="area"),
     ["flanges[1].weights", "distributing"]),
    ("unknown coupling", lambda s: s["flanges"][1].update(coupling="rbe3"),
     ["flanges[1].coupling", "distributing"]),
    ("area weights on an inner cross-section",
     lambda s: s["flanges"][1].update(coupling="distributing", weights="area",
                                      nodes={"plane": {"point": [0.5, 0, 0], "normal": [1, 0, 0]}}),
     ["flanges[1].weights", "no face of the part's surface", "uniform"]),
    ("stiffening on a free body",
     lambda s: (set_path(s, ["flanges", 0, "role"], "force"), s.update(scene={"geometric_stiffening": True})),
     ["scene.geometric_stiffening", "mounted"]),
    ("unknown element", lambda s: set_path(s, ["geometry", "element"], "tet4"), ["geometry.element"]),
    ("negative damping", lambda s: set_path(s, ["damping", "alpha"], -1.0), ["damping.alpha"]),
    ("negative stop time", lambda s: s.update(experiment={"stop_time": -1.0}), ["experiment.stop_time"]),
    ("tolerance 1", lambda s: s.update(experiment={"tolerance": 1.0}), ["experiment.tolerance"]),
    ("step longer than the run", lambda s: s.update(experiment={"stop_time": 0.1, "step_size": 0.5}),
     ["experiment.step_size", "longer than experiment.stop_time"]),
    ("unknown experiment field", lambda s: s.update(experiment={"solver": "euler"}), ["experiment", "solver"]),
    # found by fuzzing: each used to abort, hang, print a Debug dump or build an FMU of NaNs
    ("huge box", lambda s: set_path(s, ["geometry", "boxes", 0, "elements"], [100000] * 3),
     ["geometry.boxes[0].elements", "GiB", "available", "fewer elements"]),
    ("long huge box, Krylov, mount only",
     lambda s: (set_path(s, ["geometry", "boxes", 0, "elements"], [100000, 10, 10]), s["flanges"].pop(),
                s.update(reduction={"method": "krylov", "real_expansion_points": [1e-9]})),
     ["geometry.boxes[0].elements", "GiB", "fewer elements"]),
    ("second box touching nothing",
     lambda s: s["geometry"]["boxes"].append({"min": [2, 0, 0], "max": [3, 0.01, 0.02], "elements": [4, 1, 1]}),
     ["geometry.boxes", "not held by the mount", "base", "[2.0, 0.0, 0.0]"]),
    ("second box joined at an edge only (a hinge)",
     lambda s: (s["geometry"]["boxes"].append({"min": [1, 0.005, -0.01], "max": [1.1, 0.015, 0.01], "elements": [1, 1, 1]}),
                set_path(s, ["flanges", 1, "nodes"], {"box_face": {"box": 1, "face": "+x"}})),
     ["geometry", "not positive definite", "fails at"]),
    ("free body whose second box hangs on an edge",
     lambda s: (s["geometry"]["boxes"].append({"min": [1, 0.005, -0.01], "max": [1.1, 0.015, 0.01], "elements": [1, 1, 1]}),
                set_path(s, ["flanges", 1, "nodes"], {"box_face": {"box": 1, "face": "+x"}}),
                set_path(s, ["flanges", 0, "role"], "force")),
     ["geometry", "without deforming", "mechanism"]),
    ("free body of two pieces",
     lambda s: (s["geometry"]["boxes"].append({"min": [2, 0, 0], "max": [3, 0.01, 0.02], "elements": [4, 1, 1]}),
                set_path(s, ["flanges", 0, "role"], "force")),
     ["geometry.boxes", "separate bodies"]),
    ("free body without flanges or modes",
     lambda s: (s.update(flanges=[]), set_path(s, ["reduction", "modes"], 0)), ["reduction.modes", "no shape"]),
    ("free body with modes 0",
     lambda s: (set_path(s, ["flanges", 0, "role"], "force"), set_path(s, ["reduction", "modes"], 0)),
     ["reduction.modes", "free-floating", "no frequency range", "\"motion\" flange"]),
    ("E = rho = 1e-300", lambda s: s["material"].update(E=1e-300, rho=1e-300), ["material.E", "outside"]),
    ("rho in t/mm^3", lambda s: set_path(s, ["material", "rho"], 7.85e-9), ["material.rho", "t/mm^3"]),
    ("nu = 0.4999999999", lambda s: set_path(s, ["material", "nu"], 0.4999999999), ["material.nu", "outside"]),
    ("alpha = beta = 1e300", lambda s: s["damping"].update(alpha=1e300, beta=1e300), ["damping.alpha", "outside"]),
    ("beta = 1e300", lambda s: set_path(s, ["damping", "beta"], 1e300), ["damping.beta", "outside"]),
    ("modal ratio 1e300", lambda s: set_path(s, ["damping", "modal_ratio"], 1e300), ["damping.modal_ratio", "critical"]),
    ("modal band ratio 1e300", lambda s: set_path(s, ["damping", "modal_bands"], [{"below": 100, "ratio": 1e300}]),
     ["damping.modal_bands[0].ratio"]),
    ("selector in millimetres",
     lambda s: set_path(s, ["flanges", 1, "nodes"], {"plane": {"point": [1000.0, 0, 0], "normal": [1, 0, 0]}}),
     ["flanges[1].nodes", "selects no node", "spans [0.0, -0.005, -0.01] to [1.0, 0.005, 0.01]"]),
    ("collinear selector names the part's extent",
     lambda s: set_path(s, ["flanges", 1, "nodes"], {"plane": {"point": [1.0, 0, 0.01], "normal": [1, 0, 1]}}),
     ["flanges[1].nodes", "on a line", "spans"]),
    ("free body's flange named initial",
     lambda s: (set_path(s, ["flanges", 0, "role"], "force"), set_path(s, ["flanges", 0, "name"], "initial")),
     ["flanges[0].name", "reserved", "initial"]),
    ("flange named body", lambda s: set_path(s, ["flanges", 1, "name"], "body"), ["flanges[1].name", "reserved"]),
    ("element aspect ratio 1e7", lambda s: set_path(s, ["geometry", "boxes", 0, "max"], [1e6, 0.005, 0.01]),
     ["geometry.boxes[0].elements", "aspect ratio"]),
    ("a thousand Krylov points", lambda s: s.update(reduction={"method": "krylov", "expansion_points": list(range(1, 1001))}),
     ["reduction.expansion_points", "factorisation"]),
    ("Krylov basis too large",
     lambda s: s.update(reduction={"method": "krylov", "expansion_points": list(range(10, 200, 10)), "moments": 50}),
     ["reduction.moments", "basis vectors"]),
    ("reference point a light year away", lambda s: s["flanges"][1].update(reference_point=[1e16, 0, 0]),
     ["flanges[1].reference_point", "joint"]),
    # stress recovery (outputs.stress)
    ("stress at a node set that does not exist", lambda s: s.update(outputs={"stress": {"node_sets": ["ROOT"]}}),
     ["outputs.stress.node_sets[0]", "no node set \"ROOT\"", "no node sets"]),
    ("zero hot spots", lambda s: s.update(outputs={"stress": {"hot_spots": 0}}),
     ["outputs.stress.hot_spots", "minimum of 1"]),
    ("negative hot spots", lambda s: s.update(outputs={"stress": {"hot_spots": -3}}),
     ["outputs.stress.hot_spots", "minimum of 1"]),
    ("too many stress points",
     lambda s: s.update(outputs={"stress": {"points": [[0.5, 0.0, 0.0]], "hot_spots": 1000}}),
     ["outputs.stress", "1001 recovery points", "at most 1000"]),
    ("too many hot spots", lambda s: s.update(outputs={"stress": {"hot_spots": 5000}}),
     ["outputs.stress.hot_spots", "1000"]),
    ("stress point not a point", lambda s: s.update(outputs={"stress": {"points": [[0.5, 0.0]]}}),
     ["outputs.stress.points[0]"]),
    # the PETSc back-end: what it does not run, and its settings without choosing it
    ("Krylov expansion point on the petsc back-end",
     lambda s: s.update(reduction={"method": "krylov", "expansion_points": [100.0], "backend": {"kind": "petsc"}}),
     ["reduction.expansion_points", "s = 0 only", "in process"]),
    ("order selection by tolerance on the petsc back-end",
     lambda s: (s.update(scene={"band": [0, 500], "tolerance": 1e-3}),
                set_path(s, ["reduction", "backend"], {"kind": "petsc"})),
     ["scene.tolerance", "reduction.modes"]),
    ("petsc settings without the petsc back-end",
     lambda s: set_path(s, ["reduction", "backend"], {"kind": "in_process", "launcher": "srun"}),
     ["reduction.backend", "petsc"]),
    ("zero MPI ranks", lambda s: set_path(s, ["reduction", "backend"], {"kind": "petsc", "ranks": 0}),
     ["reduction.backend.ranks"]),
    ("unknown length unit", lambda s: set_path(s, ["geometry", "length_unit"], "km"),
     ["geometry.length_unit", '"km"', '"m", "cm", "mm", "in", "ft"']),
    ("modes above the builder's 1000", lambda s: set_path(s, ["reduction", "modes"], 1500),
     ["reduction.modes", "1500", "maximum of 1000"]),
    ("box far from the origin",
     lambda s: (set_path(s, ["geometry", "boxes", 0, "min"], [1e15, 0, 0]),
                set_path(s, ["geometry", "boxes", 0, "max"], [1e15 + 1, 0.01, 0.02])),
     ["geometry.boxes[0]", "origin"]),
    # a float that becomes a Duration: refused at input (it used to panic in Duration::from_secs_f64)
    ("connect timeout beyond a Duration",
     lambda s: s["reduction"].update(backend={"kind": "petsc", "connect_timeout": 1e19}),
     ["reduction.backend.connect_timeout", "1e+19", "at most 1e6 s"]),
]


@pytest.mark.parametrize("name,change,expected", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_named(tmp_path, name, change, expected):
    path = tmp_path / "bad.json"
    if change is None:
        path.write_text(json.dumps(BASE)[:-20])
    else:
        path.write_text(json.dumps(variant(change), indent=2))
    proc = run_builder([path, "-o", tmp_path / "bad.fmu"], check=False)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "panicked" not in proc.stderr
    assert str(path) in proc.stderr
    for text in expected:
        assert text in proc.stderr, f"{name}: {text!r} not in {proc.stderr!r}"
    assert not (tmp_path / "bad.fmu").exists()


LONG = "x" * 100_000


@pytest.mark.parametrize("where", ["enum value", "string for a number", "unknown key", "huge number"])
def test_a_huge_bad_value_is_quoted_cut(tmp_path, where):
    """A 100 KB value pasted into a field: the message names the field and quotes the value's
    start and length, not all of it."""
    change = {
        "enum value": lambda s: set_path(s, ["reduction", "method"], LONG),
        "string for a number": lambda s: set_path(s, ["material", "E"], LONG),
        "unknown key": lambda s: s["material"].update({LONG: 1}),
        "huge number": lambda s: set_path(s, ["reduction", "modes"], int("9" * 4000)),
    }[where]
    path = tmp_path / "bad.json"
    text = json.dumps(variant(change))
    path.write_text(text)
    proc = run_builder([path, "-o", tmp_path / "bad.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    field = {"enum value": "reduction.method", "string for a number": "material.E", "unknown key": "material.",
             # beyond a double: refused by the JSON reader, which names the line and column
             "huge number": "number out of range at line 1 column"}[where]
    assert field in proc.stderr, proc.stderr[:2000]
    # the file, the field, what was found (60 characters of it) and what is expected fit in a
    # few lines; the 100 KB value took 100 KB per mention before
    assert len(proc.stderr) < 2000, f"{len(proc.stderr)} characters: {proc.stderr[:3000]}"


def test_duplicate_key_is_named_with_its_line(tmp_path):
    """JSON parsers keep the last of two equal keys without a word: the builder refuses them."""
    path = tmp_path / "dup.json"
    text = json.dumps(BASE, indent=2).replace('"E": 200000000000.0,', '"E": 200000000000.0,\n    "E": 200000.0,')
    assert text.count('"E"') == 2
    path.write_text(text)
    line = next(i + 1 for i, l in enumerate(text.splitlines()) if '"E": 200000.0' in l)
    proc = run_builder([path, "-o", tmp_path / "dup.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for expected in [str(path), "material.E", "twice", f"line {line}"]:
        assert expected in proc.stderr, f"{expected!r} not in {proc.stderr!r}"


def test_huge_box_is_refused_at_once(tmp_path):
    """The size estimate comes before any allocation: refused in well under a second."""
    import time
    path = tmp_path / "huge.json"
    path.write_text(json.dumps(variant(lambda s: set_path(s, ["geometry", "boxes", 0, "elements"], [100000] * 3))))
    start = time.monotonic()
    proc = run_builder([path, "-o", tmp_path / "huge.fmu"], check=False)
    assert proc.returncode == 1 and time.monotonic() - start < 5.0, proc.stderr


def test_inverted_element_names_file_and_element_id(tmp_path):
    """An inverted element is named by its id in the mesh file, not by a 0-based index."""
    nodes = [(1, 0, 0, 0), (2, 1, 0, 0), (3, 1, 1, 0), (4, 0, 1, 0), (5, 0, 0, 1), (6, 1, 0, 1), (7, 1, 1, 1),
             (8, 0, 1, 1), (9, 2, 0, 0), (10, 2, 1, 0), (11, 2, 0, 1), (12, 2, 1, 1)]
    deck = ["*NODE"] + [f"{i}, {x}, {y}, {z}" for i, x, y, z in nodes]
    # element 7 is the right, element 42 the mirrored (inverted) node order
    deck += ["*ELEMENT, TYPE=C3D8, ELSET=ALL", "7, 1, 2, 3, 4, 5, 6, 7, 8", "42, 2, 3, 10, 9, 6, 7, 12, 11",
             "*NSET, NSET=BASE", "1, 4, 5, 8", "*NSET, NSET=TIP", "9, 10, 11, 12"]
    (tmp_path / "part.inp").write_text("\n".join(deck) + "\n")
    spec = {"name": "P", "geometry": {"mesh": "part.inp"}, "material": {"E": 2e11, "nu": 0.3, "rho": 7850},
            "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}},
                        {"name": "tip", "role": "force", "nodes": {"node_set": "TIP"}}],
            "reduction": {"modes": 1}}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(spec))
    proc = run_builder([path, "-o", tmp_path / "bad.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for expected in ["part.inp", "element 42", "inverted", "node order"]:
        assert expected in proc.stderr, f"{expected!r} not in {proc.stderr!r}"


def test_missing_file_is_named(tmp_path):
    proc = run_builder([tmp_path / "nope.json", "-o", tmp_path / "x.fmu"], check=False)
    assert proc.returncode == 1 and "nope.json" in proc.stderr and "panicked" not in proc.stderr


def matrix_input(tmp_path):
    """BASE as a part given by its matrices (exported into tmp_path/m), flanges by boxes."""
    small = tmp_path / "small.json"
    small.write_text(json.dumps(BASE))
    run_builder([small, "-o", tmp_path / "small.fmu", "--export-free-free", tmp_path / "m", "-q"])
    spec = copy.deepcopy(BASE)
    spec["geometry"] = {"matrices": {"stiffness": "m/K.mtx", "mass": "m/M.mtx", "dofs": "m/dofs.txt",
                                     "nodes": "m/nodes.txt"}}
    spec.pop("material")
    spec["flanges"] = [{"name": "base", "role": "motion", "nodes": {"box": {"min": [-1, -1, -1], "max": [1e-9, 1, 1]}}},
                       {"name": "tip", "role": "force", "nodes": {"box": {"min": [0.999, -1, -1], "max": [2, 1, 1]}}}]
    return spec


def test_area_weights_from_matrix_input_are_refused(tmp_path):
    """Area weights need the element faces; a part given as matrices has none: refused, naming the
    field and the way out (uniform weights)."""
    spec = matrix_input(tmp_path)
    spec["flanges"][1].update(coupling="distributing", weights="area")
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(spec))
    proc = run_builder([path, "-o", tmp_path / "bad.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr, proc.stderr
    for expected in [str(path), "flanges[1].weights", "matrix input has no elements", "uniform"]:
        assert expected in proc.stderr, f"{expected!r} not in {proc.stderr!r}"
    assert not (tmp_path / "bad.fmu").exists()
    # uniform weights on the same matrices build, and the coupling enters as for the mesh: the
    # same full-model compliance (a consistency check of one constraint for both inputs)
    spec["flanges"][1]["weights"] = "uniform"
    path.write_text(json.dumps(spec))
    run_builder([path, "-o", tmp_path / "matrices.fmu", "-q"])
    meshed = copy.deepcopy(BASE)
    meshed["flanges"] = spec["flanges"]
    (tmp_path / "mesh.json").write_text(json.dumps(meshed))
    run_builder([tmp_path / "mesh.json", "-o", tmp_path / "mesh.fmu", "-q"])
    g = [np.array(json.loads(zipfile.ZipFile(tmp_path / f).read("documentation/report.json"))["accuracy"]["compliance_full"])
         for f in ["matrices.fmu", "mesh.fmu"]]
    assert g[0].shape == g[1].shape == (6, 6)
    # the matrices are the mesh's, written to 17 digits: the two agree to round-off
    assert np.abs(g[0] - g[1]).max() <= 1e-10 * np.abs(g[1]).max()


def test_stress_outputs_from_matrix_input_are_refused(tmp_path):
    """Stresses need the elements; a part given as matrices has none: refused, naming the field."""
    spec = matrix_input(tmp_path)
    spec["outputs"] = {"stress": {"hot_spots": 2}}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(spec))
    proc = run_builder([path, "-o", tmp_path / "bad.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr, proc.stderr
    for expected in [str(path), "outputs.stress", "matrices", "without elements"]:
        assert expected in proc.stderr, f"{expected!r} not in {proc.stderr!r}"
    assert not (tmp_path / "bad.fmu").exists()


# A steel bar 0.2 x 0.02 x 0.03 m of C3D20 elements, the same mesh written in metres and in
# millimetres: held at x = 0 by its node set, a force flange selected by a plane at the tip.
BAR = (0.2, 0.02, 0.03)
STEEL = (2.1e11, 0.3, 7850.0)


def bar_input(tmp_path, unit_scale, name, length_unit=None):
    """The bar's deck with coordinates times `unit_scale` (1: metres, 1000: millimetres) and its
    input; the tip flange's plane is given in the same unit."""
    mesh = BoxMesh("C3D20", [c * unit_scale for c in BAR], (8, 1, 2))
    base = mesh.nodes_where(lambda x: x[0] == 0.0)
    (tmp_path / f"{name}.inp").write_text(mesh.deck({"BASE": base}, material=STEEL))
    spec = {"name": name, "geometry": {"mesh": f"{name}.inp"},
            "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}},
                        {"name": "tip", "role": "force",
                         "nodes": {"plane": {"point": [BAR[0] * unit_scale, 0, 0], "normal": [1, 0, 0]}}}],
            "reduction": {"modes": 4}}
    if length_unit is not None:
        spec["geometry"]["length_unit"] = length_unit
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(spec))
    return path


def build_report(tmp_path, path):
    fmu = tmp_path / (path.stem + ".fmu")
    proc = run_builder([path, "-o", fmu])
    return json.loads(zipfile.ZipFile(fmu).read("documentation/report.json")), proc


def test_a_mesh_in_millimetres_with_its_unit_builds_the_metre_part(tmp_path):
    """geometry.length_unit "mm" scales the mesh and the selectors: the same mass as rho V and
    the same frequencies as the mesh written in metres."""
    metres, _ = build_report(tmp_path, bar_input(tmp_path, 1.0, "BarM"))
    millimetres, proc = build_report(tmp_path, bar_input(tmp_path, 1000.0, "BarMM", "mm"))
    mass = STEEL[2] * BAR[0] * BAR[1] * BAR[2]
    # the mass of a C3D20 mesh of a box is exact to round-off (measured 1.1e-14 relative for both)
    for r in (metres, millimetres):
        assert abs(r["mass"] - mass) <= 1e-13 * mass, (r["mass"], mass)
    f_m, f_mm = np.array(metres["accuracy"]["full_hz"]), np.array(millimetres["accuracy"]["full_hz"])
    assert len(f_m) == len(f_mm) >= 4
    # the coordinates differ by the round-off of scaling by 1e-3 (measured 5.0e-12 relative)
    assert np.abs(f_mm / f_m - 1).max() <= 5e-11, (f_m, f_mm)
    assert [f["slave_nodes"] for f in millimetres["flanges"]] == [f["slave_nodes"] for f in metres["flanges"]]
    assert "warning" not in proc.stderr, proc.stderr


def test_a_mesh_in_millimetres_without_its_unit_is_named_with_its_mass(tmp_path):
    """Read as metres the bar is 1000 times too long each way: the warning states the absurd
    mass and the field that fixes it."""
    path = bar_input(tmp_path, 1000.0, "BarRaw")
    _, proc = build_report(tmp_path, path)
    warning = next(l for l in proc.stderr.splitlines() if "across" in l)
    assert '"geometry": {"length_unit": "mm"}' in warning, warning
    weighs = re.search(r"would weigh ([0-9.e+-]+) kg", warning)
    assert weighs, warning
    mass = STEEL[2] * BAR[0] * BAR[1] * BAR[2] * 1e9
    # printed with four digits
    assert abs(float(weighs.group(1)) - mass) <= 1e-3 * mass, (weighs.group(1), mass)


def test_unreadable_mesh_and_matrix_paths_name_field_path_and_folder(tmp_path):
    """A file that cannot be read is named by its field, its path as resolved and the folder
    relative paths start from."""
    sub = tmp_path / "inputs"
    sub.mkdir()
    spec = {"name": "Missing", "geometry": {"mesh": "meshes/part.inp"},
            "material": {"E": 2e11, "nu": 0.3, "rho": 7850},
            "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}}],
            "reduction": {"modes": 2}}
    path = sub / "in.json"
    path.write_text(json.dumps(spec))
    proc = run_builder([path, "-o", tmp_path / "x.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for text in [str(path), "geometry.mesh", str(sub / "meshes" / "part.inp"),
                 f"relative paths resolve from the input file's folder {sub}", "No such file"]:
        assert text in proc.stderr, f"{text!r} not in {proc.stderr!r}"
    spec["geometry"] = {"matrices": {"stiffness": "K.mtx", "mass": "M.mtx", "dofs": "d.txt", "nodes": "n.txt"}}
    spec.pop("material")
    (sub / "K.mtx").mkdir()
    path.write_text(json.dumps(spec))
    proc = run_builder([path, "-o", tmp_path / "x.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for text in ["geometry.matrices.stiffness", str(sub / "K.mtx"), "is a folder", str(sub)]:
        assert text in proc.stderr, f"{text!r} not in {proc.stderr!r}"


def save_all_deck(tmp_path, volume):
    """A deck as Gmsh writes it with "save all elements": nodes, two CPS6 triangles of the
    boundary in their own element set, (optionally) the C3D4 volume, and a physical group's
    element set listing the triangles."""
    mesh = BoxMesh("C3D4", (0.1, 0.02, 0.02), (5, 1, 1))
    base = mesh.nodes_where(lambda x: x[0] == 0.0)
    deck = mesh.deck({"BASE": base}, material=STEEL) if volume else "\n".join(
        ["*NODE"] + [f"{n}, {float(x[0])!r}, {float(x[1])!r}, {float(x[2])!r}" for n, x in ((n, mesh.coords[n - 1]) for n in mesh.used)]
        + ["*NSET, NSET=BASE", ", ".join(map(str, base))]) + "\n"
    first = 1000
    tri = mesh.used[:6]
    deck += "*ELEMENT, type=CPS6, ELSET=Surface1\n"
    deck += "".join(f"{first + k}, " + ", ".join(map(str, tri)) + "\n" for k in range(2))
    deck += f"*ELSET, ELSET=PhysicalSurface\n{first}, {first + 1}\n"
    path = tmp_path / "saveall.inp"
    path.write_text(deck)
    spec = {"name": "SaveAll", "geometry": {"mesh": path.name},
            "flanges": [{"name": "base", "role": "motion", "nodes": {"node_set": "BASE"}}],
            "reduction": {"modes": 2}}
    if not volume:
        spec["material"] = {"E": STEEL[0], "nu": STEEL[1], "rho": STEEL[2]}
    (tmp_path / "saveall.json").write_text(json.dumps(spec))
    return tmp_path / "saveall.json", path


def test_surface_elements_of_a_save_all_deck_are_skipped_with_a_warning(tmp_path):
    spec, deck = save_all_deck(tmp_path, volume=True)
    report, proc = build_report(tmp_path, spec)
    expected = (f"warning: skipped 2 surface elements (CPS6) of {deck}: export only volume elements "
                "(Gmsh: uncheck 'save all elements' / use physical groups of the volume)")
    assert expected in proc.stderr, proc.stderr
    # the part is the volume alone: its mass is rho V (C3D4 integrates a box's volume exactly;
    # measured 8.8e-16 relative)
    mass = STEEL[2] * 0.1 * 0.02 * 0.02
    assert abs(report["mass"] - mass) <= 1e-14 * mass, report["mass"]


def test_a_save_all_deck_without_volume_elements_is_refused(tmp_path):
    spec, deck = save_all_deck(tmp_path, volume=False)
    proc = run_builder([spec, "-o", tmp_path / "x.fmu"], check=False)
    assert proc.returncode == 1 and "panicked" not in proc.stderr
    for text in [str(deck), "no volume elements, only 2 surface elements (CPS6)", "uncheck 'save all elements'",
                 "physical groups of the volume", "C3D4"]:
        assert text in proc.stderr, f"{text!r} not in {proc.stderr!r}"
    assert not (tmp_path / "x.fmu").exists()


def test_a_body_without_flanges_builds_as_a_free_floating_body(tmp_path):
    """No flange at all is a valid free body (driven by its initial conditions): it builds, and
    the report says what it is instead of speaking of a mount."""
    path = tmp_path / "free.json"
    path.write_text(json.dumps(variant(lambda s: s.update(flanges=[]))))
    report, proc = build_report(tmp_path, path)
    assert report["flanges"] == []
    assert report["scene"]["body"] == "free-floating body without flanges"
    assert "free-floating body without flanges" in proc.stdout and "mount" not in proc.stdout, proc.stdout
