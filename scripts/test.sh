#!/usr/bin/env bash
# Set up everything a fresh machine needs, then run the whole test suite: ruff, mypy, pytest.
# Extra arguments go to pytest (e.g. `-m "not slow"`, `-k optimize`).
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${THRUSTSHAPE_VENV:-.venv}
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
"$VENV/bin/python" -m pip install -q --disable-pip-version-check -e '.[dev]'
"$VENV/bin/ruff" check .
"$VENV/bin/mypy"
exec "$VENV/bin/python" -m pytest "$@"
