"""The server readies the camera sets' live count when it starts (Settings.LIVE_WARM_UP), so that the first batch
of the first set does not pay for the live path's first run (the webcam's live filter, processing.online.live_filter,
and the repetition counter's first evaluations)."""

from __future__ import annotations

from fastapi.testclient import TestClient

from backend.camera import live_count
from backend.config import Settings
from backend.main import create_app
from kinect_agent.processing.joint_smoother import JointFilter


def test_the_server_warms_the_live_filter_up_at_start_up_once(monkeypatch):
    monkeypatch.setitem(live_count._WARMING, "thread", None)  # as in a process that never warmed up
    made = []

    def live_filter(config):
        made.append(JointFilter(config))
        return made[-1]

    monkeypatch.setattr(live_count, "live_filter", live_filter)
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", LIVE_WARM_UP=True)
    with TestClient(create_app(settings)):
        thread = live_count._WARMING["thread"]
        assert thread is not None and thread.name == "camera-warm-up"
        thread.join(timeout=600)
        assert not thread.is_alive()
    assert made and made[0].z_last is not None, "the webcam's live filter ran before any set"
    assert live_count.start_warm_up() is thread  # once per process, however many apps start


def test_no_warm_up_when_it_is_turned_off(monkeypatch):
    monkeypatch.setitem(live_count._WARMING, "thread", None)
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", LIVE_WARM_UP=False)
    with TestClient(create_app(settings)):
        assert live_count._WARMING["thread"] is None
