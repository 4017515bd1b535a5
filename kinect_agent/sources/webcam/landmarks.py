"""The wire contract of camera-only capture: a batch of BlazePose landmark frames, as the browser page sends them to
the server and as the agent's webcam source makes them, with a strict parser.

JSON form (version 1)::

    {"version": 1,
     "image_size": [640, 480],                      # width, height of the analysed image, pixels
     "frames": [{"t": 12.345,                       # seconds, monotonic clock of the capturing device
                 "world": [[x, y, z], ... 33],      # metres, MediaPipe world frame (below)
                 "image": [[x, y, z], ... 33],      # normalised image coordinates (below)
                 "visibility": [v, ... 33]}, ...]}  # 0..1, the model's estimate that the point is in view, unoccluded

Frames:
- world landmarks: MediaPipe's pose world frame: origin at the midpoint of the hips, x to the image's right, y down
  the image, z away from the camera, metres (the scale comes from the model's body-size prior);
- image landmarks: x / image width and y / image height from the top-left corner (0..1 inside the image, a little
  outside allowed for points the model places beyond the border), z a relative depth on roughly x's scale.
Landmark order: BlazePose's 33 points (LANDMARKS).

The parser refuses, naming the field and frame: a missing or extra field, wrong shapes, non-numbers, NaN or
infinities, world coordinates beyond MAX_WORLD_M of the hips, image coordinates beyond MAX_IMAGE_COORD, visibility
outside 0..1, times that do not increase (within the batch, or against the last time of the previous batch), more
than MAX_FRAMES frames, an image size outside 16..8192 px.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

VERSION = 1
N_LANDMARKS = 33
LANDMARKS: tuple[str, ...] = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
    "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder", "left_elbow",
    "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky", "left_index", "right_index",
    "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
    "left_heel", "right_heel", "left_foot_index", "right_foot_index",
)  # fmt: skip
LANDMARK: dict[str, int] = {name: i for i, name in enumerate(LANDMARKS)}
MAX_FRAMES = 300  # 10 s at 30 fps: a batch is sent several times a second
MAX_WORLD_M = 3.0  # no body point is farther than this from the hips
MAX_IMAGE_COORD = 3.0  # |normalised coordinate| beyond this is not a point of this image
MAX_TIME_S = 1e9  # a monotonic clock in seconds (31 years): anything larger is not seconds
IMAGE_SIZE_RANGE = (16, 8192)
FIELDS = ("t", "world", "image", "visibility")


class LandmarkError(ValueError):
    """A landmark batch breaks the contract: names the field and, when one is to blame, the frame (0-based)."""

    def __init__(self, field: str, message: str, frame: int | None = None) -> None:
        self.field = field
        self.frame = frame
        self.message = message
        where = field if frame is None else f"frames[{frame}].{field}"
        super().__init__(f"{where}: {message}")


@dataclass(frozen=True)
class LandmarkBatch:
    """Landmark frames of one person, in time order.

    t: (N,) float64, s, strictly increasing, the capturing device's monotonic clock.
    world: (N, 33, 3) float64, m, MediaPipe world frame (x image-right, y image-down, z away from camera, hips origin).
    image: (N, 33, 3) float64, normalised image coordinates (x / width, y / height, relative z).
    visibility: (N, 33) float64, 0..1.
    image_size: (width, height) of the analysed image, pixels.
    """

    t: np.ndarray
    world: np.ndarray
    image: np.ndarray
    visibility: np.ndarray
    image_size: tuple[int, int]

    @property
    def n_frames(self) -> int:
        """Number of frames N."""
        return int(self.t.shape[0])

    def to_json(self) -> dict[str, Any]:
        """Returns the batch in its wire form (parse_batch reads it back)."""
        return {
            "version": VERSION,
            "image_size": list(self.image_size),
            "frames": [
                {
                    "t": float(self.t[i]),
                    "world": self.world[i].tolist(),
                    "image": self.image[i].tolist(),
                    "visibility": self.visibility[i].tolist(),
                }  # fmt: skip
                for i in range(self.n_frames)
            ],
        }

    @classmethod
    def concatenate(cls, batches: list[LandmarkBatch]) -> LandmarkBatch:
        """Joins batches of one image size in order; raises LandmarkError when times go back or sizes differ."""
        if not batches:
            raise LandmarkError("frames", "no batch to join")
        sizes = {b.image_size for b in batches}
        if len(sizes) > 1:
            raise LandmarkError("image_size", f"batches of different image sizes cannot be joined: {sorted(sizes)}")
        t = np.concatenate([b.t for b in batches])
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            raise LandmarkError("t", f"time goes back when joining batches: {t[back[0] + 1]} after {t[back[0]]}")
        return cls(t, np.concatenate([b.world for b in batches]), np.concatenate([b.image for b in batches]),
                   np.concatenate([b.visibility for b in batches]), batches[0].image_size)  # fmt: skip


def parse_batch(data: Any, *, after_t: float | None = None, max_frames: int = MAX_FRAMES) -> LandmarkBatch:
    """Returns the checked batch of a decoded JSON document; raises LandmarkError naming the field and frame.

    after_t: the last time already received in this set (s); the batch's first frame must come after it.
    """
    if not isinstance(data, dict):
        raise LandmarkError("batch", f"must be an object, got {type(data).__name__}")
    unknown = sorted(set(data) - {"version", "image_size", "frames"})
    if unknown:
        raise LandmarkError(unknown[0], "unknown field")
    if data.get("version") != VERSION or isinstance(data.get("version"), bool):
        raise LandmarkError("version", f"must be {VERSION}, got {data.get('version')!r}")
    size = data.get("image_size")
    low, high = IMAGE_SIZE_RANGE
    if not (isinstance(size, list) and len(size) == 2 and all(_is_int(v) and low <= v <= high for v in size)):
        raise LandmarkError("image_size", f"must be [width, height], integers in {low}..{high} px, got {size!r}")
    frames = data.get("frames")
    if not isinstance(frames, list):
        raise LandmarkError("frames", f"must be a list, got {type(frames).__name__}")
    if not frames:
        raise LandmarkError("frames", "is empty")
    if len(frames) > max_frames:
        raise LandmarkError("frames", f"has {len(frames)} frames, at most {max_frames} are allowed in one batch")
    n = len(frames)
    t = np.empty(n)
    world = np.empty((n, N_LANDMARKS, 3))
    image = np.empty((n, N_LANDMARKS, 3))
    visibility = np.empty((n, N_LANDMARKS))
    for i, frame in enumerate(frames):
        if not isinstance(frame, dict):
            raise LandmarkError("frame", f"must be an object, got {type(frame).__name__}", i)
        for name in FIELDS:
            if name not in frame:
                raise LandmarkError(name, "is missing", i)
        extra = sorted(set(frame) - set(FIELDS))
        if extra:
            raise LandmarkError(extra[0], "unknown field", i)
        t[i] = _number(frame["t"], "t", i)
        world[i] = _array(frame["world"], (N_LANDMARKS, 3), "world", i)
        image[i] = _array(frame["image"], (N_LANDMARKS, 3), "image", i)
        visibility[i] = _array(frame["visibility"], (N_LANDMARKS,), "visibility", i)
    return check_arrays(t, world, image, visibility, (int(size[0]), int(size[1])), after_t=after_t)


def check_arrays(
    t: np.ndarray,
    world: np.ndarray,
    image: np.ndarray,
    visibility: np.ndarray,
    image_size: tuple[int, int],
    *,
    after_t: float | None = None,
) -> LandmarkBatch:
    """Returns a LandmarkBatch of arrays that hold to the contract (shapes as LandmarkBatch); raises LandmarkError."""
    t, world, image, visibility = (np.asarray(a, dtype=np.float64) for a in (t, world, image, visibility))
    n = t.shape[0] if t.ndim == 1 else -1
    expected = {"t": ((n,), "(N,)"), "world": ((n, N_LANDMARKS, 3), "(N, 33, 3)"),
                "image": ((n, N_LANDMARKS, 3), "(N, 33, 3)"), "visibility": ((n, N_LANDMARKS), "(N, 33)")}  # fmt: skip
    for name, arr in (("t", t), ("world", world), ("image", image), ("visibility", visibility)):
        shape, shown = expected[name]
        if n < 0 or arr.shape != shape:
            raise LandmarkError(name, f"must have shape {shown} with N = len(t), got {arr.shape}")
    for name, arr in (("t", t), ("world", world), ("image", image), ("visibility", visibility)):
        bad = ~np.isfinite(arr.reshape(n, -1)).all(axis=1)
        if bad.any():
            raise LandmarkError(name, "has NaN or infinite values", int(np.argmax(bad)))
    if np.any(np.abs(t) > MAX_TIME_S):
        raise LandmarkError(
            "t", f"must be a monotonic time in seconds (|t| <= {MAX_TIME_S:g})", _first(np.abs(t) > MAX_TIME_S)
        )
    _check_range(world, MAX_WORLD_M, "world", "m from the hips: not a body point")
    _check_range(image, MAX_IMAGE_COORD, "image", "image widths from the corner: not a point of this image")
    if np.any((visibility < 0) | (visibility > 1)):
        raise LandmarkError(
            "visibility", "must be within 0..1", _first(np.any((visibility < 0) | (visibility > 1), axis=1))
        )
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise LandmarkError("t", f"must increase: {t[i]} after {t[i - 1]}", i)
    if after_t is not None and n and t[0] <= after_t:
        raise LandmarkError("t", f"must come after the previous batch's last time {after_t}, got {t[0]}", 0)
    width, height = image_size
    return LandmarkBatch(t, world, image, visibility, (int(width), int(height)))


def _check_range(arr: np.ndarray, limit: float, name: str, what: str) -> None:
    over = np.abs(arr) > limit
    if over.any():
        i, j, _ = np.argwhere(over)[0]
        raise LandmarkError(name, f"landmark {j} ({LANDMARKS[j]}) is {float(np.abs(arr[i, j]).max()):.3g} {what} "
                                  f"(limit {limit:g})", int(i))  # fmt: skip


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any, name: str, frame: int) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise LandmarkError(name, f"must be a number, got {type(value).__name__}", frame)
    if not math.isfinite(value):
        raise LandmarkError(name, "is NaN or infinite", frame)
    return float(value)


def _array(value: Any, shape: tuple[int, ...], name: str, frame: int) -> np.ndarray:
    """Returns a nested list of numbers as an array of `shape`; raises LandmarkError (wrong shape, not numbers)."""
    if not isinstance(value, list):
        raise LandmarkError(name, f"must be a list of shape {shape}, got {type(value).__name__}", frame)
    rows = value if len(shape) == 2 else [value]
    width = shape[-1]
    if len(shape) == 2 and len(value) != shape[0]:
        raise LandmarkError(name, f"must have {shape[0]} landmarks, got {len(value)}", frame)
    for row in rows:
        if not isinstance(row, list) or len(row) != width:
            got = len(row) if isinstance(row, list) else type(row).__name__
            raise LandmarkError(name, f"must have shape {shape}: a row of {width} numbers, got {got}", frame)
        for v in row:
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise LandmarkError(name, f"must hold numbers only, got {type(v).__name__}", frame)
    arr = np.asarray(value, dtype=np.float64)
    if not np.isfinite(arr).all():
        raise LandmarkError(name, "has NaN or infinite values", frame)
    return arr
