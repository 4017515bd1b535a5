"""A home computer whose clock is wrong: its sessions are stored (a file refused for it before goes on
`upload --retry-rejected`), and `kinect-agent status` tells the family in plain words that the clock is wrong."""

from __future__ import annotations

import datetime as dt
import json

import pytest

from kinect_agent import cli, clock
from kinect_agent.config import load_config
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.queue import SessionQueue
from tests.kinect_agent._backend import *  # noqa: F403  (the real server's fixtures: pytest registers those imported)
from tests.kinect_agent.test_held_sessions import session_payload

THREE_DAYS = dt.timedelta(days=3)


@pytest.fixture
def paired(tmp_path, monkeypatch, live_server, pairing_code) -> None:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    _, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url, "--code", code]) == 0


def _fast_clock(monkeypatch, skew: dt.timedelta) -> None:
    real = clock.utc_now
    monkeypatch.setattr(clock, "utc_now", lambda: real() + skew)


@pytest.mark.parametrize("skew", [THREE_DAYS, dt.timedelta(days=-30 * 365)], ids=["3_days_fast", "30_years_slow"])
def test_a_session_refused_for_a_wrong_clock_goes_on_retry(paired, capsys, skew) -> None:
    config = load_config()
    made_at = (dt.datetime.now(dt.UTC) + skew).isoformat(timespec="seconds").replace("+00:00", "Z")
    base = session_payload(4)
    payload = SessionPayload(session_id=base.session_id, raw=base.raw, created_at=made_at,
                             recorded_by=config.recorded_by)  # fmt: skip
    queue = SessionQueue(config.queue_dir)
    refused = {"status_code": 400, "detail": f"InvalidSessionFile: bad_header: created_at {made_at!r} is not between "
               "2000-01-01 and tomorrow"}  # fmt: skip
    queue.mark_rejected(queue.enqueue(payload), refused)  # as the server before this change answered
    assert cli.main(["upload", "--once", "--retry-rejected"]) == 0, capsys.readouterr().err
    counts = queue.counts()
    assert (counts.sent, counts.rejected, counts.pending) == (1, 0, 0)


def test_status_says_the_clock_is_wrong(paired, monkeypatch, capsys) -> None:
    _fast_clock(monkeypatch, THREE_DAYS)
    capsys.readouterr()
    assert cli.main(["status"]) == 0
    out = capsys.readouterr().out
    assert "This computer's clock is wrong: it is 3 days ahead of the server's." in out, out
    assert "Set the computer's date and time" in out
    assert cli.main(["status", "--json"]) == 0
    server = json.loads(capsys.readouterr().out)["server"]
    assert server["clock_off_s"] == pytest.approx(THREE_DAYS.total_seconds(), abs=5)


def test_status_says_nothing_of_a_right_clock(paired, capsys) -> None:
    capsys.readouterr()
    assert cli.main(["status"]) == 0
    assert "clock" not in capsys.readouterr().out
