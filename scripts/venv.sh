# Sourced by serve.sh and test.sh: make the virtual environment $VENV (default .venv) and install this project
# into it with the extras given as "$1" (e.g. "dev"), editable. uv installs it (about 50 s into a new venv here,
# against about 90 s for pip); pip does when uv cannot be had or fails, so a machine without uv still works.
# --compile-bytecode, as pip does: with PYTHONDONTWRITEBYTECODE set (as on this machine) nothing else writes the
# .pyc files, and every process (each server, worker, CLI run) then compiled its imports again: 10 s, not 4 s.
# The project's own sources (installed editable, so not compiled by the installer) are compiled after it: ~0.1 s of
# each CLI run's start-up (a source edited later is compiled again in memory, as before).
VENV=${THRUSTSHAPE_VENV:-.venv}
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
fi
# (UV_LINK_MODE=copy: uv's cache and a venv under /tmp may be on different file systems, where it warns of hard links)
venv_install() {
  if ! { "$VENV/bin/python" -m pip install -q --disable-pip-version-check uv \
      && UV_LINK_MODE=copy "$VENV/bin/python" -m uv pip install -q --compile-bytecode --python "$VENV/bin/python" -e ".[$1]"; }; then
    echo "venv.sh: uv could not install; pip does" >&2
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --upgrade pip
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check -e ".[$1]"
  fi
  "$VENV/bin/python" -m compileall -q ocp service clients >/dev/null
}
