"""UTKinect-Action3D joint files (Xia et al., CVPR-W 2012), Kinect v1.

`joints_sXX_eYY.txt`: one frame per line, the frame id then 20 joints x y z (metres, Kinect v1 camera
space, y up) in SDK v1 order, whitespace separated. Frame ids have gaps (kept as time gaps, t = id / 30 s)
and repeated ids: exact duplicate lines are dropped, and a repeated id with different data keeps its first
line (the count goes to meta.extra["dropped_duplicate_frames"]). `actionLabel.txt` beside the file gives
action intervals in frame ids, put into meta.extra["actions"]; an action marked `NaN NaN` (it did not happen in that
sequence) is left out and named in meta.extra["actions_not_performed"]; one with a single NaN (start or end unknown)
is left out and named in meta.extra["actions_without_span"]. A missing joint may be written nan (not tracked).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from kinect_agent.errors import FormatError
from kinect_agent.formats import kinect_joints
from kinect_agent.formats._text import read_lines
from kinect_agent.recording import Metadata, Recording

NAME = "utkinect"
DESCRIPTION = "UTKinect-Action3D joints_*.txt (frame id + 20 Kinect v1 joints x y z, 30 Hz)"
RATE_HZ = 30.0
N_FIELDS = 1 + 20 * 3
_NAME = re.compile(r"joints_(s\d+)_(e\d+)", re.IGNORECASE)


def sniff(path: Path, head: bytes) -> bool:
    """True when the first line has 61 numbers and the first is an integer frame id."""
    cells = kinect_joints.first_line_fields(head)
    if cells is None or len(cells) != N_FIELDS:
        return False
    return path.name.lower().startswith("joints_") or re.fullmatch(r"\d+", cells[0]) is not None


def read(path: Path) -> Recording:
    """Reads a UTKinect joints file into a 30 Hz kinect1 recording; raises FormatError naming file and line."""
    path = Path(path)
    values, line_numbers, texts = kinect_joints.read_numeric_rows(path, N_FIELDS)
    frame_ids = values[:, 0]
    bad = np.flatnonzero(frame_ids != np.round(frame_ids))
    if bad.size:
        raise FormatError(path, f"frame id must be an integer, found {frame_ids[bad[0]]}", line_numbers[bad[0]])
    keep, exact, conflicting = _first_of_each_frame(path, frame_ids, texts, line_numbers)
    positions, state = kinect_joints.to_skeleton(values[keep, 1:].reshape(-1, 20, 3), "kinect1")
    meta = Metadata(device="kinect1", rate_hz=RATE_HZ, source=str(path))
    match = _NAME.search(path.name)
    if match:
        meta.subject, meta.extra["sequence"] = match.group(1).lower(), f"{match.group(1)}_{match.group(2)}".lower()
    meta.extra["dropped_duplicate_lines"] = exact
    meta.extra["dropped_duplicate_frames"] = conflicting
    meta.extra["first_frame_id"] = int(frame_ids[keep[0]])
    labels = _actions(path.parent / "actionLabel.txt", meta.extra.get("sequence"))
    if labels is not None:
        meta.extra["actions"], meta.extra["actions_not_performed"], without_span = labels
        if without_span:
            meta.extra["actions_without_span"] = without_span
    return Recording(frame_ids[keep] / RATE_HZ, positions, state, meta)


def _first_of_each_frame(
    path: Path, frame_ids: np.ndarray, texts: list[str], line_numbers: list[int]
) -> tuple[np.ndarray, int, int]:
    """Returns the row indices to keep (first line of each frame id), the exact-duplicate lines dropped and
    the conflicting repeated frames dropped. Frame ids must not go backwards."""
    keep: list[int] = []
    exact, conflicting = 0, 0
    for i in range(len(frame_ids)):
        if keep and frame_ids[i] < frame_ids[keep[-1]]:
            message = f"frame id {int(frame_ids[i])} after {int(frame_ids[keep[-1]])}: ids must not decrease"
            raise FormatError(path, message, line_numbers[i])
        if keep and frame_ids[i] == frame_ids[keep[-1]]:
            if texts[i] == texts[keep[-1]]:
                exact += 1
            else:
                conflicting += 1
            continue
        keep.append(i)
    return np.array(keep), exact, conflicting


def _actions(label_path: Path, sequence: str | None) -> tuple[dict[str, list[int]], list[str], list[str]] | None:
    """Returns ({action: [start id, end id]}, [actions marked NaN NaN], [actions with one NaN]) for `sequence` from
    actionLabel.txt, or None when absent."""
    if sequence is None or not label_path.is_file():
        return None
    actions: dict[str, list[int]] | None = None
    not_performed: list[str] = []
    without_span: list[str] = []
    for line_no, line in enumerate(read_lines(label_path), start=1):
        text = line.strip()
        if not text:
            continue
        if ":" not in text:
            if actions is not None:
                break
            if text.lower() == sequence:
                actions = {}
            continue
        if actions is not None:
            name, _, span = text.partition(":")
            numbers = span.split()
            nans = [n.lower() == "nan" for n in numbers]
            if len(numbers) == 2 and any(nans):
                (not_performed if all(nans) else without_span).append(name.strip())
                continue
            if len(numbers) != 2 or not all(n.lstrip("+-").isdigit() for n in numbers):
                raise FormatError(label_path, f"expected 'action: start end', found {text!r}", line_no)
            actions[name.strip()] = [int(n) for n in numbers]
    return None if actions is None else (actions, not_performed, without_span)
