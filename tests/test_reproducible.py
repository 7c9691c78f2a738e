"""Reproducible FMUs: the same input and builder give the same bytes when SOURCE_DATE_EPOCH fixes
the generation time (reproducible-builds.org's convention), and a malformed value is refused
with the reason."""

import os
import subprocess
import zipfile

from conftest import BUILDER, EXAMPLES


def build(out, epoch):
    env = dict(os.environ, SOURCE_DATE_EPOCH=epoch)
    return subprocess.run([str(BUILDER), str(EXAMPLES / "beam.json"), "-o", str(out), "-q"],
                          capture_output=True, text=True, env=env, timeout=600)


def test_same_input_gives_the_same_bytes(tmp_path):
    first, second = tmp_path / "a.fmu", tmp_path / "b.fmu"
    assert build(first, "1795000000").returncode == 0
    assert build(second, "1795000000").returncode == 0
    assert first.read_bytes() == second.read_bytes()
    xml = zipfile.ZipFile(first).read("modelDescription.xml").decode()
    # `date -u -d @1795000000` prints 2026-11-18 11:06:40 UTC
    assert 'generationDateAndTime="2026-11-18T11:06:40Z"' in xml


def test_malformed_source_date_epoch_is_refused(tmp_path):
    proc = build(tmp_path / "c.fmu", "yesterday")
    assert proc.returncode != 0 and not (tmp_path / "c.fmu").exists()
    assert "SOURCE_DATE_EPOCH" in proc.stderr and "whole seconds" in proc.stderr, proc.stderr
