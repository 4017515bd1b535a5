"""`kinect-agent status [--json]`: what the home agent is doing, in words a patient's family can read.

Paired to which server and patient; whether the server answers and accepts the device token; sessions waiting,
uploaded (and when last), and set aside (refused by the server, or held after the same server error again and
again) with the reason; whether this computer's clock is wrong (compared with the server's Date header); the disk
the queue uses and what is left on that disk. `--json` gives the same facts for scripts. Exit status 0 (2 when the
agent is not paired: the configuration error says what to do).
"""

from __future__ import annotations

import argparse
import json
import shutil
from email.utils import parsedate_to_datetime
from pathlib import Path
from typing import Any

import httpx

from kinect_agent import __version__, clock
from kinect_agent.config import AgentConfig, load_config
from kinect_agent.queue import SessionQueue

NAME = "status"
HELP = "Say what the agent is doing: pairing, server reachable, sessions waiting, uploaded and set aside, disk used."
CHECK_PATH = "/api/v1/devices/me"
TIMEOUT_S = 5.0
CLOCK_OFF_S = 300.0  # the server stores sessions under its own time beyond 5 minutes ahead: say so from there on


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the status options."""
    parser.add_argument("--json", action="store_true", help="print the facts as JSON")


def server_check(config: AgentConfig, transport: httpx.BaseTransport | None = None) -> dict[str, Any]:
    """Returns {"reachable": bool, "token_accepted": bool | None, "detail": str, "clock_off_s": float | None} from
    GET /api/v1/devices/me; clock_off_s is this computer's clock minus the server's (its Date header), seconds."""
    headers = {"Authorization": f"Bearer {config.device_token}", "User-Agent": f"kinect-agent/{__version__}"}
    try:
        with httpx.Client(base_url=config.server_url, transport=transport, timeout=TIMEOUT_S) as client:
            response = client.get(CHECK_PATH, headers=headers)
    except httpx.HTTPError as exc:
        return {"reachable": False, "token_accepted": None, "detail": f"{type(exc).__name__}: {exc}",
                "clock_off_s": None}  # fmt: skip
    facts: dict[str, Any] = {"reachable": True, "token_accepted": None, "clock_off_s": clock_off_s(response)}
    if response.status_code == 200:
        return facts | {"token_accepted": True, "detail": "device token accepted"}
    if response.status_code == 401:
        return facts | {"token_accepted": False, "detail": "the server no longer accepts this device"}
    return facts | {"detail": f"HTTP {response.status_code} from {CHECK_PATH}"}


def clock_off_s(response: httpx.Response) -> float | None:
    """Returns this computer's clock minus the server's Date header, seconds (None without a readable Date). The
    server's time is set against the middle of the round trip (as NTP does), so a slow answer does not count as a
    clock off; the header has whole seconds, so the result is good to about a second."""
    try:
        server_now = parsedate_to_datetime(response.headers["Date"])
    except (KeyError, TypeError, ValueError):
        return None
    return round((clock.utc_now() - response.elapsed / 2 - server_now).total_seconds())


def _clock_sentence(off_s: float) -> str:
    """Returns the plain words for a clock off_s seconds ahead (negative: behind) of the server's."""
    amount = abs(off_s)
    for unit, size in (("years", 365 * 86400), ("days", 86400), ("hours", 3600), ("minutes", 60)):
        if amount >= size:
            how_far = f"{amount / size:.0f} {unit}"
            break
    way = "ahead of" if off_s > 0 else "behind"
    return (f"This computer's clock is wrong: it is {how_far} {way} the server's. Sessions are still stored, under "
            "the time the server receives them. Set the computer's date and time (or turn on setting them "
            "automatically).")  # fmt: skip


def queue_facts(queue: SessionQueue) -> dict[str, Any]:
    """Returns the queue's counts, last confirmed upload (ISO time or None), sessions set aside and disk use."""
    counts = queue.counts()
    confirmed = []
    for path in queue.sent_dir.glob("*.json"):
        try:
            confirmed.append(json.loads(path.read_text(encoding="utf-8")).get("confirmed_at") or "")
        except (OSError, ValueError):
            continue
    used = sum(p.stat().st_size for p in Path(queue.root).rglob("*") if p.is_file())
    return {
        "pending": counts.pending,
        "uploaded": counts.sent,
        "rejected": counts.rejected,
        "held": counts.held,
        "last_upload": max(confirmed, default=None) or None,
        "set_aside": queue.set_aside(),
        "queue_bytes": used,
        "disk_free_bytes": shutil.disk_usage(queue.root).free,
    }


def collect(config: AgentConfig, transport: httpx.BaseTransport | None = None) -> dict[str, Any]:
    """Returns every fact `status` reports."""
    return {
        "server_url": config.server_url,
        "device_id": config.device_id,
        "device_name": config.device_name,
        "patient_id": config.patient_id,
        "queue_dir": config.queue_dir,
        "server": server_check(config, transport),
        "queue": queue_facts(SessionQueue(config.queue_dir)),
    }


def _size(n: float) -> str:
    for unit in ("bytes", "KB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} TB"


def describe(facts: dict[str, Any]) -> list[str]:
    """Returns the report as plain sentences, one a line."""
    device = f"device {facts['device_id']}" if facts["device_id"] is not None else "a device"
    if facts["device_name"]:
        device += f" ({facts['device_name']})"
    patient = f"patient {facts['patient_id']}" if facts["patient_id"] is not None else "its patient"
    lines = [f"Paired with {facts['server_url']} as {device} for {patient}."]
    server = facts["server"]
    if not server["reachable"]:
        lines.append(f"The server cannot be reached right now ({server['detail']}). Sessions wait safely on this "
                     "computer and go as soon as it answers.")  # fmt: skip
    elif server["token_accepted"] is False:
        lines.append("The server answers but no longer accepts this computer: ask the clinic for a new pairing code "
                     "and run kinect-agent pair. Sessions wait safely on this computer.")  # fmt: skip
    else:
        lines.append(f"The server answers ({server['detail']}).")
    if server.get("clock_off_s") is not None and abs(server["clock_off_s"]) > CLOCK_OFF_S:
        lines.append(_clock_sentence(server["clock_off_s"]))
    q = facts["queue"]
    last = f" (last on {q['last_upload'].replace('T', ' ').replace('Z', ' UTC')})" if q["last_upload"] else ""
    lines.append(f"Sessions: {q['pending']} waiting to be sent, {q['uploaded']} sent{last}, "
                 f"{len(q['set_aside'])} set aside.")  # fmt: skip
    for item in q["set_aside"]:
        why = f"HTTP {item['status_code']}: {item['detail']}" if item["status_code"] else item["detail"]
        if item["where"] == "held":
            lines.append(f"  {item['session_id']}: the server failed on it again and again ({why}); it is kept in "
                         "held/ and goes again with: kinect-agent upload --retry-held")  # fmt: skip
        else:
            lines.append(f"  {item['session_id']}: the server refused it ({why}); it is kept in rejected/ and goes "
                         "again with: kinect-agent upload --retry-rejected")  # fmt: skip
    lines.append(f"Disk: the queue uses {_size(q['queue_bytes'])} in {facts['queue_dir']}; "
                 f"{_size(q['disk_free_bytes'])} free on that disk.")  # fmt: skip
    return lines


def run(args: argparse.Namespace) -> int:
    """Prints the status (plain words, or JSON with --json); returns 0."""
    facts = collect(load_config())
    print(json.dumps(facts, indent=2) if args.json else "\n".join(describe(facts)))
    return 0
