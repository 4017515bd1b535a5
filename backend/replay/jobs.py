"""The replay build on the job queue: a page asks for a session's replay, a worker builds it off the request path.

`request_replay` is what a request does: the recording is ready (stored, of today's scene version), or one job is
queued to build it (key `replay:<session id>:<scene version>`, `…:raw` or `…:filtered` for one skeleton alone, so
concurrent requests and several server processes queue it once, and several workers build it once), or its build
failed (said in words; asking again queues a bounded number of further tries, backend.jobs.asking; a stored file
that cannot be read is said at once and not tried again). `run` is the job: it builds and stores the recording
unless it is stored already (a job run twice builds once).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from sqlalchemy.orm import Session

from backend.exceptions import InvalidSessionFile
from backend.i18n import ENGLISH, N_, Translator
from backend.jobs.asking import ask
from backend.replay import scene, service
from backend.replay.models import BOTH
from backend.sessions.models import ExerciseSession
from backend.sessions.service import require_recording

KIND = "replay"
READY = N_("The replay is ready.")


@dataclass(frozen=True)
class ReplayState:
    """Where a session's replay is: "ready", "preparing" (queued or being built) or "failed"; detail in words."""

    state: str
    detail: str


def job_key(session_id: int, layers: str = BOTH) -> str:
    """Returns the queue key of the build of one session's replay (of the skeletons `layers`) at today's scene
    version."""
    tail = "" if layers == BOTH else f":{layers}"
    return f"{KIND}:{session_id}:{scene.VERSION}{tail}"


def request_replay(*, db_session: Session, session_id: int, layers: str = BOTH, t: Translator = ENGLISH) -> ReplayState:
    """Returns the state of a session's replay (of the skeletons `layers`), queueing its build when it is neither
    stored nor queued, or when it failed and may be tried again; flushes.

    Raises SessionNotFound, or SessionFileRemoved when the retention period removed the recording.
    """
    if service.stored_replay_key(db_session=db_session, session_id=session_id, layers=layers) is not None:
        return ReplayState("ready", t.gettext(READY))
    require_recording(db_session=db_session, session_id=session_id)
    payload = {"session_id": session_id, "layers": layers.split(",")}
    found = ask(db_session=db_session, kind=KIND, key=job_key(session_id, layers), payload=payload, t=t)
    return ReplayState(found.state, found.detail)


def run(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int,
        layers: tuple[str, ...] = scene.LAYERS) -> dict[str, Any]:  # fmt: skip
    """Runs the job of one session: builds and stores its replay (of the skeletons `layers`) unless stored already;
    returns what it did."""
    name = service.layers_name(layers)
    if db_session.get(ExerciseSession, session_id) is None:
        return {"session_id": session_id, "built": False, "skipped": "the session no longer exists"}
    if service.stored_replay_key(db_session=db_session, session_id=session_id, layers=name) is not None:
        return {"session_id": session_id, "built": False, "version": scene.VERSION, "layers": name}
    try:
        replay = service.build_and_store(db_session=db_session, session_id=session_id, max_frames=max_frames,
                                         max_decoded_bytes=max_decoded_bytes, layers=layers)  # fmt: skip
    except InvalidSessionFile as exc:  # no retry reads it otherwise: said to whoever asks (backend.jobs.asking)
        return {"session_id": session_id, "built": False, "layers": name, "invalid": exc.message}
    return {"session_id": session_id, "built": True, "version": scene.VERSION, "layers": name,
            "n_frames": replay.n_frames, "size": len(replay.data)}  # fmt: skip
