"""Agent configuration and the pair / upload / run commands, against the real server where one is needed."""

from __future__ import annotations

import json
import os
import stat

import httpx
import pytest

from kinect_agent import cli
from kinect_agent.config import AgentConfig, ConfigError, config_path, load_config, save_config
from kinect_agent.queue import SessionQueue
from tests.kinect_agent._backend import *  # noqa: F403  (the real server's fixtures: pytest registers those imported)
from tests.kinect_agent._backend import LOADED_S, free_port


@pytest.fixture
def home(tmp_path, monkeypatch):
    """An empty agent home selected through $KINECT_AGENT_HOME."""
    folder = tmp_path / "agent"
    monkeypatch.setenv("KINECT_AGENT_HOME", str(folder))
    return folder


def _config(home, server_url: str) -> AgentConfig:
    config = AgentConfig(server_url=server_url, device_token="khd_x", queue_dir=str(home / "queue"), patient_id=1)
    save_config(config)
    return config


# ---------------------------------------------------------------------------------------------------- config


def test_config_round_trip_uses_agent_home_and_mode_0600(home) -> None:
    path = save_config(AgentConfig(server_url="https://c.example.org/", device_token="khd_t", queue_dir="/q"))
    assert path == home / "config.json"
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    loaded = load_config()
    assert loaded.server_url == "https://c.example.org" and loaded.device_token == "khd_t"


def test_missing_config_says_to_pair_first(home) -> None:
    with pytest.raises(ConfigError, match="kinect-agent pair --server URL --code CODE"):
        load_config()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{not json", "not JSON"),
        ("[1, 2]", "expected a JSON object"),
        ('{"server_url": "http://h"}', "'device_token' must be"),
        ('{"server_url": "x", "device_token": "t", "queue_dir": "/q"}', "must look like https://"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),  # was a RecursionError traceback
    ],
)
def test_corrupt_config_is_named(home, text, message) -> None:
    home.mkdir()
    path = config_path()
    path.write_text(text)
    path.chmod(0o600)
    with pytest.raises(ConfigError, match=message) as info:
        load_config()
    assert str(path) in str(info.value)


def test_config_readable_by_others_is_refused(home) -> None:
    path = save_config(AgentConfig(server_url="http://h", device_token="khd_t", queue_dir="/q"))
    path.chmod(0o644)
    with pytest.raises(ConfigError, match="chmod 600"):
        load_config()


def test_cli_reports_missing_config_as_one_line(home, capsys) -> None:
    assert cli.main(["upload", "--once"]) == 2
    assert "kinect-agent upload: error:" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------- pair


def test_pair_stores_a_working_device_token(home, live_server, pairing_code, capsys) -> None:
    patient, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url + "/", "--code", code, "--name", "test kinect"]) == 0
    config = load_config()
    assert config.patient_id == patient.id and config.device_token.startswith("khd_")
    assert config.server_url == live_server.url and config.queue_dir == str((home / "queue").resolve())
    me = httpx.get(
        f"{live_server.url}/api/v1/devices/me",
        headers={"Authorization": f"Bearer {config.device_token}"},
        timeout=LOADED_S,
    )
    assert me.status_code == 200 and me.json()["name"] == "test kinect"
    assert stat.S_IMODE(config_path().stat().st_mode) == 0o600


def test_pair_with_a_used_code_fails_clearly(home, live_server, pairing_code, capsys) -> None:
    _, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url, "--code", code]) == 0
    assert cli.main(["pair", "--server", live_server.url, "--code", code, "--force"]) == 2
    err = capsys.readouterr().err
    assert "HTTP 403" in err and "already used" in err


def test_pair_with_server_down_fails_clearly(home, capsys) -> None:
    assert cli.main(["pair", "--server", f"http://127.0.0.1:{free_port()}", "--code", "ABCD-EFGH"]) == 2
    assert "cannot reach" in capsys.readouterr().err
    assert not config_path().exists()


def test_pair_refuses_while_sessions_of_the_old_pairing_wait(home, capsys) -> None:
    config = _config(home, f"http://127.0.0.1:{free_port()}")
    SessionQueue(config.queue_dir).enqueue_bytes("a1", b"queued session")
    assert cli.main(["pair", "--server", config.server_url, "--code", "ABCD-EFGH"]) == 2
    assert "1 session(s) of the current pairing" in capsys.readouterr().err


def test_pair_refuses_a_bad_url(home, capsys) -> None:
    assert cli.main(["pair", "--server", "coach.example.org", "--code", "ABCD-EFGH"]) == 2
    assert "must look like https://" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------- run


def test_run_queues_first_even_when_the_server_is_down(home, capsys) -> None:
    config = _config(home, f"http://127.0.0.1:{free_port()}")
    status = cli.main(["run", "--source", "simulator", "--exercise", "squat", "--reps", "2", "--seed", "3"])
    assert status == 0
    pending = SessionQueue(config.queue_dir).pending()
    assert len(pending) == 1
    from kinect_agent.formats.session_file import read_payload

    payload = read_payload(pending[0])
    assert payload.filtered is not None and payload.raw.meta.exercise == "squat"
    assert payload.params["pipeline"].startswith("ukf-4pass")
    err = capsys.readouterr().err
    assert "kept in the queue" in err and "1 session(s) wait" in err
    assert list((home / "queue" / "captured").iterdir()) == []


def test_run_writes_whose_session_it_is_into_the_file(home) -> None:
    config = AgentConfig(server_url="http://127.0.0.1:1", device_token="khd_x", queue_dir=str(home / "queue"),
                         device_id=4, patient_id=9)  # fmt: skip
    save_config(config)
    assert cli.main(["run", "--source", "simulator", "--exercise", "squat", "--reps", "2", "--no-upload"]) == 0
    from kinect_agent.formats.session_file import read_payload

    (pending,) = SessionQueue(config.queue_dir).pending()
    assert read_payload(pending).recorded_by == {"device_id": 4, "patient_id": 9}


def test_run_replay_needs_a_file(home, capsys) -> None:
    _config(home, "http://127.0.0.1:1")
    assert cli.main(["run", "--source", "replay", "--exercise", "squat"]) == 2
    assert "FILE is needed" in capsys.readouterr().err


def test_run_refuses_a_bad_exercise_name(home, capsys) -> None:
    _config(home, "http://127.0.0.1:1")
    assert cli.main(["run", "--source", "simulator", "--exercise", "Squat Deep!"]) == 2
    assert "exercise slug" in capsys.readouterr().err


def test_config_json_holds_no_extra_secrets(home) -> None:
    _config(home, "http://h")
    assert set(json.loads(config_path().read_text())) == {
        "server_url", "device_token", "queue_dir", "device_id", "patient_id", "device_name"
    }  # fmt: skip
    assert os.access(config_path(), os.R_OK)


def test_the_same_session_is_rebuilt_byte_for_byte() -> None:
    """Same recording, id and start time -> same bytes, so a rebuilt session is deduplicated by the server."""
    from kinect_agent.capture import capture, make_payload
    from kinect_agent.formats.session_file import encode

    def build() -> bytes:
        rec = capture("simulator", exercise="elbow_flexion", reps=2, seed=5)
        return encode(
            make_payload(rec, session_id="5d0c1f3e-0000-4000-8000-000000000001", created_at="2026-11-01T09:00:00Z")
        )

    assert build() == build()


def test_pair_then_run_uploads_the_session(home, live_server, pairing_code, capsys) -> None:
    patient, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url, "--code", code]) == 0
    assert cli.main(["run", "--source", "simulator", "--exercise", "elbow_flexion", "--reps", "2"]) == 0
    queue = SessionQueue(load_config().queue_dir)
    assert (queue.counts().pending, queue.counts().sent, queue.counts().rejected) == (0, 1, 0)
    (receipt_file,) = queue.sent_dir.glob("*.json")
    receipt = json.loads(receipt_file.read_text())
    assert receipt["status_code"] == 201 and receipt["patient_id"] == patient.id
    assert receipt["exercise_slug"] == "elbow_flexion"
    assert "stored on the server (HTTP 201" in capsys.readouterr().err


def test_run_replays_a_file_into_the_queue(home, tmp_path) -> None:
    from kinect_agent import formats
    from kinect_agent.formats.session_file import read_payload
    from kinect_agent.sources.simulator import simulate

    config = _config(home, "http://127.0.0.1:1")
    recording = tmp_path / "squat.csv"
    formats.write(simulate("squat", 2, seed=4)[0], recording)
    assert cli.main(["run", "--source", "replay", str(recording), "--exercise", "squat", "--no-upload"]) == 0
    (path,) = SessionQueue(config.queue_dir).pending()
    payload = read_payload(path)
    assert payload.filtered is not None
    assert payload.raw.meta.exercise == "squat" and payload.filtered.n_frames == payload.raw.n_frames


# ---------------------------------------------------------------------------------------------------- start-up


@pytest.mark.parametrize("command", ["status", "upload", "pair", "convert"])
def test_a_command_loads_only_its_own_module(command: str) -> None:
    """`kinect-agent status` (and the other commands that do not filter) load neither the filter nor SciPy / numba:
    the agent's scheduled upload and a patient's status check start in a fraction of a second."""
    import subprocess
    import sys

    code = (
        "import sys\nfrom kinect_agent import cli\n"
        f"try:\n    cli.main([{command!r}, '--help'])\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in ('scipy.linalg', 'numba', 'kinect_agent.processing.pipeline') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]", out


def test_unknown_command_lists_every_command(capsys) -> None:
    with pytest.raises(SystemExit) as info:
        cli.main(["nope"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'nope'" in err and "'status'" in err and "'run'" in err
