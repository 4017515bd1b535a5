"""Kinect v2 tab-separated export reader.

../shared/data has no file of this layout, so the tests build it from the real KERAAL Kinect v2 recordings
(all 25 joints, SDK tick time stamps with jitter, tracking states where KERAAL has zeros) and check that the
reader gives back exactly what the KERAAL reader gives for the same frames.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.errors import FormatError
from kinect_agent.formats import keraal, kinect_joints, kinect_v2_tsv
from kinect_agent.recording import Recording

TICKS_PER_S = 10_000_000


def _keraal_files(data_dir: Path) -> list[Path]:
    root = data_dir / "keraal"
    files = sorted(root.glob("kinect_vicon_pairs/*Kinect*.txt")) + sorted(root.glob("kinect_gmm_examples/*/*.txt"))
    assert files, "no KERAAL Kinect files"
    return files


def _export(source: Path, out: Path, *, rng_seed: int = 0) -> np.ndarray:
    """Writes the KERAAL file `source` as a Kinect v2 TSV export at `out`; returns the tick stamps (T,)."""
    values = np.loadtxt(source).reshape(-1, 25, 7)
    rng = np.random.default_rng(rng_seed)
    ticks = 130_000_000 + np.cumsum(np.full(len(values), TICKS_PER_S // 30) + rng.integers(-2000, 2000, len(values)))
    names = kinect_joints.KINECT_V2_JOINTS
    head = ["Timestamp", "BodyIndex"] + [f"{n}_{c}" for n in names for c in ("X", "Y", "Z", "TrackingState")]
    lines = ["# Kinect v2 body export", "# Subject: P1T1", "# Exercise: CTK", "\t".join(head)]
    for i, frame in enumerate(values):
        cells = [str(ticks[i]), "0"]
        for p in frame[:, :3]:
            lost = bool(np.all(p == 0.0))
            cells += ["", "", "", "NotTracked"] if lost else [f"{v:.6f}" for v in p] + ["Tracked"]
        lines.append("\t".join(cells))
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return ticks


@pytest.fixture
def export(data_dir: Path, tmp_path: Path) -> tuple[Path, Path, np.ndarray]:
    source = _keraal_files(data_dir)[0]
    out = tmp_path / "body.tsv"
    return source, out, _export(source, out)


def test_reads_real_keraal_frames_as_keraal_does(data_dir: Path, tmp_path: Path) -> None:
    for k, source in enumerate(_keraal_files(data_dir)):
        out = tmp_path / f"body{k}.tsv"
        ticks = _export(source, out, rng_seed=k)
        rec, ref = kinect_v2_tsv.read(out), keraal.read(source)
        assert rec.n_frames == ref.n_frames and rec.meta.device == "kinect2", source
        np.testing.assert_allclose(rec.positions, ref.positions, atol=1e-6, err_msg=str(source))
        np.testing.assert_array_equal(rec.state, ref.state, err_msg=str(source))
        np.testing.assert_allclose(rec.t, (ticks - ticks[0]) / TICKS_PER_S, atol=1e-12)


def test_metadata_units_and_ignored_columns(export) -> None:
    _, out, ticks = export
    rec = kinect_v2_tsv.read(out)
    assert rec.meta.subject == "P1T1" and rec.meta.exercise == "CTK"
    assert rec.meta.extra["timestamp_unit"] == "ticks" and rec.meta.extra["start_timestamp"] == ticks[0]
    assert rec.meta.extra["ignored_columns"] == ["BodyIndex"]
    assert rec.rate_hz == pytest.approx(30.0, rel=0.01)


def test_units_from_header_and_seconds_inferred(export, tmp_path: Path) -> None:
    _, out, _ = export
    lines = out.read_text().splitlines()
    data = [line.split("\t") for line in lines[4:]]
    for unit, scale in (("ms", 1e3), ("s", 1.0)):
        body = ["\t".join([f"{(i / 30) * scale:.6f}"] + row[1:]) for i, row in enumerate(data)]
        path = tmp_path / f"{unit}.tsv"
        path.write_text("\n".join(lines[:4] + body) + "\n")
        rec = kinect_v2_tsv.read(path)
        assert rec.meta.extra["timestamp_unit"] == unit
        np.testing.assert_allclose(rec.t, np.arange(len(data)) / 30, atol=1e-6)


def test_detect_and_convert(export, tmp_path: Path) -> None:
    source, out, _ = export
    assert formats.detect(out) is kinect_v2_tsv
    assert formats.detect(source) is keraal
    csv = tmp_path / "o.csv"
    assert cli.main(["convert", str(out), "-o", str(csv)]) == 0
    np.testing.assert_allclose(formats.read(csv).positions, keraal.read(source).positions, atol=1e-5)


def test_write_then_read_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(5, skeleton.J, 3))
    positions[2, 4] = np.nan
    rec = Recording.from_positions(np.arange(5) / 30.0, positions)
    path = tmp_path / "w.tsv"
    kinect_v2_tsv.write(rec, path)
    back = kinect_v2_tsv.read(path)
    np.testing.assert_allclose(back.positions, rec.positions, atol=1e-6)
    np.testing.assert_array_equal(back.state, rec.state)


def _bad(export, tmp_path: Path, row: int, edit) -> Path:
    """Copies the export keeping 6 frames, with data row `row` (0-based) edited; returns its path."""
    _, out, _ = export
    lines = out.read_text().splitlines()[:10]
    lines[4 + row] = edit(lines[4 + row].split("\t"))
    path = tmp_path / "bad.tsv"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(
    ("row", "edit", "words"),
    [
        (2, lambda c: "\t".join(c[:-3]), "expected 102 tab-separated fields as in the header, found 99"),
        (2, lambda c: "\t".join(c[:4] + ["1.2x"] + c[5:]), "column 5 'SpineBase_Z': expected a number, found '1.2x'"),
        (2, lambda c: "\t".join(c[:5] + ["Maybe"] + c[6:]), "expected Tracked, Inferred, NotTracked"),
        (3, lambda c: "\t".join([str(int(c[0]) - 400_000)] + c[1:]), "timestamps must strictly increase"),
        (5, lambda c: "\t".join(c[:20]), "(file truncated?)"),
    ],
)  # fmt: skip
def test_bad_rows_name_file_line_and_expectation(export, tmp_path: Path, row: int, edit, words: str) -> None:
    path = _bad(export, tmp_path, row, edit)
    with pytest.raises(FormatError) as info:
        kinect_v2_tsv.read(path)
    assert info.value.path == str(path) and info.value.line == 5 + row, str(info.value)
    assert words in info.value.message, info.value.message


def test_duplicate_timestamp_names_line(export, tmp_path: Path) -> None:
    lines = export[1].read_text().splitlines()[:10]
    lines[6] = "\t".join([lines[5].split("\t")[0]] + lines[6].split("\t")[1:])
    path = tmp_path / "dup.tsv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=r"dup.tsv:7: timestamp \d+ repeats"):
        kinect_v2_tsv.read(path)


def test_unknown_joint_and_missing_joint_name_the_header(export, tmp_path: Path) -> None:
    lines = export[1].read_text().splitlines()[:8]
    for old, new, words in (("SpineMid_X", "Tail_X", "unknown joint 'Tail'"), ("KneeLeft_Y", "Comment", "KneeLeft_Y")):
        path = tmp_path / "h.tsv"
        path.write_text("\n".join(lines[:3] + [lines[3].replace(old, new)] + lines[4:]) + "\n")
        with pytest.raises(FormatError) as info:
            kinect_v2_tsv.read(path)
        assert info.value.line == 4 and words in info.value.message, info.value.message


def test_bad_file_convert_returns_2_and_leaves_no_output(export, tmp_path: Path) -> None:
    path = _bad(export, tmp_path, 5, lambda c: "\t".join(c[:20]))
    out = tmp_path / "o.csv"
    assert cli.main(["convert", str(path), "-o", str(out)]) == 2
    assert not out.exists() and list(tmp_path.glob("*o.csv*")) == []


def test_reads_an_export_with_a_key_value_header_21_joints_and_irregular_16_hz(data_dir: Path, tmp_path: Path):
    """The layout of some Kinect v2 recorders: `key<TAB>value` header lines without '#', Timestamp in seconds,
    the SDK's first 21 joints (no hand tips or thumbs), frames about 16 Hz apart with jitter."""
    source = _keraal_files(data_dir)[0]
    values = np.loadtxt(source).reshape(-1, 25, 7)[:, :21]
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.045, 0.080, len(values)))  # irregular, median about 16 Hz
    names = kinect_joints.KINECT_V2_JOINTS[:21]
    block = ["FrameID\t1", "SensorID\tKinect-2 0042", "Date recording\t2025-03-14 10:22:05", "Floor\t-0.98 0.99 0.05",
             "processing_steps\tnone"]  # fmt: skip
    lines = block + ["\t".join(["Timestamp"] + [f"{n}_{c}" for n in names for c in "XYZ"])]
    for i, frame in enumerate(values):
        lines.append("\t".join([f"{t[i]:.4f}"] + [f"{v:.6f}" for p in frame[:, :3] for v in p]))
    out = tmp_path / "session.txt"
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert formats.detect(out) is kinect_v2_tsv  # found without --format
    rec, ref = formats.read(out), keraal.read(source)
    assert rec.n_frames == ref.n_frames and rec.meta.extra["timestamp_unit"] == "s"
    np.testing.assert_allclose(rec.t, np.round(t, 4) - round(t[0], 4), atol=1e-9)
    np.testing.assert_allclose(rec.positions, ref.positions, atol=1e-6, equal_nan=True)
    header = rec.meta.extra["header"]
    assert header["sensorid"] == "Kinect-2 0042" and header["daterecording"] == "2025-03-14 10:22:05"
    assert rec.meta.rate_hz is not None and 14 < rec.meta.rate_hz < 18
