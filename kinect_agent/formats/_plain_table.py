"""A table of plain CSV rows parsed at once by numpy's C reader (np.loadtxt), or None when a row is not plain.

Plain: ASCII; no quote, '#', space, '+', tab or other character below ','; no blank line; every line exactly n cells
(n − 1 commas); no line repeating the one before; the first cell never empty. Empty cells are read as NaN. Anything
else returns None, and the caller reads the rows its own way (which names the wrong cell); so a file gives the same
numbers either way.

np.loadtxt converts a cell with PyOS_string_to_double, as Python's float() does, so the numbers are float()'s bit
for bit; a cell float() reads and it does not (an underscore: "1_0") raises, i.e. None. A 10-minute 30 Hz Skeleton
CSV (18 000 rows of 81 cells) reads in 0.10-0.13 s CPU against 0.27-0.30 s cell by cell (bench/README.md, "Speed
on hard recordings").
"""

from __future__ import annotations

import io
import operator

import numpy as np


def plain_table(lines: list[str], n: int, columns: list[int], single_char: list[int]) -> np.ndarray | None:
    """Returns (N, len(columns)) float64: the given columns of the N lines (cells of n per line; NaN for an empty
    cell), or None when the lines are not plain (module docstring) or a cell is not a number.

    single_char: positions in `columns` whose cells must be empty or one character (state columns: "0", "1", "2");
    a longer cell there returns None (the caller's checks of those cells see only such cells).
    """
    if not lines or n < 1:
        return None
    text = "\n".join(lines) + "\n"
    if not text.isascii() or '"' in text or "#" in text or any(map(operator.eq, lines[1:], lines)):
        return None
    codes = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    ends = np.flatnonzero(codes <= ord(","))  # where each cell ends: ',' or '\n' (a blank, '+' or tab: declined)
    if ends.size != len(lines) * n:
        return None
    by_line = codes[ends].reshape(len(lines), n)
    if not (np.all(by_line[:, -1] == ord("\n")) and np.all(by_line[:, :-1] == ord(","))):
        return None  # some line has another number of cells, or a character below ',' in a cell
    widths = np.diff(ends, prepend=-1) - 1
    by_line = widths.reshape(len(lines), n)
    if np.any(by_line[:, 0] == 0) or np.any(by_line[:, [columns[i] for i in single_char]] > 1):
        return None
    empty = ends[widths == 0]  # "nan" goes before the delimiter that ends an empty cell
    filled = np.insert(codes, np.repeat(empty, 3), np.tile(np.frombuffer(b"nan", np.uint8), empty.size))
    try:
        table = np.loadtxt(io.BytesIO(filled.tobytes()), dtype=np.float64, delimiter=",", comments=None,
                           quotechar=None, usecols=columns, ndmin=2, encoding="ascii")  # fmt: skip
    except ValueError:
        return None
    return table if table.shape == (len(lines), len(columns)) else None


__all__ = ["plain_table"]
