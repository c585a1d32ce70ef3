#!/usr/bin/env bash
# Quick start 2: set up if needed, then run the default test suite (arguments go to pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
# One worker per core (at most 4: each loads the engines); the slowest tests are listed to keep
# the suite in budget. A later "-n 0" in the arguments runs in one process.
exec .venv/bin/python -m pytest -q -n auto --maxprocesses 4 --durations=25 "$@"
