#!/usr/bin/env bash
# The main job: the coaching server on embedded SQLite with a seeded demo clinic, and simulated
# home agents that record, filter, queue and upload sessions. Prints the URLs to open.
set -euo pipefail
source "$(dirname "$0")/_venv.sh" dev
cd "$ROOT"
exec coach-server demo "$@"
