"""Kinect SDK joint sets (v1: 20 joints, v2: 25 joints) and their mapping onto our 20-joint skeleton.

Kinect v1 joint order is exactly `kinect_agent.skeleton.JOINTS`. Kinect v2 adds SpineShoulder (the v1
ShoulderCenter equivalent, our NECK), hand tips and thumbs; the v2 "Neck" sits between SpineShoulder
and Head and has no counterpart in our model, so it is dropped with the hand tips and thumbs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats._rows import is_number, number_hint
from kinect_agent.formats._text import last_content_line, read_lines

KINECT_V1_JOINTS: tuple[str, ...] = (
    "HipCenter", "Spine", "ShoulderCenter", "Head",
    "ShoulderLeft", "ElbowLeft", "WristLeft", "HandLeft",
    "ShoulderRight", "ElbowRight", "WristRight", "HandRight",
    "HipLeft", "KneeLeft", "AnkleLeft", "FootLeft",
    "HipRight", "KneeRight", "AnkleRight", "FootRight",
)  # fmt: skip

KINECT_V2_JOINTS: tuple[str, ...] = (
    "SpineBase", "SpineMid", "Neck", "Head",
    "ShoulderLeft", "ElbowLeft", "WristLeft", "HandLeft",
    "ShoulderRight", "ElbowRight", "WristRight", "HandRight",
    "HipLeft", "KneeLeft", "AnkleLeft", "FootLeft",
    "HipRight", "KneeRight", "AnkleRight", "FootRight",
    "SpineShoulder", "HandTipLeft", "ThumbLeft", "HandTipRight", "ThumbRight",
)  # fmt: skip

# Our joint name -> source joint name, for each joint set.
V1_TO_SKELETON: dict[str, str] = dict(zip(skeleton.JOINTS, KINECT_V1_JOINTS, strict=True))
V2_TO_SKELETON: dict[str, str] = {
    **V1_TO_SKELETON,
    "ROOT": "SpineBase",
    "SPINE": "SpineMid",
    "NECK": "SpineShoulder",
}

JOINT_SETS: dict[str, tuple[tuple[str, ...], dict[str, str]]] = {
    "kinect1": (KINECT_V1_JOINTS, V1_TO_SKELETON),
    "kinect2": (KINECT_V2_JOINTS, V2_TO_SKELETON),
}


def source_indices(joint_set: str) -> np.ndarray:
    """Returns (20,) int: for each of our joints (JOINTS order), its index in the named source joint set."""
    if joint_set not in JOINT_SETS:
        raise ValueError(f"unknown joint set {joint_set!r}; expected one of {', '.join(JOINT_SETS)}")
    names, mapping = JOINT_SETS[joint_set]
    return np.array([names.index(mapping[j]) for j in skeleton.JOINTS])


def to_skeleton(
    positions: np.ndarray, joint_set: str, state: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Selects and reorders Kinect joints into our 20-joint skeleton.

    positions: (T, n_src, 3) float, metres, Kinect camera space (y up); NaN = untracked.
    joint_set: "kinect1" (n_src = 20) or "kinect2" (n_src = 25).
    state: (T, n_src) int 0/1/2, or None for 2 wherever the position is finite.
    returns: positions (T, 20, 3) float64 metres, state (T, 20) int8; state 0 exactly where NaN.
    """
    positions = np.asarray(positions, dtype=np.float64)
    n_src = len(JOINT_SETS[joint_set][0]) if joint_set in JOINT_SETS else -1
    index = source_indices(joint_set)
    if positions.ndim != 3 or positions.shape[1:] != (n_src, 3):
        raise ValueError(f"positions must have shape (T, {n_src}, 3) for {joint_set}, got {positions.shape}")
    out = positions[:, index, :].copy()
    finite = np.all(np.isfinite(out), axis=-1)
    if state is None:
        out_state = np.where(finite, skeleton.TRACKED, skeleton.NOT_TRACKED).astype(np.int8)
    else:
        state = np.asarray(state)
        if state.shape != positions.shape[:2]:
            raise ValueError(f"state must have shape {positions.shape[:2]}, got {state.shape}")
        out_state = state[:, index].astype(np.int8)
        out_state[~finite] = skeleton.NOT_TRACKED
    out[~finite] = np.nan
    return out, out_state


def read_numeric_rows(path: Path, n_fields: int) -> tuple[np.ndarray, list[int], list[str]]:
    """Reads a whitespace-separated text file of numbers, `n_fields` per non-blank line.

    returns: values (N, n_fields) float64 (nan allowed: a lost value), the 1-based line number of each row, and
    each row's raw text (fields joined by one space). Plain or gzip, any line ends, BOM (formats._text). Raises
    FormatError naming the file and line on a wrong field count or a non-number.
    """
    rows, line_numbers, texts = [], [], []
    lines = read_lines(path)
    last = last_content_line(lines)
    for i, line in enumerate(lines):
        cells = line.split()
        if not cells:
            continue
        if len(cells) != n_fields:
            hint = " (file truncated?)" if i == last and len(cells) < n_fields else ""
            message = f"expected {n_fields} whitespace-separated numbers, found {len(cells)}{hint}"
            raise FormatError(path, message, i + 1)
        try:
            values = [float(c) for c in cells]
        except ValueError:
            bad = next(k for k, c in enumerate(cells) if not is_number(c))
            message = f"field {bad + 1}: expected a number, found {cells[bad]!r}{number_hint(cells[bad])}"
            raise FormatError(path, message, i + 1) from None
        rows.append(values)
        line_numbers.append(i + 1)
        texts.append(" ".join(cells))
    if not rows:
        raise FormatError(path, f"no frames: expected lines of {n_fields} numbers")
    return np.array(rows, dtype=np.float64), line_numbers, texts


def first_line_fields(head: bytes) -> list[str] | None:
    """Returns the fields of the first non-blank line of `head`; None when any is not a number or head is binary."""
    if b"\0" in head:
        return None
    for line in head.decode("utf-8", "replace").splitlines():
        cells = line.split()
        if cells:
            return cells if all(is_number(c) for c in cells) else None
    return None
