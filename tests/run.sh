#!/usr/bin/env bash
# The project's test command: formatting and lints, Rust tests, the benchmark's targets (short
# mode), the release builder, then the end-to-end tests with FMPy in a virtual environment this
# script creates (tests/.venv).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
# formatting and lints first: cheap, and the code base must be clean under both
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
cargo test --workspace --release
# the benchmark's targets (ratios to the full model, no allocation per step, hard cases) in
# its short mode: under two minutes, non-zero exit on a missed target
cargo run --release -p bench -- --short
cargo build --release -p fmu-builder
if [ ! -x tests/.venv/bin/python ]; then
    python3 -m venv tests/.venv
fi
tests/.venv/bin/python -m pip install --quiet --upgrade pip
tests/.venv/bin/python -m pip install --quiet -r tests/requirements.txt
cd tests
.venv/bin/python -m pytest -v -s "$@"
