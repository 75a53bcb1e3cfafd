#!/usr/bin/env bash
# Set up everything a fresh machine needs, then run the service on the embedded defaults:
# SQLite job store under ./thrustshape-data, local worker processes, http://127.0.0.1:8000 (docs at /docs).
# Extra arguments go to `thrustshape serve` (e.g. `--port 9000 --workers 4`).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/venv.sh
venv_install flightlogs,xlsx  # flight logs and .xlsx sweeps for the model check; add ,dask for --dask
exec "$VENV/bin/thrustshape" serve "$@"
