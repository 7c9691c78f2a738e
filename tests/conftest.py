"""Shared fixtures: build the example FMUs once per test session with the release builder."""

import json
import os
import subprocess
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# CARGO_TARGET_DIR as cargo reads it: a build elsewhere is tested where it was built
BUILDER = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "fmu-builder"
EXAMPLES = ROOT / "examples"


def pytest_configure(config):
    # tests/run.sh deselects these unless asked (-m slow): they build the project from scratch
    config.addinivalue_line("markers", "slow: takes many minutes (a build from scratch); run with -m slow")


def run_builder(args, check=True):
    """Run fmu-builder; returns the CompletedProcess (stdout/stderr as text). A build with -o
    may replace its own earlier output (--force): the tests write into their temporary folders,
    and test_cli.py checks the refusal without it."""
    args = [str(a) for a in args]
    if "-o" in args and "--force" not in args:
        args.append("--force")
    proc = subprocess.run([str(BUILDER), *args], capture_output=True, text=True, timeout=600)
    if check and proc.returncode != 0:
        raise AssertionError(f"fmu-builder {args} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


@pytest.fixture(scope="session")
def build_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fmus")


def _build(example, build_dir):
    out = build_dir / (Path(example).stem + ".fmu")
    proc = run_builder([EXAMPLES / example, "-o", out])
    report = json.loads(zipfile.ZipFile(out).read("documentation/report.json"))
    return out, report, proc.stdout


@pytest.fixture(scope="session")
def beam(build_dir):
    return _build("beam.json", build_dir)


@pytest.fixture(scope="session")
def lbeam(build_dir):
    return _build("l-beam.json", build_dir)
