#!/usr/bin/env bash
# The project's test command: the Python environment and the portable-build tools first, then
# formatting and lints, Rust tests, the benchmark's targets (short mode), the release builder,
# and the end-to-end tests with FMPy in the virtual environment this script creates
# (tests/.venv).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
# Before any cargo command: every one of them runs fmu-builder/build.rs, which links the FMU's
# linux64 runtime with zig against glibc 2.17 when it finds zig (the ziglang package of
# tests/.venv, pinned in requirements.txt) and cargo-zigbuild, so that every test below runs on
# the portable binary. In CI a missing tool fails the build (FMU_RUNTIME_PORTABLE=require)
# instead of falling back to a native binary.
setup_start=$SECONDS
if [ ! -x tests/.venv/bin/python ]; then
    python3 -m venv tests/.venv
fi
tests/.venv/bin/python -m pip install --quiet --upgrade pip
tests/.venv/bin/python -m pip install --quiet -r tests/requirements.txt
if ! cargo zigbuild --help >/dev/null 2>&1; then
    cargo install --locked cargo-zigbuild --version 0.24.1
fi
if [ -n "${CI:-}" ]; then
    export FMU_RUNTIME_PORTABLE=require
fi
# the distributed back-end's tests: PETSc, SLEPc (with MUMPS) and OpenMPI from Debian, for
# Debian's own Python (/usr/bin/python3), which the driver runs under mpirun
# (OpenBLAS: MUMPS on Debian's reference BLAS factors about four times slower)
petsc_packages="python3-petsc4py-real python3-slepc4py-real python3-mpi4py openmpi-bin libopenblas0-serial"
# shellcheck disable=SC2086
if ! dpkg -s $petsc_packages >/dev/null 2>&1; then
    if command -v apt-get >/dev/null; then
        if [ "$(id -u)" = 0 ]; then sudo=""; else sudo="sudo"; fi
        # shellcheck disable=SC2086
        $sudo apt-get install -y $petsc_packages >/dev/null || { $sudo apt-get update >/dev/null && $sudo apt-get install -y $petsc_packages >/dev/null; }
    elif [ -n "${CI:-}" ]; then
        echo "the PETSc back-end's tests need Debian's $petsc_packages" >&2
        exit 1
    fi
fi
echo "Python environment and portable-build tools ready in $((SECONDS - setup_start)) s ($(tests/.venv/bin/python -m ziglang version | sed 's/^/zig /'), $(cargo-zigbuild --version 2>/dev/null || echo cargo-zigbuild))"
# formatting and lints first: cheap, and the code base must be clean under both
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace --release
# the benchmark's targets (ratios to the full model, no allocation per step, hard cases) in
# its short mode: under two minutes, non-zero exit on a missed target
cargo run --release -p bench -- --short
cargo build --release -p fmu-builder
"${CARGO_TARGET_DIR:-target}/release/fmu-builder" --version
cd tests
.venv/bin/python -m pytest -v -s "$@"
