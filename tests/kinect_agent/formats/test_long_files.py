"""Reading time grows linearly with the file: each reader reads a file 4x as long in well under 8x the time (a
quadratic step would take 16x). The absolute times of 10-minute files are printed by bench/readers.py."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest

from kinect_agent import formats

from .test_variants import BUILDERS


def _lengthened(path: Path, factor: int) -> Path:
    """Writes a copy of the short sample with its frames repeated `factor` times (frame ids, times kept increasing)."""
    text = path.read_bytes().decode("latin-1")
    lines = text.splitlines()
    out = path.parent / f"x{factor}" / path.name  # the AMC's asf/ folder is still found one level up
    out.parent.mkdir()
    if path.suffix == ".bvh":
        k = next(i for i, line in enumerate(lines) if line.startswith("Frame Time"))
        rows = lines[k + 1 :] * factor
        lines = lines[: k - 1] + [f"Frames: {len(rows)}", lines[k]] + rows
    elif path.suffix == ".amc":
        start = next(i for i, line in enumerate(lines) if line.strip() == "1")
        body = lines[start:]
        frames = sum(line.strip().isdigit() for line in body)
        lines = lines[:start] + [
            str(int(line) + r * frames) if line.strip().isdigit() else line for r in range(factor) for line in body
        ]
    elif path.suffix == ".tsv" or path.suffix == ".csv":
        head = next(i for i, line in enumerate(lines) if line.lower().startswith(("time,", "timestamp\t"))) + 1
        rows = lines[head:]
        step = float(rows[1].split()[0].split(",")[0]) - float(rows[0].split()[0].split(",")[0])
        span = step * len(rows)
        lines = lines[:head] + [_shift(row, r * span) for r in range(factor) for row in rows]
    elif path.name.startswith("joints_"):
        rows = [line for line in lines if line.strip()]
        ids = int(rows[-1].split()[0]) + 1
        lines = [f"{int(row.split()[0]) + r * ids} {row.split(None, 1)[1]}" for r in range(factor) for row in rows]
    else:
        lines = lines * factor
    out.write_bytes(("\n".join(lines) + "\n").encode("latin-1"))
    return out


def _shift(row: str, seconds: float) -> str:
    sep = "\t" if "\t" in row else ","
    first, rest = row.split(sep, 1)
    return f"{float(first) + seconds:.6f}{sep}{rest}"


def _cpu_seconds(read: Callable[[], object], repeats: int = 2) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        read()
        best = min(best, time.process_time() - start)
    return best


@pytest.mark.parametrize("name", ["csv", "kinect_v2_tsv", "utkinect", "keraal", "bvh", "amc"])
def test_reading_time_is_linear_in_the_length(data_dir: Path, tmp_path: Path, name: str) -> None:
    sample = BUILDERS[name](data_dir, tmp_path)
    small = {"amc": 30, "bvh": 30}.get(name, 25)
    short, long = _lengthened(sample, small), _lengthened(sample, 4 * small)
    n_short, n_long = formats.read(short).n_frames, formats.read(long).n_frames
    assert n_long == 4 * n_short, (n_short, n_long)
    ratio = _cpu_seconds(lambda: formats.read(long)) / _cpu_seconds(lambda: formats.read(short))
    assert ratio < 8.0, f"{name}: {n_long} frames took {ratio:.1f} x the time of {n_short}"
