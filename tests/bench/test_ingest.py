"""bench/ingest.py helpers: every timed upload is a valid file with a new session id; the report's verdicts."""

import json

from bench.ingest import summarise, with_new_session_id
from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import make_khs


def test_new_session_id_keeps_a_valid_file_with_the_same_recordings() -> None:
    data = make_khs("squat", 2, seed=3)
    fresh = with_new_session_id(data)
    before, after = sf.decode(data), sf.decode(fresh)
    assert after.session_id != before.session_id
    assert len(fresh) == len(data)
    assert after.raw.n_frames == before.raw.n_frames
    assert json.dumps(after.params) == json.dumps(before.params)


def test_summary_medians_and_verdicts() -> None:
    runs = [{"total": x, "decode": 0.1, "metrics": 0.2, "store": 0.0, "commit": 0.0, "other": x - 0.3}
            for x in (0.4, 0.45, 0.9)]  # fmt: skip
    report = summarise(runs, size=2_100_000, frames=18000, db="SQLite")
    assert report["total_median_s"] == 0.45
    assert (report["total_min_s"], report["total_max_s"]) == (0.4, 0.9)
    assert report["time_pass"] is True
    assert report["size_pass"] is False
