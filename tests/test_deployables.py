"""The two deployables of docs/deployment.md, as a home computer and a clinic get them: each distribution's wheel built
from this repository (packages/agent, packages/server), installed into a fresh environment of its own from its lock
file (requirements/agent.lock, requirements/server.lock), its commands run there, and a selection of its tests run
there too, with that environment's Python, from a copy of tests/ beside no source of the repository (the tools from
requirements/agent-tests.lock, requirements/server-tests.lock). The agent's environment holds nothing of the server
(no backend, pages or migrations, no web or database package); the server's holds none of the agent's services or CLI,
and every module of the agent's package that the server imports. A side's code that imports what its distribution
does not ship fails its tests there.

The two environments are made once for this module (a fixture), side by side. uv (pinned in the `test` extra, as in
scripts/lock.sh) makes them: offline from its cache when the cache has every file, from the package index otherwise
(the first run on a machine)."""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import SHARED
from tests.test_layers import imports_of, project_modules

pytestmark = pytest.mark.own_database  # each install migrates a SQLite file of its own
REPO = Path(__file__).resolve().parents[1]
SOURCES = ("kinect_agent", "backend", "frontend", "migrations", "packages")
# distributions only the server installs (requirements/server.lock), by their normalised names
SERVER_ONLY = {"fastapi", "starlette", "uvicorn", "sqlalchemy", "alembic", "psycopg", "psycopg-binary", "argon2-cffi",
               "python-multipart", "jinja2", "viser", "babel", "boto3", "botocore", "reportlab", "pydantic-settings",
               "fastapi-offline"}  # fmt: skip
AGENT_ONLY = {"numba", "llvmlite"}  # (tqdm comes with viser too)
# the agent's services, its CLI and the accuracy study: kinect_agent's modules the server's wheel must not hold
AGENT_SIDE = ("cli", "commands", "config", "capture", "home", "live", "pairing", "queue", "upload", "evaluation")
SIDES = ("agent", "server")
# the capture sources the server never imports (the device adapters above all): its wheel must not hold them, the
# agent's must (issue 26); any other kinect_agent.sources module the server does not import fails the same check
SERVER_NEVER_SHIPS = ("kinect_agent/sources/kinect_v2.py", "kinect_agent/sources/azure_kinect.py",
                      "kinect_agent/sources/webcam/source.py", "kinect_agent/sources/replay.py",
                      "kinect_agent/sources/body_choice.py", "kinect_agent/sources/mocap_truth.py")  # fmt: skip
# Each side's tests that run in its own environment: those that import nothing of the other side, chosen to reach each
# layer of the side's code for little time (the time it takes: README, "Installing each side").
# tests/installed_alone.py checks that the run imports the installed distribution and cannot import the other side.
SIDE_TESTS = {
    "agent": (
        "tests/installed_alone.py::test_the_agent_alone",
        "tests/kinect_agent/test_skeleton.py",  # the body model and the recording contract
        "tests/kinect_agent/test_recording.py",
        "tests/kinect_agent/body",  # geometry: rotations, forward kinematics, angles
        "tests/kinect_agent/formats/test_skeleton_csv.py",  # the interchange format
        "tests/kinect_agent/formats/test_kinect_v2_tsv.py",  # a Kinect export
        "tests/kinect_agent/sources/test_simulator.py",  # the simulated camera the demo and the tests record with
        "tests/kinect_agent/sources/test_commands.py",  # `simulate`, `capture`
        "tests/kinect_agent/sources/test_device_adapters.py",
        "tests/kinect_agent/processing/test_filter_command.py",  # the filter: numba's kernels, `filter`
        "tests/kinect_agent/processing/test_outliers_numba.py",
        "tests/kinect_agent/live/test_journal.py",  # a live set's frames on disk
        "tests/kinect_agent/test_queue.py",  # the disk queue, then the upload command's held sessions
        "tests/kinect_agent/test_held_sessions.py",
        "tests/kinect_agent/analysis/test_quality.py",  # the session metrics' one home ships with the agent
        "tests/kinect_agent/analysis/test_range_of_motion.py",
        "tests/kinect_agent/analysis/test_indicators.py",  # the document and its indicators, from the exercise spec
    ),
    "server": (
        "tests/installed_alone.py::test_the_server_alone",
        "tests/backend/test_access_matrix.py",  # every route of the API and the pages against every kind of caller
        "tests/backend/test_devices.py",  # pairing a home computer
        "tests/backend/test_sessions_upload.py",  # an agent's upload: stored, analysed by the pure core, refused
        # but the files of the one below are made by the agent's capture (the two sides together), and the 25 hostile
        # files of the other take a third of the time: both in the suite's own runs only
        "--deselect=tests/backend/test_sessions_upload.py::test_a_simulated_uiprmd_set_filtered_by_the_agent",
        "--deselect=tests/backend/test_sessions_upload.py::test_bad_file_is_400_and_stores_nothing",
    ),
}


def _uv() -> str:
    """Returns the uv executable of the test environment."""
    try:
        import uv  # type: ignore[import-not-found,unused-ignore]

        return str(uv.find_uv_bin())
    except ImportError:
        found = shutil.which("uv")
        assert found, "uv is not installed: it is in the test extra (requirements/test.lock)"
        return found


def _env(venv: Path | None = None) -> dict[str, str]:
    """Returns this process's environment without its Python paths, with venv's bin first on PATH."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    if venv is not None:
        env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
        env["VIRTUAL_ENV"] = str(venv)
    return env


def _run(command: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """Runs command; fails the test with its output when it fails."""
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, (
        f"{' '.join(command)} exited {done.returncode}:\n{done.stdout[-2000:]}{done.stderr[-3000:]}"
    )
    return done


def _uv_run(args: list[str], cwd: Path) -> None:
    """Runs uv offline (its cache), and again online when the cache misses a file."""
    offline = subprocess.run([_uv(), *args, "--offline"], cwd=cwd, env=_env(), capture_output=True, text=True)
    if offline.returncode != 0:
        _run([_uv(), *args], cwd, _env())


def _source_copy(tmp: Path) -> Path:
    """Returns a copy of the sources as a fresh clone has them (no fetched browser assets, no caches)."""
    src = tmp / "src"
    skip = shutil.ignore_patterns("__pycache__", "*.pyc", "build", "*.egg-info")
    for name in SOURCES:
        shutil.copytree(REPO / name, src / name, ignore=skip, symlinks=True)
    vendored = src / "kinect_agent" / "vendor" / "files"
    if vendored.is_symlink() or vendored.is_file():
        vendored.unlink()
    else:
        shutil.rmtree(vendored, ignore_errors=True)
    return src


def _install(side: str, wheel: Path, tmp: Path) -> Path:
    """Returns a fresh environment holding side's lock file, its tests' tools and then its wheel (without
    dependencies)."""
    venv = tmp / side
    _run([_uv(), "venv", "--quiet", "--python", sys.executable, str(venv)], tmp, _env())
    python = str(venv / "bin" / "python")
    locks = [str(REPO / "requirements" / f"{side}.lock"), str(REPO / "requirements" / f"{side}-tests.lock")]
    _uv_run(["pip", "install", "--quiet", "--python", python, "--require-hashes", "-r", locks[0], "-r", locks[1]], tmp)
    _run([_uv(), "pip", "install", "--quiet", "--python", python, "--no-deps", str(wheel)], tmp, _env())
    return venv


def _distributions(venv: Path) -> set[str]:
    """Returns the normalised names of the distributions installed in venv."""
    listed = _run([_uv(), "pip", "list", "--python", str(venv / "bin" / "python"), "--format", "json"], venv, _env())
    return {d["name"].lower().replace("_", "-") for d in json.loads(listed.stdout)}


def _site_packages(venv: Path) -> Path:
    """Returns venv's site-packages folder."""
    (found,) = (venv / "lib").glob("python3*/site-packages")
    return found


def _modules_the_server_imports() -> set[str]:
    """Returns kinect_agent's modules that backend, frontend and migrations import, directly or through others (the
    demo's simulated agents, backend.demo_agents, aside: they need the agent installed too)."""
    modules = project_modules()

    def module_of(target: str) -> str:
        while target not in modules and "." in target:
            target = target.rpartition(".")[0]
        return target

    seen: set[str] = set()
    todo = [
        m for m in modules if m.split(".")[0] in ("backend", "frontend", "migrations") and m != "backend.demo_agents"
    ]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo += [module_of(i.imported) for i in imports_of(name, modules[name], modules)]
    return {m for m in seen if m.split(".")[0] == "kinect_agent"}


def _files_of(module: str) -> set[str]:
    """Returns the wheel paths one module can have: a module's file, or a package's __init__."""
    path = module.replace(".", "/")
    return {f"{path}.py", f"{path}/__init__.py"}


def _agent_side(path: str) -> bool:
    """Tells whether a wheel path under kinect_agent/ is one of the agent's services, its CLI or its accuracy study."""
    part = path.split("/")[1]
    return part.removesuffix(".py") in AGENT_SIDE


def _names(requirements: list[str]) -> dict[str, str]:
    return {r.split("==")[0].split("[")[0].strip().lower(): r for r in requirements}


def test_the_deployables_pin_what_the_development_install_pins() -> None:
    root = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    for side in SIDES:
        pyproject = tomllib.loads((REPO / "packages" / side / "pyproject.toml").read_text())
        project = pyproject["project"]
        expected = _names(root["dependencies"] + root["optional-dependencies"][side])
        assert _names(project["dependencies"]) == expected, f"packages/{side}/pyproject.toml and the root's differ"
        for extra, requirements in project.get("optional-dependencies", {}).items():
            assert _names(requirements) == _names(root["optional-dependencies"][extra]), f"{side}'s extra {extra}"
        tools = _names(pyproject["dependency-groups"]["tests"])
        test_extra = _names(root["optional-dependencies"]["test"])
        assert tools.items() <= test_extra.items(), f"packages/{side}'s tests group pins what the test extra does not"


@dataclass(frozen=True)
class Deployable:
    """One side's wheel, and the fresh environment that holds it (and its tests' tools)."""

    side: str
    wheel: Path
    venv: Path


@pytest.fixture(scope="module")
def deployables(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Deployable]:
    """Builds both wheels from a copy of the sources and installs each into an environment of its own, side by side."""
    tmp = tmp_path_factory.mktemp("deployables")
    src = _source_copy(tmp)
    dist = tmp / "dist"
    for side in SIDES:
        _uv_run(["build", "--quiet", "--wheel", "-o", str(dist), str(src / "packages" / side)], src)
    wheels = {side: next(iter(dist.glob(f"kinect_home_coach_{side}-*.whl"))) for side in SIDES}
    with ThreadPoolExecutor(max_workers=2) as pool:
        venvs = dict(zip(SIDES, pool.map(lambda side: _install(side, wheels[side], tmp), SIDES), strict=True))
    return {side: Deployable(side, wheels[side], venvs[side]) for side in SIDES}


def _capture_sources_in(wheel_files: set[str]) -> list[str]:
    """Returns the kinect_agent.sources modules in a wheel's files that the server does not import (a package's
    __init__ counts as imported with any module of it)."""
    modules = _modules_the_server_imports()
    packages = {m.rsplit(".", i)[0] for m in modules for i in range(1, m.count(".") + 1)}
    imported = set().union(*(_files_of(m) for m in modules | packages))
    return sorted(f for f in wheel_files if f.startswith("kinect_agent/sources/") and f.endswith(".py")
                  and f not in imported)  # fmt: skip


def test_the_servers_wheel_holds_no_capture_source(tmp_path: Path) -> None:
    """Builds the server's wheel alone (no install: seconds) and reads its file list."""
    src = _source_copy(tmp_path)
    _uv_run(["build", "--quiet", "--wheel", "-o", str(tmp_path / "dist"), str(src / "packages" / "server")], src)
    (wheel,) = (tmp_path / "dist").glob("kinect_home_coach_server-*.whl")
    files = set(zipfile.ZipFile(wheel).namelist())
    assert _capture_sources_in(files) == [], "the server's wheel holds capture sources it never imports"
    assert not files & set(SERVER_NEVER_SHIPS)
    assert {"kinect_agent/sources/simulator.py", "kinect_agent/sources/webcam/landmarks.py",
            "kinect_agent/sources/calibration/joint_offset_standing_mm.csv"} <= files  # fmt: skip


def test_each_wheel_ships_its_own_side(deployables: dict[str, Deployable]) -> None:
    server_files = set(zipfile.ZipFile(deployables["server"].wheel).namelist())
    missing = sorted(m for m in _modules_the_server_imports() if not _files_of(m) & server_files)
    assert not missing, f"the server imports modules its wheel lacks: {missing}"
    agent_side = sorted(f for f in server_files if f.split("/")[0] == "kinect_agent" and _agent_side(f))
    assert not agent_side, f"the server's wheel holds the agent's own modules: {agent_side[:5]}"
    assert _capture_sources_in(server_files) == [], "the server's wheel holds capture sources it never imports"
    agent_files = set(zipfile.ZipFile(deployables["agent"].wheel).namelist())
    assert set(SERVER_NEVER_SHIPS) <= agent_files, "the agent's wheel lacks a capture source"
    agent_tops = {f.split("/")[0] for f in zipfile.ZipFile(deployables["agent"].wheel).namelist()} - {"kinect_agent"}
    assert [top.endswith(".dist-info") for top in agent_tops] == [True], f"the agent's wheel holds {agent_tops}"


def test_each_side_runs_its_commands_then_its_tests_in_its_own_environment(
    deployables: dict[str, Deployable], tmp_path: Path
) -> None:
    """The two sides side by side, each mostly on one core (the agent's first filter compiles numba's kernels into
    the environment's cache, which its tests then use; the server's tests migrate and hash passwords)."""
    with ThreadPoolExecutor(max_workers=2) as pool:
        running = {side: pool.submit(_check_side, deployables[side], tmp_path / side) for side in SIDES}
    failed = {}
    for side, outcome in running.items():
        try:
            outcome.result()
        except AssertionError as exc:
            failed[side] = str(exc)
    assert not failed, "\n\n".join(f"the {side}: {why}" for side, why in failed.items())


def _check_side(deployable: Deployable, tmp: Path) -> None:
    """Runs a side's commands, then its tests, in its environment."""
    work = tmp / "work"
    work.mkdir(parents=True)
    (_check_agent if deployable.side == "agent" else _check_server)(deployable.venv, work)
    _run_side_tests(deployable, tmp / "tests-only")


def _check_agent(agent: Path, work: Path) -> None:
    """Checks the agent's environment holds nothing of the server, and runs its commands: simulate a set, filter it."""
    installed = _distributions(agent)
    assert not installed & SERVER_ONLY, f"the agent's install has server packages: {sorted(installed & SERVER_ONLY)}"
    assert AGENT_ONLY <= installed
    site = _site_packages(agent)
    assert not [n for n in ("backend", "frontend", "migrations") if (site / n).exists()]
    assert not (agent / "bin" / "coach-server").exists()
    env = _env(agent)
    assert "simulate" in _run(["kinect-agent", "--help"], work, env).stdout
    _run(["kinect-agent", "simulate", "--exercise", "squat", "--reps", "2", "-o", "m.csv"], work, env)
    _run(["kinect-agent", "filter", "m.csv", "-o", "f.csv"], work, env)
    assert (work / "f.csv").stat().st_size > 1000


def _check_server(server: Path, work: Path) -> None:
    """Checks the server's environment holds nothing of the agent's own, and runs its commands: migrate a SQLite file
    to head; the demo asks for the agent."""
    installed = _distributions(server)
    assert not installed & AGENT_ONLY, f"the server's install has agent packages: {sorted(installed & AGENT_ONLY)}"
    assert SERVER_ONLY <= installed
    assert not (server / "bin" / "kinect-agent").exists()
    env = {**_env(server), "COACH_DATABASE_URL": f"sqlite:///{work / 'server.db'}", "COACH_ENVIRONMENT": "local"}
    assert "migrate" in _run(["coach-server", "--help"], work, env).stdout
    _run(["coach-server", "migrate"], work, env)
    with sqlite3.connect(work / "server.db") as db:
        assert db.execute("SELECT version_num FROM alembic_version").fetchall(), "migrate left no revision"
    demo = subprocess.run(["coach-server", "demo", "--port", "1"], cwd=work, env=env, capture_output=True, text=True)
    assert demo.returncode == 2 and "the agent" in demo.stderr, demo.stderr[-2000:]


def _run_side_tests(deployable: Deployable, root: Path) -> None:
    """Runs SIDE_TESTS[side] with the environment's Python from a copy of tests/ (and the root's pytest settings) in
    root, a folder without the repository's sources, on SQLite and the local object store: every one passes, none
    skips."""
    shutil.copytree(REPO / "tests", root / "tests", ignore=shutil.ignore_patterns("__pycache__", ".hypothesis"))
    shutil.copy(REPO / "pyproject.toml", root)
    env = {k: v for k, v in _env(deployable.venv).items() if not k.startswith("COACH_TEST_")}
    env["COACH_SHARED_DIR"] = str(SHARED)
    report = root / "report.xml"
    python = str(deployable.venv / "bin" / "python")
    _run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--basetemp", str(root / "tmp"), "--junit-xml",
          str(report), *SIDE_TESTS[deployable.side]], root, env)  # fmt: skip
    cases = {
        f"{case.get('classname')}.{case.get('name')}": [child.tag for child in case]
        for case in ET.parse(report).iter("testcase")
    }
    assert f"tests.installed_alone.test_the_{deployable.side}_alone" in cases, sorted(cases)[:5]
    not_passed = {name: tags for name, tags in cases.items() if set(tags) - {"system-out", "system-err"}}
    assert not not_passed, f"{len(not_passed)} of {len(cases)} did not pass: {sorted(not_passed.items())[:5]}"
