"""Smoke test of bench/builder_vs_calculix.py (the builder's speed and memory against CalculiX):
the smallest size (about 2e4 DoF, well under a minute) in report-only mode. It must print its
rows and its summary, and its CalculiX frequencies must agree with the builder's full model to
1e-6, the benchmark's own accuracy target (which proves the two solve the same problem). The
speed and memory targets are not checked here: they belong to the long run on a quiet machine."""

import json
import subprocess
import sys

import pytest

from conftest import ROOT

SCRIPT = ROOT / "bench" / "builder_vs_calculix.py"


def test_builder_bench_smallest_size(tmp_path):
    pytest.importorskip("gmsh", reason="Gmsh's Python API (pip install gmsh==4.15.2) meshes the bracket")
    rows_json = tmp_path / "rows.json"
    proc = subprocess.run([sys.executable, str(SCRIPT), "--sizes", "2e4", "--no-targets",
                           "--work", str(tmp_path / "work"), "--json", str(rows_json)],
                          capture_output=True, text=True, timeout=600)
    print(proc.stdout[-6000:])
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = proc.stdout
    for expected in ["builder ", "CalculiX ", "ratio builder/CalculiX", "builder phase profile",
                     "| size | DoF |", "targets:"]:
        assert expected in out, f"{expected!r} missing from the output"
    [row] = json.loads(rows_json.read_text())
    assert 1.5e4 < row["dof"] < 2.5e4, row["dof"]
    assert len(row["ccx_hz"]) == len(row["full_hz"]) == 5
    assert row["max_rel_diff"] <= 1e-6, (row["ccx_hz"], row["full_hz"])
    assert row["builder_wall_s"] > 0 and row["ccx_wall_s"] > 0
    assert row["builder_peak_mib"] > 0 and row["ccx_peak_mib"] > 0
    assert "PASS" in out and "first 5 frequencies" in out
