"""The FMU's linux64 binary loads on old Linux distributions: every glibc symbol version the
packaged .so needs is at most GLIBC_2.17 (`cargo xtask runtime` links fmu-runtime with zig against
glibc 2.17 when zig and cargo-zigbuild are there, and fmu-builder embeds it; tests/run.sh sets both
up and runs it before its first cargo build). Read with binutils
(`readelf --version-info`, `objdump -T`), independently of the builder. In CI (CI set) a native
binary fails the test; elsewhere it is skipped with the reason."""

import os
import re
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from conftest import BUILDER, EXAMPLES, run_builder

# Rust's own minimum for x86_64-unknown-linux-gnu (RHEL/CentOS 7); RHEL/Rocky 8 has 2.28,
# Ubuntu 20.04 2.31, Debian 11 2.31
BASELINE = (2, 17)


def version_tuple(name):
    """GLIBC_2.3.4 -> (2, 3, 4)."""
    return tuple(int(p) for p in name.removeprefix("GLIBC_").split("."))


def glibc_versions_readelf(so):
    """The GLIBC_* versions of the .so's version-needs section (what the dynamic loader checks)."""
    out = subprocess.run(["readelf", "--version-info", "-W", str(so)], capture_output=True, text=True,
                         check=True).stdout
    needs = out.split("Version needs section", 1)
    assert len(needs) == 2, f"readelf shows no version needs:\n{out}"
    return set(re.findall(r"Name: (GLIBC_[0-9.]+)", needs[1]))


def glibc_versions_objdump(so):
    """The GLIBC_* versions of the .so's dynamic symbols, with the symbols needing each."""
    out = subprocess.run(["objdump", "-T", str(so)], capture_output=True, text=True, check=True).stdout
    symbols = {}
    for line in out.splitlines():
        m = re.search(r"\(?(GLIBC_[0-9.]+)\)?\s+(\S+)$", line)
        if m:
            symbols.setdefault(m.group(1), []).append(m.group(2))
    return symbols


def builder_kind():
    """What the builder says of its linux64 runtime (`--version`: the kind `cargo xtask runtime`
    recorded, passed on by fmu-builder/build.rs)."""
    return subprocess.run([str(BUILDER), "--version"], capture_output=True, text=True, check=True).stdout.strip()


@pytest.fixture(scope="module")
def packaged_so(beam, tmp_path_factory):
    path, _, _ = beam
    with zipfile.ZipFile(path) as z:
        so = tmp_path_factory.mktemp("portable") / "Beam.so"
        so.write_bytes(z.read("binaries/linux64/Beam.so"))
    return so


def test_linux64_binary_needs_at_most_glibc_2_17(packaged_so):
    kind = builder_kind()
    by_readelf = glibc_versions_readelf(packaged_so)
    by_objdump = glibc_versions_objdump(packaged_so)
    print(f"\n{kind}")
    print("readelf --version-info:", ", ".join(sorted(by_readelf, key=version_tuple)))
    for v in sorted(by_objdump, key=version_tuple):
        print(f"objdump -T {v}: {', '.join(sorted(by_objdump[v]))}")
    assert by_readelf, "no GLIBC version needed at all: not a glibc binary?"
    # both tools read the same table: a version one of them misses would be a parsing slip here
    assert set(by_objdump) == by_readelf
    too_new = sorted((v for v in by_readelf if version_tuple(v) > BASELINE), key=version_tuple)
    if too_new and "native" in kind and not os.environ.get("CI"):
        pytest.skip(f"the builder embeds a native runtime ({kind}): zig or cargo-zigbuild was missing when it "
                    f"was built (see its build warning; bash tests/run.sh sets both up); needs {', '.join(too_new)}")
    assert not too_new, (f"{kind}: the linux64 binary needs {', '.join(too_new)} "
                         f"({', '.join(s for v in too_new for s in by_objdump.get(v, []))}), newer than GLIBC_2.17")
    assert "portable" in kind, kind


def test_linux64_binary_links_only_glibc(packaged_so):
    """No library beyond glibc's own (a libgcc_s or libstdc++ would bring its own version floor)."""
    out = subprocess.run(["readelf", "-d", str(packaged_so)], capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", out))
    print("\nNEEDED:", ", ".join(sorted(needed)))
    glibc = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1", "ld-linux-x86-64.so.2"}
    kind = builder_kind()
    # rustc links a native cdylib against libgcc_s (unwinding); zig's link does not need it
    if not needed <= glibc and "native" in kind and not os.environ.get("CI"):
        pytest.skip(f"the builder embeds a native runtime ({kind.splitlines()[0]}), which links "
                    f"{', '.join(sorted(needed - glibc))}: see test_linux64_binary_needs_at_most_glibc_2_17")
    assert needed and needed <= glibc, needed - glibc


def test_native_runtime_is_announced(tmp_path):
    """A natively linked runtime is said loudly, with the glibc it needs and the way to the
    portable one: by `--version` and after every FMU's summary; a portable one is not warned of."""
    kind = builder_kind()
    proc = run_builder([EXAMPLES / "beam.json", "-o", tmp_path / "Beam.fmu"])
    warning = "warning: the FMU's linux64 binary is linked natively"
    print(f"\n{kind}")
    if "native" in kind.splitlines()[0]:
        assert re.search(r"^warning: .*GLIBC_2\.\d+.*tests/run\.sh --setup-only", kind, re.MULTILINE), kind
        assert warning in proc.stderr, proc.stderr
    else:
        assert "warning" not in kind, kind
        assert warning not in proc.stderr, proc.stderr


def test_portable_fmu_validates_and_simulates(beam):
    path = str(beam[0])
    assert validate_fmu(path) == []
    for kind in ["ModelExchange", "CoSimulation"]:
        res = simulate_fmu(path, fmi_type=kind, stop_time=0.05, output_interval=1e-3,
                           start_values={"tip.f[3]": 10.0}, output=["tip.u[3]"])
        assert np.all(np.isfinite(res["tip.u[3]"])) and res["tip.u[3]"][-1] != 0.0
