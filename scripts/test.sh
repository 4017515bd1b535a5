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

# Fast checks first (seconds; mypy's first run without its cache about 1 CPU min): lint, formatting, types (the
# product and the tests: [tool.mypy] in pyproject.toml) and the import layers of docs/architecture.md.
echo "=== ruff check, ruff format --check, mypy, import layers ===" >&2
ruff check .
ruff format --check .
mypy
python -m pytest -q -p no:cacheprovider tests/test_layers.py

# Three passes run side by side, each in its own process (the two cores serve them: the browser pass waits on
# servers and Chromium much of the time):
#   - PostgreSQL, the browser tests (marker "browser"): slow, and they exercise the pages, not the database, so they
#     run once, on the production database (one of their own, below);
#   - PostgreSQL, every other test that opens the suite's database (marker "database", which tests/conftest.py sets
#     from the fixtures a test uses), and the tests below tests/conftest.py's ONCE_ON_POSTGRESQL (marker
#     "once_on_postgresql": the analysis, capture source and evaluation tests, which never open the database);
#   - SQLite, every test but the browser tests and those: the database tests again, and every other test that never
#     opens the suite's database (the signal code, readers, benchmarks' helpers, the demo's and the lean installs'
#     own SQLite files, pure functions of the server), once.
# Before, the tests that never open the database but sat beside database tests ran in both passes (404 tests, 56 CPU
# s on a busy machine, 2026-11-28).
# Each pass's output is printed whole when all have ended.
echo "=== tests: PostgreSQL ($PG_URL: the browser tests, and the rest) and SQLite, side by side ===" >&2
LOGS="$(mktemp -d)"
trap 'rm -rf "$LOGS"' EXIT
# The browser pass gets a database of its own beside PG_URL's (NAME_browser): its servers' LISTEN/NOTIFY events must
# not reach the other pass's listeners, and two schemas of one database would share them.
BROWSER_PG_URL="$(python - "$PG_URL" <<'PY'
import sys
import sqlalchemy as sa
url = sa.make_url(sys.argv[1])
name = f"{url.database}_browser"
admin = sa.create_engine(url, isolation_level="AUTOCOMMIT")
with admin.connect() as conn:
    if conn.execute(sa.text("SELECT 1 FROM pg_database WHERE datname = :n"), {"n": name}).scalar() is None:
        conn.execute(sa.text(f'CREATE DATABASE "{name}"'))
admin.dispose()
print(url.set(database=name).render_as_string(hide_password=False))
PY
)"
# Each log ends with its pass's wall time and CPU time (its pytest and every process that pytest waited for: servers,
# Chromium, command-line runs): a pass whose CPU is well under its wall time waits, one near it computes.
TIMEFORMAT="pass time: %R s wall, %U s user, %S s sys"
{ time COACH_TEST_DATABASE_URL="$BROWSER_PG_URL" python -m pytest -m browser "$@"; } >"$LOGS/browser" 2>&1 &
browser_pid=$!
{ time COACH_TEST_DATABASE_URL="$PG_URL" python -m pytest -m "not browser and (database or once_on_postgresql)" "$@"
} >"$LOGS/postgresql" 2>&1 &
pg_pid=$!
{ time COACH_TEST_DATABASE_URL="" python -m pytest -m "not browser and not once_on_postgresql" "$@"; } \
  >"$LOGS/sqlite" 2>&1 &
sqlite_pid=$!
browser_rc=0 pg_rc=0 sqlite_rc=0
wait "$browser_pid" || browser_rc=$?
wait "$pg_pid" || pg_rc=$?
wait "$sqlite_pid" || sqlite_rc=$?
# pytest's 5 is "no test collected": a pass that `-k` leaves empty has nothing to fail
[ "$browser_rc" -eq 5 ] && browser_rc=0
[ "$pg_rc" -eq 5 ] && pg_rc=0
[ "$sqlite_rc" -eq 5 ] && sqlite_rc=0
for pass in browser postgresql sqlite; do
  echo "=== tests: $pass ===" >&2
  cat "$LOGS/$pass"
done
echo "=== browser (PostgreSQL): exit $browser_rc; PostgreSQL: exit $pg_rc; SQLite: exit $sqlite_rc ===" >&2
[ "$browser_rc" -eq 0 ] && [ "$pg_rc" -eq 0 ] && [ "$sqlite_rc" -eq 0 ]
