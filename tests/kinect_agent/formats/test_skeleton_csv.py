"""Skeleton CSV: round trip and clear errors for bad input."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from kinect_agent import formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import _csv_numba, skeleton_csv
from kinect_agent.recording import Metadata, Recording


def _recording(rng: np.random.Generator, frames: int = 30) -> Recording:
    positions = rng.normal(0.0, 0.3, size=(frames, skeleton.J, 3))
    state = np.full((frames, skeleton.J), skeleton.TRACKED, dtype=np.int8)
    positions[3, 5] = np.nan
    state[3, 5] = skeleton.NOT_TRACKED
    state[4, 7] = skeleton.INFERRED
    return Recording(np.arange(frames) / 30.0, positions, state, Metadata(device="kinect2", rate_hz=30.0, subject="s1"))


def test_round_trip_keeps_positions_states_and_metadata(tmp_path: Path, rng: np.random.Generator) -> None:
    rec = _recording(rng)
    out = tmp_path / "r.csv"
    formats.write(rec, out)
    back = formats.read(out)
    np.testing.assert_allclose(back.positions, rec.positions, atol=1e-5, equal_nan=True, err_msg="positions")
    np.testing.assert_array_equal(back.state, rec.state)
    np.testing.assert_allclose(back.t, rec.t, atol=1e-6)
    assert back.meta.device == "kinect2" and back.meta.subject == "s1"


def test_the_csv_is_plain_with_its_metadata_beside_it(tmp_path: Path, rng: np.random.Generator) -> None:
    import csv
    import json

    out = tmp_path / "r.csv"
    formats.write(_recording(rng), out)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))  # what spreadsheet tools and pandas' defaults do: header first, no comment line
    assert rows[0] == skeleton_csv.header() and len(rows) == 31 and all(len(r) == len(rows[0]) for r in rows)
    side = json.loads((tmp_path / "r.meta.json").read_text())
    assert side["device"] == "kinect2" and side["subject"] == "s1" and side["rate_hz"] == 30.0


def test_files_with_a_meta_comment_line_are_still_read(tmp_path: Path, rng: np.random.Generator) -> None:
    out = tmp_path / "old.csv"
    formats.write(_recording(rng), out)
    (tmp_path / "old.meta.json").unlink()
    text = out.read_text()
    out.write_text('# meta: {"device":"kinect1","subject":"s9","exercise":"squat"}\n' + text)
    back = formats.read(out)
    assert (back.meta.device, back.meta.subject, back.meta.exercise) == ("kinect1", "s9", "squat")
    assert back.n_frames == 30


def test_a_broken_sidecar_is_named(tmp_path: Path, rng: np.random.Generator) -> None:
    out = tmp_path / "r.csv"
    formats.write(_recording(rng), out)
    (tmp_path / "r.meta.json").write_text("{not json")
    with pytest.raises(FormatError, match=r"r\.meta\.json.*unreadable metadata sidecar of r\.csv"):
        formats.read(out)


def test_a_deeply_nested_sidecar_or_meta_line_is_named(tmp_path: Path, rng: np.random.Generator) -> None:
    out = tmp_path / "r.csv"
    formats.write(_recording(rng), out)
    deep = "[" * 100_000 + "]" * 100_000
    (tmp_path / "r.meta.json").write_text(deep)
    with pytest.raises(FormatError, match=r"r\.meta\.json.*unreadable metadata sidecar of r\.csv"):
        formats.read(out)
    (tmp_path / "r.meta.json").unlink()
    out.write_text(f"# meta: {deep}\n" + out.read_text())
    with pytest.raises(FormatError, match=r"r\.csv:1: unreadable '# meta:' line"):
        skeleton_csv.read(out)


def test_minimal_file_without_state_columns_marks_empty_cells_untracked(tmp_path: Path) -> None:
    cols = skeleton_csv.header()[: 1 + 3 * skeleton.J] + ["comment"]
    row = ["0.0"] + ["0.1"] * (3 * skeleton.J) + ["hello"]
    row[1:4] = ["", "", ""]
    path = tmp_path / "m.csv"
    path.write_text(",".join(cols) + "\n" + ",".join(row) + "\n")
    rec = formats.read(path)
    assert rec.state[0, 0] == skeleton.NOT_TRACKED and np.isnan(rec.positions[0, 0]).all()
    assert rec.state[0, 1] == skeleton.TRACKED


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_all_rows_at_once_read_what_row_by_row_reads(tmp_path: Path, seed: int) -> None:
    rec = _recording(np.random.default_rng(seed), frames=40)
    plain = tmp_path / "plain.csv"
    skeleton_csv.write(rec, plain)
    lines = plain.read_text().splitlines()
    lines[7] = lines[7].replace(",", ',"', 1).replace(",", '",', 2).replace('",', ",", 1)  # one quoted cell
    assert '"' in lines[7]
    quoted = tmp_path / "quoted.csv"  # a quoted cell: every row read by _parse_row
    quoted.write_text("\n".join(lines) + "\n")
    fast, slow = formats.read(plain), formats.read(quoted)
    for name in ("t", "positions", "state"):
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_array_equal(a, b, err_msg=name)
        assert a.dtype == b.dtype and a.flags.c_contiguous, name


def test_a_wrong_cell_is_named_before_a_wrong_width_below_it(tmp_path: Path) -> None:
    cols = ",".join(skeleton_csv.header()[: 1 + 3 * skeleton.J])
    rows = [",".join([f"{i / 30:.4f}"] + ["0.1"] * (3 * skeleton.J)) for i in range(4)]
    rows[1] = rows[1].replace("0.1", "inf", 1)
    rows[3] = rows[3][: len(rows[3]) // 2]
    path = tmp_path / "bad.csv"
    path.write_text(cols + "\n" + "\n".join(rows) + "\n")
    with pytest.raises(FormatError, match="must be finite") as err:
        formats.read(path)
    assert err.value.line == 3


@pytest.mark.parametrize(
    ("mutate", "message", "line"),
    [
        (lambda rows: rows[:2] + [rows[2][: len(rows[2]) // 2]], "expected 61 columns", 4),
        (lambda rows: rows[:2] + [rows[2].replace("0.1", "abc", 1)], "expected a number", 4),
        (lambda rows: rows[:2] + [rows[1].replace("0.1", "0.2")], "duplicate time stamp", 4),
        (lambda rows: [rows[0], rows[2], rows[1]], "decreasing time stamp", 4),
        (lambda rows: [rows[0].replace("HEAD_x", "NOSE_x")] + rows[1:], "unknown joint 'NOSE'", 2),
        (lambda rows: rows[:1], "no frames", None),
    ],
)
def test_bad_input_names_file_line_and_problem(tmp_path: Path, mutate, message: str, line: int | None) -> None:
    cols = ",".join(skeleton_csv.header()[: 1 + 3 * skeleton.J])
    rows = [cols] + [",".join([f"{i / 30:.4f}"] + ["0.1"] * (3 * skeleton.J)) for i in range(2)]
    path = tmp_path / "bad.csv"
    path.write_text("# a comment\n" + "\n".join(mutate(rows)) + "\n")
    with pytest.raises(FormatError) as err:
        formats.read(path)
    assert message in str(err.value)
    assert str(path) in str(err.value)
    assert err.value.line == line


def test_failed_write_leaves_no_partial_file(tmp_path: Path, rng: np.random.Generator, monkeypatch) -> None:
    rec = _recording(rng)
    out = tmp_path / "out.csv"

    def explode(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(skeleton_csv, "_rows", explode)  # fails while the file is open
    with pytest.raises(OSError):
        formats.write(rec, out)
    assert list(tmp_path.iterdir()) == []


def _rows_per_value(rec: Recording) -> list[str]:
    """The writer's lines as it formatted them before its one-format-per-row speed-up: np.char.mod per value."""
    times = np.char.mod("%.6f", rec.t)
    coords = np.char.mod("%.5f", rec.positions.reshape(rec.n_frames, -1))
    coords[~np.isfinite(rec.positions.reshape(rec.n_frames, -1))] = ""
    states = rec.state.astype(str)
    return [times[i] + "," + ",".join(coords[i]) + "," + ",".join(states[i]) + "\n" for i in range(rec.n_frames)]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_rows_are_byte_for_byte_those_of_per_value_formatting(seed: int) -> None:
    """Missing (NaN), infinite and tiny negative values, large times: the same text as np.char.mod per value."""
    rng = np.random.default_rng(seed)
    rec = _recording(rng, frames=200)
    positions = rec.positions.copy()
    positions[rng.random(positions.shape) < 0.05] = np.nan
    positions[7, 2, 1], positions[8, 3, 0], positions[9, 4, 2] = np.inf, -np.inf, -4e-7
    rec = Recording(rec.t + rng.uniform(0, 1e5), positions, np.where(np.isfinite(positions).all(-1), rec.state, 0),
                    rec.meta)  # fmt: skip
    assert skeleton_csv._rows(rec) == _rows_per_value(rec)


def _variants(plain: list[str]) -> dict[str, tuple[list[str], bool]]:
    """Returns {name: (lines, plain)}: a written file's lines and variants, and whether the all-at-once reading
    (_parse_plain) takes them (True) or leaves them to the row-by-row reading (False)."""
    header, rows = plain[0], plain[1:]
    cells = rows[5].split(",")

    def row5(i: int, value: str) -> list[str]:
        changed = cells.copy()
        changed[i] = value
        return [header, *rows[:5], ",".join(changed), *rows[6:]]

    state = len(cells) - 3  # a state column
    return {
        "as written": (plain, True),
        "first coordinate empty": (row5(1, ""), True),
        "padded number": (row5(4, f" {cells[4]} "), False),
        "plus sign": (row5(4, f"+{cells[4].lstrip('-')}"), False),
        "nan written out": (row5(4, "nan"), True),
        "empty state": (row5(state, ""), True),
        "blank cell": (row5(4, " "), False),
        "underscore in a number": (row5(4, "1_0"), False),
        "infinite": (row5(4, "-inf"), False),
        "state padded": (row5(state, " 2"), False),
        "state with a leading zero": (row5(state, "02"), False),
        "state out of range": (row5(state, "3"), False),
        "time empty": (row5(0, ""), False),
        "trailing comma": ([header, *(r + "," for r in rows)], False),
        "repeated row": ([header, *rows[:5], rows[4], *rows[5:]], False),
        "comment between rows": ([header, *rows[:5], "# note", *rows[5:]], False),
        "blank line between rows": ([header, *rows[:5], "", *rows[5:]], False),
        "short row": ([header, *rows[:5], rows[5].rsplit(",", 1)[0], *rows[6:]], False),
        "non-ASCII comment after the rows": ([header, *rows, "# é"], False),
    }


@pytest.mark.parametrize("seed", [0, 1])
def test_the_plain_path_reads_what_row_by_row_reads(tmp_path: Path, seed: int, monkeypatch) -> None:
    """Every variant read with and without the all-at-once path (_parse_plain, np.loadtxt): the same arrays and
    metadata, or the same FormatError (message and line); the path takes the plain files and declines the others."""
    rec = _recording(np.random.default_rng(seed), frames=40)
    written = tmp_path / "written.csv"
    skeleton_csv.write(rec, written)
    real = skeleton_csv._parse_plain
    taken: list[bool] = []

    def spy(lines: list[str], columns: dict[str, Any]) -> object:
        out = real(lines, columns)
        taken.append(out is not None)
        return out

    for k, (name, (lines, plain)) in enumerate(_variants(written.read_text().splitlines()).items()):
        path = tmp_path / f"{k}.csv"
        path.write_text("\n".join(lines) + "\n")
        taken.clear()
        monkeypatch.setattr(skeleton_csv, "_parse_plain", spy)
        outcomes: list[object] = []
        for declined in (False, True):
            if declined:
                monkeypatch.setattr(skeleton_csv, "_parse_plain", lambda *a: None)
            try:
                outcomes.append(formats.read(path, "csv"))
            except FormatError as exc:
                outcomes.append((str(exc), exc.line))
        monkeypatch.undo()
        assert taken == [plain], name
        fast, slow = outcomes
        if isinstance(slow, tuple):
            assert fast == slow, name
            continue
        assert isinstance(fast, Recording) and isinstance(slow, Recording), name
        for field in ("t", "positions", "state"):
            a, b = getattr(fast, field), getattr(slow, field)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), f"{name}: {field}"
        assert fast.meta.to_dict() == slow.meta.to_dict(), name


def test_compiled_rows_are_byte_for_byte_those_of_the_percent_format() -> None:
    """Long recordings' rows by _csv_numba's kernel: the same text as % per row on values made to be hard: exact
    halves of the last decimal (k/64 m), values a rounding away from a half, -0.0, tiny negatives, whole metres, large
    coordinates and times, NaN, infinities (emptied), a time of NaN."""
    rng = np.random.default_rng(7)
    frames = skeleton_csv.COMPILED_MIN_ROWS + 100
    rec = _recording(rng, frames=frames)
    positions = rec.positions.reshape(frames, -1).copy()
    kinds = rng.integers(0, 200, positions.shape)  # each hard kind in 0.5 % of the cells
    halves = rng.integers(-256, 256, positions.shape) / 64.0
    near = (rng.integers(-(10**6), 10**6, positions.shape) + 0.5) / 1e5
    near = near + rng.choice([-1, 0, 1], positions.shape) * np.spacing(near)
    tiny = -rng.uniform(0, 5e-6, positions.shape)
    large = rng.uniform(-1e9, 1e9, positions.shape)
    for k, values in enumerate((halves, near, tiny, large, np.round(positions), np.zeros_like(positions) * -1.0)):
        positions = np.where(kinds == k, values, positions)
    positions[rng.random(positions.shape) < 0.02] = np.nan
    positions[3, 4], positions[5, 6] = np.inf, -np.inf
    t = rec.t * 1e3 + rng.uniform(0, 1e6)
    t[9] = np.nan
    joints = positions.reshape(frames, skeleton.J, 3)
    state = np.where(np.isfinite(joints).all(-1), rec.state, 0)
    odd = Recording.__new__(Recording)  # times and values a recording would refuse: the writer still writes them
    odd.__dict__.update(rec.__dict__, t=t, positions=joints, state=state)
    compiled = skeleton_csv._rows(odd)
    assert compiled == skeleton_csv._rows(odd, compiled=False)
    assert compiled[:9] + compiled[10:] == (per_value := _rows_per_value(odd))[:9] + per_value[10:]
    finite = np.where(np.isfinite(positions), positions, np.nan)
    table = np.concatenate([t[:, None], finite, state.astype(float)], axis=1)
    _, left = _csv_numba.rows_text(table, skeleton_csv._DECIMALS)
    assert 0.1 < left.mean() < 0.5  # the kernel wrote most rows, and left the ones with a half to %
