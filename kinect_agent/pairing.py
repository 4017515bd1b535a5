"""Pairing as a library: exchanges a pairing code for a device token and saves the agent's configuration. The
`pair` command and the server's demo clinic (through kinect_agent.home) call it."""

from __future__ import annotations

import socket
from pathlib import Path

import httpx

from kinect_agent.config import (
    AgentConfig,
    ConfigError,
    agent_home,
    config_path,
    default_queue_dir,
    load_config,
    normalize_server_url,
    save_config,
)
from kinect_agent.errors import AgentError
from kinect_agent.queue import SessionQueue

PAIR_PATH = "/api/v1/devices/pair"


class PairingFailed(AgentError):
    """The server refused the pairing code or could not be reached."""


def pair(
    server_url: str,
    code: str,
    *,
    name: str | None = None,
    home: str | Path | None = None,
    queue_dir: str | Path | None = None,
    force: bool = False,
    transport: httpx.BaseTransport | None = None,
) -> AgentConfig:
    """Pairs with the server and saves the configuration (mode 0600); returns it. Raises PairingFailed/ConfigError."""
    server_url = normalize_server_url(server_url)
    name = name or f"{socket.gethostname()[:80]} Kinect"
    _refuse_if_sessions_wait(home, force)
    try:
        with httpx.Client(base_url=server_url, transport=transport, timeout=httpx.Timeout(30.0, connect=5.0)) as c:
            response = c.post(PAIR_PATH, json={"code": code, "name": name})
    except httpx.TransportError as exc:
        raise PairingFailed(f"cannot reach {server_url}: {type(exc).__name__}: {exc}") from None
    body = _body(response)
    if response.status_code != 201:
        detail = body.get("detail", response.text[:300]) if isinstance(body, dict) else response.text[:300]
        raise PairingFailed(f"{server_url}{PAIR_PATH} answered HTTP {response.status_code}: {detail}")
    if not isinstance(body, dict) or not isinstance(body.get("token"), str):
        raise PairingFailed(f"{server_url}{PAIR_PATH} answered 201 without a device token")
    queue = Path(queue_dir).resolve() if queue_dir is not None else default_queue_dir(home)
    config = AgentConfig(
        server_url=server_url,
        device_token=body["token"],
        queue_dir=str(queue),
        device_id=body.get("device_id"),
        patient_id=body.get("patient_id"),
        device_name=name,
    )
    SessionQueue(queue)
    save_config(config, home)
    return config


def _body(response: httpx.Response):
    try:
        return response.json()
    except ValueError:
        return None


def _refuse_if_sessions_wait(home: str | Path | None, force: bool) -> None:
    """Refuses to re-pair while sessions of the current pairing wait: they would go to the new patient."""
    if force or not config_path(home).exists():
        return
    try:
        old = load_config(home)
    except ConfigError:
        return  # a corrupt configuration is replaced
    waiting = SessionQueue(old.queue_dir).counts().pending
    if waiting:
        raise ConfigError(
            f"{agent_home(home)}: {waiting} session(s) of the current pairing (patient {old.patient_id}) still wait "
            "for upload; run `kinect-agent upload --once` first, or pass --force"
        )
