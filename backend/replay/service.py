"""The replay recording of a session: read from the object store, or built from the stored file and kept there.

Workers and replicas share the database and the store, so a recording built by one is served by all; two workers
building the same recording at once both succeed and one row is kept (the unique session id decides).
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


def replay_data(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int,
                layer: str | None = None) -> bytes:  # fmt: skip
    """Returns the `.viser` recording of a session, building and storing it when missing or of an older version;
    the stored file is read with the server's upload limits (max_frames, max_decoded_bytes). layer: one skeleton
    alone ("raw" or "filtered"; built each time, not stored), None: both."""
    if layer is not None:
        return _build(db_session=db_session, session_id=session_id, max_frames=max_frames,
                      max_decoded_bytes=max_decoded_bytes, layers=(layer,)).data  # fmt: skip
    row = db_session.execute(
        select(SessionReplay.data_key, SessionReplay.data_hash, SessionReplay.data).where(
            SessionReplay.session_id == session_id, SessionReplay.version == scene.VERSION
        )
    ).first()
    if row is not None and row.data_key and row.data_hash:
        return get_store().get(row.data_key, row.data_hash)
    if row is not None and row.data is not None:
        return row.data
    return _build_and_store(db_session=db_session, session_id=session_id, max_frames=max_frames,
                            max_decoded_bytes=max_decoded_bytes)  # fmt: skip


def _build_and_store(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int) -> bytes:
    replay = _build(db_session=db_session, session_id=session_id, max_frames=max_frames,
                    max_decoded_bytes=max_decoded_bytes, layers=scene.LAYERS)  # fmt: skip
    _store(db_session=db_session, session_id=session_id, replay=replay)
    return replay.data


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
