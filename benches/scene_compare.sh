#!/usr/bin/env bash
# The scenes of benches/scenes/ in urdyn and MuJoCo, in one run: writes
# benches/scene_results.md (benches/scene_compare.py's docstring says how each
# engine gets the scene and what every column is).
#
#   benches/scene_compare.sh [scene_compare.py options, e.g. --scenes box_stack --repeats 3]
#
# $PYTHON: a Python with mujoco (4.0), example-robot-data and numpy (default
# /work/venv/bin/python, else python3); $URDYN: the urdyn binary (default: build
# target/release/urdyn).
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-/work/venv/bin/python}"
[ -x "$PY" ] || PY=python3
if [ -z "${URDYN:-}" ]; then
  cargo build --release --quiet --bin urdyn
  URDYN=target/release/urdyn
fi
exec "$PY" benches/scene_compare.py --urdyn "$URDYN" "$@"
