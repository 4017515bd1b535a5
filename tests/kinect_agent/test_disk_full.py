"""A full disk at home (OSError ENOSPC injected at the queue's one write call; a real full filesystem cannot be made
here): `kinect-agent run` keeps the set's frames in memory, says so in plain words, writes the session once there
is room, and never prints a traceback."""

from __future__ import annotations

import errno

import pytest

from kinect_agent import cli, disk_full, queue
from kinect_agent.config import AgentConfig, load_config, save_config
from kinect_agent.queue import SessionQueue
from tests.kinect_agent._backend import *  # noqa: F403  (the real server's fixtures: pytest registers those imported)

RUN = ["run", "--source", "simulator", "--exercise", "elbow_flexion", "--reps", "2", "--no-upload"]


@pytest.fixture
def paired(tmp_path, monkeypatch) -> SessionQueue:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    save_config(AgentConfig(server_url="http://coach.test", device_token="khd_x", queue_dir=str(tmp_path / "q"),
                            device_id=3, patient_id=7))  # fmt: skip
    monkeypatch.setattr(disk_full, "RETRY_S", 0.01)
    return SessionQueue(load_config().queue_dir)


def _disk_full_for(monkeypatch, n_writes: int, folder: str = "/") -> list[str]:
    """Makes the queue's next n_writes writes into folder fail with ENOSPC (then the disk has room again); returns
    the paths that were refused."""
    real = queue._write_durably
    refused: list[str] = []

    def write(path, data) -> None:
        if len(refused) < n_writes and folder in str(path):
            refused.append(str(path))
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(path, data)

    monkeypatch.setattr(queue, "_write_durably", write)
    return refused


def test_a_set_whose_safety_copy_hits_a_full_disk_is_still_queued(paired, monkeypatch, capsys) -> None:
    refused = _disk_full_for(monkeypatch, 1)
    assert cli.main(RUN) == 0
    err = capsys.readouterr().err
    assert "/captured/" in refused[0]
    assert "The disk of this computer is full" in err and "its frames are kept in memory" in err, err
    assert "Traceback" not in err
    assert paired.counts().pending == 1 and not list(paired.captured_dir.iterdir())


def test_the_session_is_written_as_soon_as_space_frees(paired, monkeypatch, capsys) -> None:
    refused = _disk_full_for(monkeypatch, 5)  # the safety copy, then four tries of the session itself
    assert cli.main(RUN) == 0
    err = capsys.readouterr().err
    assert len(refused) == 5 and all("/pending/" in path for path in refused[1:])
    assert err.count("This session is kept in memory and saved as soon as there is room") == 1, err
    assert "Traceback" not in err
    assert paired.counts().pending == 1


def test_a_full_disk_elsewhere_is_one_plain_line(paired, monkeypatch, capsys) -> None:
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", "/q/pending/x.khs")

    monkeypatch.setattr(queue.SessionQueue, "recover_held", full)
    assert cli.main(RUN) == 1
    err = capsys.readouterr().err
    assert err.startswith("kinect-agent run: The disk of this computer is full (writing /q/pending/x.khs)."), err


def test_a_receipt_the_full_disk_refuses_leaves_the_session_queued(tmp_path, monkeypatch, capsys, live_server,
                                                                   pairing_code) -> None:  # fmt: skip
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    _, code = pairing_code()
    assert cli.main(["pair", "--server", live_server.url, "--code", code]) == 0
    _disk_full_for(monkeypatch, 1, "/sent/")
    assert cli.main(RUN[:-1]) == 0
    err = capsys.readouterr().err
    assert "The disk of this computer is full" in err and "goes with `kinect-agent upload`" in err, err
    sessions = SessionQueue(load_config().queue_dir)
    assert sessions.counts().pending == 1  # stored on the server; the next pass gets "already stored" and a receipt
    assert cli.main(["upload", "--once"]) == 0
    assert "already stored on the server" in capsys.readouterr().err
    assert (sessions.counts().pending, sessions.counts().sent) == (0, 1)
