"""`kinect-agent capture|run|serve --source webcam [--camera N] [VIDEO]` on a real video (Sports2D's demo)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from kinect_agent import cli, formats
from kinect_agent.config import AgentConfig, save_config
from kinect_agent.formats.session_file import read_payload
from kinect_agent.queue import SessionQueue
from kinect_agent.vendor import model_info
from tests.media import sports2d_demo

pytest.importorskip("mediapipe")


def test_capture_from_a_video_records_a_webcam_session(tmp_path, capsys) -> None:
    out = tmp_path / "w.khs"
    assert cli.main(["capture", "--source", "webcam", str(sports2d_demo()), "--seconds", "1", "--fast",
                     "-o", str(out)]) == 0  # fmt: skip
    assert "webcam ->" in capsys.readouterr().err
    rec = formats.read(out)
    assert rec.meta.device == "webcam" and 25 <= rec.n_frames <= 31
    webcam = rec.meta.extra["webcam"]
    assert webcam["model"]["sha256"] == model_info("lite").sha256 and webcam["fps_achieved"] > 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--source", "webcam", "--camera", "7"], "camera 7 cannot be opened"),
        (["--source", "webcam", "--camera", "-1"], "camera index 0..99"),
        (["--source", "kinect_v2", "--camera", "0"], "only for the webcam source"),
        (["--source", "simulator", "VIDEO.mp4"], "only for --source webcam"),
        (["--source", "webcam", "--exercise", "squat"], "only for the simulator"),
    ],
)
def test_capture_refuses_in_one_line_and_writes_nothing(tmp_path, capsys, args, message) -> None:
    out = tmp_path / "w.khs"
    assert cli.main(["capture", *args, "--seconds", "1", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_run_queues_a_filtered_webcam_session(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "agent"))
    save_config(AgentConfig(server_url="http://127.0.0.1:1", device_token="khd_x", queue_dir=str(tmp_path / "q"),
                            patient_id=1))  # fmt: skip
    assert cli.main(["run", "--source", "webcam", str(sports2d_demo()), "--exercise", "squat", "--seconds", "1",
                     "--no-upload"]) == 0  # fmt: skip
    (pending,) = SessionQueue(str(tmp_path / "q")).pending()
    session = read_payload(pending)
    assert session.raw.meta.device == "webcam" and session.raw.meta.exercise == "squat"
    assert session.filtered is not None and session.filtered.n_frames == session.raw.n_frames


def test_serve_says_a_missing_camera_before_connecting(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "agent"))
    assert cli.main(["serve", "--source", "webcam", "--camera", "9"]) == 2
    assert "camera 9 cannot be opened" in capsys.readouterr().err


def test_the_agent_loads_without_mediapipe_until_a_webcam_is_opened() -> None:
    code = (
        "import sys\n"
        "from kinect_agent.sources import make_source\n"
        "source = make_source('webcam', camera=0)\n"
        "import kinect_agent.cli\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('mediapipe', 'cv2')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert done.stdout.strip() == "[]"
