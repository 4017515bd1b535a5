"""backend.sessions.ingest: the streamed size limit, the declared length, and identity fields of a file."""

from __future__ import annotations

import asyncio
import datetime as dt
import uuid

import pytest

from backend.exceptions import InvalidSessionFile, SessionTooLarge
from backend.sessions.ingest import check_declared_length, decode_upload, read_limited
from tests.backend import khs_files
from tests.backend.khs_files import make_khs


def test_read_limited_stops_pulling_chunks_once_over_the_limit():
    pulled = []

    async def chunks():
        for i in range(100):
            pulled.append(i)
            yield b"x" * 1000

    with pytest.raises(SessionTooLarge, match="the upload exceeds 2500 bytes"):
        asyncio.run(read_limited(chunks(), 2500))
    assert len(pulled) == 3


def test_read_limited_returns_a_body_at_the_limit():
    async def chunks():
        yield b"ab"
        yield b"cd"

    assert asyncio.run(read_limited(chunks(), 4)) == b"abcd"


@pytest.mark.parametrize(
    ("header", "error"),
    [("11", SessionTooLarge), ("abc", InvalidSessionFile)],
)
def test_declared_length_is_checked(header, error):
    with pytest.raises(error):
        check_declared_length(header, 10)
    check_declared_length("10", 10)
    check_declared_length(None, 10)


def test_decode_upload_takes_id_and_start_from_the_file():
    sid = str(uuid.uuid4())
    upload = decode_upload(make_khs(session_id=sid, created_at="2026-11-20T10:00:00Z"), max_frames=10**5,
                           max_decoded_bytes=2**26)  # fmt: skip
    assert upload.client_session_id == uuid.UUID(sid)
    assert upload.started_at == dt.datetime(2026, 11, 20, 10, tzinfo=dt.UTC)
    assert upload.exercise_slug == "squat"


def test_decode_upload_refuses_a_start_without_time_zone():
    data = khs_files.with_header(make_khs(), lambda h: h.__setitem__("created_at", "2026-11-20T10:00:00"))
    with pytest.raises(InvalidSessionFile, match="created_at '2026-11-20T10:00:00' has no time zone"):
        decode_upload(data, max_frames=10**5, max_decoded_bytes=2**26)


def test_decode_upload_honours_the_decoded_size_budget():
    data = make_khs()
    with pytest.raises(InvalidSessionFile, match="^too_large: recordings decode to"):
        decode_upload(data, max_frames=10**5, max_decoded_bytes=1000)
