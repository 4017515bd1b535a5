#!/usr/bin/env bash
# The whole test suite: ruff, mypy, the import layers, then pytest on embedded SQLite and on PostgreSQL (127.0.0.1:5432,
# database test).
# Extra arguments go to pytest (e.g. -k upload). Set COACH_TEST_PG_URL for another PostgreSQL.
set -euo pipefail
source "$(dirname "$0")/_venv.sh" test
cd "$ROOT"
PG_URL="${COACH_TEST_PG_URL:-postgresql+psycopg://postgres@127.0.0.1:5432/test}"

pg_ready() { python - "$PG_URL" <<'PY'
import sys
import sqlalchemy as sa
try:
    sa.create_engine(sys.argv[1]).connect().close()
except Exception as exc:  # noqa: BLE001 - any failure means "not ready"
    print(f"PostgreSQL not reachable at {sys.argv[1]}: {exc}", file=sys.stderr)
    sys.exit(1)
PY
}

if ! pg_ready 2>/dev/null; then
  if command -v pg_ctlcluster >/dev/null && [ -d /etc/postgresql ]; then
    echo "Starting PostgreSQL ..." >&2
    pg_ctlcluster --skip-systemctl-redirect "$(ls /etc/postgresql | head -n1)" main start || true
    for _ in $(seq 30); do pg_ready 2>/dev/null && break; sleep 1; done
  fi
  pg_ready || { echo "error: the suite runs on PostgreSQL too, and none answers at $PG_URL" >&2; exit 1; }
fi

# Fast checks first (seconds): lint, formatting, types ([tool.mypy] in pyproject.toml says which packages) and the
# import layers of docs/architecture.md.
echo "=== ruff check, ruff format --check, mypy, import layers ===" >&2
ruff check .
ruff format --check .
mypy
python -m pytest -q -p no:cacheprovider tests/test_layers.py

# The browser tests (marker "browser") are slow and exercise the pages, not the database: they run once, on
# PostgreSQL, the production database. The two passes run side by side (each waits on servers, browsers and the
# database much of the time, so two cores serve both); the SQLite pass's output follows the PostgreSQL pass's.
echo "=== tests on PostgreSQL ($PG_URL), and on SQLite beside it (browser tests on PostgreSQL only) ===" >&2
SQLITE_LOG="$(mktemp)"
trap 'rm -f "$SQLITE_LOG"' EXIT
COACH_TEST_DATABASE_URL="" python -m pytest -m "not browser" "$@" >"$SQLITE_LOG" 2>&1 &
sqlite_pid=$!
# Tests that never open a database (the signal code, readers, analysis, benchmarks' helpers) run once, in the SQLite
# pass: on PostgreSQL they would repeat the same computation.
NO_DATABASE=(tests/kinect_agent/analysis tests/kinect_agent/body tests/kinect_agent/evaluation tests/kinect_agent/export
  tests/kinect_agent/formats tests/kinect_agent/live tests/kinect_agent/processing tests/kinect_agent/sources
  tests/kinect_agent/vendor tests/bench tests/backend/analysis)
pg_rc=0
COACH_TEST_DATABASE_URL="$PG_URL" python -m pytest "${NO_DATABASE[@]/#/--ignore=}" "$@" || pg_rc=$?
sqlite_rc=0
wait "$sqlite_pid" || sqlite_rc=$?
echo "=== tests on SQLite (exit $sqlite_rc) ===" >&2
cat "$SQLITE_LOG"
echo "=== PostgreSQL pass: exit $pg_rc; SQLite pass: exit $sqlite_rc ===" >&2
[ "$pg_rc" -eq 0 ] && [ "$sqlite_rc" -eq 0 ]
