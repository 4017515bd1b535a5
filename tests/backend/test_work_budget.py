"""A session file cannot choose the server's work: its params["config"] is recorded, not obeyed, and the frames
analysed are bounded by the recording's duration (backend.session_texts.work_budget)."""

from __future__ import annotations

import time
import tracemalloc
from typing import Any

import numpy as np
import pytest

from backend.replay import scene
from backend.session_texts import work_budget
from backend.sessions.detail import detail_body
from backend.sessions.models import ExerciseSession
from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import make_khs, n_frames, with_header, with_time

HOSTILE_CONFIG = {"outlier_threshold": 0.5, "outlier_iterations": 200, "outlier_window_s": 100.0}


def _with_config(data: bytes, config: dict[str, Any]) -> bytes:
    def change(header: dict[str, Any]) -> None:
        header["params"] = {"config": config}

    return with_header(data, change)


def _at_1khz(data: bytes) -> bytes:
    """The same frames, 1 ms apart (the issue's 'default config at 1 kHz' file)."""
    return with_time(data, np.arange(n_frames(data)) * 0.0010001)


def _cost(run) -> tuple[float, int]:
    """Returns (CPU seconds of this process, peak bytes traced) of run(), each measured on a run of its own (tracing
    slows Python code, so the CPU run is untraced)."""
    cpu = time.process_time()
    run()
    cpu = time.process_time() - cpu
    tracemalloc.start()
    try:
        run()
        return cpu, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_detail_analyses_with_the_servers_settings_not_the_files(client, upload, auth_headers):
    data = make_khs("squat", 3, seed=4)
    plain, _, therapist = upload(data, "squat")
    hostile, _, other = upload(_with_config(make_khs("squat", 3, seed=4), {"outlier_threshold": 0.5}), "squat")
    a = client.get(f"/api/v1/sessions/{plain}/detail", headers=auth_headers(therapist)).json()
    b = client.get(f"/api/v1/sessions/{hostile}/detail", headers=auth_headers(other)).json()
    assert b["quality"]["outlier_strip"]["threshold"] == work_budget.SERVER_PIPELINE.outlier_threshold == 0.95
    assert b["quality"]["outlier_strip"]["prob"] == a["quality"]["outlier_strip"]["prob"]
    assert b["processing"]["file_params"] == {"config": {"outlier_threshold": 0.5}}, "what the file says is shown"


def test_replay_flags_outliers_with_the_servers_settings(monkeypatch):
    payload = sf.decode(_with_config(make_khs("squat", 2, seed=5), HOSTILE_CONFIG))
    used = []
    real = scene.outlier_flags

    def outlier_flags(raw, config=None):
        used.append(config)
        return real(raw, config)

    monkeypatch.setattr(scene, "outlier_flags", outlier_flags)
    scene.build(payload, "sagittal")
    assert used == [work_budget.SERVER_PIPELINE]


@pytest.mark.parametrize("config", [{"outlier_iterations": 200}, {"outlier_window_s": 100.0}])
def test_a_files_config_does_not_raise_the_cost_of_its_detail(config):
    data = _with_config(make_khs("squat", 3, seed=6), config)
    payload = sf.decode(data)
    session = ExerciseSession(id=1, patient_id=1, started_at=None, status="processed")
    limits = {"max_frames": 216_000, "max_decoded_bytes": 128 * 2**20}
    cpu, peak = _cost(lambda: detail_body(session, "squat", None, data, **limits))
    budget_cpu, budget_bytes = work_budget.budget(payload.raw.duration)
    assert peak < budget_bytes / 4, f"peak {peak / 2**20:.0f} MiB"
    assert cpu < budget_cpu, f"{cpu:.2f} s CPU"


def test_a_1khz_file_costs_what_its_duration_allows():
    data = _at_1khz(make_khs("squat", 3, seed=7))
    payload = sf.decode(data)
    session = ExerciseSession(id=1, patient_id=1, started_at=None, status="processed")
    limits = {"max_frames": 216_000, "max_decoded_bytes": 128 * 2**20}
    budget_cpu, budget_bytes = work_budget.budget(payload.raw.duration)
    cpu, peak = _cost(lambda: detail_body(session, "squat", None, data, **limits))
    assert peak < budget_bytes and cpu < budget_cpu, f"detail: {peak / 2**20:.0f} MiB, {cpu:.2f} s CPU"
    budget_cpu, budget_bytes = work_budget.budget(payload.raw.duration, "replay")
    cpu, peak = _cost(lambda: scene.build(payload, "sagittal"))
    assert peak < budget_bytes and cpu < budget_cpu, f"replay: {peak / 2**20:.0f} MiB, {cpu:.2f} s CPU"


def test_analysis_frames_are_bounded_by_duration_and_spaced_in_time():
    rng = np.random.default_rng(0)
    for t in (
        np.arange(5000) / 1000.0,  # 1 kHz
        np.cumsum(rng.choice([1e-6, 0.03], size=4000)),  # pairs of frames a microsecond apart
        np.cumsum(rng.uniform(1e-6, 0.05, size=4000)),
    ):
        keep = work_budget.analysis_frames(t)
        assert keep[0] == 0 and np.all(np.diff(keep) > 0)
        assert len(keep) <= work_budget.MAX_ANALYSIS_RATE_HZ * (t[-1] - t[0]) + 1
        assert np.min(np.diff(t[keep])) >= 1.0 / work_budget.MAX_ANALYSIS_RATE_HZ - 1e-12


def test_a_30hz_cameras_frames_are_all_analysed():
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(1 / 30 - 0.008, 1 / 30 + 0.008, size=3000))
    np.testing.assert_array_equal(work_budget.analysis_frames(t), np.arange(3000))


def test_budget_grows_per_started_ten_minutes():
    assert work_budget.budget(0.0) == (8.0, 512 * 2**20) == work_budget.BUDGETS["detail"]
    assert work_budget.budget(600.0, "replay") == work_budget.BUDGETS["replay"]
    assert work_budget.budget(601.0, "upload") == (4.0, 512 * 2**20)
