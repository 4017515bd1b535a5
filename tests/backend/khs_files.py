"""Session files (.khs) for server tests: valid ones from the simulator, and each kind of defect."""

from __future__ import annotations

import hashlib
import json
import lzma
import struct
import uuid
import zlib

import numpy as np

from kinect_agent.formats import session_file as sf
from kinect_agent.sources.simulator import simulate

_FIXED = struct.Struct("<8sHHIQ")
_LEN = struct.Struct("<I")


def make_khs(
    exercise: str = "squat",
    reps: int = 3,
    *,
    seed: int = 0,
    session_id: str | None = None,
    created_at: str = "2026-11-20T10:00:00Z",
    filtered: bool = True,
) -> bytes:
    """Returns a valid session file of a simulated set (measured raw + the exact recording as 'filtered')."""
    measured, truth, _ = simulate(exercise, reps, seed=seed)
    payload = sf.SessionPayload(
        session_id=session_id or str(uuid.uuid4()),
        raw=measured,
        filtered=truth if filtered else None,
        params={"filter": "test"},
        created_at=created_at,
    )
    return sf.encode(payload)


def split(data: bytes) -> tuple[int, dict, list[bytes]]:
    """Returns (version, JSON header, compressed blocks) of a valid file."""
    _, version, _, header_len, _ = _FIXED.unpack_from(data)
    header = json.loads(data[_FIXED.size : _FIXED.size + header_len])
    pos, end, blocks = _FIXED.size + header_len, len(data) - 32, []
    while pos < end:
        (n,) = _LEN.unpack_from(data, pos)
        blocks.append(data[pos + 4 : pos + 4 + n])
        pos += 4 + n
    return version, header, blocks


def join(header: dict, blocks: list[bytes], version: int = sf.VERSION) -> bytes:
    """Returns a file with a correct length and checksum around any header and blocks."""
    return join_text(json.dumps(header, separators=(",", ":")), blocks, version)


def join_text(text: str, blocks: list[bytes], version: int = sf.VERSION) -> bytes:
    """Returns a file with a correct length and checksum around any header text and blocks."""
    head = text.encode()
    body = b"".join(_LEN.pack(len(b)) + b for b in blocks)
    total = _FIXED.size + len(head) + len(body) + 32
    data = _FIXED.pack(sf.MAGIC, version, 0, len(head), total) + head + body
    return data + hashlib.sha256(data).digest()


def with_header(data: bytes, change) -> bytes:
    """Returns the file with change(header) applied to its JSON header (checksum recomputed)."""
    version, header, blocks = split(data)
    change(header)
    return join(header, blocks, version)


def compress(raw: bytes, version: int) -> bytes:
    """Returns `raw` compressed with the codec of that format version (1: zlib, 2: xz)."""
    if version == 1:
        return zlib.compress(raw, 9)
    return lzma.compress(raw, format=lzma.FORMAT_XZ, check=lzma.CHECK_NONE, preset=1)


def with_time(data: bytes, t: np.ndarray) -> bytes:
    """Returns the file with the raw recording's time stamps replaced by t (T,) s (checksum recomputed)."""
    version, header, blocks = split(data)
    dt = np.concatenate([t[:1], np.diff(t)]).astype("<f8")
    blocks[0] = compress(sf._shuffle(dt), version)
    return join(header, blocks, version)


def with_block(data: bytes, index: int, raw: bytes) -> bytes:
    """Returns the file with block index replaced by raw compressed with the file's codec (checksum recomputed)."""
    version, header, blocks = split(data)
    blocks[index] = compress(raw, version)
    return join(header, blocks, version)


def n_frames(data: bytes) -> int:
    """Returns the raw recording's frame count."""
    return split(data)[1]["recordings"]["raw"]["n_frames"]
