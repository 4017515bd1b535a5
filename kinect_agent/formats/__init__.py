"""Recording file formats: one module per format, found by name or detected from the file.

Every format module defines:
    NAME: str                         the name given to --format
    DESCRIPTION: str                  one line for --help
    def sniff(path: Path, head: bytes) -> bool      True when the file looks like this format (head: its first
                                                    bytes as UTF-8 text, gunzipped and without a BOM)
    def read(path: Path) -> Recording               raises FormatError naming file and line
    def write(rec: Recording, path: Path) -> None   optional; writes atomically
"""

from __future__ import annotations

import importlib
from pathlib import Path
from types import ModuleType

from kinect_agent.errors import FormatError, UnknownFormat
from kinect_agent.formats._text import decoded_head
from kinect_agent.recording import Recording

# Detection order matters: the most specific formats first.
_MODULES = (
    "session_file",
    "skeleton_csv",
    "kinect_v2_tsv",
    "utkinect",
    "keraal",
    "keraal_vicon",
    "ui_prmd_vicon",
    "ui_prmd",
    "bvh",
    "amc",
)
_HEAD_BYTES = 8192


def available() -> dict[str, ModuleType]:
    """Returns the format modules that exist, by NAME."""
    found = {}
    for module_name in _MODULES:
        try:
            module = importlib.import_module(f"kinect_agent.formats.{module_name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"kinect_agent.formats.{module_name}":
                continue
            raise
        found[module.NAME] = module
    return found


def get(name: str) -> ModuleType:
    """Returns the format module called `name`."""
    formats = available()
    if name not in formats:
        raise UnknownFormat(None, f"unknown format {name!r}; known formats: {', '.join(sorted(formats))}")
    return formats[name]


def detect(path: str | Path) -> ModuleType:
    """Returns the format module that recognises the file at `path`."""
    path = Path(path)
    if not path.exists():
        raise FormatError(path, "no such file or directory")
    if path.is_file() and path.stat().st_size == 0:
        raise FormatError(path, "empty file (0 bytes): expected a recording")
    head = b"" if path.is_dir() else decoded_head(_read_head(path))
    for module in available().values():
        if module.sniff(path, head):
            return module
    known = ", ".join(sorted(available()))
    if b"\0" in head:
        raise UnknownFormat(path, f"binary data that is not a recording in a known format ({known})")
    raise UnknownFormat(path, f"format not recognised; name one with --format ({known})")


def read(path: str | Path, format: str | None = None) -> Recording:
    """Reads a recording from `path`, detecting its format unless `format` names one."""
    path = Path(path)
    module = get(format) if format else detect(path)
    if not path.exists():
        raise FormatError(path, "no such file or directory")
    if path.is_file() and path.stat().st_size == 0:
        raise FormatError(path, "empty file (0 bytes): expected a recording")
    rec = module.read(path)
    rec.meta.source = rec.meta.source or str(path)
    return rec


def write(rec: Recording, path: str | Path, format: str | None = None) -> None:
    """Writes `rec` to `path` in the named format, or by the file's extension (.csv, .khs)."""
    path = Path(path)
    name = format or {".csv": "csv", ".khs": "session"}.get(path.suffix.lower())
    if name is None:
        raise UnknownFormat(path, "cannot tell the output format from the extension; use .csv or .khs or --format")
    module = get(name)
    if not hasattr(module, "write"):
        raise UnknownFormat(path, f"format {name!r} can be read but not written")
    module.write(rec, path)


def _read_head(path: Path) -> bytes:
    with open(path, "rb") as f:
        return f.read(_HEAD_BYTES)
