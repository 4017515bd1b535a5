"""The agent's wall-clock stamps: the time now as ISO 8601 UTC, to the second, with a Z (2026-11-26T17:05:00Z)."""

from __future__ import annotations

from datetime import UTC, datetime


def utc_now_iso() -> str:
    """Returns the current time as ISO 8601 UTC to the second, e.g. '2026-11-26T17:05:00Z'."""
    return datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
