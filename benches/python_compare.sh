#!/usr/bin/env bash
# urdyn from Python against Pinocchio and MuJoCo from Python, in one run: writes
# benches/python_results.md and benches/python_results.json (see the docstring of
# benches/python_compare.py for the scenes and the timing).
#
#   benches/python_compare.sh [python_compare.py options, e.g. --repeats 5]
#
# Makes (once) a venv with pin, mujoco, example-robot-data and numpy from PyPI at
# $PY_COMPARE_VENV (default target/python-compare-venv) and installs ./python into it.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${PY_COMPARE_VENV:-target/python-compare-venv}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet pin mujoco example-robot-data numpy
"$VENV/bin/python" -m pip install --quiet ./python
exec "$VENV/bin/python" benches/python_compare.py "$@"
