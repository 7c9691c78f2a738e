"""Reductions with many modes stay exact. Consistency checks (reduced model against the full FE
model on the same mesh, both from the builder's report; the physics of these examples is
checked against CalculiX and analytic theory in test_calculix.py and test_beam.py):
- a Galerkin (Rayleigh-Ritz) projection never lowers an eigenvalue: every reduced frequency is
  at or above the full model's of the same index;
- the basis holds the flange loads' static shapes, so the static flange compliance is exact.
Before the dense eigensolver was replaced, the beam with 300 modes had f1 = 8.0900 Hz against
8.1709 Hz, 19 frequencies below the full model's and its compliance off by 1.7e-2."""

import json
import time

import numpy as np
import pytest

from conftest import EXAMPLES, run_builder


def build(tmp_path, example, modes, name):
    spec = json.loads((EXAMPLES / example).read_text())
    spec.pop("$schema", None)
    spec["reduction"] = {"method": "craig_bampton", "modes": modes}
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(spec))
    report_path = tmp_path / f"{name}.report.json"
    run_builder([path, "-o", tmp_path / f"{name}.fmu", "--report", report_path])
    return json.loads(report_path.read_text())


def check_projection(report, example, modes):
    acc = report["accuracy"]
    reduced, full = np.array(acc["reduced_hz"]), np.array(acc["full_hz"])
    assert report["fixed_interface_modes"] == modes
    assert len(reduced) == modes + 6 and len(full) == len(reduced)
    error = (reduced - full) / full
    compliance = acc["compliance_max_relative_error"]
    print(f"\n{example} {modes} modes: f1 {reduced[0]:.9f} vs {full[0]:.9f} Hz, lowest 10 within "
          f"{np.abs(error[:10]).max():.1e}, most negative (reduced - full)/full {error.min():.1e}, "
          f"compliance {compliance:.1e}")
    # reduced >= full up to the eigensolver's tolerance (1e-10 on lambda, 5e-11 on f); measured
    # (reduced - full) / full >= +3e-13 on every build here
    assert error.min() >= -1e-10
    # measured 7e-14 .. 2.6e-13 (the issue asks 1e-9)
    assert compliance < 3e-12
    return np.abs(error[:10]).max()


def test_beam_with_many_modes_keeps_the_projection_exact(tmp_path):
    """12 .. 600 fixed-interface modes of the beam. The lowest ten frequencies converge as the
    basis grows (nested spaces; measured 4.4e-3, 2.0e-5, 2.3e-6, 5.8e-7, 9.6e-8, 3.1e-8, 1.2e-9)
    and are within 1e-6 of the full model's from 150 modes on; below that the difference is the
    reduction's own, not round-off."""
    counts = [12, 50, 100, 150, 200, 300, 600]
    errors = [check_projection(build(tmp_path, "beam.json", m, f"beam{m}"), "beam.json", m) for m in counts]
    assert len(errors) == len(counts)
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert all(e < 1e-6 for m, e in zip(counts, errors) if m >= 150), errors


def test_lbeam_with_200_modes_keeps_the_projection_exact(tmp_path):
    error = check_projection(build(tmp_path, "l-beam.json", 200, "lbeam"), "l-beam.json", 200)
    print(f"lowest ten within {error:.1e}")
    assert error < 3e-7  # measured 2.7e-8


def test_too_many_modes_are_refused_quickly(tmp_path):
    """2000 modes of a 1000-element hex8 bar (12012 DoFs) are refused with the reason and the
    limit, at once; so are more modes than a quarter of a small mesh's DoFs."""
    base = {
        "name": "Bar",
        "geometry": {"element": "hex8", "boxes": [{"min": [0, 0, 0], "max": [1.0, 0.001, 0.001],
                                                   "elements": [1000, 1, 1]}]},
        "material": {"E": 2.0e11, "nu": 0.3, "rho": 7850.0},
        "flanges": [
            {"name": "base", "role": "motion", "nodes": {"box_face": {"box": 0, "face": "-x"}}},
            {"name": "tip", "role": "force", "nodes": {"box_face": {"box": 0, "face": "+x"}}},
        ],
        "reduction": {"method": "craig_bampton", "modes": 2000},
    }
    for elements, modes, expected in (([1000, 1, 1], 2000, "greater than the maximum of 1000"),
                                      ([6, 1, 1], 25, "at most a quarter of the DoFs (21)")):
        spec = dict(base)
        spec["geometry"] = {**base["geometry"], "boxes": [{**base["geometry"]["boxes"][0], "elements": elements}]}
        spec["reduction"] = {"method": "craig_bampton", "modes": modes}
        path = tmp_path / "bar.json"
        path.write_text(json.dumps(spec))
        start = time.monotonic()
        proc = run_builder([path, "-o", tmp_path / "Bar.fmu"], check=False)
        elapsed = time.monotonic() - start
        print(f"\n{modes} modes of {elements}: exit {proc.returncode} after {elapsed:.1f} s: {proc.stderr.strip()}")
        assert proc.returncode != 0 and not (tmp_path / "Bar.fmu").exists()
        assert "reduction.modes" in proc.stderr and "bar.json" in proc.stderr, proc.stderr
        assert expected in proc.stderr, proc.stderr
        assert elapsed < 2  # measured 0.1 s (the builder's start-up; a loaded machine can double it)
