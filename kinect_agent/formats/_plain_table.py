"""A table of plain CSV rows parsed at once by numpy's C reader (np.loadtxt), or None when a row is not plain.

Plain: ASCII, no quote or '#', no blank line, every line exactly n cells (n − 1 commas), no line repeating the one
before, the first cell never empty. Empty cells are read as NaN. Anything else returns None, and the caller reads
the rows its own way (which names the wrong cell); so a file gives the same numbers either way.

np.loadtxt converts a cell with PyOS_string_to_double after stripping its blanks, as Python's float() does, so the
numbers are float()'s bit for bit; a cell float() reads and it does not (an underscore: "1_0") raises, i.e. None.
For a 10-minute 30 Hz Skeleton CSV (18 000 rows of 81 cells) 0.07 s CPU against 0.2 s cell by cell
(bench/README.md, "Speed on hard recordings").
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
    comma, newline = codes == ord(","), codes == ord("\n")
    ends = np.flatnonzero(comma | newline)  # where each cell ends
    if ends.size != len(lines) * n:
        return None
    by_line = ends.reshape(len(lines), n)
    if not (np.all(newline[by_line[:, -1]]) and np.all(comma[by_line[:, :-1]])):
        return None  # some line has another number of cells
    starts = np.empty_like(ends)
    starts[0] = 0
    starts[1:] = ends[:-1] + 1
    widths = (ends - starts).reshape(len(lines), n)
    if np.any(widths[:, 0] == 0) or np.any(widths[:, [columns[i] for i in single_char]] > 1):
        return None
    empty = ends[ends == starts]  # "nan" goes before the delimiter that ends an empty cell
    filled = np.insert(codes, np.repeat(empty, 3), np.tile(np.frombuffer(b"nan", np.uint8), empty.size))
    try:
        table = np.loadtxt(io.BytesIO(filled.tobytes()), dtype=np.float64, delimiter=",", comments=None,
                           quotechar=None, usecols=columns, ndmin=2, encoding="ascii")  # fmt: skip
    except ValueError:
        return None
    return table if table.shape == (len(lines), len(columns)) else None


__all__ = ["plain_table"]
