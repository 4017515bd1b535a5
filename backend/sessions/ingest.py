"""Turning an uploaded .khs body into a checked upload: size-limited reading, decoding, identity and analysis."""

from __future__ import annotations

import datetime as dt
import uuid
from collections.abc import AsyncIterator
from dataclasses import dataclass

from starlette.requests import ClientDisconnect

from backend.exceptions import InvalidSessionFile, SessionOwnerMismatch, SessionTooLarge, UploadCutOff
from kinect_agent.formats import session_file
from kinect_agent.formats.session_file import SessionFileError, SessionPayload


@dataclass(frozen=True)
class Upload:
    """A decoded, checked session file: its bytes, SHA-256, payload and the identity fields taken from it."""

    data: bytes
    content_hash: str
    payload: SessionPayload
    client_session_id: uuid.UUID
    started_at: dt.datetime

    @property
    def exercise_slug(self) -> str | None:
        """Returns the exercise the recording names in its metadata (None when it names none)."""
        return self.payload.raw.meta.exercise or None


def check_declared_length(content_length: str | None, limit: int) -> None:
    """Raises SessionTooLarge when a Content-Length header already announces more than limit bytes."""
    if content_length is None:
        return
    try:
        declared = int(content_length)
    except ValueError:
        raise InvalidSessionFile(f"Content-Length header {content_length[:40]!r} is not a number") from None
    if declared > limit:
        raise SessionTooLarge(f"the upload declares {declared} bytes, the limit is {limit}")


async def read_limited(chunks: AsyncIterator[bytes], limit: int) -> bytes:
    """Returns the streamed body; raises SessionTooLarge as soon as more than limit bytes arrived, and UploadCutOff
    when the client goes away before the end (a home connection dropping mid-upload: an answer, not a server
    error; nothing is stored and the agent sends the file again)."""
    parts: list[bytes] = []
    size = 0
    try:
        async for chunk in chunks:
            size += len(chunk)
            if size > limit:
                raise SessionTooLarge(f"the upload exceeds {limit} bytes")
            parts.append(chunk)
    except ClientDisconnect:
        raise UploadCutOff(f"the upload was cut off after {size} bytes") from None
    return b"".join(parts)


def decode_upload(
    data: bytes, *, max_frames: int, max_decoded_bytes: int, max_duration_s: float | None = None
) -> Upload:
    """Decodes and checks session file bytes; raises InvalidSessionFile '<code>: <message>' on any defect, and for a
    recording longer than max_duration_s seconds (None: no limit)."""
    try:
        payload = session_file.decode(data, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
    except SessionFileError as exc:
        raise InvalidSessionFile(f"{exc.code}: {exc.detail}") from None
    check_showable(payload)
    if max_duration_s is not None and payload.raw.duration > max_duration_s:
        raise InvalidSessionFile(f"too_long: the recording lasts {payload.raw.duration:.0f} s; a session lasts at "
                                 f"most {max_duration_s:g} s (COACH_SESSION_MAX_DURATION_S)")  # fmt: skip
    return Upload(
        data=data,
        content_hash=session_file.content_hash(data),
        payload=payload,
        client_session_id=_session_uuid(payload.session_id),
        started_at=_started_at(payload.created_at),
    )


def check_showable(payload: SessionPayload) -> None:
    """Raises InvalidSessionFile for a file the session page, replay and exports could not show: fewer than 2 raw
    frames, or a filtered recording of another length than the raw one (refused at upload, not stored)."""
    raw, filtered = payload.raw, payload.filtered
    if raw.n_frames < 2:
        raise InvalidSessionFile(f"too_short: the raw recording has {raw.n_frames} frame(s); at least 2 are needed")
    if filtered is not None and filtered.n_frames != raw.n_frames:
        raise InvalidSessionFile(
            f"recordings_disagree: the filtered recording has {filtered.n_frames} frames, the raw one {raw.n_frames}"
        )


def check_owner(upload: Upload, *, patient_id: int, device_id: int | None) -> None:
    """Raises SessionOwnerMismatch when the file's recorded_by names another patient than patient_id, or another
    device than device_id (the uploading device; None for users, who may relay a file of the right patient)."""
    recorded_by = upload.payload.recorded_by
    if recorded_by is None:
        return
    if recorded_by["patient_id"] != patient_id:
        raise SessionOwnerMismatch(
            f"recorded_by.patient_id: this session was recorded for another patient, not for patient {patient_id}"
        )
    if device_id is not None and recorded_by["device_id"] != device_id:
        raise SessionOwnerMismatch(
            f"recorded_by.device_id: this session was recorded by device {recorded_by['device_id']}, "
            f"not by device {device_id} that sends it"
        )


def _session_uuid(value: str) -> uuid.UUID:
    try:
        return uuid.UUID(value)
    except ValueError:
        raise InvalidSessionFile(f"bad_header: session_id {value[:80]!r} is not a UUID") from None


EARLIEST_START = dt.datetime(2000, 1, 1, tzinfo=dt.UTC)  # no session of this system is older
CLOCK_TOLERANCE = dt.timedelta(minutes=5)  # how far ahead of the server's clock an agent's created_at may be


def _started_at(value: str) -> dt.datetime:
    """Returns the file's created_at as the session's start, or the time the server received it when the agent's
    clock was plainly wrong (before EARLIEST_START, or more than CLOCK_TOLERANCE in the future): a wrong clock at
    home is no defect of the file, which is stored as sent and keeps the agent's value as it reported it."""
    try:
        when = dt.datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError:
        raise InvalidSessionFile(f"bad_header: created_at {value[:80]!r} is not an ISO 8601 time") from None
    if when.tzinfo is None:
        raise InvalidSessionFile(f"bad_header: created_at {value[:80]!r} has no time zone (expected UTC, '...Z')")
    received = dt.datetime.now(dt.UTC)
    try:
        when = when.astimezone(dt.UTC)
    except OverflowError:  # 0001-01-01T00:00:00+23:59: before year 1 in UTC
        return received
    return when if EARLIEST_START <= when <= received + CLOCK_TOLERANCE else received
