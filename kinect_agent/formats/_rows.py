"""Parsing rows of numbers, with errors that name the file, the line and the column."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from kinect_agent.errors import FormatError
from kinect_agent.formats._text import last_content_line, read_lines


def parse_csv_row(path: Path, line_no: int, line: str, n_columns: int, layout: str) -> list[float]:
    """Returns the row's n_columns numbers; an empty cell or nan is a lost value (NaN); raises FormatError otherwise.

    layout: what the columns are, for the message, e.g. "22 joints x 3". Infinity is refused.
    """
    cells = line.strip().split(",")
    if len(cells) != n_columns:
        raise FormatError(path, f"expected {n_columns} columns ({layout}), found {len(cells)}", line_no)
    try:
        values = [float(c) if c.strip() else math.nan for c in cells]
    except ValueError:
        bad = next(i for i, c in enumerate(cells) if c.strip() and not is_number(c))
        raise FormatError(path, f"column {bad + 1}: expected a number, found {cells[bad]!r}", line_no) from None
    if math.inf in values or -math.inf in values:
        bad = next(i for i, v in enumerate(values) if math.isinf(v))
        raise FormatError(path, f"column {bad + 1}: expected a finite number, found {cells[bad]!r}", line_no)
    return values


_DECIMAL_COMMA = re.compile(r"\s*[-+]?\d+,\d+\s*")


def number_hint(text: str) -> str:
    """Returns a hint for a cell that is not a number: decimal commas (0,5) are not read, since 1,250 could be
    1.25 or 1250; '' for other text."""
    if _DECIMAL_COMMA.fullmatch(text):
        return " (a decimal comma? write numbers with a decimal point, as 0.5)"
    return ""


def is_number(text: str) -> bool:
    """True when float() reads the text."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_csv_table(path: Path, n_columns: int, layout: str) -> np.ndarray:
    """Returns the rows (T, n_columns) of a headerless comma-separated file of numbers, plain or gzip (by content).

    Blank lines are skipped; empty cells and nan are NaN (lost); any bad row raises FormatError naming its line.
    layout: what the columns are.
    """
    lines = read_lines(path)
    last = last_content_line(lines)
    rows = []
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        if i == last and line.count(",") < n_columns - 1:
            found = line.count(",") + 1
            raise FormatError(path, f"expected {n_columns} columns ({layout}), found {found} (file truncated?)", i + 1)
        rows.append(parse_csv_row(path, i + 1, line, n_columns, layout))
    if not rows:
        raise FormatError(path, f"no frames: expected rows of {n_columns} comma-separated numbers")
    return np.array(rows)


def parse_floats(path: Path, line_no: int, cells: list[str], n: int, what: str) -> np.ndarray:
    """Returns n finite numbers (n,) read from cells; raises FormatError naming the line and `what` otherwise."""
    if len(cells) != n:
        raise FormatError(path, f"expected {n} {what}, found {len(cells)}", line_no)
    try:
        values = np.array([float(c) for c in cells])
    except ValueError:
        bad = next(c for c in cells if not is_number(c))
        raise FormatError(path, f"expected numbers for {what}, found {' '.join(cells[:5])!r}{number_hint(bad)}",
                          line_no) from None  # fmt: skip
    if not np.all(np.isfinite(values)):
        raise FormatError(path, f"{what} must be finite", line_no)
    return values
