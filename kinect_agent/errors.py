"""Typed errors of the home agent; each says what was wrong and where."""

from __future__ import annotations

from pathlib import Path


class AgentError(Exception):
    """Base class of every error the agent reports to a user."""


class FormatError(AgentError):
    """A recording file could not be read: names the file, the line (when known) and what was expected."""

    def __init__(self, path: str | Path | None, message: str, line: int | None = None) -> None:
        self.path = str(path) if path is not None else None
        self.line = line
        self.message = message
        where = self.path or "<input>"
        if line is not None:
            where = f"{where}:{line}"
        super().__init__(f"{where}: {message}")


class UnknownFormat(FormatError):
    """No reader recognises the file, or the named format does not exist."""


class DeviceUnavailable(AgentError):
    """A hardware source cannot be opened (SDK missing or no device attached)."""
