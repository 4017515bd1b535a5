"""Kinect v2 (25-joint) tab-separated body exports with a header block and a Timestamp column.

No file of this layout is in ../shared/data (KERAAL's Kinect files are headerless, 175 numbers per line, read by
`keraal`); this module reads the layout that Kinect SDK 2.0 body recorders commonly write:

    # Kinect v2 body export            <- optional header block: `# key: value` lines (Device, Subject, Exercise,
    # Subject: P1                         FrameRate, TimestampUnit ...), kept in meta.extra["header"]
    Timestamp<TAB>SpineBase_X<TAB>SpineBase_Y<TAB>SpineBase_Z<TAB>SpineBase_State<TAB>SpineMid_X ...
    1250000<TAB>0.0123<TAB>-0.31<TAB>2.05<TAB>Tracked<TAB>...

The header block may also be `key<TAB>value` lines without `#` (FrameID, SensorID, Date recording, Floor,
processing_steps ...), as some recorders write it; keys are kept lower-case without spaces ("daterecording"), a
value of several cells joined by spaces.

Columns: `Timestamp` first; `<Joint>_X|_Y|_Z` (metres, Kinect camera space, y up) for joints named as the SDK's
JointType (kinect_joints.KINECT_V2_JOINTS); optional `<Joint>_State` / `<Joint>_TrackingState`
(Tracked / Inferred / NotTracked, or 2 / 1 / 0); other columns without a joint suffix (BodyIndex, TrackingId,
orientations `<Joint>_QX`...) are ignored and listed in meta.extra["ignored_columns"]. The 20 joints our
skeleton uses must be present (Neck, hand tips and thumbs may be absent). An empty cell or nan = not tracked;
trailing tabs after the last column are ignored. Plain or gzip, UTF-8 (BOM or not) or UTF-16, any line ends.
Timestamps may be clock times, as a .NET TimeSpan (`00:01:02.1234567`, the SDK's RelativeTime written with
ToString()) or an ISO 8601 date and time (`2025-03-14T10:22:05.123`): meta.extra["timestamp_unit"] = "clock".
Timestamp unit of numbers: `TimestampUnit: s|ms|us|ticks` in the header or a column named `Timestamp[ms]`,
`Timestamp_ms`, `Time (s)`, else inferred from the median step: the one unit of s, ms, us or 100 ns SDK ticks that
gives 5-120 Hz; a step that fits none or two (e.g. 100000: 100 Hz in ticks or 10 Hz in us) is refused.
Timestamps must strictly increase; a row repeating the row before exactly (a frame written twice) is dropped
(meta.extra["dropped_duplicate_rows"]). t starts at 0 and the first raw stamp goes to meta.extra["start_timestamp"].
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import kinect_joints
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.formats._rows import is_number, number_hint
from kinect_agent.formats._text import read_lines
from kinect_agent.recording import Metadata, Recording

NAME = "kinect_v2_tsv"
DESCRIPTION = "Kinect v2 tab-separated export (header block, Timestamp, <Joint>_X/_Y/_Z[/_State] columns)"
UNITS_S = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ticks": 1e-7}
_UNIT_NAMES = {"sec": "s", "seconds": "s", "msec": "ms", "milliseconds": "ms", "µs": "us", "microseconds": "us",
               "100ns": "ticks", "tick": "ticks"}  # fmt: skip
_STATES = {"tracked": 2, "inferred": 1, "nottracked": 0, "not_tracked": 0, "2": 2, "1": 1, "0": 0}
_COLUMN = re.compile(r"^(?P<joint>[A-Za-z]+)_(?P<field>X|Y|Z|State|TrackingState)$", re.IGNORECASE)
_TIME = re.compile(r"^(timestamp|time|relativetime)(?:\s*[\[_(]?\s*(?P<unit>[a-zµ0-9]+)\s*[\])]?)?$", re.IGNORECASE)
_RATE_RANGE_HZ = (5.0, 120.0)
_TIMESPAN = re.compile(r"(?:(\d+)\.)?(\d{1,2}):(\d{2}):(\d{2}(?:\.\d+)?)")  # [d.]hh:mm:ss[.fffffff]
_V2_INDEX = {name.lower(): i for i, name in enumerate(kinect_joints.KINECT_V2_JOINTS)}
_NEEDED = sorted(set(kinect_joints.source_indices("kinect2").tolist()))


def sniff(path: Path, head: bytes) -> bool:
    """True when a line of the head is the column header: tab separated, starting with Timestamp."""
    if b"\0" in head:
        return False
    return any(_is_column_header(line) for line in head.decode("utf-8", "replace").splitlines())


def _is_column_header(line: str) -> bool:
    """True for the line of column names: more than 3 tab-separated cells, the first Timestamp (or Time ...)."""
    cells = line.split("\t")
    return len(cells) > 3 and _TIME.match(cells[0].strip()) is not None


def read(path: Path) -> Recording:
    """Reads a Kinect v2 TSV export into a kinect2 Recording; FormatError names file, line and expectation."""
    path = Path(path)
    lines = list(enumerate(read_lines(path), start=1))
    header, pos = _header_block(lines)
    if pos >= len(lines) or not _is_column_header(lines[pos][1]):
        where = lines[pos][0] if pos < len(lines) else None
        raise FormatError(path, "no column header: expected a tab-separated line starting with 'Timestamp' before "
                          "the data", where)  # fmt: skip
    header_no, header_line = lines[pos]
    names = [c.strip() for c in header_line.split("\t")]
    while len(names) > 1 and not names[-1]:
        names.pop()  # a trailing tab after the last column name
    time_match = _TIME.match(names[0])
    columns, ignored = _columns(path, header_no, names)
    rows = _rows(path, lines[pos + 1 :], names, columns)
    xyz, state = rows.xyz, rows.state
    if rows.clock:
        unit, t = "clock", rows.stamps
    else:
        if time_match is None:
            raise FormatError(path, f"the first column {names[0]!r} is not a time column", header_no)
        unit = _unit(path, header, time_match.group("unit"), rows.stamps, rows.row_lines, header_no)
        t = (rows.stamps - rows.stamps[0]) * UNITS_S[unit]
    xyz[state == 0] = np.nan
    state[~np.all(np.isfinite(xyz), axis=-1)] = 0
    positions, out_state = kinect_joints.to_skeleton(xyz, "kinect2", state)
    meta = Metadata(device="kinect2", source=str(path), subject=header.get("subject"), exercise=header.get("exercise"))
    rate = header.get("framerate") or header.get("rate")
    meta.rate_hz = _float_or_none(rate) or (float(1.0 / np.median(np.diff(t))) if len(t) > 1 else None)
    start = rows.first_stamp if rows.clock else float(rows.stamps[0])
    meta.extra.update(header=header, ignored_columns=ignored, start_timestamp=start, timestamp_unit=unit)
    meta.extra["dropped_duplicate_rows"] = rows.dropped
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
    """Returns ({lower-case key: value} of the `# key: value` and `key<TAB>value[<TAB>value ...]` lines before the
    column header, index of the column header line (len(lines) when there is none)."""
    header: dict[str, str] = {}
    pos = 0
    while pos < len(lines) and not _is_column_header(lines[pos][1]):
        text = lines[pos][1]
        cells = text.split("\t")
        if not text.startswith("#") and len(cells) > 3 and is_number(cells[0]):
            break  # a data row: the column header is missing
        if text.startswith("#"):
            key, sep, value = text.lstrip("#").partition(":")
        else:
            key, sep, value = text.partition("\t")
        if sep and key.strip():
            header[key.strip().lower().replace(" ", "")] = " ".join(value.split())
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


@dataclass
class _Rows:
    """The data rows of an export: stamps (T,) as written (clock: seconds from the first), xyz (T, 25, 3) metres
    (NaN = empty or nan), state (T, 25) int8, each row's line number, and the rows dropped as exact repeats of the
    row before (a recorder writing one frame twice)."""

    stamps: np.ndarray
    clock: bool
    first_stamp: str
    xyz: np.ndarray
    state: np.ndarray
    row_lines: list[int]
    dropped: int


def _rows(path: Path, lines: list[tuple[int, str]], names: list[str], columns: dict[tuple[int, str], int]) -> _Rows:
    """Reads the data rows; FormatError names the line of a bad one."""
    content = [(no, line) for no, line in lines if line.strip()]
    if not content:
        raise FormatError(path, "no frames after the column header", lines[0][0] if lines else None)
    table: list[list[str]] = []
    row_lines: list[int] = []
    dropped = 0
    for k, (line_no, line) in enumerate(content):
        cells = _cells(path, line_no, line, len(names), last=k == len(content) - 1)
        if table and cells[0].strip() == table[-1][0].strip():
            if cells == table[-1]:
                dropped += 1
                continue
            raise FormatError(path, f"timestamp {cells[0].strip()} repeats the row before with other values: "
                              "timestamps must strictly increase", line_no)  # fmt: skip
        table.append(cells)
        row_lines.append(line_no)
    stamps = _clock_seconds(table)
    clock = stamps is not None
    if stamps is None:
        stamps = _numbers(path, table, [0], names, row_lines, allow_empty=False)[:, 0]
    back = np.flatnonzero(np.diff(stamps) <= 0)
    if back.size:
        i = int(back[0]) + 1
        word = "repeats" if stamps[i] == stamps[i - 1] else "goes back from"
        raise FormatError(path, f"timestamp {table[i][0].strip()} {word} {table[i - 1][0].strip()}: timestamps must "
                          "strictly increase", row_lines[i])  # fmt: skip
    coords = [(j, "xyz".index(field), c) for (j, field), c in columns.items() if field != "state"]
    xyz = np.full((len(table), 25, 3), np.nan)
    values = _numbers(path, table, [c for _, _, c in coords], names, row_lines, allow_empty=True)
    xyz[:, [j for j, _, _ in coords], [a for _, a, _ in coords]] = values
    state = np.full((len(table), 25), 2, dtype=np.int8)
    for (j, field), c in columns.items():
        if field == "state":
            state[:, j] = _states(path, table, c, names, row_lines)
    return _Rows(stamps, clock, table[0][0].strip(), xyz, state, row_lines, dropped)


def _clock_seconds(table: list[list[str]]) -> np.ndarray | None:
    """Returns the stamps (T,) as seconds from the first when every stamp is a clock time: a .NET TimeSpan as Kinect
    SDK exporters write RelativeTime ([d.]hh:mm:ss[.fffffff]) or an ISO 8601 date and time; None otherwise (numbers,
    or anything else, left to _numbers)."""
    first = table[0][0].strip()
    if ":" not in first:
        return None
    if _TIMESPAN.fullmatch(first):
        parts = [_TIMESPAN.fullmatch(row[0].strip()) for row in table]
        if not all(parts):
            return None
        fields = (p.groups() for p in parts if p is not None)
        seconds = [86400 * int(d or 0) + 3600 * int(h) + 60 * int(m) + float(s) for d, h, m, s in fields]
        return np.array(seconds) - seconds[0]
    try:
        times = [datetime.fromisoformat(row[0].strip()) for row in table]
        return np.array([(t - times[0]).total_seconds() for t in times])
    except (ValueError, TypeError):  # not ISO 8601, or naive and aware times mixed
        return None


def _cells(path: Path, line_no: int, line: str, n: int, *, last: bool) -> list[str]:
    """Returns the n tab-separated cells of a row; empty cells after the n-th (trailing tabs) are dropped."""
    cells = line.split("\t")
    if len(cells) > n and not "".join(cells[n:]).strip():
        cells = cells[:n]
    if len(cells) != n:
        hint = " (file truncated?)" if last and len(cells) < n else ""
        raise FormatError(path, f"expected {n} tab-separated fields as in the header, found {len(cells)}{hint}",
                          line_no)  # fmt: skip
    return cells


def _numbers(
    path: Path, table: list[list[str]], cols: list[int], names: list[str], row_lines: list[int], *, allow_empty: bool
) -> np.ndarray:
    """Returns (T, len(cols)) float: the cells as numbers; empty cells and nan are NaN when allow_empty, else (and
    for any other text or infinity) FormatError naming the line and column."""
    try:
        flat = [float(row[c]) if row[c].strip() or not allow_empty else np.nan for row in table for c in cols]
        values = np.array(flat, dtype=np.float64).reshape(len(table), len(cols))
    except ValueError:
        values = None
    if values is not None:
        bad = ~np.isfinite(values) & ~(np.isnan(values) if allow_empty else False)
        if not bad.any():
            return values
    for i, row in enumerate(table):  # the slow twin, to name the first bad cell
        for c in cols:
            text = row[c].strip()
            if allow_empty and (not text or text.lower() == "nan"):
                continue
            try:
                value = float(text)
            except ValueError:
                value = np.nan
            if not np.isfinite(value):
                hint = " (file truncated?)" if i == len(table) - 1 else ""
                hint = number_hint(text) + hint
                raise FormatError(path, f"column {c + 1} {names[c]!r}: expected a number, found {text!r}{hint}",
                                  row_lines[i])  # fmt: skip
    raise AssertionError("a bad cell was found above")


def _states(path: Path, table: list[list[str]], c: int, names: list[str], row_lines: list[int]) -> list[int]:
    """Returns the tracking states (T,) 0/1/2 of column c; FormatError names the line of a value not in _STATES."""
    try:
        return [_STATES[row[c].strip().lower()] for row in table]
    except KeyError:
        i = next(i for i, row in enumerate(table) if row[c].strip().lower() not in _STATES)
        hint = " (file truncated?)" if i == len(table) - 1 else ""
        raise FormatError(path, f"column {c + 1} {names[c]!r}: expected Tracked, Inferred, NotTracked or 2/1/0, "
                          f"found {table[i][c].strip()!r}{hint}", row_lines[i]) from None  # fmt: skip


def _unit(
    path: Path,
    header: dict[str, str],
    column_unit: str | None,
    stamps: np.ndarray,
    row_lines: list[int],
    header_no: int,
) -> str:
    """Returns the timestamp unit (a key of UNITS_S): from the header, the column name, or else the one unit whose
    median step gives 5-120 Hz; refuses a file where no unit or more than one does (say it with TimestampUnit)."""
    named = (header.get("timestampunit") or column_unit or "").lower()
    if named:
        named = _UNIT_NAMES.get(named, named)
        if named not in UNITS_S:
            raise FormatError(path, f"timestamp unit {named!r}: expected one of {', '.join(UNITS_S)}", header_no)
        return named
    if len(stamps) < 2:
        return "s"
    step = float(np.median(np.diff(stamps)))
    fits = [unit for unit, scale in UNITS_S.items() if _RATE_RANGE_HZ[0] <= 1.0 / (step * scale) <= _RATE_RANGE_HZ[1]]
    if len(fits) == 1:
        return fits[0]
    rates = ", ".join(f"{1.0 / (step * UNITS_S[u]):.3g} Hz in {u}" for u in (fits or UNITS_S))
    why = "fits more than one unit" if fits else "fits no unit between 5 and 120 Hz"
    raise FormatError(path, f"cannot tell the timestamp unit: the median step {step:g} {why} ({rates}); add a "
                      "header line '# TimestampUnit: s|ms|us|ticks'", row_lines[1])  # fmt: skip


def _float_or_none(text: str | None) -> float | None:
    try:
        return float(text) if text else None
    except ValueError:
        return None
