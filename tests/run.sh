#!/usr/bin/env bash
# The project's test command: Rust unit tests, the release builder, then the end-to-end tests
# with FMPy in a virtual environment this script creates (tests/.venv).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
cargo test --workspace --release
cargo build --release -p fmu-builder
if [ ! -x tests/.venv/bin/python ]; then
    python3 -m venv tests/.venv
fi
tests/.venv/bin/python -m pip install --quiet --upgrade pip
tests/.venv/bin/python -m pip install --quiet -r tests/requirements.txt
cd tests
.venv/bin/python -m pytest -v -s "$@"
