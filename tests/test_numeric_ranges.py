"""Every number of the input that becomes a count, an index, a duration or a size (what the
builder allocates, loops over or waits for) is range-checked at input, with the field named: a
sweep of each with 0, -1, 1e300, an integer past 2^64, a non-finite literal and NaN-like strings.
No value panics, hangs or aborts; a value out of range is refused naming its field; the schema's
limits are the builder's (the sweep runs the builder, which checks the schema and then its own
rules, so a value the schema lets through and the code cannot take shows up here)."""

import json
import subprocess

import pytest

from conftest import BUILDER, EXAMPLES

BASE = json.loads((EXAMPLES / "beam.json").read_text())
BASE.pop("$schema")
BASE["geometry"]["boxes"][0]["elements"] = [10, 1, 1]
BASE["reduction"]["modes"] = 2


def with_outputs(spec):
    spec["outputs"] = {"stress": {"points": [[0.5, 0, 0]], "hot_spots": 1}}


def with_krylov(spec):
    spec["reduction"] = {"method": "krylov", "expansion_points": [0.0], "moments": 2}


def with_backend(spec):
    spec["reduction"]["backend"] = {"kind": "in_process", "ranks": 2, "connect_timeout": 30}


def with_experiment(spec):
    spec["experiment"] = {"stop_time": 1, "step_size": 1e-3}


def with_scene(spec):
    spec["scene"] = {"band": [0, 100]}


def with_bands(spec):
    spec["damping"] = {"modal_bands": [{"below": 1000, "ratio": 0.01}]}


# (field as messages name it, how to reach it in the spec, set-up making the field meaningful)
FIELDS = [
    ("geometry.boxes[0].elements[0]", ["geometry", "boxes", 0, "elements", 0], None),
    ("flanges[1].nodes.box_face.box", ["flanges", 1, "nodes", "box_face", "box"], None),
    ("reduction.modes", ["reduction", "modes"], None),
    ("reduction.max_frequency", ["reduction", "max_frequency"], lambda s: s["reduction"].pop("modes")),
    ("reduction.moments", ["reduction", "moments"], with_krylov),
    # frequencies that become shifts and thresholds, not counts: 1e300 Hz means "every mode" (or
    # a Krylov point beyond every mode: its moments are the static shapes') and may build
    ("reduction.expansion_points[0]", ["reduction", "expansion_points", 0], with_krylov),
    ("reduction.dynamic_cutoff", ["reduction", "dynamic_cutoff"], None),
    ("reduction.backend.ranks", ["reduction", "backend", "ranks"], with_backend),
    ("reduction.backend.connect_timeout", ["reduction", "backend", "connect_timeout"], with_backend),
    ("outputs.stress.hot_spots", ["outputs", "stress", "hot_spots"], with_outputs),
    ("experiment.stop_time", ["experiment", "stop_time"], with_experiment),
    ("experiment.step_size", ["experiment", "step_size"], with_experiment),
    ("scene.band[1]", ["scene", "band", 1], with_scene),
    ("damping.modal_bands[0].below", ["damping", "modal_bands", 0, "below"], with_bands),
]

PLACEHOLDER = 7777777.25
# raw JSON text put where the placeholder stands: numbers JSON can hold but no count, index or
# duration can be, and what a hand-edited or generated file holds instead of a number
VALUES = ["0", "-1", "1e300", "18446744073709551616", "1e999", '"NaN"', '"inf"', '"1e300"', "null", "true"]
# refused wherever they stand (0 may be valid: a box index, a band's end, an expansion point)
ALWAYS_REFUSED = set(VALUES) - {"0"}
# fields whose 1e300 (or 2^64) is a frequency above every mode, not a count or a duration
FREQUENCY_THRESHOLDS = {"reduction.expansion_points[0]", "reduction.dynamic_cutoff", "scene.band[1]",
                        "damping.modal_bands[0].below"}


def spec_text(path, setup):
    spec = json.loads(json.dumps(BASE))
    if setup:
        setup(spec)
    node = spec
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = PLACEHOLDER
    return json.dumps(spec)


@pytest.mark.parametrize("field,path,setup", FIELDS, ids=[f[0] for f in FIELDS])
def test_a_count_index_duration_or_size_field_refuses_what_it_cannot_hold(tmp_path, field, path, setup):
    text = spec_text(path, setup)
    for raw in VALUES:
        input_path = tmp_path / "part.json"
        input_path.write_text(text.replace(str(PLACEHOLDER), raw))
        out = tmp_path / "P.fmu"
        proc = subprocess.run([str(BUILDER), input_path, "-o", out, "-q", "--force"], capture_output=True,
                              text=True, timeout=120)
        shown = f"{field} = {raw}: rc {proc.returncode}\n{proc.stderr}"
        # no panic, no abort, no Debug dump: 0 (built) or 1 (refused with a sentence)
        assert proc.returncode in (0, 1), shown
        assert "panicked" not in proc.stderr and "RUST_BACKTRACE" not in proc.stderr, shown
        huge = raw in ("1e300", "18446744073709551616")
        if raw in ALWAYS_REFUSED and not (huge and field in FREQUENCY_THRESHOLDS):
            assert proc.returncode == 1, shown
        if proc.returncode == 1:
            # the field is named: as a path, or (a JSON syntax error: 1e999) by line and column
            named = field in proc.stderr or field.rsplit(".", 1)[-1].split("[")[0] in proc.stderr
            assert named or "line 1 column" in proc.stderr, shown
            assert len(proc.stderr) < 4000, shown
