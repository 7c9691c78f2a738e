"""The FMU's runtime is built once, by `cargo xtask runtime`, and fmu-builder/build.rs only embeds
it (docs/PLATFORMS.md): the build script runs no cargo and no other program, refuses a runtime
that is missing, not a runtime, stale or (under FMU_RUNTIME_PORTABLE=require) native, each time
with the command that builds it, and the FMUs carry exactly the binary xtask placed.

The build script's refusals are checked by compiling fmu-builder/build.rs with rustc, as cargo
does, and running it with the environment cargo gives it (OUT_DIR, CARGO_MANIFEST_DIR,
FMU_RUNTIME_SO): the same code and messages as in `cargo build`, without making cargo rebuild the
builder afterwards (a build script run under another environment recompiles the crate, some
minutes)."""

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from conftest import ROOT

BUILD_RS = ROOT / "fmu-builder" / "build.rs"
TARGET = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
# where `cargo xtask runtime` places the runtime and its record (fmu-builder/build/runtime_stamp.rs)
RUNTIME_DIR = TARGET / "fmu-runtime"
RUNTIME_SO = RUNTIME_DIR / "libfmu_runtime.so"
RUNTIME_INFO = RUNTIME_DIR / "runtime.info"
COMMAND = "cargo xtask runtime"


def rust_without_comments(path):
    """The Rust source with its comments removed (they may name cargo freely)."""
    text = path.read_text()
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def build_script_sources():
    """build.rs and every file it includes with #[path]."""
    sources = [BUILD_RS]
    for rel in re.findall(r'#\[path\s*=\s*"([^"]+)"\]', BUILD_RS.read_text()):
        sources.append(BUILD_RS.parent / rel)
    return sources


def test_the_build_script_runs_no_cargo_and_no_program():
    sources = build_script_sources()
    assert len(sources) >= 2, sources
    for path in sources:
        code = rust_without_comments(path)
        for word in ["Command", "process::", "\"cargo\"", "var(\"CARGO\")", "var_os(\"CARGO\")", "\"zigbuild\""]:
            assert word not in code, f"{path.relative_to(ROOT)} uses {word}: the runtime is built by {COMMAND}, " \
                                     "never inside the builder's build"
    manifest = (ROOT / "fmu-builder" / "Cargo.toml").read_text()
    assert "[build-dependencies]" not in manifest, "the build script needs nothing beyond std"


@pytest.fixture(scope="module")
def build_script(tmp_path_factory):
    """fmu-builder/build.rs compiled as cargo compiles it (std only)."""
    exe = tmp_path_factory.mktemp("build-script") / "build-script-build"
    proc = subprocess.run(["rustc", "--edition", "2024", "--crate-name", "build_script_build", "--crate-type", "bin",
                           "--cap-lints", "warn", "-o", str(exe), str(BUILD_RS)], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    return exe


def run_build_script(exe, manifest_dir, out_dir, **env):
    """Run the build script with cargo's variables; its instructions and errors."""
    out_dir.mkdir(parents=True, exist_ok=True)
    base = {k: v for k, v in os.environ.items() if not k.startswith("FMU_RUNTIME_")}
    base.update({"CARGO_MANIFEST_DIR": str(manifest_dir), "OUT_DIR": str(out_dir)})
    base.update({k: str(v) for k, v in env.items()})
    proc = subprocess.run([str(exe)], capture_output=True, text=True, env=base, timeout=120)
    assert proc.returncode == 0, f"the build script should report through cargo::error, not crash:\n{proc.stderr}"
    errors = [line.removeprefix("cargo::error=") for line in proc.stdout.splitlines()
              if line.startswith("cargo::error=")]
    return proc.stdout, errors


def a_target_folder(tmp_path, runtime_files=None):
    """A target folder as cargo makes one (CACHEDIR.TAG at its root), with the given files in
    its fmu-runtime/; the OUT_DIR of fmu-builder's build inside it."""
    target = tmp_path / "target"
    (target / "fmu-runtime").mkdir(parents=True)
    (target / "CACHEDIR.TAG").write_text("Signature: 8a477f597d28d172789f06886806bc55\n")
    for name, data in (runtime_files or {}).items():
        (target / "fmu-runtime" / name).write_bytes(data)
    return target / "release" / "build" / "fmu-builder-0123456789abcdef" / "out"


def a_workspace_without_runtime(tmp_path):
    """A source tree like this one (fmu-builder beside fmu-runtime and fmi2), nothing built."""
    ws = tmp_path / "ws"
    for rel in ["Cargo.toml", "Cargo.lock", "fmi2/Cargo.toml", "fmu-runtime/Cargo.toml", "fmu-runtime/build.rs"]:
        (ws / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / rel, ws / rel)
    for rel in ["fmi2/src", "fmu-runtime/src"]:
        shutil.copytree(ROOT / rel, ws / rel)
    (ws / "fmu-builder").mkdir()
    return ws


@pytest.fixture(scope="module")
def built_runtime():
    """The runtime and record `cargo xtask runtime` placed (tests/run.sh runs it first)."""
    if not (RUNTIME_SO.is_file() and RUNTIME_INFO.is_file()):
        pytest.skip(f"no runtime in {RUNTIME_DIR}: run {COMMAND}")
    return RUNTIME_SO.read_bytes(), RUNTIME_INFO.read_text()


def record_field(info, key):
    return re.search(rf"^{key}=(.*)$", info, re.M).group(1)


def test_a_missing_prebuilt_runtime_is_refused_with_the_way_out(build_script, tmp_path):
    missing = tmp_path / "nowhere" / "libfmu_runtime.so"
    stdout, errors = run_build_script(build_script, ROOT / "fmu-builder", tmp_path / "out", FMU_RUNTIME_SO=missing)
    print("\n" + "\n".join(errors))
    assert len(errors) == 1, stdout
    assert f"FMU_RUNTIME_SO={missing}" in errors[0] and "No such file" in errors[0], errors[0]
    assert COMMAND in errors[0], errors[0]
    assert "rustc-env" not in stdout and not (tmp_path / "out" / "fmu_runtime.so").exists()


def test_no_runtime_built_yet_names_the_command_that_builds_it(build_script, tmp_path):
    ws = a_workspace_without_runtime(tmp_path)
    out_dir = a_target_folder(tmp_path)
    stdout, errors = run_build_script(build_script, ws / "fmu-builder", out_dir)
    print("\n" + "\n".join(errors))
    assert len(errors) == 1, stdout
    assert errors[0].startswith("no fmu-runtime binary to embed"), errors[0]
    assert f"`{COMMAND}`" in errors[0] and "cargo xtask build" in errors[0], errors[0]
    # both places it looked: the build's target folder and the workspace's target/
    assert str(tmp_path / "target" / "fmu-runtime" / "libfmu_runtime.so") in errors[0], errors[0]
    assert str(ws / "target" / "fmu-runtime" / "libfmu_runtime.so") in errors[0], errors[0]


def test_a_file_that_is_no_runtime_is_refused(build_script, tmp_path):
    text = tmp_path / "libfmu_runtime.so"
    text.write_text("not a shared object\n")
    _, errors = run_build_script(build_script, ROOT / "fmu-builder", tmp_path / "out", FMU_RUNTIME_SO=text)
    assert errors == [f"FMU_RUNTIME_SO {text} is no fmu-runtime binary: it is not an ELF file "
                      "(a 64-bit ELF shared object exporting fmi2Instantiate is needed)"], errors


def test_the_runtime_of_the_target_folder_is_embedded_with_its_kind(build_script, built_runtime, tmp_path):
    so, info = built_runtime
    out_dir = a_target_folder(tmp_path, {"libfmu_runtime.so": so, "runtime.info": info.encode()})
    stdout, errors = run_build_script(build_script, ROOT / "fmu-builder", out_dir)
    assert errors == [], errors
    assert f"cargo:rustc-env=FMU_RUNTIME_LINUX64={record_field(info, 'kind')}" in stdout.splitlines(), stdout
    assert f"cargo:rustc-env=FMU_RUNTIME_NATIVE_GLIBC={record_field(info, 'native_glibc')}" in stdout.splitlines()
    assert (out_dir / "fmu_runtime.so").read_bytes() == so
    # reruns when the runtime's sources change, so a stale runtime is noticed at the next build
    reruns = {line.removeprefix("cargo:rerun-if-changed=") for line in stdout.splitlines()
              if line.startswith("cargo:rerun-if-changed=")}
    for rel in ["fmu-runtime/src", "fmi2/src", "Cargo.lock", "target/fmu-runtime/runtime.info"]:
        assert any(r.endswith(rel) for r in reruns), (rel, sorted(reruns))


def test_a_stale_runtime_is_refused(build_script, built_runtime, tmp_path):
    """A runtime built from other sources than those of the tree (here: one source file more)."""
    so, info = built_runtime
    ws = a_workspace_without_runtime(tmp_path)
    (ws / "fmu-runtime" / "src" / "lib.rs").write_text((ws / "fmu-runtime" / "src" / "lib.rs").read_text() + "\n")
    out_dir = a_target_folder(tmp_path, {"libfmu_runtime.so": so, "runtime.info": info.encode()})
    stdout, errors = run_build_script(build_script, ws / "fmu-builder", out_dir)
    print("\n" + "\n".join(errors))
    assert len(errors) == 1 and " is stale: " in errors[0], stdout
    assert errors[0].endswith(f"rebuild it with `{COMMAND}`"), errors[0]
    assert "rustc-env" not in stdout


def test_a_runtime_that_is_not_the_recorded_one_is_refused(build_script, built_runtime, tmp_path):
    so, info = built_runtime
    out_dir = a_target_folder(tmp_path, {"libfmu_runtime.so": so + b"\0", "runtime.info": info.encode()})
    _, errors = run_build_script(build_script, ROOT / "fmu-builder", out_dir)
    assert len(errors) == 1 and "is not the binary" in errors[0] and COMMAND in errors[0], errors


def test_require_refuses_a_native_runtime(build_script, built_runtime, tmp_path):
    so, info = built_runtime
    native = re.sub(r"^kind=.*$", "kind=native, glibc of the build machine or newer", info, flags=re.M)
    out_dir = a_target_folder(tmp_path, {"libfmu_runtime.so": so, "runtime.info": native.encode()})
    _, errors = run_build_script(build_script, ROOT / "fmu-builder", out_dir, FMU_RUNTIME_PORTABLE="require")
    assert len(errors) == 1 and errors[0].startswith("FMU_RUNTIME_PORTABLE=require, but"), errors
    _, errors = run_build_script(build_script, ROOT / "fmu-builder", out_dir)
    assert errors == [], errors


def test_xtask_require_without_zig_fails_before_building(tmp_path):
    """FMU_RUNTIME_PORTABLE=require: no zig, no runtime (and the one in place stays as it was)."""
    before = RUNTIME_INFO.read_bytes() if RUNTIME_INFO.exists() else None
    env = {**os.environ, "FMU_RUNTIME_PORTABLE": "require", "FMU_RUNTIME_ZIG": str(tmp_path / "no-zig")}
    proc = subprocess.run(["cargo", "xtask", "runtime"], cwd=ROOT, capture_output=True, text=True, env=env,
                          timeout=1200)
    print("\n" + proc.stderr.strip())
    assert proc.returncode != 0
    assert "FMU_RUNTIME_PORTABLE=require, but the runtime cannot be built portable" in proc.stderr, proc.stderr
    assert f"FMU_RUNTIME_ZIG={tmp_path / 'no-zig'}: `zig version` fails" in proc.stderr, proc.stderr
    assert (RUNTIME_INFO.read_bytes() if RUNTIME_INFO.exists() else None) == before


def test_the_fmu_carries_the_runtime_xtask_built(beam, built_runtime):
    """One runtime: the FMU's linux64 binary is, byte for byte, the file `cargo xtask runtime`
    placed, and the builder says the kind recorded beside it."""
    if os.environ.get("FMU_RUNTIME_SO"):
        pytest.skip("FMU_RUNTIME_SO is set: the builder embeds that file")
    so, info = built_runtime
    with zipfile.ZipFile(beam[0]) as z:
        packaged = z.read("binaries/linux64/Beam.so")
    assert packaged == so, "the builder embeds another runtime than the one in target/fmu-runtime"
    from test_portable import builder_kind
    assert f"(linux64 runtime: {record_field(info, 'kind')})" in builder_kind()
