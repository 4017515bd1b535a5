"""A video file as Chromium's fake camera: writes a YUV4MPEG2 (.y4m) clip that
`--use-fake-device-for-media-stream --use-file-for-fake-video-capture=FILE.y4m` plays as the webcam.

    from tests.fake_camera import sports2d_y4m
    path = sports2d_y4m(tmp_path / "camera.y4m")          # Sports2D's demo (BSD-3-Clause), see tests/media.py
    append_blank(path, 4.0)                                # then 4 s of an empty grey picture (nobody in view)

The clip is made at test time from a public video shipped in a registry package (tests/media.py); OpenCV (from the
`webcam` extra's mediapipe dependencies) decodes it, no ffmpeg is needed. Frames are scaled to fit width x height,
letterboxed with black, converted to I420 (BT.601, full range: the `C420jpeg` tag) and written raw.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.media import pose2sim_multi_view, sports2d_demo


def write_y4m(
    source: Path,
    out: Path,
    *,
    width: int = 640,
    height: int = 360,
    fps: int = 30,
    start_s: float = 0.0,
    seconds: float | None = None,
    hold_s: tuple[float, float] = (0.0, 0.0),
    crop: tuple[float, float, float, float] | None = None,
) -> Path:
    """Writes frames of the video `source` from start_s on (all, or `seconds` of them) to `out` as .y4m at `fps`
    (frames are dropped or repeated to reach it), the first picture shown hold_s[0] seconds before them and the last
    hold_s[1] seconds after (a patient standing still before and after the set); returns out. width and height must
    be even. crop: (x0, y0, x1, y1), the part of the source's picture kept, as fractions of its width and height
    (None: all of it)."""
    import cv2

    if width % 2 or height % 2:
        raise ValueError(f"width and height must be even for I420, got {width}x{height}")
    cap = cv2.VideoCapture(str(source))
    if not cap.isOpened():
        raise RuntimeError(f"cannot open video {source}")
    src_fps = cap.get(cv2.CAP_PROP_FPS) or 30.0
    first = int(round(start_s * src_fps))
    wanted = None if seconds is None else int(np.ceil(seconds * src_fps)) + 1
    frames: list[np.ndarray] = []
    for _ in range(first):  # skipped without decoding into arrays
        if not cap.grab():
            break
    while wanted is None or len(frames) < wanted:
        ok, frame = cap.read()
        if not ok:
            break
        if crop is not None:
            h, w = frame.shape[:2]
            frame = frame[int(crop[1] * h) : int(crop[3] * h), int(crop[0] * w) : int(crop[2] * w)]
        frames.append(frame)
    cap.release()
    if not frames:
        raise RuntimeError(f"{source}: no frame after {start_s} s")
    n_out = int(len(frames) / src_fps * fps) if seconds is None else int(round(seconds * fps))
    picks = np.minimum((np.arange(n_out) * src_fps / fps).astype(int), len(frames) - 1)
    before, after = (int(round(h * fps)) for h in hold_s)
    picks = np.concatenate([np.zeros(before, dtype=int), picks, np.full(after, picks[-1])])
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "wb") as f:
        f.write(f"YUV4MPEG2 W{width} H{height} F{fps}:1 Ip A1:1 C420jpeg\n".encode())
        for i in picks:
            f.write(b"FRAME\n")
            f.write(cv2.cvtColor(_fit(frames[i], width, height), cv2.COLOR_BGR2YUV_I420).tobytes())
    return out


def _fit(frame: np.ndarray, width: int, height: int) -> np.ndarray:
    """Returns the BGR frame scaled to fit width x height, centred on black."""
    import cv2

    h, w = frame.shape[:2]
    scale = min(width / w, height / h)
    nw, nh = max(2, int(round(w * scale))), max(2, int(round(h * scale)))
    canvas = np.zeros((height, width, 3), dtype=np.uint8)
    x0, y0 = (width - nw) // 2, (height - nh) // 2
    canvas[y0 : y0 + nh, x0 : x0 + nw] = cv2.resize(frame, (nw, nh), interpolation=cv2.INTER_AREA)
    return canvas


def append_blank(path: Path, seconds: float, luma: int = 128) -> Path:
    """Appends `seconds` of one grey level (0 black .. 255 white; nobody in view) to the .y4m at path, at its own size
    and frame rate (read from its header); returns path."""
    with open(path, "rb") as f:
        header = f.readline().decode().split()
    fields = {h[0]: h[1:] for h in header[1:]}
    width, height = int(fields["W"]), int(fields["H"])
    num, den = (int(v) for v in fields["F"].split(":"))
    frame = b"FRAME\n" + bytes([luma]) * (width * height) + bytes([128]) * (width * height // 2)
    with open(path, "ab") as f:
        f.write(frame * int(round(seconds * num / den)))
    return path


def sports2d_y4m(out: Path, **kwargs) -> Path:
    """Writes Sports2D's demo (one person, side view, BSD-3-Clause) as a fake-camera clip; see write_y4m."""
    return write_y4m(sports2d_demo(), out, **kwargs)


def _y4m_layout(path: Path) -> tuple[int, int, int, int]:
    """Returns (header bytes, width, height, bytes per frame with its FRAME line) of a .y4m written here."""
    with open(path, "rb") as f:
        header = f.readline()
    fields = {h[0]: h[1:] for h in header.decode().split()[1:]}
    width, height = int(fields["W"]), int(fields["H"])
    return len(header), width, height, len(b"FRAME\n") + width * height * 3 // 2


def y4m_frame_count(path: Path) -> int:
    """Returns how many frames the .y4m at path holds."""
    head, _, _, frame = _y4m_layout(path)
    return (path.stat().st_size - head) // frame


def read_y4m(path: Path, indices: list[int]) -> list[np.ndarray]:
    """Returns the frames `indices` of the .y4m at path as RGB images (height, width, 3) uint8: what the fake camera
    plays, decoded back (I420 to RGB by OpenCV)."""
    import cv2

    head, width, height, frame = _y4m_layout(path)
    out = []
    with open(path, "rb") as f:
        for i in indices:
            f.seek(head + i * frame)
            data = f.read(frame)
            if len(data) != frame or not data.startswith(b"FRAME\n"):
                raise ValueError(f"{path}: no frame {i}")
            yuv = np.frombuffer(data[6:], dtype=np.uint8).reshape(height * 3 // 2, width)
            out.append(cv2.cvtColor(yuv, cv2.COLOR_YUV2RGB_I420))
    return out


# Pose2Sim's two-person demo, camera 2 (portrait 1080 x 1920): the band where both people are, whole (heads to feet)
TWO_PEOPLE_CROP = (0.0, 0.25, 1.0, 0.85)


def two_people_y4m(out: Path, **kwargs) -> Path:
    """Writes Pose2Sim's two-person demo (camera 2, BSD-3-Clause, tests/media.py; 1.7 s, two people walking about a
    room, both in view throughout), cropped to TWO_PEOPLE_CROP, as a fake-camera clip; see write_y4m."""
    return write_y4m(pose2sim_multi_view(2), out, crop=TWO_PEOPLE_CROP, **kwargs)
