"""`kinect-agent status`: pairing, server, queue and disk in plain words (and JSON), in every state a family meets."""

from __future__ import annotations

import json

import httpx

from kinect_agent import cli
from kinect_agent.commands import status
from kinect_agent.config import AgentConfig, save_config
from kinect_agent.queue import SessionQueue
from tests.kinect_agent._backend import *  # noqa: F403  (the real server's fixtures: pytest registers those imported)
from tests.kinect_agent._backend import free_port
from tests.kinect_agent.test_held_sessions import session_payload


def _config(tmp_path, monkeypatch, url: str) -> AgentConfig:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    config = AgentConfig(server_url=url, device_token="khd_x", queue_dir=str(tmp_path / "queue"), device_id=3,
                         patient_id=7, device_name="living-room Kinect")  # fmt: skip
    save_config(config)
    return config


def test_not_paired_says_to_pair_first(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "nobody"))
    assert cli.main(["status"]) == 2
    assert "pair" in capsys.readouterr().err


def test_server_down_is_said_plainly_and_sessions_wait(tmp_path, monkeypatch, capsys) -> None:
    config = _config(tmp_path, monkeypatch, f"http://127.0.0.1:{free_port()}")
    SessionQueue(config.queue_dir).enqueue(session_payload(1))
    assert cli.main(["status"]) == 0
    out = capsys.readouterr().out
    assert "Paired with http://127.0.0.1" in out and "device 3 (living-room Kinect) for patient 7" in out
    assert "cannot be reached right now" in out and "Sessions: 1 waiting to be sent, 0 sent, 0 set aside." in out
    assert "Disk: the queue uses" in out and "free on that disk" in out


def test_a_refused_device_and_sessions_set_aside_are_explained(tmp_path, monkeypatch) -> None:
    config = _config(tmp_path, monkeypatch, "http://coach.test")
    queue = SessionQueue(config.queue_dir)
    bad, held = queue.enqueue(session_payload(2)), queue.enqueue(session_payload(3))
    queue.mark_rejected(bad, {"status_code": 400, "detail": "InvalidSessionFile: truncated: file is 9 bytes"})
    queue.mark_held(held, {"status_code": 500, "detail": "InternalError: internal server error", "passes": 5})
    refused = httpx.MockTransport(lambda request: httpx.Response(401, json={"error": "NotAuthenticated"}))
    facts = status.collect(config, transport=refused)
    text = "\n".join(status.describe(facts))
    assert "no longer accepts this computer" in text and "kinect-agent pair" in text
    assert f"{bad.stem}: the server refused it (HTTP 400: InvalidSessionFile: truncated" in text
    assert f"{held.stem}: the server failed on it again and again (HTTP 500" in text and "--retry-held" in text
    assert facts["queue"]["rejected"] == 1 and facts["queue"]["held"] == 1


def test_a_working_agent_with_json_for_scripts(tmp_path, monkeypatch, capsys, live_server, pairing_code) -> None:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    _, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url, "--code", code]) == 0
    assert cli.main(["run", "--source", "simulator", "--exercise", "elbow_flexion", "--reps", "2"]) == 0
    capsys.readouterr()
    assert cli.main(["status", "--json"]) == 0
    facts = json.loads(capsys.readouterr().out)
    # this computer's clock agrees with the server's (whole seconds, a busy machine's answer late by a few more; the
    # command speaks of a wrong clock beyond status.CLOCK_OFF_S, 300 s)
    assert abs(facts["server"].pop("clock_off_s")) <= 5
    assert facts["server"] == {"reachable": True, "token_accepted": True, "detail": "device token accepted"}
    assert facts["queue"]["pending"] == 0 and facts["queue"]["uploaded"] == 1 and facts["queue"]["last_upload"]
    assert facts["queue"]["queue_bytes"] > 0 and facts["queue"]["set_aside"] == []
    assert cli.main(["status"]) == 0
    assert "The server answers (device token accepted)." in capsys.readouterr().out
