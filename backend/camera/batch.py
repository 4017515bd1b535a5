"""A landmark batch as the page sends it, checked and packed for storage.

The frames follow the webcam's wire contract (kinect_agent.sources.webcam.landmarks, version 1): t (N,) s on the
set's clock, world (N, 33, 3) m in MediaPipe's world frame (hips origin, x image-right, y down, z away), image
(N, 33, 3) normalised, visibility (N, 33) in 0..1, and the analysed image's size. The server's own limits
(backend.camera.limits) are checked first, each refusal naming the exact value (frames[i].world[j][k]); then the
contract's checks (check_arrays), so that a batch stored here is one the mapping takes.
"""

from __future__ import annotations

import hashlib
import zlib

import numpy as np

from backend.camera import limits
from backend.camera.schemas import BatchIn
from backend.exceptions import InvalidInput
from kinect_agent.formats import session_file
from kinect_agent.sources.webcam.landmarks import LandmarkBatch, LandmarkError, check_arrays

L = limits.N_LANDMARKS
MIN_STEP_S = session_file.MIN_FRAME_INTERVAL_S  # the closest two frames of a set may be (s), as in a session file


def _first_bad(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.argwhere(mask)[0])


def _where(field: str, index: tuple[int, ...]) -> str:
    frame, *rest = index
    return f"frames[{frame}].{field}" + "".join(f"[{i}]" for i in rest)


def _refuse_outside(field: str, values: np.ndarray, low: float, high: float, unit: str, offset: int = 0) -> None:
    """Raises InvalidInput naming the first value that is not finite or not within low..high (offset: the index of
    values' last axis in the full array)."""
    finite = np.isfinite(values)
    if not finite.all():
        index = _first_bad(~finite)
        where = _where(field, (*index[:-1], index[-1] + offset))
        raise InvalidInput(f"body.{where}: must be a finite number, got {values[index]}")
    outside = (values < low) | (values > high)
    if outside.any():
        index = _first_bad(outside)
        where = _where(field, (*index[:-1], index[-1] + offset))
        raise InvalidInput(f"body.{where}: {float(values[index]):.6g} is outside {low:g}..{high:g}{unit}")


def follows(later: np.ndarray, earlier: np.ndarray) -> np.ndarray:
    """Returns (N,) whether each time of later (N,) s comes at least MIN_STEP_S after that of earlier (N,) s: the
    frames a session file may hold (two frames 1 ms apart on the page's millisecond clock do)."""
    return later - earlier >= MIN_STEP_S - session_file.TIME_ROUNDING_S


def check_batch(body: BatchIn) -> LandmarkBatch:
    """Returns the body's frames as a LandmarkBatch; raises InvalidInput naming the first implausible value: NaN or
    infinite, a world landmark farther than MAX_WORLD_M, an image landmark far outside the picture, a visibility
    outside 0..1, a time outside 0..MAX_SET_S, or less than MIN_STEP_S after the frame before (the set's last frame
    received before is checked by service.add_batch, once it knows the batch is not a repeat)."""
    t = np.array([f.t for f in body.frames], dtype=np.float64)
    world = np.array([f.world for f in body.frames], dtype=np.float64)
    image = np.array([f.image for f in body.frames], dtype=np.float64)
    visibility = np.array([f.visibility for f in body.frames], dtype=np.float64)
    bad_t = ~np.isfinite(t) | (t < 0) | (t > limits.MAX_SET_S)
    if bad_t.any():
        i = int(np.argmax(bad_t))
        raise InvalidInput(f"body.frames[{i}].t: {t[i]} is not a time in 0..{limits.MAX_SET_S:g} s of the set")
    back = np.flatnonzero(~follows(t[1:], t[:-1]))
    if back.size:
        i = int(back[0]) + 1
        raise InvalidInput(f"body.frames[{i}].t: {t[i]} s does not come {MIN_STEP_S:g} s or more after the frame "
                           f"before ({t[i - 1]} s)")  # fmt: skip
    w = limits.MAX_WORLD_M
    _refuse_outside("world", world, -w, w, " m")
    lo, hi = limits.IMAGE_XY_RANGE
    _refuse_outside("image", image[..., :2], lo, hi, " of the image")
    _refuse_outside("image", image[..., 2:], -limits.MAX_IMAGE_Z, limits.MAX_IMAGE_Z, "", offset=2)
    _refuse_outside("visibility", visibility, 0.0, 1.0, "")
    try:
        return check_arrays(t, world, image, visibility, (body.image_size[0], body.image_size[1]))
    except LandmarkError as exc:
        raise InvalidInput(f"body.{exc}") from None


def pack(batch: LandmarkBatch) -> bytes:
    """Returns the batch's arrays as stored bytes: zlib of t float64, then world, image, visibility float32."""
    raw = b"".join((batch.t.astype("<f8").tobytes(), batch.world.astype("<f4").tobytes(),
                    batch.image.astype("<f4").tobytes(), batch.visibility.astype("<f4").tobytes()))  # fmt: skip
    return zlib.compress(raw, 6)


def unpack(data: bytes, n_frames: int, image_size: tuple[int, int]) -> LandmarkBatch:
    """Returns the batch packed by pack(); n_frames: its N; image_size: (width, height) px."""
    raw = zlib.decompress(data)
    sizes = (8 * n_frames, 4 * n_frames * L * 3, 4 * n_frames * L * 3, 4 * n_frames * L)
    if len(raw) != sum(sizes):
        raise ValueError(f"a stored batch of {n_frames} frames has {len(raw)} bytes, expected {sum(sizes)}")
    cuts = np.cumsum((0, *sizes))
    part = [raw[a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
    return LandmarkBatch(
        np.frombuffer(part[0], "<f8").astype(np.float64),
        np.frombuffer(part[1], "<f4").reshape(n_frames, L, 3).astype(np.float64),
        np.frombuffer(part[2], "<f4").reshape(n_frames, L, 3).astype(np.float64),
        np.frombuffer(part[3], "<f4").reshape(n_frames, L).astype(np.float64),
        (int(image_size[0]), int(image_size[1])),
    )


def content_hash(data: bytes) -> str:
    """Returns the SHA-256 (hex) of packed batch bytes."""
    return hashlib.sha256(data).hexdigest()
