"""Every text reader on the variants real files take once they leave the lab: each is read exactly as the clean file
(same frames, joints, units and times) or refused with one FormatError naming the file (and the line where there is
one); `kinect-agent convert` then exits with 2, prints one line and leaves no output.

The clean files are short cuts of the real samples in ../shared/data, written to tmp_path (never into the repository).
"""

from __future__ import annotations

import codecs
import gzip
import re
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import cli, formats
from kinect_agent.errors import FormatError
from kinect_agent.formats import keraal, kinect_v2_tsv, skeleton_csv
from kinect_agent.formats._text import cut_inside_number
from kinect_agent.recording import Recording

UI_PRMD = "ui-prmd/Segmented Movements"
KERAAL_PAIR = "keraal/kinect_vicon_pairs/G3-{}-CTK-P1T1-Unknown-C-0.txt"


def _head_lines(source: Path, n: int) -> bytes:
    """The first n lines of a text file (gunzipped), as bytes with their own line ends."""
    raw = gzip.decompress(source.read_bytes()) if source.name.endswith(".gz") else source.read_bytes()
    return b"".join(raw.splitlines(keepends=True)[:n])


def build_utkinect(data: Path, tmp: Path) -> Path:
    (tmp / "joints_s01_e01.txt").write_bytes(_head_lines(data / "utkinect/joints_s01_e01.txt", 40))
    return tmp / "joints_s01_e01.txt"


def build_keraal(data: Path, tmp: Path) -> Path:
    out = tmp / Path(KERAAL_PAIR.format("Kinect")).name
    out.write_bytes(_head_lines(data / KERAAL_PAIR.format("Kinect"), 40))
    return out


def build_keraal_vicon(data: Path, tmp: Path) -> Path:
    out = tmp / Path(KERAAL_PAIR.format("Vicon")).name
    out.write_bytes(_head_lines(data / KERAAL_PAIR.format("Vicon"), 80))
    return out


def build_ui_prmd(data: Path, tmp: Path) -> Path:
    for kind in ("positions", "angles"):
        folder = tmp / "Kinect" / kind.capitalize()
        folder.mkdir(parents=True)
        name = f"m01_s01_e01_{kind}.txt.gz"
        source = data / UI_PRMD / "Kinect" / kind.capitalize() / name
        (folder / name).write_bytes(gzip.compress(_head_lines(source, 40)))
    return tmp / "Kinect/Positions/m01_s01_e01_positions.txt.gz"


def build_ui_prmd_vicon(data: Path, tmp: Path) -> Path:
    folder = tmp / "Vicon/Positions"
    folder.mkdir(parents=True)
    name = "m01_s01_e01_positions.txt.gz"
    (folder / name).write_bytes(gzip.compress(_head_lines(data / UI_PRMD / "Vicon/Positions" / name, 60)))
    return folder / name


def build_csv(data: Path, tmp: Path) -> Path:
    skeleton_csv.write(formats.read(build_utkinect(data, tmp)), tmp / "rec.csv")
    (tmp / "rec.meta.json").unlink()
    (tmp / "joints_s01_e01.txt").unlink()
    return tmp / "rec.csv"


def build_tsv(data: Path, tmp: Path) -> Path:
    kinect_v2_tsv.write(keraal.read(build_keraal(data, tmp)), tmp / "body.tsv")
    next(tmp.glob("G3-*")).unlink()
    return tmp / "body.tsv"


def build_bvh(data: Path, tmp: Path) -> Path:
    text = (data / "cmu-mocap/13_29.bvh").read_text()
    head, _, motion = text.partition("MOTION\n")
    rows = motion.splitlines()[2:32]
    (tmp / "13_29.bvh").write_text(head + "MOTION\nFrames: 30\nFrame Time: .0083333\n" + "\n".join(rows) + "\n")
    return tmp / "13_29.bvh"


def build_amc(data: Path, tmp: Path) -> Path:
    (tmp / "asf").mkdir()
    shutil.copy(data / "hdm05/asf/HDM_bd.asf", tmp / "asf")
    raw = (data / "hdm05/squat1Reps/HDM_bd_squat1Reps_001_120.amc").read_bytes().splitlines(keepends=True)
    frame_21 = next(i for i, line in enumerate(raw) if line.strip() == b"21")
    (tmp / "HDM_bd_squat1Reps_001_120.amc").write_bytes(b"".join(raw[:frame_21]))
    return tmp / "HDM_bd_squat1Reps_001_120.amc"


BUILDERS: dict[str, Callable[[Path, Path], Path]] = {
    "csv": build_csv, "kinect_v2_tsv": build_tsv, "utkinect": build_utkinect, "keraal": build_keraal,
    "keraal_vicon": build_keraal_vicon, "ui_prmd": build_ui_prmd, "ui_prmd_vicon": build_ui_prmd_vicon,
    "bvh": build_bvh, "amc": build_amc,
}  # fmt: skip
_NUMBER = re.compile(rb"(?<![\w.+-])(-?)(\d+\.\d+)(?![\d.eE])")


def _data_lines(text: bytes) -> tuple[list[bytes], int]:
    """Splits text into lines (ends kept) and returns the index of the first data line (after any header)."""
    lines = text.splitlines(keepends=True)
    for marker in (b"Frame Time", b"Timestamp", b"time,", b":DEGREES"):
        found = [i for i, line in enumerate(lines) if line.startswith(marker)]
        if found:
            return lines, found[0] + 1
    return lines, 0


def _on_numbers(edit: Callable[[re.Match[bytes]], bytes]) -> Callable[[bytes], bytes]:
    def apply(text: bytes) -> bytes:
        lines, start = _data_lines(text)
        return b"".join(lines[:start] + [_NUMBER.sub(edit, line) for line in lines[start:]])

    return apply


def _trailing_whitespace(text: bytes) -> bytes:
    lines, start = _data_lines(text)
    return b"".join(lines[:start] + [line.rstrip(b"\r\n") + b" \t\n" for line in lines[start:]])


READ_THE_SAME: dict[str, Callable[[bytes], bytes]] = {
    "crlf": lambda t: t.replace(b"\r\n", b"\n").replace(b"\n", b"\r\n"),
    "lf": lambda t: t.replace(b"\r\n", b"\n"),
    "cr_only": lambda t: t.replace(b"\r\n", b"\n").replace(b"\n", b"\r"),
    "utf8_bom": lambda t: codecs.BOM_UTF8 + t,
    "utf16_bom": lambda t: t.decode("latin-1").encode("utf-16"),
    "trailing_blank_lines": lambda t: t.rstrip(b"\r\n") + b"\n\n \n\t\n\n",
    "trailing_whitespace_and_tabs": _trailing_whitespace,
    "no_final_line_end": lambda t: t.rstrip(b"\r\n"),
    "scientific_notation": _on_numbers(lambda m: b"%s%.12e" % (m.group(1), float(m.group(2)))),
    "leading_plus": _on_numbers(lambda m: (m.group(1) or b"+") + m.group(2)),
}


def _text_of(path: Path) -> bytes:
    raw = path.read_bytes()
    return gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw


def _put(path: Path, text: bytes) -> None:
    path.write_bytes(gzip.compress(text) if path.name.endswith(".gz") else text)


def _assert_same(rec: Recording, clean: Recording, what: str) -> None:
    assert rec.n_frames == clean.n_frames, what
    np.testing.assert_allclose(rec.t, clean.t, atol=1e-9, err_msg=what)
    np.testing.assert_allclose(rec.positions, clean.positions, atol=1e-9, equal_nan=True, err_msg=what)
    np.testing.assert_array_equal(rec.state, clean.state, err_msg=what)
    assert rec.meta.device == clean.meta.device, what


@pytest.fixture(params=sorted(BUILDERS))
def sample(request, data_dir: Path, tmp_path: Path) -> tuple[str, Path, Recording]:
    """(format name, path of a short real file, its clean reading)."""
    path = BUILDERS[request.param](data_dir, tmp_path)
    return request.param, path, formats.read(path)


def test_variants_read_as_the_clean_file(sample) -> None:
    name, path, clean = sample
    original = _text_of(path)
    for variant, edit in READ_THE_SAME.items():
        _put(path, edit(original))
        assert formats.detect(path).NAME == name, variant
        _assert_same(formats.read(path), clean, f"{name} {variant}")


def test_gzip_is_told_by_content_not_by_name(sample) -> None:
    name, path, clean = sample
    original = _text_of(path)
    if path.name.endswith(".gz"):  # a plain file that kept its .gz name
        path.write_bytes(original)
        _assert_same(formats.read(path), clean, f"{name} plain under .gz")
        return
    path.write_bytes(gzip.compress(original))  # gzipped, name unchanged
    _assert_same(formats.read(path), clean, f"{name} gzip content")
    zipped = path.with_name(path.name + ".gz")
    zipped.write_bytes(gzip.compress(original))
    if name in ("utkinect", "keraal", "keraal_vicon", "bvh", "csv", "kinect_v2_tsv"):
        path.write_bytes(original)
        _assert_same(formats.read(zipped, name), clean, f"{name} .gz")


def _truncated(text: bytes) -> bytes:
    """The file cut two thirds into its last line (AMC: into the third last line, inside the last frame)."""
    body = text.rstrip(b"\r\n")
    if body.startswith(b"#!OML:ASF"):
        body = b"".join(body.splitlines(keepends=True)[:-2]).rstrip(b"\r\n")
    last = len(body.splitlines()[-1])
    return body[: len(body) - last // 3]


def _truncation_line(text: bytes) -> int:
    """The line a truncated file's error names: the last line, or for AMC the number line of the unfinished frame."""
    lines = text.splitlines()
    if text.startswith(b"#!OML:ASF"):
        return max(i for i, line in enumerate(lines) if line.strip().isdigit()) + 1
    return len(lines)


def _cut_inside_number(text: bytes) -> bytes:
    """The file cut inside the last number of its last line (the number keeps a digit after its point)."""
    body = text.rstrip(b"\r\n ")
    return body[:-3]


REFUSED: dict[str, tuple[Callable[[bytes], bytes], str]] = {
    "empty": (lambda t: b"", "empty file"),
    "binary_garbage": (lambda t: np.random.default_rng(5).integers(0, 256, 4000, dtype=np.uint8).tobytes(), "binary"),
    "truncated_last_line": (_truncated, "truncated"),
    "cut_inside_the_last_number": (_cut_inside_number, "truncated"),
    "gzip_cut_short": (lambda t: gzip.compress(t)[:-30], "truncated"),
}
# Formats whose writers give every number of a column the same count of decimals: a cut inside the last number can be
# told from a complete line. BVH (CMU writes 0, 21, -3.5) and AMC (%g) numbers vary, so a cut there reads as written.
FIXED_DECIMALS = {"csv", "kinect_v2_tsv", "utkinect", "keraal", "keraal_vicon", "ui_prmd", "ui_prmd_vicon"}


@pytest.mark.parametrize("variant", sorted(REFUSED))
def test_refused_variants_name_the_file_and_line(sample, variant: str) -> None:
    name, path, _ = sample
    if variant == "cut_inside_the_last_number" and name not in FIXED_DECIMALS:
        pytest.skip(f"{name} numbers have varying decimals")
    edit, words = REFUSED[variant]
    text = edit(_text_of(path))
    path.write_bytes(gzip.compress(text) if path.name.endswith(".gz") and variant != "gzip_cut_short" else text)
    for fmt in (None, name):
        with pytest.raises(FormatError) as info:
            formats.read(path, fmt)
        message = str(info.value)
        assert info.value.path == str(path), message
        if variant in ("truncated_last_line", "cut_inside_the_last_number"):
            assert info.value.line == _truncation_line(text) and words in message, message
        elif variant == "empty":
            assert "empty" in message or "no frames" in message, message  # a gzip of nothing: no frames
        else:
            assert words in message, message


@pytest.mark.parametrize("variant", ["truncated_last_line", "binary_garbage", "empty"])
def test_cli_refuses_with_status_2_one_line_and_no_output(sample, variant: str, tmp_path: Path, capsys) -> None:
    name, path, _ = sample
    text = REFUSED[variant][0](_text_of(path))
    _put(path, text)
    for out in (tmp_path / "out" / "o.csv", tmp_path / "out" / "o.khs"):
        assert cli.main(["convert", str(path), "-o", str(out)]) == 2, name
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(path) in err and "Traceback" not in err, err
        assert not out.parent.exists() or list(out.parent.iterdir()) == []


@pytest.mark.parametrize(
    ("last", "cut"),
    [("4 0.400000 2.8", True), ("4 0.400000 2.", True), ("4 0.400000 -", True), ("4 0.400000 2.800000", False)],
)
def test_a_cut_is_told_only_in_fixed_decimals(last: str, cut: bool) -> None:
    fixed = ["1 0.100000 2.500000", "2 0.200000 -2.600000", "3 0.300000 2.700000"]
    assert cut_inside_number(fixed + [last]) is cut
    varying = ["rfoot 0.1234 12.3456", "rfoot 1.2345 12.3457", "rfoot 0.12 12.3458"]  # %g: never judged
    assert cut_inside_number(varying + [last.replace("4", "rfoot", 1)]) is False
    exponent = ["1,0.100000,2.5e-01", "2,0.100000,2.500000", "3,0.100000,2.500000"]
    assert cut_inside_number(exponent + [last.replace(" ", ",")]) is False
