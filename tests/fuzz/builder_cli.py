#!/usr/bin/env python3
"""Command-line fuzzer of fmu-builder: random command lines over hostile paths and small models.

Each case gets a fresh folder holding the input, a FIFO, a socket, an existing file, a link to the input, a
folder and an existing FMU, and a command line drawn from them: the input (or the FIFO, a device,
the link, a missing file), `-o`, every export option (--report, --export-inp, --export-vtk,
--export-matrices, --export-free-free) and --platform-binary, each naming one of those, a new
name, or another option's target, with and without --force. The input is a small model (boxes of
1-3 hex8/hex20/hex20r elements per side, mounted or free-floating, 0-30 modes, Craig-Bampton,
modal or Krylov: the tiny models that once failed to build), and in a third of the cases one
count, index, duration or frequency field holds a hostile value (0, -1, 1e300, 2^64, NaN-like
strings, null).

Oracle: no crash, abort or hang (30 s per case); no panic, Rust allocation abort or backtrace in
the output; exit 0 or 1; an error is one "error: " sentence of readable length; the input and
every file not named as an output with --force keeps its bytes (the input even with --force);
a refused build (exit 1) leaves no new output behind unless it says which was written; a build
that succeeds wrote every output it was asked for (the FMU a zip archive). Each distinct
violation is printed once with its command line and input.

    python tests/fuzz/builder_cli.py --seconds 60 --seed 1

Exit status 1 on any violation.
"""

import argparse
import hashlib
import json
import os
import random
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BUILDER = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "fmu-builder"
CASE_TIMEOUT_S = 30

HOSTILE = [0, -1, 1e300, 18446744073709551616, "NaN", "inf", "1e300", None, True]
# (path in the spec, set-up that makes it meaningful)
FIELDS = [
    (["geometry", "boxes", 0, "elements", 0], None),
    (["flanges", 1, "nodes", "box_face", "box"], None),
    (["reduction", "modes"], None),
    (["reduction", "backend", "connect_timeout"], "backend"),
    (["reduction", "backend", "ranks"], "backend"),
    (["outputs", "stress", "hot_spots"], "stress"),
    (["experiment", "stop_time"], "experiment"),
    (["experiment", "step_size"], "experiment"),
    (["reduction", "dynamic_cutoff"], None),
    (["scene", "band", 1], "scene"),
]


def small_model(rng):
    """A small valid model, then perhaps one hostile value."""
    n = [rng.randint(1, 3) for _ in range(3)]
    length = rng.choice([0.1, 1.0])
    spec = {
        "name": "Part",
        "geometry": {"element": rng.choice(["hex8", "hex20", "hex20r"]),
                     "boxes": [{"min": [0, 0, 0], "max": [length, 0.02, 0.03], "elements": n}]},
        "material": {"E": 2.1e11, "nu": 0.3, "rho": 7850},
        "flanges": [
            {"name": "base", "role": rng.choice(["motion", "force"]),
             "nodes": {"box_face": {"box": 0, "face": "-x"}}},
            {"name": "tip", "role": "force", "nodes": {"box_face": {"box": 0, "face": "+x"}}},
        ],
    }
    method = rng.choice(["craig_bampton", "modal", "krylov"])
    if method == "krylov":
        spec["reduction"] = {"method": "krylov", "expansion_points": [0.0], "moments": rng.randint(1, 3)}
    else:
        spec["reduction"] = {"method": method, "modes": rng.randint(0, 30)}
    if rng.random() < 0.3:
        path, setup = rng.choice(FIELDS)
        if setup == "backend":
            spec["reduction"]["backend"] = {"kind": "in_process", "ranks": 2, "connect_timeout": 10}
        elif setup == "stress":
            spec["outputs"] = {"stress": {"hot_spots": 1}}
        elif setup == "experiment":
            spec["experiment"] = {"stop_time": 1, "step_size": 1e-3}
        elif setup == "scene":
            spec["scene"] = {"band": [0, 100]}
        node = spec
        for key in path[:-1]:
            if isinstance(key, str):
                node = node.setdefault(key, {})
            else:
                node = node[key]
        node[path[-1]] = rng.choice(HOSTILE)
    return spec


def digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else None


def snapshot(folder):
    return {p: digest(p) for p in folder.rglob("*") if p.is_file() and not p.is_symlink()}


def make_case(rng, folder):
    """Writes the case's files; returns (argv, outputs named, force)."""
    spec = small_model(rng)
    (folder / "part.json").write_text(json.dumps(spec, indent=1))
    os.mkfifo(folder / "pipe")
    (folder / "old.txt").write_text("an existing file\n")
    (folder / "Old.fmu").write_bytes(b"PK\x05\x06" + b"\0" * 18)
    (folder / "dir").mkdir()
    os.symlink(folder / "part.json", folder / "link")
    # a socket, not /dev/null: a lost check would rename the FMU over whatever stands here
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(folder / "sock"))
    sock.close()
    pool = ["part.json", "link", "pipe", "sock", "old.txt", "Old.fmu", "dir", ".", "missing/x"]

    def target(new_name):
        return rng.choice(pool + [new_name] * 16)

    inputs = ["part.json"] * 8 + ["link", "pipe", "/dev/zero", "missing.json", "dir"]
    argv = [rng.choice(inputs)]
    outputs = {}
    if rng.random() < 0.8:
        outputs["-o"] = target("B.fmu")
    for option, new in [("--report", "r.json"), ("--export-inp", "d.inp"), ("--export-vtk", "v.vtk"),
                        ("--export-matrices", "mm"), ("--export-free-free", "ff")]:
        if rng.random() < 0.25:
            outputs[option] = target(new) if rng.random() < 0.8 else outputs.get("-o", "B.fmu")
    for option, value in outputs.items():
        argv += [option, value]
    if rng.random() < 0.1:
        argv += ["--platform-binary", "win64=" + rng.choice(["pipe", "/dev/zero", "dir", "old.txt", "part.json"])]
    force = rng.random() < 0.3
    if force:
        argv.append("--force")
    argv.append("-q")
    return argv, outputs, force


def violations_of(proc, folder, before, argv, outputs, force):
    found = []
    err = proc.stderr
    if proc.returncode not in (0, 1):
        found.append(f"exit status {proc.returncode}")
    for bad in ["panicked", "RUST_BACKTRACE", "memory allocation of", "{ ", "Some("]:
        if bad in err:
            found.append(f"stderr holds {bad!r}")
    if proc.returncode == 1 and (not err.startswith("error: ") or len(err) > 4000):
        found.append("an error that is not one readable sentence")
    after = snapshot(folder)
    named = {(folder / v).resolve() for v in outputs.values()}
    for path, old in before.items():
        new = after.get(path)
        if path.name == "part.json" and new != old:
            found.append("the input was changed")
        elif new != old and not (force and path.resolve() in named) and not path.is_relative_to(folder / "dir"):
            # a folder export may write into an existing folder with --force (or fresh files)
            found.append(f"{path.name} was changed without being a --force output")
    created = set(after) - set(before)
    if proc.returncode == 1 and created and "was written" not in err:
        found.append(f"refused, yet wrote {sorted(p.name for p in created)}")
    if proc.returncode == 0:
        fmu = folder / outputs.get("-o", "Part.fmu")
        if not (fmu.is_file() and zipfile.is_zipfile(fmu)):
            found.append("built, but the FMU is not a zip archive")
        for option, value in outputs.items():
            if not (folder / value).exists():
                found.append(f"built, but {option} {value} was not written")
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=30)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if not BUILDER.is_file():
        sys.exit(f"{BUILDER}: build it first (cargo build --release -p fmu-builder)")
    rng = random.Random(args.seed)
    end = time.monotonic() + args.seconds
    cases = built = hangs = 0
    distinct = {}
    while time.monotonic() < end:
        folder = Path(tempfile.mkdtemp(prefix="builder-cli-fuzz-"))
        try:
            argv, outputs, force = make_case(rng, folder)
            before = snapshot(folder)
            try:
                proc = subprocess.run([str(BUILDER), *argv], cwd=folder, capture_output=True, text=True,
                                      timeout=CASE_TIMEOUT_S)
                found = violations_of(proc, folder, before, argv, outputs, force)
                built += proc.returncode == 0
            except subprocess.TimeoutExpired:
                hangs += 1
                found, proc = [f"no answer within {CASE_TIMEOUT_S} s"], None
            cases += 1
            for v in found:
                if v not in distinct:
                    distinct[v] = (argv, (folder / "part.json").read_text(), proc.stderr if proc else "")
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    print(f"{cases} command lines, {built} built, {cases - built - hangs} refused, {hangs} hangs, "
          f"{len(distinct)} distinct violations")
    for v, (argv, spec, err) in distinct.items():
        print(f"\nVIOLATION {v}\n  fmu-builder {' '.join(argv)}\n  stderr: {err.strip()[:600]}\n  input: {json.dumps(json.loads(spec))[:800]}")
    return 1 if distinct else 0


if __name__ == "__main__":
    sys.exit(main())
