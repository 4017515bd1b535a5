"""The agent's wall-clock stamps: the time now as ISO 8601 UTC, to the second, with a Z (2026-11-26T17:05:00Z)."""

from __future__ import annotations

from datetime import UTC, datetime


def utc_now() -> datetime:
    """Returns this computer's time now, UTC (as its clock says: it may be wrong, see commands/status.py)."""
    return datetime.now(UTC)


def utc_now_iso() -> str:
    """Returns the current time as ISO 8601 UTC to the second, e.g. '2026-11-26T17:05:00Z'."""
    return utc_now().isoformat(timespec="seconds").replace("+00:00", "Z")
