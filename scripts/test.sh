#!/usr/bin/env bash
# Quick start 2: set up if needed, then run the default test suite (arguments go to pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
exec .venv/bin/python -m pytest -q --durations=25 "$@"  # the slowest tests, to keep the suite in budget
