"""Two lean installs from one repository: the home computer installs the agent (packages/agent: the pure core, numba,
no web server or database), the clinic installs the server (packages/server: the pure core and the web stack, no
numba). Here each runs from the source tree in a fresh interpreter where the other side's packages cannot be imported;
tests/test_deployables.py installs each distribution into an environment of its own."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

pytestmark = pytest.mark.own_database  # each install runs on a SQLite file of its own
REPO = Path(__file__).resolve().parents[1]
# pydantic is in the shared core (the pipeline's settings, kinect_agent.processing.config); pydantic_settings is not.
SERVER_ONLY = ("fastapi", "starlette", "uvicorn", "sqlalchemy", "alembic", "psycopg", "pydantic_settings", "argon2",
               "jinja2", "viser", "babel")  # fmt: skip
AGENT_ONLY = ("numba", "llvmlite", "tqdm")
# a benchmark's baseline and the evaluation figures, not the product's; plotly's Python package (the pages' plotly.js
# is a pinned npm asset, kinect_agent/vendor/lock.json)
NEVER = ("filterpy", "matplotlib", "plotly")

BLOCK = """
import sys
class _Blocked:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"{name} is not installed here", name=name)
        return None
sys.meta_path.insert(0, _Blocked())
sys.path.insert(0, REPO)
"""


def _run(blocked: tuple[str, ...], body: str, tmp_path: Path) -> str:
    script = f"BLOCKED = {blocked!r}\nREPO = {str(REPO)!r}\n" + BLOCK + textwrap.dedent(body)
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def _extras() -> dict[str, list[str]]:
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    return {"core": project["dependencies"], **project["optional-dependencies"]}


def _names(requirements: list[str]) -> set[str]:
    return {r.split("[")[0].split("=")[0].split(">")[0].strip().lower().replace("-", "_") for r in requirements}


def test_the_dependency_groups_keep_the_two_sides_apart() -> None:
    extras = _extras()
    core, agent, server = _names(extras["core"]), _names(extras["agent"]), _names(extras["server"])
    assert not (core | agent) & {"fastapi", "uvicorn", "sqlalchemy", "alembic", "psycopg", "viser", "pydantic_settings"}
    assert "pydantic" in core  # the agent's pipeline settings
    assert not (core | server) & {"numba", "llvmlite", "filterpy"}
    assert "filterpy" in _names(extras["test"]) and "filterpy" not in core | agent | server


def test_the_agent_runs_without_the_server_packages(tmp_path: Path) -> None:
    out = _run(SERVER_ONLY + NEVER, """
        from kinect_agent import cli
        assert cli.main(["simulate", "--exercise", "squat", "--reps", "2", "-o", "m.csv"]) == 0
        assert cli.main(["filter", "m.csv", "-o", "f.csv"]) == 0
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
        print("loaded:", loaded)
    """, tmp_path)  # fmt: skip
    assert "loaded: []" in out
    assert (tmp_path / "f.csv").exists()


def test_the_session_analysis_runs_without_the_server(tmp_path: Path) -> None:
    """Every module of kinect_agent.analysis (the one home of the metrics) imports and computes with the server's
    packages and `backend` itself blocked: the agent deployable ships only kinect_agent."""
    out = _run(SERVER_ONLY + NEVER + ("backend",), """
        import importlib, pkgutil
        import kinect_agent.analysis as home
        names = sorted(m.name for m in pkgutil.iter_modules(home.__path__))
        for name in names:
            importlib.import_module("kinect_agent.analysis." + name)
        from kinect_agent.analysis import quality
        from kinect_agent.sources.simulator import simulate_truth
        assert quality.assess(simulate_truth("squat", 2, seed=1), None)["reasons"] == []
        print("modules:", len(names))
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED)
        print("loaded:", loaded)
    """, tmp_path)  # fmt: skip
    assert "loaded: []" in out
    assert "modules: 22" in out  # exercise, report and indicators among them (moved from the server); anatomy


def test_the_server_ingests_analyses_and_replays_without_numba(tmp_path: Path) -> None:
    out = _run(AGENT_ONLY + NEVER, """
        import os
        url = "sqlite:///" + os.path.abspath("lean.db")
        os.environ["COACH_DATABASE_URL"] = url  # the app's get_db reads the configured database
        from fastapi.testclient import TestClient
        from sqlalchemy.orm import Session
        from backend.config import Settings
        from backend.database import make_engine, import_all_models
        from backend.devices.models import Device
        from backend.exercises.service import sync_exercise_library
        from backend.jobs.worker import work
        from backend.main import create_app
        from backend.migrate import upgrade
        from backend.security import DEVICE_TOKEN_PREFIX, new_token, token_hash
        from backend.users.service import create_api_token, create_user
        from tests.backend.khs_files import make_khs

        import_all_models()
        engine = make_engine(url)
        with engine.begin() as conn:
            upgrade(conn, "head")
        token = new_token(DEVICE_TOKEN_PREFIX)
        with Session(engine) as s, s.begin():
            sync_exercise_library(db_session=s)
            patient = create_user(db_session=s, email="lean@example.org", password=None, role="patient")
            s.add(Device(patient_id=patient.id, name="lean", token_hash=token_hash(token)))
            admin = create_user(db_session=s, email="admin@example.org", password=None, role="admin")
            _, admin_token = create_api_token(db_session=s, user=admin, name="lean", scopes=["read"], days=1)
        app = create_app(Settings(ENVIRONMENT="local", DATABASE_URL=url), engine)
        headers = {"Authorization": f"Bearer {token}"}
        with TestClient(app) as client:
            r = client.post("/api/v1/sessions", content=make_khs("squat", 3, seed=2),
                            headers={**headers, "Content-Type": "application/octet-stream"})
            assert r.status_code == 201 and r.json()["status"] == "processed", r.text
            sid, admin = r.json()["id"], {"Authorization": f"Bearer {admin_token}"}
            detail = client.get(f"/api/v1/sessions/{sid}/detail", headers=admin)  # a worker builds it
            assert detail.status_code == 202, detail.text[:500]
            queued = client.get(f"/api/v1/sessions/{sid}/replay", headers=admin)  # and the scene
            assert queued.status_code == 202, queued.text[:500]
            settings = Settings(ENVIRONMENT="local", DATABASE_URL=url)
            assert work(sessionmaker=lambda: Session(engine), settings=settings, name="lean", once=True) == 2
            detail = client.get(f"/api/v1/sessions/{sid}/detail", headers=admin)  # angles, repetitions, reach
            assert detail.status_code == 200 and detail.json()["repetitions"], detail.text[:500]
            replay = client.get(f"/api/v1/sessions/{sid}/replay", headers=admin)  # the viser scene
            assert replay.status_code == 200 and len(replay.content) > 1000, replay.text[:500]
            charts = client.get("/static/vendor/plotly/plotly.min.js")  # the pages' charting library
            assert charts.status_code == 200 and b"plotly.js (cartesian" in charts.content[:200], charts.text[:500]
        print("loaded:", sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED))
        from kinect_agent.body import _fk_numba
        from kinect_agent.processing import _ukf_numba
        print("compiled paths:", _fk_numba.AVAILABLE, _ukf_numba.AVAILABLE)
    """, tmp_path)  # fmt: skip
    assert "loaded: []" in out and "compiled paths: False False" in out
