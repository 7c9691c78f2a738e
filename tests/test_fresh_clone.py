"""A fresh clone, built in the README's order, packages the portable linux64 binary from its
first command on.

The README's first command (`cargo xtask run -- ...`: the runtime, the builder, then the builder
run) comes before its second (`bash tests/run.sh`) sets up zig (the ziglang package in
tests/.venv) and cargo-zigbuild, so on a fresh machine `cargo xtask runtime` fetches both into
the clone's target/tools/ (zig with the machine's pip from PyPI, cargo-zigbuild from crates.io)
and links the FMU's runtime with zig against glibc 2.17 at once. This follows a user on a
machine without the tools: `git clone` of the committed HEAD into a temporary folder, a cargo
home of its own (the registry's cache shared, no installed cargo-zigbuild) and a PATH with the
Rust toolchain's commands but no cargo-zigbuild and no virtual environment; the README's first
command exactly as its first code block writes it; then the set-up part of the second (`bash
tests/run.sh --setup-only`) and the first command again, as a user rebuilds. After each, the FMU
it writes must need at most GLIBC_2.17 (objdump -T, as test_portable.py reads it) and the
builder's `--version` must say "portable".

Slow (a build from scratch in a fresh target folder, cargo-zigbuild compiled, and a fresh
virtual environment from PyPI: a cold release build alone took 37 minutes on a 2-core machine
shared with other builds), so marked `slow`, which tests/run.sh leaves out unless asked for:

    cd tests && .venv/bin/python -m pytest -m slow test_fresh_clone.py
    bash tests/run.sh -m slow -k fresh_clone
"""

import os
import shlex
import shutil
import subprocess
import time
import zipfile
from pathlib import Path

import pytest

from conftest import ROOT
from test_portable import BASELINE, glibc_versions_objdump, version_tuple

pytestmark = pytest.mark.slow

# a build from scratch on a busy 2-core machine takes tens of minutes; a hang must still end
STEP_TIMEOUT = 2 * 3600


def readme_commands():
    """The commands of README.md's first two fenced code blocks (the README starts with its two
    commands, one block each), each as its argument list (comments dropped, as the shell does)."""
    lines = (ROOT / "README.md").read_text().splitlines()
    fences = [i for i, line in enumerate(lines) if line.lstrip().startswith("```")]
    assert len(fences) >= 4, "README.md does not start with two fenced code blocks"
    block = lines[fences[0] + 1:fences[1]] + lines[fences[2] + 1:fences[3]]
    commands = [shlex.split(line, comments=True) for line in block]
    return [c for c in commands if c]


TOOLCHAIN = ["cargo", "rustc", "rustup", "rustfmt", "cargo-fmt", "cargo-clippy", "clippy-driver", "rustdoc"]


def user_env(home):
    """The environment of a user who has just cloned onto a machine without the portable build's
    tools: none of this session's build settings, no Python environment of the tested checkout
    on the PATH (its ziglang would be found), a cargo home of its own under `home` (no
    cargo-zigbuild installed; the registry's cache shared, it only saves downloads), and the
    Rust toolchain's commands from a folder of their own (the folder they come from may hold
    cargo-zigbuild)."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("FMU_RUNTIME_") and k not in ("CARGO_TARGET_DIR", "VIRTUAL_ENV", "CI")}
    venv = (ROOT / "tests" / ".venv").resolve()
    bin_dir, cargo_home = home / "bin", home / "cargo"
    bin_dir.mkdir(parents=True)
    cargo_home.mkdir()
    old_home = Path(os.environ.get("CARGO_HOME", Path.home() / ".cargo"))
    if (old_home / "registry").is_dir():
        (cargo_home / "registry").symlink_to(old_home / "registry")
    for tool in TOOLCHAIN:
        found = shutil.which(tool)
        if found:
            (bin_dir / tool).symlink_to(found)
    path = [p for p in env.get("PATH", "").split(os.pathsep)
            if p and not Path(p).resolve().is_relative_to(venv) and not Path(p).resolve().is_relative_to(ROOT)
            and not (Path(p) / "cargo-zigbuild").exists()]
    env["PATH"] = os.pathsep.join([str(bin_dir), *path])
    env["CARGO_HOME"] = str(cargo_home)
    env.setdefault("RUSTUP_HOME", str(Path.home() / ".rustup"))
    return env


def newest_glibc(fmu, tmp_path):
    """The newest GLIBC symbol version the FMU's linux64 binary needs."""
    with zipfile.ZipFile(fmu) as z:
        names = [n for n in z.namelist() if n.startswith("binaries/linux64/") and n.endswith(".so")]
        assert len(names) == 1, names
        so = tmp_path / Path(names[0]).name
        so.write_bytes(z.read(names[0]))
    versions = glibc_versions_objdump(so)
    assert versions, f"{names[0]}: objdump -T shows no GLIBC symbol version"
    newest = max(versions, key=version_tuple)
    print(f"newest GLIBC version of {names[0]}: {newest} ({', '.join(sorted(versions[newest]))})")
    return newest


def run(argv, clone, env, log):
    """Run a step in the clone; its output goes to the log (a build's output is long)."""
    start = time.monotonic()
    with open(log, "a") as out:
        out.write(f"\n$ {shlex.join(argv)}\n")
        out.flush()
        proc = subprocess.run(argv, cwd=clone, env=env, stdin=subprocess.DEVNULL, stdout=out,
                              stderr=subprocess.STDOUT, timeout=STEP_TIMEOUT)
    seconds = time.monotonic() - start
    print(f"{shlex.join(argv)}: {seconds:.0f} s, exit {proc.returncode}")
    assert proc.returncode == 0, f"{shlex.join(argv)} failed in {clone}; its output is in {log}"
    return seconds


def test_fresh_clone_in_readme_order_packages_portable_binary(tmp_path):
    commands = readme_commands()
    assert len(commands) >= 2 and commands[0][:3] == ["cargo", "xtask", "run"], commands
    first = commands[0]
    setup = next((c for c in commands if c[:2] == ["bash", "tests/run.sh"]), None)
    assert setup is not None, f"README's first two blocks have no `bash tests/run.sh`: {commands}"
    assert "-o" in first, f"the README's first command names no output FMU: {first}"
    fmu = first[first.index("-o") + 1]

    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.strip()
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
    subprocess.run(["git", "checkout", "--quiet", head], cwd=clone, check=True)
    env = user_env(tmp_path / "home")
    log = tmp_path / "fresh-clone.log"
    builder = clone / "target" / "release" / "fmu-builder"
    print(f"\nclone of {head[:12]} in {clone}, log {log}")
    has_zig = subprocess.run(["python3", "-c", "import ziglang"], env=env, capture_output=True).returncode == 0

    # 1. the README's first command, before any set-up: it fetches the tools and is portable
    t_first = run(first, clone, env, log)
    kind_first = subprocess.run([str(builder), "--version"], capture_output=True, text=True,
                                check=True).stdout
    print(f"first build: {kind_first.strip()}")
    text = log.read_text()
    assert "installing cargo-zigbuild" in text, "the first command did not install cargo-zigbuild"
    assert has_zig or "fetching zig" in text, "the first command did not fetch zig"
    assert "portable" in kind_first and "warning" not in kind_first, kind_first
    assert version_tuple(newest_glibc(clone / fmu, tmp_path)) <= BASELINE

    # 2. the set-up part of the README's second command
    t_setup = run([*setup, "--setup-only"], clone, env, log)
    assert (clone / "tests" / ".venv" / "bin" / "python").is_file()

    # 3. the first command again, as the user rebuilds: still portable
    t_again = run(first, clone, env, log)
    kind = subprocess.run([str(builder), "--version"], capture_output=True, text=True, check=True).stdout
    print(f"after the set-up: {kind.strip()}")
    print(f"wall time: first command {t_first:.0f} s, set-up {t_setup:.0f} s, rebuild {t_again:.0f} s")
    assert version_tuple(newest_glibc(clone / fmu, tmp_path)) <= BASELINE
    assert "portable" in kind and "warning" not in kind, kind
