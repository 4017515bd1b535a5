"""Skeleton CSV, the interchange format (spec: ../shared/reference/README.md).

One row per frame: `time` (s), then `<JOINT>_x,<JOINT>_y,<JOINT>_z` (m, y up) for the 20 joints;
an empty cell (or nan, as numpy and R write it) means not tracked. Optional `<JOINT>_state` columns (0/1/2) may
follow. Columns that are not joint columns are ignored; a joint column naming an unknown joint is an error.

The file is plain CSV, header first, so spreadsheets and pandas' defaults read it. The recording's metadata
(device, exercise, rate, history ...) goes to a sidecar `<name>.meta.json` beside it (`out.csv` ->
`out.meta.json`). Files of earlier versions carried it in a `# meta: {...}` line before the header; both are read.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Iterator, Sequence
from itertools import chain
from operator import itemgetter
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.formats._plain_table import plain_table
from kinect_agent.formats._text import read_lines
from kinect_agent.recording import Metadata, Recording

NAME = "csv"
DESCRIPTION = "Skeleton CSV interchange format (time + 20 joints x,y,z [+ state])"
META_PREFIX = "# meta: "
_JOINT_COLUMN = re.compile(r"^([A-Z][A-Z0-9_]*?)_(x|y|z|state)$")
_AXES = "xyz"
_EMPTY_AS_NAN = {"": "nan"}  # .get(cell, cell): the text float() reads for a cell
_STATE_OF = {"0": 0, "1": 1, "2": 2, "": 0}


def header() -> list[str]:
    """Returns the column names written by `write`."""
    cols = ["time"]
    cols += [f"{j}_{a}" for j in skeleton.JOINTS for a in _AXES]
    cols += [f"{j}_state" for j in skeleton.JOINTS]
    return cols


def sniff(path: Path, head: bytes) -> bool:
    """True when the first non-comment line is a header starting with `time` and naming joint columns."""
    for line in head.decode("utf-8", "replace").splitlines():
        if line.startswith("#") or not line.strip():
            continue
        cells = [c.strip().strip('"') for c in line.split(",")]
        return cells[0].lower() == "time" and "ROOT_x" in cells
    return False


def read(path: Path) -> Recording:
    """Reads a Skeleton CSV file; raises FormatError naming the line and cell that is wrong.

    A row repeating the row before exactly (a frame written twice) is dropped (meta.extra["dropped_duplicate_rows"]);
    a repeated time with other values is refused."""
    meta = _read_sidecar(Path(path))
    all_lines = read_lines(path)
    lines = _numbered_lines(all_lines, path, meta)
    first = next(lines, None)
    if first is None:
        raise FormatError(path, "empty file: expected a header line starting with 'time'")
    columns = _parse_header(path, *first)
    plain = _parse_plain(all_lines[first[0] :], columns)
    if plain is not None:  # every row plain: no row needs a look of its own
        t, coords, states = plain
        return _recording(path, t, coords, states, range(first[0] + 1, first[0] + 1 + len(t)), meta)
    kept: list[list[str]] = []
    line_numbers: list[int] = []
    dropped, previous = 0, None
    for line_no, cells in lines:
        if len(cells) != columns["n"]:
            try:
                cells = _fit_width(path, line_no, cells, columns["n"], lines)
            except FormatError:
                _parse_rows(path, line_numbers, kept, columns)  # a wrong cell above this line is named first
                raise
        if cells == previous:
            dropped += 1
            continue
        previous = cells
        kept.append(cells)
        line_numbers.append(line_no)
    if dropped:
        meta.extra["dropped_duplicate_rows"] = dropped
    if not kept:
        raise FormatError(path, "no frames after the header")
    t, coords, states = _parse_rows(path, line_numbers, kept, columns)
    return _recording(path, t, coords, states, line_numbers, meta)


def _recording(
    path: Path, t: np.ndarray, coords: np.ndarray, states: np.ndarray | None, line_numbers: Sequence[int],
    meta: Metadata,
) -> Recording:  # fmt: skip
    """Returns the recording of parsed rows: t (N,) s, coords (N, 3J) m (NaN: missing), states (N, J) int8 or None;
    FormatError when the times do not increase (line_numbers: each row's line in the file)."""
    positions = coords.reshape(len(t), skeleton.J, 3)
    _check_times(path, t, line_numbers)
    finite = np.all(np.isfinite(positions), axis=-1)
    if states is not None:
        state = states
        state[~finite] = skeleton.NOT_TRACKED
        state[finite & (state == skeleton.NOT_TRACKED)] = skeleton.INFERRED
    else:
        state = np.where(finite, skeleton.TRACKED, skeleton.NOT_TRACKED).astype(np.int8)
    return Recording(t, positions, state, meta)


def sidecar_path(path: str | Path) -> Path:
    """Returns where the metadata of the CSV file at path is kept: `out.csv` -> `out.meta.json`."""
    return Path(path).with_suffix(".meta.json")


def write(rec: Recording, path: Path) -> None:
    """Writes `rec` as Skeleton CSV with state columns, then its metadata to the sidecar; each atomically."""
    with atomic_open(path, "w", newline="", encoding="utf-8") as f:
        f.write(",".join(header()) + "\n")
        f.writelines(_rows(rec))
    with atomic_open(sidecar_path(path), "w", encoding="utf-8") as f:
        f.write(json.dumps(rec.meta.to_dict(), indent=2, sort_keys=True) + "\n")


_ROW = "%.6f," + ",".join(["%.5f"] * (3 * skeleton.J)) + "," + ",".join(["%d"] * skeleton.J) + "\n"


COMPILED_MIN_ROWS = 4096  # _rows of at least this many rows runs compiled (numba's import is lazy)
_DECIMALS = np.array([6] + [5] * (3 * skeleton.J) + [0] * skeleton.J)  # _ROW's, per column (0: %d)


def _rows(rec: Recording, compiled: bool = True) -> list[str]:
    """Returns the data lines of rec: time (6 decimals, s), x, y, z of every joint (5 decimals, m; empty when not
    finite), the states. One %-format per row (the numbers Python's % gives, as np.char.mod did, 3× faster).

    compiled: for COMPILED_MIN_ROWS rows or more, by _csv_numba's kernel when numba is installed (the same text byte
    for byte; the rows it leaves, a value within rounding of a half, are %-formatted); False: % for every row."""
    coords = rec.positions.reshape(rec.n_frames, -1)
    coords = np.where(np.isfinite(coords), coords, np.nan)  # every missing value prints "nan", emptied below
    table = np.concatenate([rec.t[:, None], coords, rec.state.astype(np.float64)], axis=1)
    if compiled and rec.n_frames >= COMPILED_MIN_ROWS:
        from kinect_agent.formats import _csv_numba

        if _csv_numba.AVAILABLE:
            lines, left = _csv_numba.rows_text(table, _DECIMALS)
            for i in np.flatnonzero(left | ~np.isfinite(rec.t)):  # a time of NaN prints "nan" unless emptied
                lines[i] = _row(table[i])
            return lines
    lines = [_ROW % tuple(row) for row in table.tolist()]
    for i in np.flatnonzero(np.isnan(coords).any(axis=1)):
        lines[i] = lines[i].replace("nan", "")
    return lines


def _row(values: np.ndarray) -> str:
    """Returns one data line of _rows: values (1 + 4J,) time, coordinates (NaN: empty), states (as _rows' own)."""
    line = _ROW % tuple(values.tolist())
    return line.replace("nan", "") if np.isnan(values[1 : 1 + 3 * skeleton.J]).any() else line


def _read_sidecar(path: Path) -> Metadata:
    """Returns the metadata of the sidecar beside path (empty metadata when there is none); names it when broken."""
    side = sidecar_path(path)
    meta = Metadata(source=str(path))
    if not side.is_file():
        return meta
    try:
        loaded = Metadata.from_dict(json.loads(side.read_text(encoding="utf-8-sig")))
    except (ValueError, TypeError, UnicodeDecodeError, RecursionError) as exc:  # RecursionError: nested too deeply
        raise FormatError(side, f"unreadable metadata sidecar of {path.name}: {exc}") from None
    loaded.source = str(path)
    return loaded


def _numbered_lines(lines: list[str], path: Path, meta: Metadata) -> Iterator[tuple[int, list[str]]]:
    """Yields (line number, cells) for non-empty, non-comment lines; reads `# meta:` lines into meta."""
    for line_no, line in enumerate(lines, start=1):
        if line.startswith("#"):
            if line.startswith(META_PREFIX):
                try:
                    loaded = Metadata.from_dict(json.loads(line[len(META_PREFIX) :]))
                except (ValueError, TypeError, RecursionError) as exc:
                    raise FormatError(path, f"unreadable '# meta:' line: {exc}", line_no) from None
                loaded.source = str(path)
                meta.__dict__.update(loaded.__dict__)
            continue
        if line.strip():
            yield line_no, line.split(",")


def _parse_header(path: Path, line_no: int, cells: list[str]) -> dict[str, Any]:
    names = [c.strip().strip('"') for c in cells]  # spreadsheets may quote the names
    while len(names) > 1 and not names[-1]:
        names.pop()  # a trailing comma after the last column name
    if names[0].lower() != "time":
        hint = "; the file is separated by ';' or tabs, expected commas" if ";" in names[0] or "\t" in names[0] else ""
        raise FormatError(path, f"first column must be 'time', found {names[0][:40]!r}{hint}", line_no)
    coord_index = np.full((skeleton.J, 3), -1)
    state_index = np.full(skeleton.J, -1)
    for col, name in enumerate(names[1:], start=1):
        match = _JOINT_COLUMN.match(name)
        if not match:
            continue  # not a joint column: ignored, as the spec says
        joint, axis = match.groups()
        if joint not in skeleton.INDEX:
            raise FormatError(path, f"column {col + 1} {name!r} names unknown joint {joint!r}", line_no)
        j = skeleton.INDEX[joint]
        if axis == "state":
            state_index[j] = col
        else:
            coord_index[j, _AXES.index(axis)] = col
    missing = [f"{skeleton.JOINTS[j]}_{_AXES[a]}" for j, a in np.argwhere(coord_index < 0)]
    if missing:
        raise FormatError(
            path, f"header lacks columns {', '.join(missing[:6])}{' ...' if len(missing) > 6 else ''}", line_no
        )
    has_state = bool(np.all(state_index >= 0))
    return {"n": len(names), "coords": coord_index.ravel(), "state": state_index if has_state else None}


def _fit_width(path: Path, line_no: int, cells: list[str], n: int, rest: Iterator[object]) -> list[str]:
    """Returns the row's n cells: empty cells after the n-th (a trailing comma) are dropped; FormatError otherwise
    (rest: the rows after this one, to tell whether it is the last)."""
    if len(cells) > n and not "".join(cells[n:]).strip():
        cells = cells[:n]
    if len(cells) != n:
        hint = " (file truncated?)" if len(cells) < n and next(rest, None) is None else ""
        raise FormatError(path, f"expected {n} columns as in the header, found {len(cells)}{hint}", line_no)
    return cells


def _parse_plain(lines: list[str], columns: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None] | None:
    """Returns _parse_rows' (t, coords, states) of the data lines when every one is plain (_plain_table: no comment,
    blank, quoted, short, long or repeated line; every cell a number or empty, a state 0, 1, 2 or empty, times
    finite, no infinite coordinate); None otherwise, and the rows are read one by one as before."""
    coords, state = list(columns["coords"]), columns["state"]
    states_at = [] if state is None else list(state)
    table = plain_table(
        lines, columns["n"], [0, *coords, *states_at], list(range(1 + len(coords), 1 + len(coords) + len(states_at)))
    )
    if table is None:
        return None
    t = table[:, 0].copy()
    xyz = np.ascontiguousarray(table[:, 1 : 1 + len(coords)])
    if not np.all(np.isfinite(t)) or np.any(np.isinf(xyz)):
        return None  # _parse_rows names the cell
    xyz[np.isnan(xyz)] = math.nan  # one NaN for every missing value, as _parse_rows
    if state is None:
        return t, xyz, None
    s = table[:, 1 + len(coords) :]
    empty = np.isnan(s)
    if not np.all(empty | (s == 0.0) | (s == 1.0) | (s == 2.0)):
        return None
    return t, xyz, np.where(empty, 0.0, s).astype(np.int8)


def _parse_rows(
    path: Path, line_numbers: list[int], rows: list[list[str]], columns: dict[str, Any]
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Returns t (N,) s, coordinates (N, 3J) m (NaN: empty or nan) and states (N, J) int8 (None without state
    columns) of N rows of cells; FormatError naming the first wrong cell, as _parse_row would.

    All rows at once when every cell is plain (Python's float of each cell, as _number; an empty cell NaN, a state
    0, 1, 2 or empty); otherwise, or when a value is not allowed, row by row (_parse_row), which also reads quoted
    and blank cells and names the first wrong one."""
    n_rows, n_numbers = len(rows), 1 + len(columns["coords"])
    text = list(chain.from_iterable(map(itemgetter(0, *columns["coords"]), rows)))  # row by row, time first
    try:
        cells: Iterable[str] = map(_EMPTY_AS_NAN.get, text, text)  # get(cell, cell): a str
        values = np.fromiter(map(float, cells), np.float64, len(text))
    except ValueError:
        values = None
    states = None
    if values is not None and columns["state"] is not None:
        state_text = list(chain.from_iterable(map(itemgetter(*columns["state"]), rows)))
        if set(state_text) <= _STATE_OF.keys():
            states = np.fromiter(map(_STATE_OF.__getitem__, state_text), np.int8, len(state_text))
            states = states.reshape(n_rows, len(columns["state"]))
        else:
            values = None
    if values is not None:
        values = values.reshape(n_rows, n_numbers)
        if np.all(np.isfinite(values[:, 0])) and not np.any(np.isinf(values[:, 1:])):
            coords = np.ascontiguousarray(values[:, 1:])
            coords[np.isnan(coords)] = math.nan  # one NaN for every missing value (float("-nan") has its sign set)
            return values[:, 0].copy(), coords, states
    parsed = [_parse_row(path, n, c, columns) for n, c in zip(line_numbers, rows, strict=True)]
    t = np.array([r[0] for r in parsed])
    coords = np.array([r[1] for r in parsed], dtype=np.float64).reshape(len(parsed), -1)
    states = None if columns["state"] is None else np.array([r[2] for r in parsed], dtype=np.int8)
    return t, coords, states


def _parse_row(
    path: Path, line_no: int, cells: list[str], columns: dict[str, Any]
) -> tuple[float, list[float], list[int] | None]:
    t = _number(path, line_no, 1, cells[0], "time", allow_empty=False)
    coords = [_number(path, line_no, c + 1, cells[c], "coordinate") for c in columns["coords"]]
    state = None
    if columns["state"] is not None:
        state = []
        for c in columns["state"]:
            cell = cells[c].strip().strip('"')
            if cell not in ("0", "1", "2", ""):
                raise FormatError(path, f"column {c + 1}: state must be 0, 1 or 2, found {cell!r}", line_no)
            state.append(int(cell or 0))
    return t, coords, state


def _number(path: Path, line_no: int, col: int, cell: str, what: str, allow_empty: bool = True) -> float:
    """Returns the cell's finite number; NaN for an empty cell or nan when allow_empty; FormatError otherwise."""
    try:
        value = float(cell)  # float() strips the blanks around the number itself
    except ValueError:
        cell = cell.strip()
        if len(cell) > 2 and cell[0] == cell[-1] == '"':  # a quoted number, as some spreadsheets write every cell
            return _number(path, line_no, col, cell[1:-1], what, allow_empty)
        if cell:
            raise FormatError(path, f"column {col}: expected a number for {what}, found {cell!r}", line_no) from None
        if allow_empty:
            return math.nan
        raise FormatError(path, f"column {col}: {what} is empty", line_no) from None
    if value - value == 0.0:  # finite: the common case first
        return value
    if value != value and allow_empty:
        return math.nan  # written by numpy / R for a lost joint, as an empty cell is
    raise FormatError(path, f"column {col}: {what} must be finite, found {cell.strip()!r}", line_no)


def _check_times(path: Path, t: np.ndarray, line_numbers: Sequence[int]) -> None:
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        kind = "duplicate" if t[i] == t[i - 1] else "decreasing"
        raise FormatError(path, f"{kind} time stamp {t[i]} after {t[i - 1]}: times must increase", line_numbers[i])
