"""Reminder times: "HH:MM" in a patient's IANA time zone, and the UTC instants they fall on (no database)."""

from __future__ import annotations

import datetime as dt
import re
from functools import lru_cache
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError, available_timezones

MAX_REMINDERS_PER_DAY = 6
_HH_MM = re.compile(r"([01][0-9]|2[0-3]):([0-5][0-9])")


def parse_time(text: str) -> dt.time:
    """Returns the time of "HH:MM" (24-hour clock, 00:00-23:59); raises ValueError that quotes the text."""
    found = _HH_MM.fullmatch(text.strip()) if isinstance(text, str) else None
    if found is None:
        raise ValueError(f"reminder time {text!r} is not a time like 08:30 (HH:MM, 24-hour clock, 00:00 to 23:59)")
    return dt.time(int(found.group(1)), int(found.group(2)))


def normalise_times(texts: list[str]) -> list[str]:
    """Returns reminder times as sorted "HH:MM" texts; raises ValueError for a malformed, repeated or extra one."""
    if len(texts) > MAX_REMINDERS_PER_DAY:
        raise ValueError(f"at most {MAX_REMINDERS_PER_DAY} reminder times a day; got {len(texts)}")
    times = [parse_time(t).strftime("%H:%M") for t in texts]
    repeated = sorted({t for t in times if times.count(t) > 1})
    if repeated:
        raise ValueError(f"reminder time {repeated[0]} is given twice; give each time once")
    return sorted(times)


@lru_cache(maxsize=1)
def zone_names() -> frozenset[str]:
    """Returns the IANA time zone names this system knows (read once: ~50 ms)."""
    return frozenset(available_timezones())


def zone(name: str) -> ZoneInfo:
    """Returns the IANA time zone of a name ("Europe/Berlin"); raises ValueError naming it when there is none."""
    if not isinstance(name, str) or name not in zone_names():
        raise ValueError(f"time zone {name!r} is not an IANA time zone name like Europe/Berlin or America/New_York")
    try:
        return ZoneInfo(name)
    except (ZoneInfoNotFoundError, ValueError) as exc:  # listed but not loadable: a broken tz database
        raise ValueError(f"time zone {name!r} cannot be loaded: {exc}") from exc


def local_date(now: dt.datetime, tz: ZoneInfo) -> dt.date:
    """Returns the calendar day in tz at the aware instant now."""
    return now.astimezone(tz).date()


def due_at(day: dt.date, hh_mm: str, tz: ZoneInfo) -> dt.datetime:
    """Returns the UTC instant of wall-clock time hh_mm on day in tz.

    Daylight saving: a time skipped in spring (02:30 in Europe/Berlin on the last Sunday of March) falls one hour
    later on the clock (03:30, the instant 01:30 UTC); a time that happens twice in autumn is its first occurrence
    (summer time). Both follow zoneinfo with fold=0 (PEP 495).
    """
    local = dt.datetime.combine(day, parse_time(hh_mm), tzinfo=tz)
    return local.astimezone(dt.UTC)
