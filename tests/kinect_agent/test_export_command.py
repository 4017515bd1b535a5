"""`kinect-agent export`: every format from a session file; bad input gives one clear error, status 2, no file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from kinect_agent.cli import main
from kinect_agent.formats import session_file as sf
from tests.kinect_agent.export.conftest import session


@pytest.fixture(scope="module")
def khs(tmp_path_factory):
    """A session file and its metrics document on disk."""
    payload, doc = session("elbow_flexion", 2, seed=21)
    folder = tmp_path_factory.mktemp("export")
    path = folder / "set.khs"
    sf.write_payload(payload, path)
    (folder / "doc.json").write_text(json.dumps(doc.model_dump(mode="json")), encoding="utf-8")
    return path


FORMATS = [("csv", "-csv.zip", b"PK"), ("trc", ".trc", b"PathFileType"), ("bvh", ".bvh", b"HIERARCHY"),
           ("fhir", "-fhir.json", b"{")]  # fmt: skip


@pytest.mark.parametrize(("fmt", "suffix", "start"), FORMATS)
def test_each_format_is_written_beside_the_session(khs, fmt, suffix, start):
    assert main(["export", str(khs), "--format", fmt, "--metrics", str(khs.with_name("doc.json"))]) == 0
    out = khs.with_name(f"set{suffix}")
    assert out.read_bytes().startswith(start)


def test_out_names_the_file(khs, tmp_path):
    out = tmp_path / "deep" / "m.trc"
    assert main(["export", str(khs), "--format", "trc", "--out", str(out)]) == 0
    assert out.is_file()


def _nothing_written(folder) -> bool:
    return not any(folder.iterdir())


def test_missing_file_is_refused(tmp_path, capsys):
    assert main(["export", str(tmp_path / "none.khs"), "--format", "bvh", "--out", str(tmp_path / "o" / "x")]) == 2
    assert "no such session file" in capsys.readouterr().err
    assert _nothing_written(tmp_path)


def test_broken_file_is_refused_and_nothing_is_left(khs, tmp_path, capsys):
    broken = tmp_path / "in" / "broken.khs"
    broken.parent.mkdir()
    data = bytearray(khs.read_bytes())
    data[100] ^= 0xFF
    broken.write_bytes(bytes(data))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    assert main(["export", str(broken), "--format", "csv", "--out", str(out_dir / "x.zip")]) == 2
    assert "checksum_mismatch" in capsys.readouterr().err
    assert _nothing_written(out_dir)


def test_unknown_format_is_a_usage_error(khs, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["export", str(khs), "--format", "xlsx"])
    assert exc.value.code == 2 and "invalid choice: 'xlsx'" in capsys.readouterr().err


def test_fhir_without_metrics_is_refused_and_nothing_is_written(khs, tmp_path, capsys):
    assert main(["export", str(khs), "--format", "fhir", "--out", str(tmp_path / "b.json")]) == 2
    assert "analysis document" in capsys.readouterr().err
    assert _nothing_written(tmp_path)


def test_a_metrics_file_that_is_not_a_document_is_refused(khs, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]", encoding="utf-8")
    assert main(["export", str(khs), "--format", "fhir", "--metrics", str(bad), "--out", str(tmp_path / "b")]) == 2
    assert "not an analysis document" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]


def test_a_document_of_an_older_schema_exports(khs, tmp_path):
    older = Path(__file__).parent / "analysis" / "documents" / "schema1_2026-11-23.json"
    out = tmp_path / "b.json"
    assert main(["export", str(khs), "--format", "fhir", "--metrics", str(older), "--out", str(out)]) == 0
    codes = [
        e["resource"].get("code", {}).get("coding", [{}])[0].get("code") for e in json.loads(out.read_text())["entry"]
    ]
    assert "indicator.flexibility" in codes and "range-of-motion.shoulder_abduction_L" in codes


def test_a_document_with_a_wrong_value_is_refused_by_its_key(khs, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    doc = json.loads(khs.with_name("doc.json").read_text(encoding="utf-8"))
    bad.write_text(json.dumps(doc | {"rom_deg": "wide"}), encoding="utf-8")
    assert main(["export", str(khs), "--format", "fhir", "--metrics", str(bad), "--out", str(tmp_path / "b")]) == 2
    assert "not an analysis document: rom_deg:" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]


@pytest.mark.parametrize("opening", ["[", '{"a":'], ids=["lists", "objects"])
def test_a_deeply_nested_metrics_file_is_named_not_a_traceback(khs, tmp_path, capsys, opening):
    deep = tmp_path / "deep.json"
    closing = "]" if opening == "[" else "}"
    deep.write_text(opening * 100_000 + ("1" if opening != "[" else "") + closing * 100_000, encoding="utf-8")
    assert main(["export", str(khs), "--format", "fhir", "--metrics", str(deep), "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert f"{deep}: the metrics document is nested too deeply" in err and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deep.json"]
