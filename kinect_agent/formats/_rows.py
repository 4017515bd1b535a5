"""Parsing one comma-separated row of numbers, with errors that name the file, the line and the column."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kinect_agent.errors import FormatError


def parse_csv_row(path: Path, line_no: int, line: str, n_columns: int, layout: str) -> list[float]:
    """Returns the row's n_columns finite numbers; raises FormatError otherwise.

    layout: what the columns are, for the message, e.g. "22 joints x 3".
    """
    cells = line.strip().split(",")
    if len(cells) != n_columns:
        raise FormatError(path, f"expected {n_columns} columns ({layout}), found {len(cells)}", line_no)
    try:
        values = [float(c) for c in cells]
    except ValueError:
        bad = next(i for i, c in enumerate(cells) if not is_number(c))
        raise FormatError(path, f"column {bad + 1}: expected a number, found {cells[bad]!r}", line_no) from None
    if not all(np.isfinite(values)):
        raise FormatError(path, "expected finite numbers, found nan/inf", line_no)
    return values


def is_number(text: str) -> bool:
    """True when float() reads the text."""
    try:
        float(text)
    except ValueError:
        return False
    return True
