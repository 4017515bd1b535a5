"""The fake-camera clip for Chromium: a valid YUV4MPEG2 file made from Sports2D's public demo (BSD-3-Clause)."""

from __future__ import annotations

import pytest

from tests.fake_camera import _fit, append_blank, read_y4m, sports2d_y4m, y4m_frame_count

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


def test_frames_read_back_are_the_pictures_written(tmp_path) -> None:
    import cv2
    import numpy as np

    from tests.media import sports2d_demo

    path = sports2d_y4m(tmp_path / "camera.y4m", width=320, height=180, fps=30, start_s=2.0, seconds=0.5)
    append_blank(path, 0.2, luma=100)
    assert y4m_frame_count(path) == 15 + 6
    first, grey = read_y4m(path, [0, 20])
    assert first.shape == (180, 320, 3) and first.dtype == np.uint8
    cap = cv2.VideoCapture(str(sports2d_demo()))
    cap.set(cv2.CAP_PROP_POS_FRAMES, 60)  # 2 s at the demo's 30 fps
    ok, bgr = cap.read()
    cap.release()
    assert ok
    truth = cv2.cvtColor(_fit(bgr, 320, 180), cv2.COLOR_BGR2RGB).astype(float)
    assert np.median(np.abs(first - truth)) <= 4, "the picture written (I420 loses a little colour)"
    assert np.abs(grey.astype(float) - 100).max() <= 2
    with pytest.raises(ValueError, match="no frame 21"):
        read_y4m(path, [21])


def test_the_first_and_last_pictures_are_held_before_and_after_the_clip(tmp_path) -> None:
    import numpy as np

    path = sports2d_y4m(tmp_path / "camera.y4m", width=320, height=180, fps=10, start_s=2.0, seconds=1.0,
                        hold_s=(0.5, 0.3))  # fmt: skip
    plain = sports2d_y4m(tmp_path / "plain.y4m", width=320, height=180, fps=10, start_s=2.0, seconds=1.0)
    assert y4m_frame_count(path) == 5 + 10 + 3
    held = read_y4m(path, list(range(18)))
    clip = read_y4m(plain, list(range(10)))
    assert all(np.array_equal(held[k], clip[0]) for k in range(6))  # 5 held, then the clip's first picture itself
    assert all(np.array_equal(held[5 + k], clip[k]) for k in range(10))
    assert all(np.array_equal(held[k], clip[-1]) for k in range(14, 18))
    assert not np.array_equal(clip[0], clip[-1]), "the clip moves, so holding is seen"
