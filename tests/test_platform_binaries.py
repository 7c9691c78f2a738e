"""`--platform-binary PLATFORM=FILE`: runtime binaries built on other platforms, packaged as
binaries/<platform>/<modelIdentifier>.<dll|so|dylib> after the builder checked each one.

CI cannot build fmu-runtime for Windows or macOS (no Rust standard library for those targets
here), so these tests use stand-ins: small C files exporting the 44 fmi2 symbols and the
runtime's build identity, cross-compiled by zig (`python -m ziglang cc -target ... -shared
-nostdlib`; no C runtime, which zig would otherwise compile for minutes for Windows). They
have the format, processor, file type and exports of the real thing, not its code: the FMUs are
run here only through their linux64 binary, the builder's own runtime."""

import os
import re
import struct
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from conftest import run_builder

# a small part: the build takes a second, the packaging is what is tested
SPEC = """{
  "name": "Bar",
  "geometry": { "element": "hex8", "boxes": [ { "min": [0, 0, 0], "max": [0.2, 0.02, 0.02], "elements": [10, 1, 1] } ] },
  "material": { "E": 2.1e11, "nu": 0.3, "rho": 7850 },
  "flanges": [
    { "name": "base", "role": "motion", "nodes": { "box_face": { "box": 0, "face": "-x" } } },
    { "name": "tip", "role": "force", "nodes": { "box_face": { "box": 0, "face": "+x" } } }
  ],
  "reduction": { "method": "craig_bampton", "modes": 2 }
}
"""

STUB_C = r"""
/* A stand-in for fmu-runtime on another platform: the fmi2 symbols and the build identity. */
#ifdef _WIN32
#define EXPORT __declspec(dllexport)
#ifdef STUB_PROGRAM
int wWinMainCRTStartup(void) { return 0; }  /* the entry lld-link looks for without a C runtime */
#else
int __stdcall DllMainCRTStartup(void *module, unsigned reason, void *reserved) { return 1; }
#endif
#else
#define EXPORT __attribute__((visibility("default")))
#endif
#ifdef BUILD_ID
EXPORT const char FMU_RUNTIME_BUILD_ID[] = "FMU_RUNTIME_BUILD_ID=" BUILD_ID;
#endif
"""


def zig_command():
    """`python -m ziglang` of this interpreter (tests/.venv, where tests/run.sh installs it)."""
    probe = subprocess.run([sys.executable, "-m", "ziglang", "version"], capture_output=True, text=True)
    if probe.returncode != 0:
        reason = "zig is missing: pip install ziglang (tests/run.sh installs it into tests/.venv)"
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)
    return [sys.executable, "-m", "ziglang"]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("platforms")
    (d / "bar.json").write_text(SPEC)
    return d


@pytest.fixture(scope="module")
def plain(workdir):
    """The FMU without other binaries; its linux64 .so gives the function list and the identity."""
    out = workdir / "plain.fmu"
    run_builder([workdir / "bar.json", "-o", out, "-q"])
    so = zipfile.ZipFile(out).read("binaries/linux64/Bar.so")
    ids = re.findall(rb"FMU_RUNTIME_BUILD_ID=([\x21-\x7e]+)\x00", so)
    assert len(ids) == 1, ids
    so_path = workdir / "Bar.so"
    so_path.write_bytes(so)
    dynsym = subprocess.run(["objdump", "-T", str(so_path)], capture_output=True, text=True, check=True).stdout
    functions = sorted(set(re.findall(r"\s(fmi2\w+)$", dynsym, re.M)))
    # FMI 2.0's fmi2Functions.h: 25 common, 10 Model Exchange, 9 Co-Simulation functions
    assert len(functions) == 44, functions
    return out, so, functions, ids[0].decode()


@pytest.fixture(scope="module")
def stub(workdir, plain):
    """stub(name, target, omit=(), build_id=<the builder's>, program=False) -> path of a stand-in."""
    zig = zig_command()
    _, _, functions, build_id = plain

    def make(name, target, omit=(), build_id=build_id, program=False):
        source = STUB_C + "".join(f"EXPORT int {f}(void) {{ return 0; }}\n" for f in functions if f not in omit)
        c = workdir / f"{name}.c"
        c.write_text(source)
        out = workdir / name
        cmd = [*zig, "cc", "-target", target, "-nostdlib", "-O1", "-o", str(out), str(c)]
        if not program:
            cmd.append("-shared")
        else:
            cmd.append("-DSTUB_PROGRAM")
        if build_id is not None:
            cmd.append(f'-DBUILD_ID="{build_id}"')
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, f"{' '.join(cmd)}:\n{proc.stderr}"
        return out

    return make


def universal(slices):
    """A universal (fat) Mach-O file of (cputype, cpusubtype, bytes) slices, each 4 KiB aligned,
    as `lipo -create` writes it."""
    align = 12
    offset = 1 << align
    header = struct.pack(">II", 0xCAFEBABE, len(slices))
    body = b""
    for cputype, subtype, data in slices:
        header += struct.pack(">IIIII", cputype, subtype, offset + len(body), len(data), align)
        body += data + b"\0" * (-len(data) % (1 << align))
    return header + b"\0" * (offset - len(header)) + body


CPU_X86_64, CPU_ARM64 = 0x01000007, 0x0100000C


def names(fmu):
    return sorted(n for n in zipfile.ZipFile(fmu).namelist() if n.startswith("binaries/") and not n.endswith("/"))


def test_stand_ins_are_packaged_under_their_platforms(workdir, plain, stub):
    plain_fmu, so, _, _ = plain
    given = {
        "win64": stub("win64.dll", "x86_64-windows-gnu"),
        "win32": stub("win32.dll", "x86-windows-gnu"),
        "darwin64": stub("darwin64.dylib", "x86_64-macos"),
        "linux32": stub("linux32.so", "x86-linux-gnu"),
    }
    out = workdir / "all.fmu"
    args = [workdir / "bar.json", "-o", out, "-q"]
    for platform, path in given.items():
        args += ["--platform-binary", f"{platform}={path}"]
    run_builder(args)
    assert names(out) == ["binaries/darwin64/Bar.dylib", "binaries/linux32/Bar.so", "binaries/linux64/Bar.so",
                          "binaries/win32/Bar.dll", "binaries/win64/Bar.dll"]
    z = zipfile.ZipFile(out)
    ext = {"win": "dll", "linux": "so", "darwin": "dylib"}
    for platform, path in given.items():
        entry = f"binaries/{platform}/Bar.{ext[platform.rstrip('0123456789')]}"
        assert z.read(entry) == path.read_bytes(), entry
        assert (z.getinfo(entry).external_attr >> 16) & 0o777 == 0o755, entry
    # the builder's own linux64 runtime, untouched, and the FMU still works through it
    assert z.read("binaries/linux64/Bar.so") == so
    assert validate_fmu(str(out)) == []
    res = simulate_fmu(str(out), fmi_type="CoSimulation", stop_time=0.02, output_interval=1e-3,
                       start_values={"tip.f[3]": 10.0}, output=["tip.u[3]"])
    assert np.all(np.isfinite(res["tip.u[3]"])) and res["tip.u[3]"][-1] != 0.0


def test_universal_macos_binary_with_an_x86_64_slice_is_accepted(workdir, stub):
    fat = workdir / "universal.dylib"
    fat.write_bytes(universal([(CPU_X86_64, 3, stub("u-x86_64.dylib", "x86_64-macos").read_bytes()),
                               (CPU_ARM64, 0, stub("u-arm64.dylib", "aarch64-macos").read_bytes())]))
    out = workdir / "universal.fmu"
    run_builder([workdir / "bar.json", "-o", out, "-q", "--platform-binary", f"darwin64={fat}"])
    assert zipfile.ZipFile(out).read("binaries/darwin64/Bar.dylib") == fat.read_bytes()


def test_a_linux64_binary_replaces_the_builders_own(workdir, plain, stub):
    so = stub("linux64.so", "x86_64-linux-gnu")
    out = workdir / "replaced.fmu"
    run_builder([workdir / "bar.json", "-o", out, "-q", "--platform-binary", f"linux64={so}"])
    assert names(out) == ["binaries/linux64/Bar.so"]
    assert zipfile.ZipFile(out).read("binaries/linux64/Bar.so") == so.read_bytes() != plain[1]


def refusal(workdir, platform, path):
    out = workdir / "refused.fmu"
    if out.exists():
        out.unlink()
    proc = run_builder([workdir / "bar.json", "-o", out, "-q", "--platform-binary", f"{platform}={path}"],
                       check=False)
    assert proc.returncode != 0 and not out.exists(), proc.stderr
    print(f"\n{proc.stderr.strip()}")
    # the file and the platform are named
    assert f"{path}: refused as the FMU's {platform} binary (--platform-binary {platform}=...): it " \
        in proc.stderr, proc.stderr
    return proc.stderr


def test_wrong_format_is_refused(workdir, stub):
    dll = stub("format.dll", "x86_64-windows-gnu")
    err = refusal(workdir, "linux64", dll)
    assert "it is a Windows DLL (PE), not a Linux shared object (ELF) as linux64 needs" in err
    err = refusal(workdir, "darwin64", stub("format.so", "x86_64-linux-gnu"))
    assert "it is a Linux shared object (ELF), not a macOS dynamic library (Mach-O) as darwin64 needs" in err
    text = workdir / "notes.txt"
    text.write_text("not a binary\n")
    assert "is not a shared library in a format this tool reads" in refusal(workdir, "win64", text)


def test_wrong_processor_is_refused(workdir, stub):
    err = refusal(workdir, "linux64", stub("arm.so", "aarch64-linux-gnu"))
    assert ("it is built for aarch64 (arm64), but linux64 is x86-64; "
            "FMI 2.0 has no platform for aarch64 (arm64) binaries") in err
    err = refusal(workdir, "win64", stub("x86.dll", "x86-windows-gnu"))
    assert "it is built for x86 (32-bit), but win64 is x86-64" in err
    err = refusal(workdir, "darwin64", stub("arm.dylib", "aarch64-macos"))
    assert "but darwin64 is x86-64" in err and "universal binary with an x86_64 slice" in err
    fat = workdir / "arm-only-universal.dylib"
    fat.write_bytes(universal([(CPU_ARM64, 0, stub("arm2.dylib", "aarch64-macos").read_bytes())]))
    assert "universal binary with slices for aarch64 (arm64) but none for x86-64" in refusal(workdir, "darwin64", fat)


def test_a_program_is_not_a_shared_library(workdir, stub):
    err = refusal(workdir, "win64", stub("program.exe", "x86_64-windows-gnu", program=True))
    assert "it is a Windows program (.exe), not a DLL" in err


def test_missing_functions_are_listed(workdir, stub):
    path = stub("partial.dll", "x86_64-windows-gnu", omit=("fmi2DoStep", "fmi2GetDerivatives"))
    err = refusal(workdir, "win64", path)
    assert ("it does not export 2 of the 44 fmi2 functions the FMU's modelDescription.xml needs: "
            "fmi2GetDerivatives, fmi2DoStep") in err


def test_a_binary_of_another_runtime_source_is_refused(workdir, stub):
    err = refusal(workdir, "win64", stub("old.dll", "x86_64-windows-gnu", build_id="0.0.1+src.0123456789abcdef"))
    assert "it was built from fmu-runtime 0.0.1+src.0123456789abcdef, this builder's runtime is" in err
    assert "build it from the same commit as the builder" in err
    err = refusal(workdir, "win64", stub("anonymous.dll", "x86_64-windows-gnu", build_id=None))
    assert "it carries no fmu-runtime build identity" in err


def test_command_line_mistakes_are_refused(workdir, stub):
    dll = stub("ok.dll", "x86_64-windows-gnu")
    cases = [
        (["--platform-binary", f"aarch64-linux={dll}"],
         "'aarch64-linux' is not an FMI 2.0 platform: expected one of win32, win64, linux32, linux64, darwin32, "
         "darwin64 (FMI 2.0 names x86 and x86-64 platforms only, none for aarch64/arm64)"),
        (["--platform-binary", str(dll)], "expected PLATFORM=FILE, e.g. win64=fmu_runtime.dll"),
        (["--platform-binary", f"win64={dll}", "--platform-binary", f"win64={dll}"],
         "--platform-binary win64: given twice"),
        (["--platform-binary", f"win64={workdir / 'missing.dll'}"],
         f"{workdir / 'missing.dll'}: refused as the FMU's win64 binary (--platform-binary win64=...): it "
         "cannot be read"),
    ]
    for extra, reason in cases:
        out = workdir / "mistake.fmu"
        proc = run_builder([workdir / "bar.json", "-o", out, "-q", *extra], check=False)
        assert proc.returncode != 0 and not out.exists() and reason in proc.stderr, (extra, proc.stderr)
