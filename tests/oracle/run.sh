#!/usr/bin/env bash
# Regenerate the reference-dynamics fixtures in tests/fixtures/ with Pinocchio
# (make_fixtures.py: states/expected/meta.json; make_derivative_fixtures.py: deriv_*.json).
# Idempotent: the venv is created (and the pinned packages installed) only when missing.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
VENV="${URDYN_ORACLE_VENV:-$HOME/.cache/urdyn-oracle}"
PY="${PYTHON:-python3}"

PKGS=(pin==4.1.0 example-robot-data==6.0.0 yourdfpy numpy)

if [ ! -x "$VENV/bin/python" ]; then
    echo "oracle: creating venv at $VENV" >&2
    "$PY" -m venv "$VENV"
fi
if ! "$VENV/bin/python" -c '
import sys, importlib.metadata as md
import pinocchio, yourdfpy, numpy
sys.exit(0 if pinocchio.__version__ == "4.1.0" and md.version("example-robot-data") == "6.0.0" else 1)
' 2>/dev/null; then
    echo "oracle: installing ${PKGS[*]}" >&2
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet "${PKGS[@]}"
fi

cd "$ROOT"
"$VENV/bin/python" "$HERE/make_fixtures.py" "$@"
exec "$VENV/bin/python" "$HERE/make_derivative_fixtures.py"
