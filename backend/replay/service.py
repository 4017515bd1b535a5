"""The replay recording of a session: read from the object store, or built from the stored file and kept there.

The recording of both skeletons is built by a job-queue worker (backend/replay/jobs.py), never in a request;
workers and replicas share the database and the store, so a recording built by one is served by all; two builds
of the same recording at once both succeed and one row is kept (the unique session id decides). One skeleton
alone (?layer=) is built in the request each time (a few hundred ms; not stored).
"""

from __future__ import annotations

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from backend.exceptions import InvalidSessionFile
from backend.exercises.models import Exercise
from backend.replay import scene
from backend.replay.models import SessionReplay
from backend.sessions.models import ExerciseSession
from backend.sessions.service import session_file
from backend.storage import get_store
from kinect_agent.formats.session_file import SessionFileError, decode


def layer_data(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int, layer: str) -> bytes:
    """Returns the `.viser` recording of one skeleton alone ("raw" or "filtered"), built now from the stored file
    read with the server's upload limits (max_frames, max_decoded_bytes); not stored."""
    return _build(db_session=db_session, session_id=session_id, max_frames=max_frames,
                  max_decoded_bytes=max_decoded_bytes, layers=(layer,)).data  # fmt: skip


def stored_replay_key(*, db_session: Session, session_id: int) -> str | None:
    """Returns where the stored recording of today's scene version is (its object key, or "database" for one not
    moved to the store yet); None when there is none."""
    row = db_session.execute(
        select(SessionReplay.data_key, SessionReplay.data.is_not(None)).where(
            SessionReplay.session_id == session_id, SessionReplay.version == scene.VERSION
        )
    ).first()
    if row is None:
        return None
    return row[0] or ("database" if row[1] else None)


def stored_replay(*, db_session: Session, session_id: int) -> bytes | None:
    """Returns the stored `.viser` recording of both skeletons at today's scene version (hash checked), or None."""
    row = db_session.execute(
        select(SessionReplay.data_key, SessionReplay.data_hash, SessionReplay.data).where(
            SessionReplay.session_id == session_id, SessionReplay.version == scene.VERSION
        )
    ).first()
    if row is not None and row.data_key and row.data_hash:
        return get_store().get(row.data_key, row.data_hash)
    if row is not None and row.data is not None:
        return row.data
    return None


def build_and_store(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int) -> scene.Replay:
    """Builds the recording of both skeletons from the stored file and keeps it (the job's work; flushes)."""
    replay = _build(db_session=db_session, session_id=session_id, max_frames=max_frames,
                    max_decoded_bytes=max_decoded_bytes, layers=scene.LAYERS)  # fmt: skip
    _store(db_session=db_session, session_id=session_id, replay=replay)
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


def _store(*, db_session: Session, session_id: int, replay: scene.Replay) -> None:
    """Keeps the recording (replacing one of an older version); a concurrent insert of the same session wins."""
    obj = get_store().put("replay", replay.data)
    fields = {"version": scene.VERSION, "data": None, "data_key": obj.key, "data_hash": obj.sha256,
              "size": len(replay.data), "n_frames": replay.n_frames, "duration_s": replay.duration_s,
              "view": replay.view}  # fmt: skip
    try:
        with db_session.begin_nested():
            stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == session_id))
            if stored is None:
                db_session.add(SessionReplay(session_id=session_id, **fields))
            else:
                for name, value in fields.items():
                    setattr(stored, name, value)
    except IntegrityError:  # another worker stored it first: the same recording
        pass
