"""The import layers of docs/architecture.md hold: every module sits in one layer and imports only what its layer
may import (imports inside functions count too), and no package inside a layer imports one its second table forbids
(e.g. backend.sessions never imports backend.suggestions). Both tables are read from the document, so the drawing
and the rules cannot drift apart."""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("kinect_agent", "backend", "frontend", "migrations")
ROOTS_EXACT = {"kinect_agent"}  # the agent's package itself: only its own __init__, not everything under it
DOC = ROOT / "docs" / "architecture.md"


@dataclass(frozen=True)
class Import:
    """One import of a project module: who imports what, where."""

    importer: str
    imported: str
    path: Path
    line: int


def read_layers(doc: Path = DOC) -> tuple[dict[str, str], dict[str, set[str]]]:
    """Returns the table of doc: module entry -> layer, and layer -> the layers it may import (itself included)."""
    entries: dict[str, str] = {}
    allowed: dict[str, set[str]] = {}
    rows = re.findall(r"^\| ([A-Za-z][A-Za-z ]*) \| (.+?) \| (.*?) ?\|$", doc.read_text(encoding="utf-8"), re.M)
    for layer, modules, may_import in rows:
        if layer == "layer":
            continue
        for entry in re.findall(r"`([\w.]+)`", modules):
            assert entry not in entries, f"{doc.name}: {entry} is in two layers"
            entries[entry] = layer
        allowed[layer] = {layer} | {name.strip() for name in may_import.split(",") if name.strip()}
    return entries, allowed


def read_forbidden(doc: Path = DOC) -> dict[str, set[str]]:
    """Returns the package pairs of doc's second table: package -> the packages it may not import."""
    rows = re.findall(r"^\| `([\w.]+)` \| (`.+?) ?\|$", doc.read_text(encoding="utf-8"), re.M)
    return {package: set(re.findall(r"`([\w.]+)`", forbidden)) for package, forbidden in rows}


def project_modules() -> dict[str, Path]:
    """Returns every module of the project's packages by dotted name (a package by its own name)."""
    modules = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            modules[name] = path
    return modules


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> list[Import]:
    """Returns the imports of project modules in one file (`from a import b` names a.b when b is a module)."""
    found = []
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(parent + ([node.module] if node.module else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
        else:
            continue
        for target in targets:
            if target.split(".")[0] in PACKAGES:
                found.append(Import(name, target, path, node.lineno))
    return found


def layer_of(module: str, entries: dict[str, str]) -> str | None:
    """Returns the layer of a module: its longest matching entry (a package entry matches its submodules too)."""
    if module in entries:
        return entries[module]
    parts = module.split(".")
    for n in range(len(parts) - 1, 0, -1):
        prefix = ".".join(parts[:n])
        if prefix in entries and prefix not in ROOTS_EXACT:
            return entries[prefix]
    return None


def violations(entries: dict[str, str], allowed: dict[str, set[str]]) -> list[str]:
    """Returns one line per import against the layers: file:line, importer -> imported, and the two layers."""
    modules = project_modules()
    lines: list[str] = []
    for name, path in modules.items():
        for imp in imports_of(name, path, modules):
            source, target = layer_of(imp.importer, entries), layer_of(imp.imported, entries)
            if source is not None and target is not None and target not in allowed[source]:
                where = f"{imp.path.relative_to(ROOT)}:{imp.line}"
                line = f"{where}: {imp.importer} -> {imp.imported} ({source} may not import {target})"
                lines += [] if line in lines else [line]
    return lines


def _within(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def pair_violations(forbidden: dict[str, set[str]]) -> list[str]:
    """Returns one line per import of a package its row forbids: file:line, importer -> imported."""
    modules = project_modules()
    lines: list[str] = []
    for name, path in modules.items():
        for imp in imports_of(name, path, modules):
            for package, others in forbidden.items():
                for other in others:
                    if _within(imp.importer, package) and _within(imp.imported, other):
                        where = f"{imp.path.relative_to(ROOT)}:{imp.line}"
                        lines.append(f"{where}: {imp.importer} -> {imp.imported} ({package} may not import {other})")
    return lines


def test_the_table_names_only_known_layers():
    entries, allowed = read_layers()
    assert len(allowed) >= 10, f"{DOC.name}: the layer table was not found ({sorted(allowed)})"
    unknown = {name for names in allowed.values() for name in names} - set(allowed)
    assert not unknown, f"{DOC.name} names layers without a row: {sorted(unknown)}"


def test_every_module_has_a_layer():
    entries, _ = read_layers()
    homeless = [name for name in project_modules() if layer_of(name, entries) is None]
    assert not homeless, f"modules in no layer of {DOC.name} (add them to its table): {homeless}"


def test_no_import_runs_against_the_layers():
    entries, allowed = read_layers()
    found = violations(entries, allowed)
    assert not found, "imports against docs/architecture.md:\n" + "\n".join(found)


@pytest.mark.parametrize(
    ("row", "module", "bad_import"),
    [
        ("formats", "kinect_agent/formats/x.py", "from kinect_agent.processing.pipeline import process"),
        ("server", "backend/x.py", "from frontend.pages import mount"),
        ("server", "backend/x.py", "import kinect_agent.commands.run"),
        ("demo", "backend/demo_agents.py", "from kinect_agent.commands import pair"),
        ("processing", "kinect_agent/processing/x.py", "from ..sources import simulator"),
        ("analysis", "kinect_agent/analysis/x.py", "from backend.exercises.library import LIBRARY"),
    ],
)
def test_a_bad_import_is_caught(tmp_path, monkeypatch, row, module, bad_import):
    """The check itself: a planted import against the layers (absolute or relative) is reported."""
    monkeypatch.setattr(
        f"{__name__}.ROOT", tmp_path
    )  # a copy of the tree's layout, with one file holding the bad import
    for package in PACKAGES:
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("")
    for name in ("processing", "sources", "formats", "commands", "analysis"):
        (tmp_path / "kinect_agent" / name).mkdir()
        (tmp_path / "kinect_agent" / name / "__init__.py").write_text("")
    (tmp_path / module).write_text(bad_import + "\n")
    entries, allowed = read_layers()
    found = violations(entries, allowed)
    assert len(found) == 1 and f"({row} may not import" in found[0], found


def agent_imports_of_the_server() -> list[str]:
    """Returns one line per import of backend, frontend or migrations by a module of kinect_agent: file:line."""
    modules = project_modules()
    return [
        f"{imp.path.relative_to(ROOT)}:{imp.line}: {imp.importer} -> {imp.imported}"
        for name, path in modules.items()
        if _within(name, "kinect_agent")
        for imp in imports_of(name, path, modules)
        if not _within(imp.imported, "kinect_agent")
    ]


def test_the_agent_never_imports_the_server():
    """Whatever the table says: the agent (its analysis above all, the one home of a session's analysis) ships alone,
    so none of its modules imports the server or the pages."""
    found = agent_imports_of_the_server()
    assert not found, "the agent imports the server:\n" + "\n".join(found)


def test_the_package_pairs_name_real_packages():
    forbidden = read_forbidden()
    assert forbidden.get("backend.sessions", set()) >= {"backend.suggestions", "backend.session_review"}, forbidden
    modules = project_modules()
    unknown = {p for package, others in forbidden.items() for p in {package, *others} if p not in modules}
    assert not unknown, f"{DOC.name}: the package pairs name no module of the tree: {sorted(unknown)}"


def test_no_package_imports_one_its_row_forbids():
    found = pair_violations(read_forbidden())
    assert not found, "imports against the package pairs of docs/architecture.md:\n" + "\n".join(found)


@pytest.mark.parametrize(
    ("module", "an_import", "caught"),
    [
        ("backend/sessions/service.py", "from backend.suggestions.service import suggest_for_session", True),
        ("backend/sessions/router.py", "from ..suggestions import service", True),
        ("backend/sessions/schemas.py", "import backend.session_review.schemas", True),
        ("backend/suggestions/service.py", "from backend.session_review import dashboard", True),
        ("backend/suggestions/service.py", "from backend.sessions.models import ExerciseSession", False),
        ("backend/session_review/service.py", "from backend.suggestions.service import suggest_for_session", False),
    ],
)
def test_a_forbidden_package_import_is_caught(tmp_path, monkeypatch, module, an_import, caught):
    """The check itself: an import a package pair forbids is reported (absolute or relative); one along the data
    flow (suggestions reading sessions, the review service above both) is not."""
    monkeypatch.setattr(f"{__name__}.ROOT", tmp_path)
    for package in (*PACKAGES, "backend/sessions", "backend/suggestions", "backend/session_review"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / module).write_text(an_import + "\n")
    found = pair_violations(read_forbidden())
    assert len(found) == int(caught), found
    assert not caught or f"{module}:1:" in found[0], found


def router_violations() -> list[str]:
    """Returns one line per import of a routes module (a module named `router`) by another module: file:line,
    importer -> imported. backend.main mounts the routers by name (importlib), so no import is needed."""
    modules = project_modules()
    lines: list[str] = []
    for name, path in modules.items():
        for imp in imports_of(name, path, modules):
            if imp.imported.rpartition(".")[2] == "router" and imp.imported in modules and imp.importer != imp.imported:
                line = f"{imp.path.relative_to(ROOT)}:{imp.line}: {imp.importer} -> {imp.imported}"
                lines += [] if line in lines else [line]
    return lines


def test_no_module_imports_a_router():
    found = router_violations()
    assert not found, "routes modules imported (docs/architecture.md, 'Package pairs inside the server'):\n" + (
        "\n".join(found)
    )


@pytest.mark.parametrize(
    ("module", "an_import", "caught"),
    [
        ("backend/session_review/router.py", "from backend.sessions.router import audit", True),
        ("backend/live/router.py", "from ..events.router import RETRY_MS", True),
        ("backend/live/service.py", "import backend.events.router", True),
        ("backend/live/router.py", "from backend.events.hub import RETRY_MS", False),
    ],
)
def test_an_import_of_a_router_is_caught(tmp_path, monkeypatch, module, an_import, caught):
    monkeypatch.setattr(f"{__name__}.ROOT", tmp_path)
    for package in (*PACKAGES, "backend/sessions", "backend/session_review", "backend/live", "backend/events"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("")
    for routes in ("backend/sessions/router.py", "backend/events/router.py", "backend/events/hub.py"):
        (tmp_path / routes).write_text("")
    (tmp_path / module).write_text(an_import + "\n")
    found = router_violations()
    assert len(found) == int(caught), found
    assert not caught or f"{module}:1:" in found[0], found


def test_the_pages_register_on_the_server_without_an_import():
    """backend.main mounts the pages through the entry-point group, so the server app serves them."""
    from backend.main import registered_mounts
    from frontend.pages import mount

    assert mount in registered_mounts(), "frontend.pages:mount is not installed in kinect_home_coach.server_mounts"
