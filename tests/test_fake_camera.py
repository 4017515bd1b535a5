"""The fake-camera clip for Chromium: a valid YUV4MPEG2 file made from Sports2D's public demo (BSD-3-Clause)."""

from __future__ import annotations

import pytest

from tests.fake_camera import append_blank, sports2d_y4m

pytest.importorskip("cv2")


def test_the_clip_has_the_header_and_frame_size_chromium_reads(tmp_path) -> None:
    path = sports2d_y4m(tmp_path / "camera.y4m", width=320, height=180, fps=10, start_s=1.0, seconds=1.5)
    data = path.read_bytes()
    header, _, rest = data.partition(b"\n")
    assert header == b"YUV4MPEG2 W320 H180 F10:1 Ip A1:1 C420jpeg"
    frame = len(b"FRAME\n") + 320 * 180 * 3 // 2  # I420: a full-size Y plane, U and V at a quarter each
    assert len(rest) == 15 * frame and rest[:6] == b"FRAME\n" and rest[frame : frame + 6] == b"FRAME\n"
    luma = rest[6 : 6 + 320 * 180]
    assert len(set(luma)) > 50, "a real picture, not a blank frame"


def test_an_empty_grey_stretch_is_appended_at_the_clips_size_and_rate(tmp_path) -> None:
    path = sports2d_y4m(tmp_path / "camera.y4m", width=320, height=180, fps=5, start_s=1.0, seconds=1.0)
    before = path.read_bytes()
    append_blank(path, 2.0, luma=100)
    data = path.read_bytes()
    frame = len(b"FRAME\n") + 320 * 180 * 3 // 2
    assert data[: len(before)] == before and len(data) == len(before) + 10 * frame  # 2 s at 5 fps
    last = data[-frame:]
    assert last[:6] == b"FRAME\n" and set(last[6 : 6 + 320 * 180]) == {100} and set(last[6 + 320 * 180 :]) == {128}


def test_odd_sizes_are_refused(tmp_path) -> None:
    with pytest.raises(ValueError, match="even"):
        sports2d_y4m(tmp_path / "c.y4m", width=321, height=180)
