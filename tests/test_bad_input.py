"""Bad input files: each gets a clear error naming the file and the field, a non-zero exit
status, and never a panic."""

import copy
import json

import pytest

from conftest import EXAMPLES, run_builder

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
    ("stiffening on a free body",
     lambda s: (set_path(s, ["flanges", 0, "role"], "force"), s.update(scene={"geometric_stiffening": True})),
     ["scene.geometric_stiffening", "mounted"]),
    ("unknown element", lambda s: set_path(s, ["geometry", "element"], "tet4"), ["geometry.element"]),
    ("negative damping", lambda s: set_path(s, ["damping", "alpha"], -1.0), ["damping.alpha"]),
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


def test_missing_file_is_named(tmp_path):
    proc = run_builder([tmp_path / "nope.json", "-o", tmp_path / "x.fmu"], check=False)
    assert proc.returncode == 1 and "nope.json" in proc.stderr and "panicked" not in proc.stderr
