"""The replay recordings of a session: read from the object store, or built from the stored file and kept there.

Every recording (both skeletons, or one alone: the replay page's ?layer=) is built by a job-queue worker
(backend/replay/jobs.py), never in a request; workers and replicas share the database and the store, so a
recording built by one is served by all; two builds of the same recording at once both succeed and one row is kept
(the unique session id and layers decide).
"""

from __future__ import annotations

from sqlalchemy import ColumnElement, select
from sqlalchemy.orm import Session

from backend.database import keep_row
from backend.exceptions import InvalidSessionFile
from backend.exercises.models import Exercise
from backend.replay import scene
from backend.replay.models import BOTH, SessionReplay
from backend.sessions.models import ExerciseSession
from backend.sessions.service import session_file
from backend.storage import get_store
from kinect_agent.formats.session_file import SessionFileError, decode


def layers_name(layers: tuple[str, ...]) -> str:
    """Returns how a recording's skeletons are named in its row: "raw", "filtered" or both (BOTH)."""
    if not layers or any(layer not in scene.LAYERS for layer in layers):
        raise ValueError(f"layers must be of {scene.LAYERS}, got {layers!r}")
    return ",".join(layer for layer in scene.LAYERS if layer in layers)


def _current(session_id: int, layers: str) -> tuple[ColumnElement[bool], ...]:
    return (SessionReplay.session_id == session_id, SessionReplay.layers == layers,
            SessionReplay.version == scene.VERSION)  # fmt: skip


def stored_replay_key(*, db_session: Session, session_id: int, layers: str = BOTH) -> str | None:
    """Returns where the stored recording of today's scene version is (its object key, or "database" for one not
    moved to the store yet); None when there is none. layers: layers_name's, both skeletons by default."""
    row = db_session.execute(
        select(SessionReplay.data_key, SessionReplay.data.is_not(None)).where(*_current(session_id, layers))
    ).first()
    if row is None:
        return None
    return row[0] or ("database" if row[1] else None)


def stored_replay(*, db_session: Session, session_id: int, layers: str = BOTH) -> bytes | None:
    """Returns the stored `.viser` recording of the skeletons `layers` at today's scene version (hash checked), or
    None."""
    row = db_session.execute(
        select(SessionReplay.data_key, SessionReplay.data_hash, SessionReplay.data).where(*_current(session_id, layers))
    ).first()
    if row is not None and row.data_key and row.data_hash:
        return get_store().get(row.data_key, row.data_hash)
    if row is not None and row.data is not None:
        return row.data
    return None


def build_and_store(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int,
                    layers: tuple[str, ...] = scene.LAYERS) -> scene.Replay:  # fmt: skip
    """Builds the recording of the skeletons `layers` from the stored file and keeps it (the job's work; flushes)."""
    replay = _build(db_session=db_session, session_id=session_id, max_frames=max_frames,
                    max_decoded_bytes=max_decoded_bytes, layers=layers)  # fmt: skip
    _store(db_session=db_session, session_id=session_id, layers=layers_name(layers), replay=replay)
    return replay


def _build(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int,
           layers: tuple[str, ...]) -> scene.Replay:  # fmt: skip
    plane = db_session.scalar(
        select(Exercise.plane).join(ExerciseSession, Exercise.id == ExerciseSession.exercise_id)
        .where(ExerciseSession.id == session_id)
    )  # fmt: skip
    data = session_file(db_session=db_session, session_id=session_id)
    try:
        payload = decode(data, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
        return scene.build(payload, plane or "frontal", layers)
    except (SessionFileError, ValueError) as exc:
        raise InvalidSessionFile(f"the stored file of session {session_id} cannot be replayed: {exc}") from None


def _store(*, db_session: Session, session_id: int, layers: str, replay: scene.Replay) -> None:
    """Keeps the recording (replacing one of an older version); a concurrent insert of the same one wins."""
    obj = get_store().put("replay", replay.data)
    fields = {"version": scene.VERSION, "data": None, "data_key": obj.key, "data_hash": obj.sha256,
              "size": len(replay.data), "n_frames": replay.n_frames, "duration_s": replay.duration_s,
              "view": replay.view}  # fmt: skip
    keep_row(db_session, SessionReplay, {"session_id": session_id, "layers": layers}, fields)
