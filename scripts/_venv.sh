# Sourced by the set-up scripts: makes ./.venv with the project and the dependencies pinned, with their hashes, in
# requirements/NAME.lock (NAME: the first argument, "dev" or "test"). Needs only python3 (>= 3.11) with venv;
# installs again only when pyproject.toml or the lock file changed. scripts/lock.sh regenerates the lock files.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
PYTHON="${PYTHON:-python3}"
LOCK="$ROOT/requirements/${1:?lock name (dev or test) expected}.lock"
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
  echo "error: Python 3.11 or newer is needed ($PYTHON is $("$PYTHON" --version 2>&1))" >&2
  exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
  "$PYTHON" -m venv "$VENV"
fi
STAMP="$VENV/.installed-$(cat "$ROOT/pyproject.toml" "$LOCK" | sha256sum | cut -c1-16)-$1"
if [ ! -f "$STAMP" ]; then
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
  "$VENV/bin/python" -m pip install --quiet --require-hashes -r "$LOCK"
  "$VENV/bin/python" -m pip install --quiet --no-deps -e "$ROOT"
  # the home agent's compiled filter code into numba's on-disk cache, so its first set counts as fast as later ones
  "$VENV/bin/kinect-agent" prepare
  touch "$STAMP"
fi
export PATH="$VENV/bin:$PATH"
# The pinned pose assets (browser runtime and models, kinect_agent/vendor/lock.json): fetched with npm and checked
# once; afterwards this only reads a stamp.
"$VENV/bin/python" -m kinect_agent.vendor.install --quiet
