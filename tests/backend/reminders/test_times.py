"""Reminder times in a patient's time zone: the UTC instant of a wall-clock time, daylight saving, bad input."""

from __future__ import annotations

import datetime as dt

import pytest

from backend.reminders.times import due_at, local_date, normalise_times, parse_time, zone

BERLIN = zone("Europe/Berlin")
UTC = dt.UTC


@pytest.mark.parametrize(
    ("day", "expected_utc"),
    [
        (dt.date(2026, 11, 27), dt.datetime(2026, 11, 27, 7, 0, tzinfo=UTC)),  # winter time, UTC+1
        (dt.date(2026, 7, 1), dt.datetime(2026, 7, 1, 6, 0, tzinfo=UTC)),  # summer time, UTC+2
        (dt.date(2026, 3, 28), dt.datetime(2026, 3, 28, 7, 0, tzinfo=UTC)),  # the day before the clocks go forward
        (dt.date(2026, 3, 29), dt.datetime(2026, 3, 29, 6, 0, tzinfo=UTC)),  # the day they do (02:00 -> 03:00)
        (dt.date(2026, 10, 25), dt.datetime(2026, 10, 25, 7, 0, tzinfo=UTC)),  # the day they go back (03:00 -> 02:00)
    ],
)
def test_eight_in_berlin_is_due_at_the_right_utc_instant(day, expected_utc):
    assert due_at(day, "08:00", BERLIN) == expected_utc


def test_a_time_the_spring_change_skips_falls_an_hour_later_on_the_clock():
    at = due_at(dt.date(2026, 3, 29), "02:30", BERLIN)
    assert at == dt.datetime(2026, 3, 29, 1, 30, tzinfo=UTC)
    assert at.astimezone(BERLIN).strftime("%H:%M") == "03:30"


def test_a_time_the_autumn_change_repeats_is_its_first_occurrence():
    at = due_at(dt.date(2026, 10, 25), "02:30", BERLIN)
    assert at == dt.datetime(2026, 10, 25, 0, 30, tzinfo=UTC)  # 02:30 summer time (UTC+2), not 01:30 UTC


def test_due_at_agrees_with_fixed_offsets_over_a_year():
    """Cross-check against the plain rule of the EU: summer time from the last Sunday of March to the last Sunday of
    October (01:00 UTC each), UTC+2 then, UTC+1 otherwise."""

    def last_sunday(year: int, month: int) -> dt.date:
        d = dt.date(year, month, 31)
        return d - dt.timedelta(days=(d.weekday() + 1) % 7)

    day = dt.date(2026, 1, 1)
    while day.year == 2026:
        summer = last_sunday(2026, 3) <= day < last_sunday(2026, 10)
        offset = dt.timedelta(hours=2 if summer else 1)
        expected = dt.datetime.combine(day, dt.time(18, 15), tzinfo=UTC) - offset
        assert due_at(day, "18:15", BERLIN) == expected, f"{day}"
        day += dt.timedelta(days=1)


def test_other_zones():
    assert due_at(dt.date(2026, 11, 27), "08:00", zone("America/New_York")) == dt.datetime(2026, 11, 27, 13, 0,
                                                                                           tzinfo=UTC)  # fmt: skip
    assert due_at(dt.date(2026, 11, 27), "08:00", zone("Asia/Kolkata")) == dt.datetime(2026, 11, 27, 2, 30, tzinfo=UTC)


def test_local_date_is_the_patients_day_not_utcs():
    late_evening_utc = dt.datetime(2026, 11, 27, 23, 30, tzinfo=UTC)
    assert local_date(late_evening_utc, BERLIN) == dt.date(2026, 11, 28)
    assert local_date(late_evening_utc, zone("America/Los_Angeles")) == dt.date(2026, 11, 27)


def test_times_are_sorted_and_written_with_two_digits():
    assert normalise_times(["18:00", " 08:30", "00:00"]) == ["00:00", "08:30", "18:00"]
    assert parse_time("23:59") == dt.time(23, 59)


@pytest.mark.parametrize(
    ("given", "says"),
    [
        (["24:00"], "reminder time '24:00' is not a time like 08:30"),
        (["8:30"], "reminder time '8:30' is not a time like 08:30"),
        (["08:60"], "reminder time '08:60' is not a time like 08:30"),
        (["noon"], "reminder time 'noon' is not a time like 08:30"),
        (["08:00", "08:00"], "reminder time 08:00 is given twice"),
        (["08:00", "09:00", "10:00", "11:00", "12:00", "13:00", "14:00"], "at most 6 reminder times a day; got 7"),
    ],
)
def test_bad_times_say_what_is_wrong(given, says):
    with pytest.raises(ValueError, match=says):
        normalise_times(given)


@pytest.mark.parametrize("name", ["Europe/Berlinn", "CEST", "+02:00", "", "../etc/passwd"])
def test_unknown_zones_are_refused_by_name(name):
    with pytest.raises(ValueError, match="is not an IANA time zone name like Europe/Berlin"):
        zone(name)
