"""Fuzzing in CI, short: the FMI call-sequence fuzzer (tests/fuzz/fmi_sequences.py) on the mounted
beam, the spinning T-square and a free-floating beam for about 10 s, and the builder's
command-line fuzzer (tests/fuzz/builder_cli.py: hostile output paths, FIFOs and devices, tiny
models, hostile count and duration fields) for 8 s. The readers' and the
reduced-model loader's fuzz targets are Rust tests (`cargo test`). Long runs: docs/FUZZING.md."""

import re
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def test_fmi_call_sequences(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(HERE / "fuzz" / "fmi_sequences.py"), "--seconds", "10", "--seed", "1",
         "--build-dir", str(tmp_path), "--shrink-seconds", "20"],
        capture_output=True, text=True, timeout=1200)
    print(proc.stdout[-20000:], proc.stderr[-5000:])
    assert proc.returncode == 0, proc.stdout[-20000:]


def test_builder_command_lines():
    proc = subprocess.run(
        [sys.executable, str(HERE / "fuzz" / "builder_cli.py"), "--seconds", "8", "--seed", "1"],
        capture_output=True, text=True, timeout=600)
    print(proc.stdout[-20000:], proc.stderr[-5000:])
    assert proc.returncode == 0, proc.stdout[-20000:]
    # the run did something: hundreds of command lines, some of which built
    cases, built = (int(w) for w in re.search(r"(\d+) command lines, (\d+) built", proc.stdout).groups())
    assert cases > 100 and built > 0, proc.stdout
