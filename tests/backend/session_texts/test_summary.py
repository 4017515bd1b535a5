"""`coach-server analyze`: the analysis document of one recording file as JSON or an English summary; a bad
exercise, file or option is one line on stderr and exit 2."""

from __future__ import annotations

import json
import re
from pathlib import Path

from backend import cli
from kinect_agent import formats
from kinect_agent.formats.session_file import SessionPayload, write_payload
from kinect_agent.sources.simulator import simulate_truth
from tests.kinect_agent.analysis._data import noisy


def test_cli_prints_json_with_the_repetition_count(tmp_path: Path, capsys) -> None:
    measured, _ = noisy("shoulder_abduction", 5, 3)
    path = tmp_path / "session.csv"
    formats.write(measured, path)
    assert cli.main(["analyze", str(path), "--exercise", "shoulder_abduction", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["repetitions"] == 5 and doc["exercise"] == "shoulder_abduction"


def test_cli_summary_names_the_count(tmp_path: Path, capsys) -> None:
    path = tmp_path / "s.khs"
    truth = simulate_truth("squat", 2, seed=1)
    write_payload(SessionPayload(session_id="abc", raw=truth, filtered=truth), path)
    assert cli.main(["analyze", str(path), "--exercise", "squat"]) == 0
    assert "squat: 2 repetitions" in capsys.readouterr().out


def test_cli_summary_gives_the_balance_or_why_it_is_missing(tmp_path: Path, capsys) -> None:
    for slug, says in (("shoulder_abduction", r"balance: sway \d+\.\d\d cm/s \(95 % \d+\.\d\d-\d+\.\d\d\) over "),
                       ("seated_knee_extension", r"balance: not measured: \w")):  # fmt: skip
        path = tmp_path / f"{slug}.khs"
        truth = simulate_truth(slug, 3, seed=2)
        write_payload(SessionPayload(session_id="abc", raw=truth, filtered=truth), path)
        assert cli.main(["analyze", str(path), "--exercise", slug]) == 0
        out = capsys.readouterr().out
        assert re.search(says, out), out


def test_cli_unknown_exercise_exits_2_with_one_line(tmp_path: Path, capsys) -> None:
    path = tmp_path / "s.csv"
    formats.write(simulate_truth("squat", 1, seed=1), path)
    assert cli.main(["analyze", str(path), "--exercise", "no_such_exercise", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    err = captured.err.strip()
    assert "unknown exercise 'no_such_exercise'" in err and "\n" not in err


def test_cli_unreadable_file_exits_2(tmp_path: Path, capsys) -> None:
    path = tmp_path / "garbage.csv"
    path.write_text("this is not a recording\n1,2,3\n")
    assert cli.main(["analyze", str(path), "--exercise", "squat", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert str(path) in err and "\n" not in err


def test_cli_missing_exercise_option_exits_2(tmp_path: Path, capsys) -> None:
    assert cli.main(["analyze", str(tmp_path / "x.csv")]) == 2
    assert "--exercise" in capsys.readouterr().err
