#!/usr/bin/env bash
# Drop the same robots in urdyn and MuJoCo, in one run: writes benches/sim_results.md,
# benches/sim_results.json and benches/sim_results.png (see benches/sim_compare.py's
# docstring for the scene, the timing and every column).
#
#   benches/sim_compare.sh [sim_compare.py options, e.g. --robots solo12,go2 --repeats 3]
#
# Makes (once) a venv with mujoco, example-robot-data, numpy and matplotlib from PyPI at
# $SIM_COMPARE_VENV (default target/sim-compare-venv), builds the release binary unless
# $URDYN names one, and runs the script with that venv's Python. example-robot-data's
# URDFs and meshes are found in the venv (site-packages/cmeel.prefix/share).
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${SIM_COMPARE_VENV:-target/sim-compare-venv}"
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet mujoco example-robot-data numpy matplotlib
if [ -z "${URDYN:-}" ]; then
  cargo build --release --quiet --bin urdyn
  URDYN=target/release/urdyn
fi
exec "$VENV/bin/python" benches/sim_compare.py --urdyn "$URDYN" "$@"
