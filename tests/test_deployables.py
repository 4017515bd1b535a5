"""The two deployables of docs/deployment.md, as a home computer and a clinic get them: each distribution's wheel built
from this repository (packages/agent, packages/server), installed into a fresh environment of its own from its lock
file (requirements/agent.lock, requirements/server.lock), and its commands run there. The agent's environment holds
nothing of the server (no backend, pages or migrations, no web or database package); the server's holds none of the
agent's services or CLI, and every module of the agent's package that the server imports.

uv (pinned in the `test` extra, as in scripts/lock.sh) makes the environments: offline from its cache when the cache
has every file, from the package index otherwise (the first run on a machine)."""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tomllib
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

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
    """Returns a fresh environment holding side's lock file and then its wheel (without dependencies)."""
    venv = tmp / side
    _run([_uv(), "venv", "--quiet", "--python", sys.executable, str(venv)], tmp, _env())
    python = str(venv / "bin" / "python")
    _uv_run(["pip", "install", "--quiet", "--python", python, "--require-hashes", "-r",
             str(REPO / "requirements" / f"{side}.lock")], tmp)  # fmt: skip
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
    for side in ("agent", "server"):
        project = tomllib.loads((REPO / "packages" / side / "pyproject.toml").read_text())["project"]
        expected = _names(root["dependencies"] + root["optional-dependencies"][side])
        assert _names(project["dependencies"]) == expected, f"packages/{side}/pyproject.toml and the root's differ"
        for extra, requirements in project.get("optional-dependencies", {}).items():
            assert _names(requirements) == _names(root["optional-dependencies"][extra]), f"{side}'s extra {extra}"


def test_each_side_installs_alone_from_its_lock_and_runs_its_commands(tmp_path: Path) -> None:
    src = _source_copy(tmp_path)
    dist = tmp_path / "dist"
    for side in ("agent", "server"):
        _uv_run(["build", "--quiet", "--wheel", "-o", str(dist), str(src / "packages" / side)], src)
    (agent_wheel,) = dist.glob("kinect_home_coach_agent-*.whl")
    (server_wheel,) = dist.glob("kinect_home_coach_server-*.whl")

    server_files = set(zipfile.ZipFile(server_wheel).namelist())
    missing = sorted(m for m in _modules_the_server_imports() if not _files_of(m) & server_files)
    assert not missing, f"the server imports modules its wheel lacks: {missing}"
    agent_side = sorted(f for f in server_files if f.split("/")[0] == "kinect_agent" and _agent_side(f))
    assert not agent_side, f"the server's wheel holds the agent's own modules: {agent_side[:5]}"
    agent_tops = {f.split("/")[0] for f in zipfile.ZipFile(agent_wheel).namelist()} - {"kinect_agent"}
    assert [top.endswith(".dist-info") for top in agent_tops] == [True], f"the agent's wheel holds {agent_tops}"

    # the two sides side by side: the agent's first filter compiles numba's kernels on one core for most of a minute
    with ThreadPoolExecutor(max_workers=2) as pool:
        done = [pool.submit(_check_agent, agent_wheel, tmp_path), pool.submit(_check_server, server_wheel, tmp_path)]
        for side in done:
            side.result()


def _check_agent(wheel: Path, tmp: Path) -> None:
    """Installs the agent alone and runs its commands: simulate a short set, filter it."""
    agent = _install("agent", wheel, tmp)
    installed = _distributions(agent)
    assert not installed & SERVER_ONLY, f"the agent's install has server packages: {sorted(installed & SERVER_ONLY)}"
    assert AGENT_ONLY <= installed
    site = _site_packages(agent)
    assert not [n for n in ("backend", "frontend", "migrations") if (site / n).exists()]
    assert not (agent / "bin" / "coach-server").exists()
    work, env = tmp / "agent-work", _env(agent)
    work.mkdir()
    assert "simulate" in _run(["kinect-agent", "--help"], work, env).stdout
    _run(["kinect-agent", "simulate", "--exercise", "squat", "--reps", "2", "-o", "m.csv"], work, env)
    _run(["kinect-agent", "filter", "m.csv", "-o", "f.csv"], work, env)
    assert (work / "f.csv").stat().st_size > 1000


def _check_server(wheel: Path, tmp: Path) -> None:
    """Installs the server alone and runs its commands: migrate a SQLite file to head; the demo asks for the agent."""
    server = _install("server", wheel, tmp)
    installed = _distributions(server)
    assert not installed & AGENT_ONLY, f"the server's install has agent packages: {sorted(installed & AGENT_ONLY)}"
    assert SERVER_ONLY <= installed
    assert not (server / "bin" / "kinect-agent").exists()
    work = tmp / "server-work"
    work.mkdir()
    env = {**_env(server), "COACH_DATABASE_URL": f"sqlite:///{work / 'server.db'}", "COACH_ENVIRONMENT": "local"}
    assert "migrate" in _run(["coach-server", "--help"], work, env).stdout
    _run(["coach-server", "migrate"], work, env)
    with sqlite3.connect(work / "server.db") as db:
        assert db.execute("SELECT version_num FROM alembic_version").fetchall(), "migrate left no revision"
    demo = subprocess.run(["coach-server", "demo", "--port", "1"], cwd=work, env=env, capture_output=True, text=True)
    assert demo.returncode == 2 and "the agent" in demo.stderr, demo.stderr[-2000:]
