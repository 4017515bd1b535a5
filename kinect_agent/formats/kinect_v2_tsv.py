"""Kinect v2 (25-joint) tab-separated body exports with a header block and a Timestamp column.

No file of this layout is in ../shared/data (KERAAL's Kinect files are headerless, 175 numbers per line, read by
`keraal`); this module reads the layout that Kinect SDK 2.0 body recorders commonly write:

    # Kinect v2 body export            <- optional header block: `# key: value` lines (Device, Subject, Exercise,
    # Subject: P1                         FrameRate, TimestampUnit ...), kept in meta.extra["header"]
    Timestamp<TAB>SpineBase_X<TAB>SpineBase_Y<TAB>SpineBase_Z<TAB>SpineBase_State<TAB>SpineMid_X ...
    1250000<TAB>0.0123<TAB>-0.31<TAB>2.05<TAB>Tracked<TAB>...

The header block may also be `key<TAB>value` lines without `#` (FrameID, SensorID, Date recording, Floor,
processing_steps ...), as some recorders write it; keys are kept lower-case without spaces ("daterecording").

Columns: `Timestamp` first; `<Joint>_X|_Y|_Z` (metres, Kinect camera space, y up) for joints named as the SDK's
JointType (kinect_joints.KINECT_V2_JOINTS); optional `<Joint>_State` / `<Joint>_TrackingState`
(Tracked / Inferred / NotTracked, or 2 / 1 / 0); other columns without a joint suffix (BodyIndex, TrackingId,
orientations `<Joint>_QX`...) are ignored and listed in meta.extra["ignored_columns"]. The 20 joints our
skeleton uses must be present (Neck, hand tips and thumbs may be absent). An empty cell = not tracked.
Timestamp unit: `TimestampUnit: s|ms|us|ticks` in the header or a column named `Timestamp[ms]`/`Timestamp_ms`,
else inferred from the median step (seconds, milliseconds or 100 ns SDK ticks for 5-120 Hz). Timestamps must
strictly increase; t starts at 0 and the first raw stamp goes to meta.extra["start_timestamp"].
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import kinect_joints
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.recording import Metadata, Recording

NAME = "kinect_v2_tsv"
DESCRIPTION = "Kinect v2 tab-separated export (header block, Timestamp, <Joint>_X/_Y/_Z[/_State] columns)"
UNITS_S = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ticks": 1e-7}
_STATES = {"tracked": 2, "inferred": 1, "nottracked": 0, "not_tracked": 0, "2": 2, "1": 1, "0": 0}
_COLUMN = re.compile(r"^(?P<joint>[A-Za-z]+)_(?P<field>X|Y|Z|State|TrackingState)$", re.IGNORECASE)
_TIME = re.compile(r"^(timestamp|time)(?:[\[_( ](?P<unit>s|ms|us|ticks)[\])]?)?$", re.IGNORECASE)
_RATE_RANGE_HZ = (5.0, 120.0)
_V2_INDEX = {name.lower(): i for i, name in enumerate(kinect_joints.KINECT_V2_JOINTS)}
_NEEDED = sorted(set(kinect_joints.source_indices("kinect2").tolist()))


def sniff(path: Path, head: bytes) -> bool:
    """True when the first line after the header block is tab separated and starts with Timestamp."""
    if b"\0" in head:
        return False
    for line in head.decode("utf-8", "replace").splitlines():
        if _is_header_line(line):
            continue
        cells = line.rstrip("\r\n").split("\t")
        return len(cells) > 3 and _TIME.match(cells[0].strip()) is not None
    return False


def _is_header_line(line: str) -> bool:
    """True for a line of the header block: blank, `# ...`, or `key<TAB>value` (at most two cells, not Timestamp)."""
    cells = line.rstrip("\r\n").split("\t")
    if line.startswith("#") or not line.strip():
        return True
    return len(cells) <= 2 and _TIME.match(cells[0].strip()) is None


def read(path: Path) -> Recording:
    """Reads a Kinect v2 TSV export into a kinect2 Recording; FormatError names file, line and expectation."""
    path = Path(path)
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = list(enumerate(f, start=1))
    header, pos = _header_block(lines)
    if pos >= len(lines):
        raise FormatError(path, "no column header: expected a tab-separated line starting with 'Timestamp'")
    header_no, header_line = lines[pos]
    names = [c.strip() for c in header_line.rstrip("\r\n").split("\t")]
    time_match = _TIME.match(names[0])
    if time_match is None:
        raise FormatError(path, f"first column must be 'Timestamp', found {names[0]!r}", header_no)
    columns, ignored = _columns(path, header_no, names)
    stamps, xyz, state, row_lines = _rows(path, lines[pos + 1 :], names, columns)
    unit = _unit(path, header, time_match.group("unit"), stamps, row_lines)
    t = (stamps - stamps[0]) * UNITS_S[unit]
    xyz[state == 0] = np.nan
    state[~np.all(np.isfinite(xyz), axis=-1)] = 0
    positions, out_state = kinect_joints.to_skeleton(xyz, "kinect2", state)
    meta = Metadata(device="kinect2", source=str(path), subject=header.get("subject"), exercise=header.get("exercise"))
    rate = header.get("framerate") or header.get("rate")
    meta.rate_hz = _float_or_none(rate) or (float(1.0 / np.median(np.diff(t))) if len(t) > 1 else None)
    meta.extra.update(header=header, ignored_columns=ignored, start_timestamp=float(stamps[0]), timestamp_unit=unit)
    return Recording(t, positions, out_state, meta)


def write(rec: Recording, path: str | Path) -> None:
    """Writes `rec` in this layout (seconds, the 20 mapped joints with _X/_Y/_Z/_State), atomically."""
    names = [kinect_joints.V2_TO_SKELETON[j] for j in skeleton.JOINTS]
    head = ["Timestamp"] + [f"{n}_{c}" for n in names for c in ("X", "Y", "Z", "State")]
    state_text = {0: "NotTracked", 1: "Inferred", 2: "Tracked"}
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("# Kinect v2 body export\n# TimestampUnit: s\n")
        if rec.meta.subject:
            f.write(f"# Subject: {rec.meta.subject}\n")
        f.write("\t".join(head) + "\n")
        for i in range(rec.n_frames):
            cells = [f"{rec.t[i]:.6f}"]
            for j in range(skeleton.J):
                p = rec.positions[i, j]
                cells += ["" if not np.isfinite(v) else f"{v:.6f}" for v in p] + [state_text[int(rec.state[i, j])]]
            f.write("\t".join(cells) + "\n")


def _header_block(lines: list[tuple[int, str]]) -> tuple[dict[str, str], int]:
    """Returns ({lower-case key: value} of the `# key: value` and `key<TAB>value` lines, index of the first line
    after the block)."""
    header: dict[str, str] = {}
    pos = 0
    while pos < len(lines) and _is_header_line(lines[pos][1]):
        text = lines[pos][1].rstrip("\r\n")
        if text.startswith("#"):
            key, sep, value = text.lstrip("#").partition(":")
        else:
            key, sep, value = text.partition("\t")
        if sep and key.strip():
            header[key.strip().lower().replace(" ", "")] = value.strip()
        pos += 1
    return header, pos


def _columns(path: Path, line_no: int, names: list[str]) -> tuple[dict[tuple[int, str], int], list[str]]:
    """Returns ({(v2 joint index, "x"|"y"|"z"|"state"): column}, ignored column names); checks joints."""
    columns: dict[tuple[int, str], int] = {}
    ignored = []
    for c, name in enumerate(names[1:], start=1):
        match = _COLUMN.match(name)
        if match is None:
            ignored.append(name)
            continue
        joint = match.group("joint").lower()
        if joint not in _V2_INDEX:
            known = ", ".join(kinect_joints.KINECT_V2_JOINTS)
            raise FormatError(path, f"column {c + 1} {name!r}: unknown joint {match.group('joint')!r}; expected one "
                              f"of the Kinect v2 JointType names ({known})", line_no)  # fmt: skip
        field = "state" if "state" in match.group("field").lower() else match.group("field").lower()
        key = (_V2_INDEX[joint], field)
        if key in columns:
            raise FormatError(path, f"column {c + 1} {name!r} repeats column {columns[key] + 1}", line_no)
        columns[key] = c
    missing = [
        f"{kinect_joints.KINECT_V2_JOINTS[j]}_{a.upper()}" for j in _NEEDED for a in "xyz" if (j, a) not in columns
    ]
    if missing:
        raise FormatError(path, f"missing joint columns {', '.join(missing[:6])}; the 20 mapped joints need X, Y, Z",
                          line_no)  # fmt: skip
    return columns, ignored


def _rows(
    path: Path, lines: list[tuple[int, str]], names: list[str], columns: dict[tuple[int, str], int]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """Returns stamps (T,), xyz (T, 25, 3) metres (NaN = empty), state (T, 25) int8, and each row's line number."""
    n = len(names)
    stamps, xyz_rows, state_rows, row_lines = [], [], [], []
    content = [(no, line) for no, line in lines if line.strip()]
    for k, (line_no, line) in enumerate(content):
        cells = line.rstrip("\r\n").split("\t")
        if len(cells) != n:
            hint = " (file truncated?)" if k == len(content) - 1 and len(cells) < n else ""
            raise FormatError(path, f"expected {n} tab-separated fields as in the header, found {len(cells)}{hint}",
                              line_no)  # fmt: skip
        stamp = _number(path, line_no, cells, 0, names, allow_empty=False)
        if stamps and stamp <= stamps[-1]:
            word = "repeats" if stamp == stamps[-1] else "goes back from"
            raise FormatError(path, f"timestamp {cells[0].strip()} {word} {stamps[-1]:g}: timestamps must strictly "
                              "increase", line_no)  # fmt: skip
        xyz = np.full((25, 3), np.nan)
        state = np.full(25, 2, dtype=np.int8)
        for (j, field), c in columns.items():
            if field == "state":
                text = cells[c].strip().lower()
                if text not in _STATES:
                    raise FormatError(path, f"column {c + 1} {names[c]!r}: expected Tracked, Inferred, NotTracked or "
                                      f"2/1/0, found {cells[c].strip()!r}", line_no)  # fmt: skip
                state[j] = _STATES[text]
            else:
                xyz[j, "xyz".index(field)] = _number(path, line_no, cells, c, names, allow_empty=True)
        stamps.append(stamp)
        xyz_rows.append(xyz)
        state_rows.append(state)
        row_lines.append(line_no)
    if not stamps:
        raise FormatError(path, "no frames after the column header", lines[0][0] if lines else None)
    return np.array(stamps), np.array(xyz_rows), np.array(state_rows), row_lines


def _number(path: Path, line_no: int, cells: list[str], c: int, names: list[str], *, allow_empty: bool) -> float:
    text = cells[c].strip()
    if not text and allow_empty:
        return float("nan")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not np.isfinite(value):
        raise FormatError(path, f"column {c + 1} {names[c]!r}: expected a number, found {text!r}", line_no)
    return value


def _unit(path: Path, header: dict[str, str], column_unit: str | None, stamps: np.ndarray, row_lines: list[int]) -> str:
    """Returns the timestamp unit (a key of UNITS_S): header, column name, or the one giving 5-120 Hz steps."""
    named = (header.get("timestampunit") or column_unit or "").lower()
    if named:
        if named not in UNITS_S:
            raise FormatError(path, f"timestamp unit {named!r}: expected one of {', '.join(UNITS_S)}")
        return named
    if len(stamps) < 2:
        return "s"
    step = float(np.median(np.diff(stamps)))
    for unit in ("s", "ms", "ticks"):
        scale = UNITS_S[unit]
        if _RATE_RANGE_HZ[0] <= 1.0 / (step * scale) <= _RATE_RANGE_HZ[1]:
            return unit
    raise FormatError(path, f"cannot tell the timestamp unit from the median step {step:g}; add a header line "
                      "'# TimestampUnit: s|ms|us|ticks'", row_lines[1])  # fmt: skip


def _float_or_none(text: str | None) -> float | None:
    try:
        return float(text) if text else None
    except ValueError:
        return None
