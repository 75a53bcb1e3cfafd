#!/usr/bin/env bash
# Set up everything a fresh machine needs, then run the whole test suite: ruff, mypy, pytest.
# Extra arguments go to pytest (e.g. `-m "not slow"`, `-k optimize`). The tests run in one process per core
# (pytest-xdist, a test file's tests together in one process, in order); THRUSTSHAPE_TEST_PROCS=0 runs them in this one.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/venv.sh
venv_install dev
# The web page's browser tests drive Debian's chromium (tests/browser.py skips them, saying why, when it is absent).
if [ ! -x /usr/bin/chromium ] && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null \
    || echo "test.sh: could not install chromium; the page tests will be skipped" >&2
fi
"$VENV/bin/ruff" check .
"$VENV/bin/mypy"
exec "$VENV/bin/python" -m pytest -n "${THRUSTSHAPE_TEST_PROCS:-auto}" --dist loadfile "$@"
