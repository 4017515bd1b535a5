"""Kinect-side readers on what real recorders write beyond our samples: lost joints as nan / NaN / empty cells,
frames written twice, times that go back, irregular timing, and the Kinect v2 TSV export's SDK joint sets, header
blocks and Timestamp units (each unit inferred right, an ambiguous step refused).

Files are generated in tmp_path from short cuts of the real samples in ../shared/data.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import keraal, kinect_joints, kinect_v2_tsv, skeleton_csv, ui_prmd, utkinect

from .test_variants import build_keraal, build_keraal_vicon, build_ui_prmd, build_ui_prmd_vicon, build_utkinect

TICKS_PER_S = 10_000_000


def _rows(path: Path) -> list[str]:
    raw = path.read_bytes()
    text = gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw
    return text.decode().splitlines()


def _write(path: Path, rows: list[str]) -> None:
    text = ("\n".join(rows) + "\n").encode()
    path.write_bytes(gzip.compress(text) if path.name.endswith(".gz") else text)


# --- lost joints -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("lost", ["nan", "NaN", ""])
def test_csv_lost_joint_as_nan_or_empty_is_not_tracked(data_dir: Path, tmp_path: Path, lost: str) -> None:
    rec = utkinect.read(build_utkinect(data_dir, tmp_path))
    path = tmp_path / "r.csv"
    skeleton_csv.write(rec, path)
    rows = _rows(path)
    cells = rows[3].split(",")
    head = skeleton_csv.header()
    for axis in "xyz":
        cells[head.index(f"ELB_L_{axis}")] = lost
    rows[3] = ",".join(cells)
    _write(path, rows)
    back = skeleton_csv.read(path)
    elbow = skeleton.INDEX["ELB_L"]
    assert back.state[2, elbow] == skeleton.NOT_TRACKED and np.isnan(back.positions[2, elbow]).all()
    keep = np.ones(rec.n_frames, bool)
    keep[2] = False
    np.testing.assert_allclose(back.positions[keep], rec.positions[keep], atol=1e-5)


def test_csv_infinity_and_nan_time_are_refused(data_dir: Path, tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    skeleton_csv.write(utkinect.read(build_utkinect(data_dir, tmp_path)), path)
    rows = _rows(path)
    for edit, words in (
        (lambda c: ["nan"] + c[1:], "time must be finite"),
        (lambda c: c[:5] + ["inf"] + c[6:], "finite"),
    ):
        bad = rows[:3] + [",".join(edit(rows[3].split(",")))] + rows[4:]
        _write(path, bad)
        with pytest.raises(FormatError, match=rf"r\.csv:4: .*{words}"):
            skeleton_csv.read(path)


@pytest.mark.parametrize("lost", ["nan", "NaN", "-nan"])
def test_whitespace_kinect_files_take_nan_for_a_lost_joint(data_dir: Path, tmp_path: Path, lost: str) -> None:
    for build, joint_fields, offset in ((build_utkinect, 3, 1), (build_keraal, 7, 0)):
        folder = tmp_path / build.__name__ / lost
        folder.mkdir(parents=True)
        path = build(data_dir, folder)
        clean = formats.read(path)
        rows = [row for row in _rows(path) if row.strip()]  # the last line is the last frame (UTKinect repeats ids)
        cells = rows[-1].split()
        v1 = kinect_joints.KINECT_V1_JOINTS.index("KneeRight")
        v2 = kinect_joints.KINECT_V2_JOINTS.index("KneeRight")
        j = v1 if build is build_utkinect else v2
        cells[offset + joint_fields * j : offset + joint_fields * j + 3] = [lost] * 3
        rows[-1] = " ".join(cells)
        _write(path, rows)
        rec = formats.read(path)
        knee = skeleton.INDEX["KNE_R"]
        assert rec.state[-1, knee] == skeleton.NOT_TRACKED, build.__name__
        clean.state[-1, knee] = skeleton.NOT_TRACKED
        clean.positions[-1, knee] = np.nan
        np.testing.assert_array_equal(rec.state, clean.state)
        np.testing.assert_allclose(rec.positions, clean.positions, equal_nan=True)


def test_ui_prmd_lost_value_loses_that_joint_and_the_ones_built_on_it(data_dir: Path, tmp_path: Path) -> None:
    path = build_ui_prmd(data_dir, tmp_path)
    clean = ui_prmd.read(path)
    rows = _rows(path)
    cells = rows[4].split(",")
    forearm = ui_prmd.SOURCE_JOINTS.index("Left forearm")
    cells[3 * forearm] = "NaN"
    cells[3 * forearm + 1] = ""
    rows[4] = ",".join(cells)
    _write(path, rows)
    rec = ui_prmd.read(path)
    lost = [skeleton.INDEX[j] for j in ("ELB_L", "WRI_L", "HAN_L")]
    assert np.all(rec.state[4, lost] == skeleton.NOT_TRACKED)
    kept = np.ones((rec.n_frames, skeleton.J), bool)
    kept[4, lost] = False
    np.testing.assert_allclose(rec.positions[kept], clean.positions[kept], atol=1e-12)


def test_ui_prmd_vicon_lost_marker_as_nan_is_missing(data_dir: Path, tmp_path: Path) -> None:
    path = build_ui_prmd_vicon(data_dir, tmp_path)
    clean = formats.read(path)
    rows = _rows(path)
    zeros, nans = rows[:], rows[:]
    for copy, lost in ((zeros, "0"), (nans, "nan")):
        cells = copy[7].split(",")
        cells[3 * 15 : 3 * 15 + 3] = [lost] * 3  # LFIN, the left hand
        copy[7] = ",".join(cells)
    _write(path, zeros)
    as_zero = formats.read(path)
    _write(path, nans)
    as_nan = formats.read(path)
    hand = skeleton.INDEX["HAN_L"]
    assert as_nan.state[7, hand] == skeleton.NOT_TRACKED and clean.state[7, hand] == skeleton.TRACKED
    np.testing.assert_array_equal(as_nan.positions, as_zero.positions)


def test_keraal_vicon_target_as_nan_is_missing(data_dir: Path, tmp_path: Path) -> None:
    path = build_keraal_vicon(data_dir, tmp_path)
    rows = _rows(path)
    cells = rows[9].split()
    head = 7 * 14  # HEAD target
    cells[head : head + 7] = ["NaN"] * 7
    rows[9] = " ".join(cells)
    _write(path, rows)
    rec = formats.read(path)
    assert rec.state[9, skeleton.INDEX["HEAD"]] == skeleton.NOT_TRACKED
    assert rec.meta.extra["missing_targets"] == {"HEAD": 1}


# --- repeated and irregular frames ------------------------------------------------------------------------------


def _csv_file(data_dir: Path, tmp_path: Path) -> tuple[Path, list[str]]:
    path = tmp_path / "r.csv"
    skeleton_csv.write(utkinect.read(build_utkinect(data_dir, tmp_path)), path)
    (tmp_path / "r.meta.json").unlink()
    return path, _rows(path)


def test_csv_row_written_twice_is_dropped(data_dir: Path, tmp_path: Path) -> None:
    path, rows = _csv_file(data_dir, tmp_path)
    clean = skeleton_csv.read(path)
    _write(path, rows[:6] + [rows[5]] + rows[6:])
    rec = skeleton_csv.read(path)
    assert rec.meta.extra["dropped_duplicate_rows"] == 1
    np.testing.assert_array_equal(rec.positions, clean.positions)


@pytest.mark.parametrize(("edit", "words"), [("same_time", "duplicate time stamp"), ("back", "decreasing time stamp")])
def test_csv_time_repeated_with_other_values_or_going_back_is_refused(data_dir, tmp_path, edit, words) -> None:
    path, rows = _csv_file(data_dir, tmp_path)
    cells = rows[6].split(",")
    cells[0] = rows[5].split(",")[0] if edit == "same_time" else rows[3].split(",")[0]
    _write(path, rows[:6] + [",".join(cells)] + rows[7:])
    with pytest.raises(FormatError, match=rf"r\.csv:7: {words}"):
        skeleton_csv.read(path)


def test_csv_irregular_times_are_kept(data_dir: Path, tmp_path: Path) -> None:
    path, rows = _csv_file(data_dir, tmp_path)
    t = np.cumsum(np.random.default_rng(4).uniform(0.01, 0.09, len(rows) - 1))
    _write(path, rows[:1] + [f"{t[i]:.6f}," + row.split(",", 1)[1] for i, row in enumerate(rows[1:])])
    np.testing.assert_allclose(skeleton_csv.read(path).t, t, atol=1e-6)


def test_utkinect_repeated_and_decreasing_frame_ids(data_dir: Path, tmp_path: Path) -> None:
    path = build_utkinect(data_dir, tmp_path)
    rows = [r for r in _rows(path) if r.strip()]
    clean = utkinect.read(path)
    _write(path, rows[:8] + [rows[7]] + rows[8:])  # a line written twice
    assert utkinect.read(path).meta.extra["dropped_duplicate_lines"] == clean.meta.extra["dropped_duplicate_lines"] + 1
    earlier = rows[2].split(None, 1)[0]
    _write(path, rows[:8] + [earlier + " " + rows[8].split(None, 1)[1]] + rows[9:])
    with pytest.raises(FormatError, match=rf"joints_s01_e01\.txt:9: frame id {earlier} after"):
        utkinect.read(path)


# --- UTKinect action labels ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("line_end", ["\n", "\r\n"])
def test_utkinect_labels_with_nan_bom_and_crlf(data_dir: Path, tmp_path: Path, line_end: str) -> None:
    path = build_utkinect(data_dir, tmp_path)
    labels = ["s01_e01", "walk: 252 390", "sitDown: NaN NaN", "standUp: 704 NaN", "carry:\t1016\t1242  ", "s01_e02",
              "walk: 1 2"]  # fmt: skip
    (tmp_path / "actionLabel.txt").write_bytes(b"\xef\xbb\xbf" + line_end.join(labels).encode() + line_end.encode())
    extra = utkinect.read(path).meta.extra
    assert extra["actions"] == {"walk": [252, 390], "carry": [1016, 1242]}
    assert extra["actions_not_performed"] == ["sitDown"] and extra["actions_without_span"] == ["standUp"]


def test_utkinect_broken_label_line_is_named(data_dir: Path, tmp_path: Path) -> None:
    path = build_utkinect(data_dir, tmp_path)
    (tmp_path / "actionLabel.txt").write_text("s01_e01\nwalk: 252 to 390\n")
    with pytest.raises(FormatError, match=r"actionLabel\.txt:2: expected 'action: start end'"):
        utkinect.read(path)


# --- Kinect v2 TSV -----------------------------------------------------------------------------------------------


def build_tsv(
    data_dir: Path,
    tmp_path: Path,
    stamps: np.ndarray | None = None,
    *,
    joints: int = 25,
    header: tuple[str, ...] = ("# Kinect v2 body export",),
    time_name: str = "Timestamp",
    states: bool = True,
    trailing_tab: bool = False,
) -> tuple[Path, np.ndarray]:
    """Writes the short KERAAL cut as a TSV export with SDK joint names; returns its path and the positions (T, 25, 3)
    it holds (NaN where KERAAL has its all-zero 'not tracked')."""
    values = np.loadtxt(build_keraal(data_dir, tmp_path)).reshape(-1, 25, 7)[:, :, :3]
    values[np.all(values == 0.0, axis=-1)] = np.nan
    if stamps is None:
        stamps = 130_000_000 + np.arange(len(values)) * (TICKS_PER_S // 30)
    names = kinect_joints.KINECT_V2_JOINTS[:joints]
    fields = ("X", "Y", "Z", "TrackingState") if states else ("X", "Y", "Z")
    lines = list(header) + ["\t".join([time_name] + [f"{n}_{f}" for n in names for f in fields])]
    for i, frame in enumerate(values):
        cells = [f"{stamps[i]}"]
        for p in frame[:joints]:
            lost = not np.all(np.isfinite(p))
            cells += ["", "", ""] if lost else [f"{v:.6f}" for v in p]
            cells += ["NotTracked" if lost else "Tracked"] if states else []
        lines.append("\t".join(cells) + ("\t" if trailing_tab else ""))
    path = tmp_path / "body.tsv"
    path.write_text("\n".join(lines) + "\n")
    return path, values


def _expected(values: np.ndarray) -> np.ndarray:
    return kinect_joints.to_skeleton(values, "kinect2")[0]


@pytest.mark.parametrize("rate_hz", [30.0, 15.0])
@pytest.mark.parametrize(("unit", "per_s"), [("s", 1.0), ("ms", 1e3), ("us", 1e6), ("ticks", 1e7)])
def test_tsv_timestamp_unit_is_inferred_right(data_dir, tmp_path, unit: str, per_s: float, rate_hz: float) -> None:
    jitter = np.random.default_rng(1).uniform(-0.002, 0.002, 40)
    seconds = 12.5 + np.arange(40) / rate_hz + jitter
    stamps = np.round(seconds * per_s, 6 if unit == "s" else 3)
    path, values = build_tsv(data_dir, tmp_path, stamps)
    rec = kinect_v2_tsv.read(path)
    assert rec.meta.extra["timestamp_unit"] == unit
    np.testing.assert_allclose(rec.t, seconds - seconds[0], atol=2e-6)
    np.testing.assert_allclose(rec.positions, _expected(values), atol=1e-6)


def test_tsv_ambiguous_timestamp_step_is_refused(data_dir: Path, tmp_path: Path) -> None:
    path, _ = build_tsv(data_dir, tmp_path, 5_000_000 + np.arange(40) * 100_000)  # 100 Hz in ticks or 10 Hz in us
    with pytest.raises(FormatError, match=r"body\.tsv:\d+: cannot tell the timestamp unit.*fits more than one unit"):
        kinect_v2_tsv.read(path)
    path.write_text("# TimestampUnit: us\n" + path.read_text())
    assert kinect_v2_tsv.read(path).rate_hz == pytest.approx(10.0)


@pytest.mark.parametrize(
    ("time_name", "unit"), [("Timestamp (ms)", "ms"), ("Time_sec", "s"), ("Timestamp[ticks]", "ticks"), ("Time", None)]
)
def test_tsv_unit_in_the_column_name(data_dir: Path, tmp_path: Path, time_name: str, unit: str | None) -> None:
    per_s = {"ms": 1e3, "s": 1.0, "ticks": 1e7, None: 1.0}[unit]
    path, _ = build_tsv(data_dir, tmp_path, np.round(np.arange(40) / 30 * per_s, 6), time_name=time_name)
    rec = kinect_v2_tsv.read(path)
    assert rec.meta.extra["timestamp_unit"] == (unit or "s")
    np.testing.assert_allclose(rec.t, np.arange(40) / 30, atol=1e-6)


@pytest.mark.parametrize("joints", [25, 21])
def test_tsv_sdk_joint_sets_with_a_key_value_header(data_dir: Path, tmp_path: Path, joints: int) -> None:
    header = ("Version\t2", "SensorID\tKinect-2\t0042", "Date recording\t2025-03-14 10:22:05",
              "Floor\t-0.98\t0.99\t0.05", "", "# Subject: P7")  # fmt: skip
    path, values = build_tsv(data_dir, tmp_path, joints=joints, header=header, states=joints == 25, trailing_tab=True)
    assert formats.detect(path) is kinect_v2_tsv
    rec = formats.read(path)
    np.testing.assert_allclose(rec.positions, _expected(values), atol=1e-6)
    head = rec.meta.extra["header"]
    assert head["sensorid"] == "Kinect-2 0042" and head["floor"] == "-0.98 0.99 0.05" and rec.meta.subject == "P7"


def test_tsv_frame_written_twice_is_dropped_other_repeats_refused(data_dir: Path, tmp_path: Path) -> None:
    path, values = build_tsv(data_dir, tmp_path)
    rows = path.read_text().splitlines()
    path.write_text("\n".join(rows[:6] + [rows[5]] + rows[6:]) + "\n")
    rec = kinect_v2_tsv.read(path)
    assert rec.meta.extra["dropped_duplicate_rows"] == 1
    np.testing.assert_allclose(rec.positions, _expected(values), atol=1e-6)
    other = rows[5].split("\t")
    other[2] = "0.123456"
    path.write_text("\n".join(rows[:6] + ["\t".join(other)] + rows[6:]) + "\n")
    with pytest.raises(FormatError, match=r"body\.tsv:7: timestamp \d+ repeats the row before with other values"):
        kinect_v2_tsv.read(path)


@pytest.mark.parametrize("lost", ["nan", "NaN", ""])
def test_tsv_lost_joint_as_nan_or_empty(data_dir: Path, tmp_path: Path, lost: str) -> None:
    path, values = build_tsv(data_dir, tmp_path, states=False)
    rows = path.read_text().splitlines()
    cells = rows[4].split("\t")
    head = kinect_joints.KINECT_V2_JOINTS.index("Head")
    cells[1 + 3 * head : 4 + 3 * head] = [lost] * 3
    rows[4] = "\t".join(cells)
    path.write_text("\n".join(rows) + "\n")
    rec = kinect_v2_tsv.read(path)
    assert rec.state[2, skeleton.INDEX["HEAD"]] == skeleton.NOT_TRACKED


def test_tsv_without_column_header_names_the_first_data_line(data_dir: Path, tmp_path: Path) -> None:
    path, _ = build_tsv(data_dir, tmp_path)
    rows = path.read_text().splitlines()
    path.write_text("\n".join(rows[:1] + rows[2:]) + "\n")
    with pytest.raises(FormatError, match=r"body\.tsv:2: no column header"):
        kinect_v2_tsv.read(path)


def test_keraal_and_tsv_agree_on_the_same_frames(data_dir: Path, tmp_path: Path) -> None:
    path, _ = build_tsv(data_dir, tmp_path)
    ref = keraal.read(next(tmp_path.glob("G3-*")))
    np.testing.assert_allclose(kinect_v2_tsv.read(path).positions, ref.positions, atol=1e-6)


@pytest.mark.parametrize(
    ("stamp", "seconds"),
    [
        (lambda s: f"00:{int(s // 60):02d}:{s % 60:010.7f}", lambda s: s),  # .NET TimeSpan, RelativeTime.ToString()
        (lambda s: f"1.02:00:{s:010.7f}", lambda s: s),  # a TimeSpan past a day
        (lambda s: f"2025-03-14T10:22:{5 + s:09.6f}", lambda s: s),  # ISO 8601
        (lambda s: f"2025-03-14 10:22:{5 + s:09.6f}+01:00", lambda s: s),
    ],
    ids=["timespan", "timespan_days", "iso", "iso_offset"],
)
def test_tsv_clock_timestamps(data_dir: Path, tmp_path: Path, stamp, seconds) -> None:
    t = 3.2 + np.arange(40) / 30.0
    path, values = build_tsv(data_dir, tmp_path, np.array([stamp(s) for s in t]))
    rec = kinect_v2_tsv.read(path)
    assert rec.meta.extra["timestamp_unit"] == "clock"
    np.testing.assert_allclose(rec.t, t - t[0], atol=1e-6)
    np.testing.assert_allclose(rec.positions, _expected(values), atol=1e-6)


def test_tsv_clock_timestamps_going_back_are_refused(data_dir: Path, tmp_path: Path) -> None:
    stamps = np.array([f"00:00:{s:06.3f}" for s in np.arange(40) / 30.0])
    stamps[9] = stamps[3]
    path, _ = build_tsv(data_dir, tmp_path, stamps)
    with pytest.raises(FormatError, match=r"body\.tsv:12: timestamp 00:00:00.100 goes back from 00:00:00.267"):
        kinect_v2_tsv.read(path)


def test_decimal_commas_are_refused_with_a_hint(data_dir: Path, tmp_path: Path) -> None:
    path, _ = build_tsv(data_dir, tmp_path, states=False)
    rows = path.read_text().splitlines()
    rows[3] = rows[3].replace(".", ",")
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(FormatError, match=r"body\.tsv:4: column 2 'SpineBase_X': expected a number, found '-?\d+,\d+' "
                       r"\(a decimal comma"):  # fmt: skip
        kinect_v2_tsv.read(path)
    ut = build_utkinect(data_dir, tmp_path)
    rows = _rows(ut)
    rows[2] = rows[2].replace(".", ",")
    _write(ut, rows)
    with pytest.raises(FormatError, match=r"joints_s01_e01\.txt:3: field 2: expected a number.*a decimal comma"):
        utkinect.read(ut)


def test_csv_with_quoted_names_and_numbers(data_dir: Path, tmp_path: Path) -> None:
    path, rows = _csv_file(data_dir, tmp_path)
    clean = skeleton_csv.read(path)
    quoted = [",".join(f'"{c}"' if c else c for c in row.split(",")) for row in rows]
    _write(path, quoted)
    assert formats.detect(path) is skeleton_csv
    rec = skeleton_csv.read(path)
    np.testing.assert_array_equal(rec.positions, clean.positions)
    np.testing.assert_array_equal(rec.state, clean.state)


def test_csv_separated_by_semicolons_is_refused_with_a_hint(data_dir: Path, tmp_path: Path) -> None:
    path, rows = _csv_file(data_dir, tmp_path)
    _write(path, [row.replace(",", ";") for row in rows])
    with pytest.raises(FormatError, match=r"r\.csv:1: first column must be 'time'.*separated by ';'"):
        skeleton_csv.read(path)
