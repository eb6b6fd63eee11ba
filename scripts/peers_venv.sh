#!/usr/bin/env bash
# Creates the peers' virtual environment (pink and PlaCo) if it is missing.
#
# The peers live apart from evoik_pin's environment because PlaCo pins its own Pinocchio (pin==3.8.0 at the
# time of writing) while evoik_pin runs on Pinocchio 4. pip resolves the versions; the script prints what it
# installed. Usage: bash scripts/peers_venv.sh [VENV_DIR]   (default /work/peers-venv)
set -euo pipefail
VENV="${1:-${PEERS_VENV:-/work/peers-venv}}"
PY="${PYTHON:-python3.11}"
if [ ! -x "$VENV/bin/python" ]; then
    "$PY" -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet placo pin-pink daqp numpy
fi
"$VENV/bin/python" - <<'PY'
import importlib.metadata as md
for name in ("placo", "pin-pink", "daqp", "qpsolvers", "pin", "numpy"):
    try:
        print(f"{name}=={md.version(name)}")
    except md.PackageNotFoundError:
        print(f"{name}: not installed")
PY
