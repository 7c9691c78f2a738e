#!/usr/bin/env bash
# The project's test command: the Python environment and the portable-build tools first, then
# formatting, the FMU's runtime (cargo xtask runtime), lints, Rust tests, the benchmark's targets
# (short mode), the release builder, and the end-to-end tests with FMPy in the virtual environment this script creates
# (tests/.venv).
#
#   bash tests/run.sh                 set up, then every test but the slow ones (pytest -m "not slow")
#   bash tests/run.sh -m slow         ... the slow ones only (any -m of yours replaces "not slow")
#   bash tests/run.sh -k portable     further arguments go to pytest
#   bash tests/run.sh --setup-only    only the set-up (venv, zig, cargo-zigbuild, PETSc), no tests
#
# The set-up installs into tests/.venv and $CARGO_HOME/bin without asking; Debian's PETSc
# packages need apt-get, so outside CI a non-root user is asked before sudo is used, and without
# a terminal to ask on they are left out (the PETSc back-end's tests are then skipped).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
setup_only=""
if [ "${1:-}" = "--setup-only" ]; then
    setup_only=1
    shift
fi
# Before any build: `cargo xtask runtime` (below) links the FMU's linux64 runtime once, with zig
# against glibc 2.17 when it finds zig (the ziglang package of tests/.venv, pinned in
# requirements.txt) and cargo-zigbuild, and every cargo build after it (clippy, the tests, the
# bench, the release builder) embeds that one binary, so that every test below runs on the
# portable binary. In CI a missing tool fails the build (FMU_RUNTIME_PORTABLE=require) instead of
# falling back to a native binary.
setup_start=$SECONDS
if [ ! -x tests/.venv/bin/python ]; then
    python3 -m venv tests/.venv
fi
tests/.venv/bin/python -m pip install --quiet --upgrade pip
tests/.venv/bin/python -m pip install --quiet -r tests/requirements.txt
# one that `cargo xtask runtime` fetched into the target folder (the README's first command on a
# fresh machine) serves as well
if ! cargo zigbuild --help >/dev/null 2>&1 && [ ! -x "${CARGO_TARGET_DIR:-target}/tools/bin/cargo-zigbuild" ]; then
    cargo install --locked cargo-zigbuild --version 0.24.1
fi
if [ -n "${CI:-}" ]; then
    export FMU_RUNTIME_PORTABLE=require
fi
# the distributed back-end's tests: PETSc (with MUMPS) and OpenMPI from Debian, for
# Debian's own Python (/usr/bin/python3), which the driver runs under mpirun
# (OpenBLAS: MUMPS on Debian's reference BLAS factors about four times slower)
petsc_packages="python3-petsc4py-real python3-mpi4py openmpi-bin libopenblas0-serial"
petsc_skipped="the PETSc back-end's tests (tests/test_petsc_backend.py) will be skipped; to run them, install
Debian's packages and run this script again:
    sudo apt-get install -y $petsc_packages"
# shellcheck disable=SC2086
if ! dpkg -s $petsc_packages >/dev/null 2>&1; then
    if command -v apt-get >/dev/null; then
        # root and CI install without asking (CI as before); a user is asked before sudo, since
        # it changes the system; with nobody to ask (no terminal), nothing is installed
        install=""
        sudo=""
        if [ "$(id -u)" = 0 ]; then
            install=1
        elif [ -n "${CI:-}" ]; then
            install=1
            sudo="sudo"
        elif [ -t 0 ]; then
            echo "The PETSc back-end's tests need Debian's $petsc_packages."
            read -r -p "Install them with sudo apt-get install? [y/N] " answer
            case "$answer" in
                [yY] | [yY][eE][sS]) install=1 sudo="sudo" ;;
                *) echo "Not installed: $petsc_skipped" ;;
            esac
        else
            echo "No terminal to ask before using sudo, so PETSc is not installed: $petsc_skipped" >&2
        fi
        if [ -n "$install" ]; then
            # shellcheck disable=SC2086
            $sudo apt-get install -y $petsc_packages >/dev/null || { $sudo apt-get update >/dev/null && $sudo apt-get install -y $petsc_packages >/dev/null; }
        fi
    elif [ -n "${CI:-}" ]; then
        echo "the PETSc back-end's tests need Debian's $petsc_packages" >&2
        exit 1
    else
        echo "No apt-get here: $petsc_skipped" >&2
    fi
fi
echo "Python environment and portable-build tools ready in $((SECONDS - setup_start)) s ($(tests/.venv/bin/python -m ziglang version | sed 's/^/zig /'), $(cargo-zigbuild --version 2>/dev/null || echo cargo-zigbuild))"
if [ -n "$setup_only" ]; then
    # the next `cargo xtask runtime` links the FMU's runtime with zig (it looks for the tools each time)
    echo "Set-up done; cargo xtask runtime (or cargo xtask build) now builds the portable runtime"
    exit 0
fi
# formatting and lints first: cheap, and the code base must be clean under both
cargo fmt --all -- --check
# the FMU's runtime, built once (release profile, portable): fmu-builder/build.rs embeds it into
# every build below, and refuses it once fmu-runtime's sources change
cargo xtask runtime
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace --release
# the benchmark's targets (ratios to the full model, no allocation per step, hard cases) in
# its short mode: under two minutes, non-zero exit on a missed target
cargo run --release -p bench -- --short
cargo build --release -p fmu-builder
"${CARGO_TARGET_DIR:-target}/release/fmu-builder" --version
cd tests
# the slow tests (a fresh clone built from scratch: test_fresh_clone.py) only when asked for, by
# a -m of the caller's own
markers=(-m "not slow")
for arg in "$@"; do
    case "$arg" in
        -m | -m?* | --markexpr | --markexpr=*) markers=() ;;
    esac
done
# the slowest tests listed at the end: where the CI budget goes
.venv/bin/python -m pytest -v -s --durations=20 "${markers[@]}" "$@"
