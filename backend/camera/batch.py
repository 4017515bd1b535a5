"""A landmark batch as arrays: checked against the limits (each refusal names the field), packed for storage.

t: (T,) float64 s, the set's clock. world: (T, 33, 3) float32 m, the model's world frame (origin between the hips,
y down as BlazePose gives it). image: (T, 33, 3) float32, x and y normalised to the image, z relative depth.
visibility: (T, 33) float32 in 0..1.
"""

from __future__ import annotations

import hashlib
import zlib
from dataclasses import dataclass

import numpy as np

from backend.camera import limits
from backend.camera.schemas import BatchIn
from backend.exceptions import InvalidInput

L = limits.N_LANDMARKS


@dataclass(frozen=True)
class LandmarkBatch:
    """The frames of one batch (shapes in the module docstring)."""

    t: np.ndarray
    world: np.ndarray
    image: np.ndarray
    visibility: np.ndarray

    @property
    def n_frames(self) -> int:
        """Number of frames T."""
        return int(self.t.shape[0])


def _first_bad(mask: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.argwhere(mask)[0])


def _where(field: str, index: tuple[int, ...]) -> str:
    frame, *rest = index
    return f"frames[{frame}].{field}" + "".join(f"[{i}]" for i in rest)


def _refuse_outside(field: str, values: np.ndarray, low: float, high: float, unit: str) -> None:
    finite = np.isfinite(values)
    if not finite.all():
        where = _where(field, _first_bad(~finite))
        raise InvalidInput(f"body.{where}: must be a finite number, got {values[~finite][0]}")
    outside = (values < low) | (values > high)
    if outside.any():
        index = _first_bad(outside)
        raise InvalidInput(
            f"body.{_where(field, index)}: {float(values[index]):.6g} is outside {low:g}..{high:g}{unit}"
        )


def check_batch(body: BatchIn) -> LandmarkBatch:
    """Returns the body's frames as arrays; raises InvalidInput naming the first implausible value: NaN or
    infinite, a world landmark farther than MAX_WORLD_M, an image landmark far outside the picture, a visibility
    outside 0..1, a time outside 0..MAX_SET_S or not increasing within the batch."""
    t = np.array([f.t for f in body.frames], dtype=np.float64)
    world = np.array([f.world for f in body.frames], dtype=np.float64)
    image = np.array([f.image for f in body.frames], dtype=np.float64)
    visibility = np.array([f.visibility for f in body.frames], dtype=np.float64)
    bad_t = ~np.isfinite(t) | (t < 0) | (t > limits.MAX_SET_S)
    if bad_t.any():
        i = int(np.argmax(bad_t))
        raise InvalidInput(f"body.frames[{i}].t: {t[i]} is not a time in 0..{limits.MAX_SET_S:g} s of the set")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise InvalidInput(f"body.frames[{i}].t: {t[i]} s does not come after the frame before ({t[i - 1]} s)")
    w = limits.MAX_WORLD_M
    _refuse_outside("world", world, -w, w, " m")
    lo, hi = limits.IMAGE_XY_RANGE
    _refuse_outside("image", image[..., :2], lo, hi, " of the image")
    _refuse_outside("image", image[..., 2:], -limits.MAX_IMAGE_Z, limits.MAX_IMAGE_Z, "")
    _refuse_outside("visibility", visibility, 0.0, 1.0, "")
    return LandmarkBatch(t, world.astype(np.float32), image.astype(np.float32), visibility.astype(np.float32))


def pack(batch: LandmarkBatch) -> bytes:
    """Returns the batch's arrays as stored bytes (zlib of t float64, world, image, visibility float32)."""
    raw = b"".join(
        (
            batch.t.astype("<f8").tobytes(),
            batch.world.astype("<f4").tobytes(),
            batch.image.astype("<f4").tobytes(),
            batch.visibility.astype("<f4").tobytes(),
        )
    )
    return zlib.compress(raw, 6)


def unpack(data: bytes, n_frames: int) -> LandmarkBatch:
    """Returns the batch packed by pack(); n_frames: its T."""
    raw = zlib.decompress(data)
    sizes = (8 * n_frames, 4 * n_frames * L * 3, 4 * n_frames * L * 3, 4 * n_frames * L)
    if len(raw) != sum(sizes):
        raise ValueError(f"a stored batch of {n_frames} frames has {len(raw)} bytes, expected {sum(sizes)}")
    cuts = np.cumsum((0, *sizes))
    part = [raw[a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
    return LandmarkBatch(
        np.frombuffer(part[0], "<f8").copy(),
        np.frombuffer(part[1], "<f4").reshape(n_frames, L, 3).copy(),
        np.frombuffer(part[2], "<f4").reshape(n_frames, L, 3).copy(),
        np.frombuffer(part[3], "<f4").reshape(n_frames, L).copy(),
    )


def concat(batches: list[LandmarkBatch]) -> LandmarkBatch:
    """Returns the batches' frames one after the other (empty arrays when there are none)."""
    if not batches:
        return LandmarkBatch(
            np.zeros(0), np.zeros((0, L, 3), np.float32), np.zeros((0, L, 3), np.float32), np.zeros((0, L), np.float32)
        )
    return LandmarkBatch(
        *(np.concatenate([getattr(b, k) for b in batches]) for k in ("t", "world", "image", "visibility"))
    )


def content_hash(data: bytes) -> str:
    """Returns the SHA-256 (hex) of packed batch bytes."""
    return hashlib.sha256(data).hexdigest()
