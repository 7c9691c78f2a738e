"""How the builder puts its outputs in place, and what it leaves when something happens meanwhile:
every output is written to a hidden temporary file in its folder and renamed when complete, after
a last look at the name (a link to the input made while the build ran is refused, the input
kept); SIGINT and SIGTERM during the FMU's write leave no temporary file, and the one a SIGKILL
leaves is swept by the next build into that folder; a write past `ulimit -f` is an error naming
the file; a second build to an output another build is writing is refused, naming that build;
a killed build's PETSc job folder is swept by the next run; a name over 255 bytes or a missing
folder is refused before the input is even read."""

import json
import os
import re
import resource
import signal
import socket
import subprocess
import time

from conftest import BUILDER, EXAMPLES

SMALL = json.loads((EXAMPLES / "beam.json").read_text())
SMALL.pop("$schema")
SMALL["geometry"]["boxes"][0]["elements"] = [10, 1, 1]
SMALL["reduction"]["modes"] = 2

# a build of a few seconds here: long enough to act on it while it runs
SLOW = json.loads(json.dumps(SMALL))
SLOW["geometry"]["boxes"][0]["elements"] = [40, 4, 4]
SLOW["reduction"]["modes"] = 4

REFUSED_WITHIN_S = 1.0


def spec_file(tmp_path, spec=SMALL, name="part.json"):
    path = tmp_path / name
    path.write_text(json.dumps(spec, indent=2))
    return path


def builder(*args, timeout=300, **kw):
    start = time.monotonic()
    proc = subprocess.run([str(BUILDER), *map(str, args)], capture_output=True, text=True, timeout=timeout, **kw)
    proc.seconds = time.monotonic() - start
    return proc


def as_a_terminal_starts_it():
    """SIGINT and SIGTERM at their defaults in the builder, as a shell in a terminal starts it: a
    test run in the background (a non-interactive shell's `&`) inherits SIGINT ignored, which the
    builder rightly keeps ignoring."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_DFL)


def start(*args, **kw):
    return subprocess.Popen([str(BUILDER), *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=as_a_terminal_starts_it, **kw)


def wait_for_line(proc, text):
    """Reads the builder's progress (stderr) until a line holds `text`; the lines read."""
    lines = []
    for line in proc.stderr:
        lines.append(line)
        if text in line:
            return lines
    raise AssertionError(f"no progress line with {text!r}:\n{''.join(lines)}")


def refused(proc, *texts):
    assert proc.returncode == 1, (proc.returncode, proc.stderr)
    assert "panicked" not in proc.stderr, proc.stderr
    assert proc.stderr.startswith("error: ") or "\nerror: " in proc.stderr, proc.stderr
    for t in texts:
        assert t in proc.stderr, (t, proc.stderr)


def hidden(folder):
    """The builder's hidden files in `folder`: temporary files and locks."""
    return sorted(p.name for p in folder.iterdir() if p.name.endswith((".tmp", ".lock")))


def test_a_report_path_that_becomes_a_link_to_the_input_during_the_build_is_refused_and_the_input_kept(tmp_path):
    path = spec_file(tmp_path, SLOW)
    before = path.read_bytes()
    report, fmu = tmp_path / "r.json", tmp_path / "B.fmu"
    proc = start(path, "-o", fmu, "--report", report)
    # the report's name is free when the build checks it; it becomes a link once the build runs
    wait_for_line(proc, "assembly")
    os.symlink(path, report)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 1, err
    assert f"error: --report: --report {report}: became a symbolic link (to {path}) while the build ran" in err, err
    assert "Remove the link" in err and f"the FMU {fmu} was written" in err, err
    assert path.read_bytes() == before and os.readlink(report) == str(path)
    assert fmu.is_file() and hidden(tmp_path) == []


def test_an_output_that_is_a_symbolic_link_is_refused_before_any_work(tmp_path):
    path = spec_file(tmp_path)
    other = tmp_path / "elsewhere.json"
    other.write_text("keep me")
    os.symlink(other, tmp_path / "r.json")
    proc = builder(path, "-o", tmp_path / "B.fmu", "--report", tmp_path / "r.json", "--force", "-q")
    refused(proc, f"error: --report {tmp_path / 'r.json'}: {tmp_path / 'r.json'} is a symbolic link (to {other})",
            "Name the file itself, or remove the link")
    assert proc.seconds < REFUSED_WITHIN_S and other.read_text() == "keep me"


def build_interrupted_in_the_fmu_write(tmp_path, sig):
    """Starts a build and sends `sig` while the FMU's temporary file is being written (the build
    is stopped the moment the file shows, so that the signal lands inside the write); the
    process, its stderr, the FMU and the temporary file's name. A write that ends before it is seen is
    tried again."""
    path = spec_file(tmp_path, SLOW)
    fmu = tmp_path / "B.fmu"
    for _ in range(5):
        proc = start(path, "-o", fmu)
        wait_for_line(proc, "checks and packaging")
        temp = None
        while proc.poll() is None and temp is None:
            temp = next((p for p in tmp_path.iterdir() if p.name.startswith(".B.fmu.") and p.name.endswith(".tmp")),
                        None)
        if temp is None:  # too late: the FMU was written
            proc.communicate(timeout=60)
            fmu.unlink()
            continue
        os.kill(proc.pid, signal.SIGSTOP)
        if temp.exists():
            os.kill(proc.pid, sig)
            os.kill(proc.pid, signal.SIGCONT)
            _, err = proc.communicate(timeout=60)
            return proc, err, fmu, temp
        os.kill(proc.pid, signal.SIGCONT)
        proc.communicate(timeout=60)
        fmu.unlink()
    raise AssertionError("the FMU's write was never caught in five builds")


def test_sigint_or_sigterm_during_the_fmu_write_leave_no_temporary_file(tmp_path):
    for sig in [signal.SIGINT, signal.SIGTERM]:
        folder = tmp_path / sig.name
        folder.mkdir()
        proc, err, fmu, temp = build_interrupted_in_the_fmu_write(folder, sig)
        assert proc.returncode == -sig, (proc.returncode, err)
        assert "error: interrupted; the unfinished outputs' temporary files were removed" in err, err
        assert not fmu.exists() and hidden(folder) == [], hidden(folder)


def test_the_temporary_file_of_a_killed_build_is_swept_by_the_next_build_into_its_folder(tmp_path):
    proc, _, fmu, temp = build_interrupted_in_the_fmu_write(tmp_path, signal.SIGKILL)
    assert proc.returncode == -signal.SIGKILL
    assert temp.exists() and not fmu.exists()
    # another output's temporary file, and one of a live process, are not the next build's
    alive = tmp_path / f".B.fmu.{os.getpid()}.0.tmp"
    alive.write_bytes(b"")
    other = tmp_path / ".C.fmu.4999999.0.tmp"
    other.write_bytes(b"")
    proc = builder(spec_file(tmp_path), "-o", fmu, "-q")
    assert proc.returncode == 0, proc.stderr
    assert not temp.exists() and alive.exists() and other.exists()
    assert hidden(tmp_path) == sorted([alive.name, other.name])


def test_a_write_past_the_file_size_limit_is_an_error_naming_the_file_and_leaves_nothing(tmp_path):
    path = spec_file(tmp_path)
    fmu = tmp_path / "B.fmu"

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, 64 * 1024))

    proc = builder(path, "-o", fmu, "-q", preexec_fn=limit)
    refused(proc, f"error: {fmu}: ", "the file size limit (ulimit -f) was reached",
            "nothing was written there")
    assert not fmu.exists() and hidden(tmp_path) == []


def test_an_export_that_fails_after_the_fmu_leaves_no_partial_file(tmp_path):
    # 1.5 MB: the FMU (0.7 MB) and the report (0.3 MB) fit, the VTK file (2.5 MB) does not,
    # as a disk that fills after the FMU
    path = spec_file(tmp_path, SLOW)
    fmu, report, vtk = tmp_path / "B.fmu", tmp_path / "r.json", tmp_path / "v.vtk"

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (1500 * 1024, 1500 * 1024))

    proc = builder(path, "-o", fmu, "--report", report, "--export-vtk", vtk, "-q", preexec_fn=limit)
    refused(proc, f"error: --export-vtk: {vtk}: ", "the file size limit (ulimit -f) was reached",
            "nothing was written there", f"the FMU {fmu} was written")
    assert fmu.is_file() and json.loads(report.read_text())["model_name"] == "Beam"
    assert not vtk.exists() and hidden(tmp_path) == []


def test_a_second_build_to_an_output_being_written_is_refused_naming_the_first(tmp_path):
    path = spec_file(tmp_path, SLOW)
    fmu = tmp_path / "B.fmu"
    first = start(path, "-o", fmu)
    wait_for_line(first, "assembly")
    second = builder(spec_file(tmp_path, name="other.json"), "-o", fmu, "-q")
    refused(second, f"error: -o {fmu}: another build (pid {first.pid} on {socket.gethostname()}) is writing "
                    "this output now; wait for it to end, or pass --force")
    assert second.seconds < REFUSED_WITHIN_S
    _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    # with --force the second waits for the first, then replaces what it wrote
    first = start(path, "-o", fmu, "--force")
    wait_for_line(first, "assembly")
    second = start(spec_file(tmp_path, name="other.json"), "-o", fmu, "--force")
    first.communicate(timeout=300)
    _, err = second.communicate(timeout=300)
    assert first.returncode == 0 and second.returncode == 0, err
    assert f"waiting for another build (pid {first.pid} on {socket.gethostname()}) that writes -o {fmu}" in err, err
    assert hidden(tmp_path) == []
    # a folder export named as the FMU (they would share a lock, and wait for themselves) is
    # refused before any work
    new = tmp_path / "C.fmu"
    proc = builder(path, "-o", new, "--export-matrices", new, "--force", "-q", timeout=60)
    refused(proc, f"error: --export-matrices {new}: {new} is also written by -o as a file; this option makes a "
                  "folder there")
    assert proc.seconds < REFUSED_WITHIN_S and hidden(tmp_path) == []


def test_a_killed_builds_petsc_job_folder_is_swept_by_the_next_run(tmp_path):
    jobs = tmp_path / "jobs"
    jobs.mkdir()
    host = re.sub(r"[^A-Za-z0-9._]", "_", socket.gethostname())
    ended = subprocess.Popen(["true"])
    ended.wait()
    gone_pid = ended.pid
    gone = jobs / f"fmu-builder-petsc-{host}-{gone_pid}-0123456789abcdef"
    live = jobs / f"fmu-builder-petsc-{host}-{os.getpid()}-0123456789abcdef"
    elsewhere = jobs / "fmu-builder-petsc-another_host-4999999-0123456789abcdef"
    for folder in [gone, live, elsewhere]:
        folder.mkdir(mode=0o700)
        (folder / "job.json").write_text('{"token": "0000"}')
    # the default place of job folders, swept at every run
    proc = builder(spec_file(tmp_path), "-o", tmp_path / "B.fmu", "-q", env=dict(os.environ, TMPDIR=str(jobs)))
    assert proc.returncode == 0, proc.stderr
    assert not gone.exists() and live.exists() and elsewhere.exists()
    # a PETSc build's own job folder, swept before anything else can fail (here: no such launcher)
    gone.mkdir(mode=0o700)
    spec = dict(SMALL, reduction=dict(SMALL["reduction"], backend={
        "kind": "petsc", "launcher": "no-such-launcher", "job_folder": str(jobs)}))
    proc = builder(spec_file(tmp_path, spec, "petsc.json"), "-o", tmp_path / "P.fmu", "-q")
    assert proc.returncode == 1 and "no-such-launcher" in proc.stderr, proc.stderr
    assert not gone.exists() and live.exists() and elsewhere.exists()


def test_an_over_long_name_or_a_missing_folder_is_refused_before_the_input_is_read(tmp_path):
    # the input does not exist: a refusal of the output shows it came first
    missing_input = tmp_path / "no-input.json"
    long_vtk = tmp_path / ("a" * 300 + ".vtk")
    cases = [
        (["--export-vtk", long_vtk], f"error: --export-vtk {long_vtk}: the name aaaa",
         "is 304 bytes long; a file or folder name may have at most 255 bytes. Name a shorter one"),
        (["-o", tmp_path / "no" / "B.fmu"], f"error: -o {tmp_path / 'no' / 'B.fmu'}: the folder "
         f"{tmp_path / 'no'} does not exist; create it first"),
        (["--report", tmp_path / ("r" * 256) / "r.json"], "error: --report", "is 256 bytes long"),
        (["--export-free-free", tmp_path / "no" / "m"], f"the folder {tmp_path / 'no'} does not exist"),
    ]
    for extra, *texts in cases:
        proc = builder(missing_input, *extra, "-q")
        refused(proc, *texts)
        assert proc.seconds < REFUSED_WITHIN_S, proc.seconds
    # and with an input: refused before any work, nothing written
    path = spec_file(tmp_path)
    proc = builder(path, "-o", tmp_path / "B.fmu", "--export-vtk", long_vtk, "-q")
    refused(proc, "is 304 bytes long")
    assert proc.seconds < REFUSED_WITHIN_S and not (tmp_path / "B.fmu").exists()
