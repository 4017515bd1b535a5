"""Reminder bodies."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, Field


class ReminderTimeOut(BaseModel):
    """One reminder time of the patient's day."""

    time: str = Field(description="wall-clock time in the patient's time zone, HH:MM", examples=["10:00"])
    due_at: dt.datetime = Field(description="the same instant in UTC", examples=["2026-11-27T09:00:00Z"])
    passed: bool = Field(description="whether the time is already past", examples=[False])


class RemindersOut(BaseModel):
    """A patient's reminders on their local day, from the plan running that day."""

    time_zone: str = Field(description="the IANA time zone of the times", examples=["Europe/Berlin"])
    local_date: dt.date = Field(description="today in that time zone", examples=["2026-11-27"])
    times: list[ReminderTimeOut]
    next: ReminderTimeOut | None = Field(description="the next reminder still to come today; null: none")
    emails: bool = Field(
        description="whether reminders also come by e-mail (server configured, patient not unsubscribed)"
    )


class UnsubscribedOut(BaseModel):
    """The answer of an unsubscribe link: the patient gets no more reminder e-mails."""

    unsubscribed: bool = Field(examples=[True])
    since: dt.datetime = Field(description="when the e-mails were stopped (the first use of a link)")
