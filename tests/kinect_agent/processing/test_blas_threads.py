"""The agent, the server and the pipeline run BLAS on one thread by themselves, whatever the environment says
(bench/speed.py --busy 2 measures what that is worth on a busy machine)."""

from __future__ import annotations

from threadpoolctl import threadpool_info, threadpool_limits

from kinect_agent.processing import pipeline
from kinect_agent.sources.simulator import simulate


def _blas_threads() -> set[int]:
    return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}


def test_the_pipeline_filters_on_one_blas_thread_and_gives_the_callers_back(monkeypatch):
    seen: list[set[int]] = []
    real_smooth = pipeline.smooth

    def watching(*args, **kwargs):
        seen.append(_blas_threads())
        return real_smooth(*args, **kwargs)

    monkeypatch.setattr(pipeline, "smooth", watching)
    measured, _, _ = simulate("elbow_flexion", 2, seed=1)
    with threadpool_limits(limits=2, user_api="blas"):
        pipeline.process(measured)
        assert _blas_threads() == {2}  # the caller's own setting, restored
    assert seen == [{1}]


def test_the_agent_command_line_sets_one_blas_thread(tmp_path):
    from kinect_agent import cli

    with threadpool_limits(limits=2, user_api="blas"):
        assert cli.main(["simulate", "--exercise", "squat", "--reps", "1", "-o", str(tmp_path / "s.csv")]) == 0
        assert _blas_threads() == {1}


def test_the_server_sets_one_blas_thread():
    from backend.config import Settings
    from backend.main import create_app

    with threadpool_limits(limits=2, user_api="blas"):
        create_app(Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://"))
        assert _blas_threads() == {1}
