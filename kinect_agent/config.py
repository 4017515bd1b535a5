"""The agent's configuration file: server URL, device token and queue folder (written atomically, mode 0600).

Location: $KINECT_AGENT_HOME/config.json when KINECT_AGENT_HOME is set, else ~/.config/kinect-agent/config.json.
The file holds the device token, so it is created with mode 0600 and refused when others can read it.
"""

from __future__ import annotations

import json
import os
import stat
from dataclasses import asdict, dataclass
from pathlib import Path
from urllib.parse import urlsplit

from kinect_agent.errors import AgentError
from kinect_agent.formats._atomic import atomic_open

ENV_HOME = "KINECT_AGENT_HOME"
CONFIG_NAME = "config.json"
FILE_MODE = 0o600
_KEYS = {"server_url": str, "device_token": str, "queue_dir": str}


class ConfigError(AgentError):
    """The agent configuration is missing, unreadable or invalid; names the file and what is wrong."""


@dataclass
class AgentConfig:
    """What a paired agent needs: where to upload, as whom, and where its queue lives."""

    server_url: str  # e.g. "https://coach.example.org" (no trailing slash)
    device_token: str  # "khd_..." from POST /api/v1/devices/pair
    queue_dir: str  # absolute path of the upload queue
    device_id: int | None = None
    patient_id: int | None = None
    device_name: str | None = None

    @property
    def recorded_by(self) -> dict[str, int] | None:
        """Returns the pairing that the agent writes into each session file, or None when it is not known."""
        if self.device_id is None or self.patient_id is None:
            return None
        return {"device_id": self.device_id, "patient_id": self.patient_id}


def agent_home(home: str | Path | None = None) -> Path:
    """Returns the agent's home folder: `home`, else $KINECT_AGENT_HOME, else ~/.config/kinect-agent."""
    if home is not None:
        return Path(home)
    env = os.environ.get(ENV_HOME)
    if env:
        return Path(env)
    return Path.home() / ".config" / "kinect-agent"


def config_path(home: str | Path | None = None) -> Path:
    """Returns the path of config.json inside the agent's home folder."""
    return agent_home(home) / CONFIG_NAME


def default_queue_dir(home: str | Path | None = None) -> Path:
    """Returns the default queue folder (home/queue)."""
    return agent_home(home).resolve() / "queue"


def normalize_server_url(url: str) -> str:
    """Returns the URL without a trailing slash; raises ConfigError unless it is http(s)://host[:port][/path]."""
    parts = urlsplit(url.strip())
    if parts.scheme not in ("http", "https") or not parts.netloc:
        raise ConfigError(f"server URL {url!r} must look like https://coach.example.org")
    if parts.query or parts.fragment:
        raise ConfigError(f"server URL {url!r} must not carry a query or fragment")
    return url.strip().rstrip("/")


def load_config(home: str | Path | None = None) -> AgentConfig:
    """Reads and checks config.json; raises ConfigError naming the file and the problem."""
    path = config_path(home)
    try:
        info = path.stat()
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(
            f"{path}: no agent configuration; pair this device first: kinect-agent pair --server URL --code CODE"
        ) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read the agent configuration: {exc}") from None
    if os.name == "posix" and stat.S_IMODE(info.st_mode) & 0o077:
        raise ConfigError(
            f"{path}: holds the device token but others may read it (mode {stat.S_IMODE(info.st_mode):o}); "
            f"run: chmod 600 {path}"
        )
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise ConfigError(f"{path}: corrupt agent configuration (not JSON: {exc}); pair again to rewrite it") from None
    except RecursionError:
        raise ConfigError(
            f"{path}: corrupt agent configuration (JSON nested too deeply); pair again to rewrite it"
        ) from None
    return _from_dict(data, path)


def _from_dict(data: object, path: Path) -> AgentConfig:
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: corrupt agent configuration (expected a JSON object)")
    for key, kind in _KEYS.items():
        if not isinstance(data.get(key), kind) or not data[key]:
            raise ConfigError(f"{path}: corrupt agent configuration ({key!r} must be a non-empty {kind.__name__})")
    for key in ("device_id", "patient_id"):
        if data.get(key) is not None and type(data[key]) is not int:
            raise ConfigError(f"{path}: corrupt agent configuration ({key!r} must be an integer)")
    try:
        server_url = normalize_server_url(data["server_url"])
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    return AgentConfig(
        server_url=server_url,
        device_token=data["device_token"],
        queue_dir=data["queue_dir"],
        device_id=data.get("device_id"),
        patient_id=data.get("patient_id"),
        device_name=data.get("device_name") if isinstance(data.get("device_name"), str) else None,
    )


def save_config(config: AgentConfig, home: str | Path | None = None) -> Path:
    """Writes config.json atomically with mode 0600 (file and folder fsynced); returns its path."""
    path = config_path(home)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(asdict(config), indent=2, sort_keys=True) + "\n"
    with atomic_open(path, "w", encoding="utf-8") as f:  # mkstemp creates the temp file with mode 0600
        if os.name == "posix":
            os.fchmod(f.fileno(), FILE_MODE)
        f.write(text)
    fsync_dir(path.parent)
    return path


def fsync_dir(folder: Path) -> None:
    """Flushes a folder's entries to disk (so a rename survives a power cut); no-op where unsupported."""
    if os.name != "posix":
        return
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
