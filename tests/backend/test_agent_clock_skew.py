"""A home computer whose clock is wrong: the server files the session under the time it received it when the file's
created_at is implausible (in the future beyond CLOCK_TOLERANCE, or before 2000), and keeps the agent's value in
the stored file; a plausible created_at (an upload days after the recording) is kept as the start."""

from __future__ import annotations

import datetime as dt

import pytest

from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import make_khs

URL = "/api/v1/sessions"
OCTET = {"Content-Type": "application/octet-stream"}


def _iso(when: dt.datetime) -> str:
    return when.astimezone(dt.UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


def _upload(client, db_session, device_headers, make_user, created_at: str):
    _, headers = device_headers(make_user("patient"))
    db_session.commit()
    return client.post(URL, content=make_khs(created_at=created_at), headers={**OCTET, **headers})


@pytest.mark.parametrize(
    "skew",
    [dt.timedelta(days=3), dt.timedelta(hours=12), dt.timedelta(days=-30 * 365), None],
    ids=["3_days_fast", "12_hours_fast", "30_years_slow", "year_9999"],
)
def test_an_implausible_agent_clock_is_replaced_by_the_time_received(client, db_session, device_headers, make_user,
                                                                      auth_headers, skew):  # fmt: skip
    now = dt.datetime.now(dt.UTC)
    reported = _iso(now + skew) if skew is not None else "9999-12-31T23:59:59Z"
    response = _upload(client, db_session, device_headers, make_user, reported)
    assert response.status_code == 201, response.text
    started = dt.datetime.fromisoformat(response.json()["started_at"]).replace(tzinfo=dt.UTC)
    assert abs((started - now).total_seconds()) < 60, (started, now)
    stored = client.get(f"{URL}/{response.json()['id']}/file", headers=auth_headers(make_user("admin")))
    assert stored.status_code == 200, stored.text
    assert sf.decode(stored.content).created_at == reported  # the agent's value, as reported, stays in the file


def test_a_plausible_created_at_is_kept(client, db_session, device_headers, make_user):
    two_days_ago = dt.datetime.now(dt.UTC).replace(microsecond=0) - dt.timedelta(days=2)
    response = _upload(client, db_session, device_headers, make_user, _iso(two_days_ago))
    assert response.status_code == 201, response.text
    started = dt.datetime.fromisoformat(response.json()["started_at"]).replace(tzinfo=dt.UTC)
    assert started == two_days_ago


def test_a_clock_a_minute_fast_is_kept(client, db_session, device_headers, make_user):
    minute_ahead = dt.datetime.now(dt.UTC).replace(microsecond=0) + dt.timedelta(minutes=1)
    response = _upload(client, db_session, device_headers, make_user, _iso(minute_ahead))
    assert response.status_code == 201, response.text
    started = dt.datetime.fromisoformat(response.json()["started_at"]).replace(tzinfo=dt.UTC)
    assert started == minute_ahead
