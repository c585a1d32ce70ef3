#!/usr/bin/env bash
# Quick start 1: set up if needed, then run the main job (extra arguments go to `femdem run`).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
MAIN_CASE=${MAIN_CASE:-beam_impact}
exec .venv/bin/femdem run "$MAIN_CASE" "$@"
