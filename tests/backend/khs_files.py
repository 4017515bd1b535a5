"""Session files (.khs) for server tests: valid ones from the simulator, and each kind of defect."""

from __future__ import annotations

import codecs
import gzip
import hashlib
import json
import lzma
import struct
import uuid
import zlib
from typing import Any

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


def make_khs_at_distance(exercise: str = "squat", reps: int = 3, *, seed: int = 0, z_m: float = 1.1) -> bytes:
    """Returns a session file of the simulator's truth moved to z_m metres from the camera (the trunk's median):
    1.1 m is too close (camera advice too_close, and the feet leave the picture)."""
    from kinect_agent.skeleton import INDEX

    _, truth, _ = simulate(exercise, reps, seed=seed)
    z = float(np.nanmedian(truth.positions[:, INDEX["ROOT"], 2]))
    moved = truth.replace(step="test: moved", positions=truth.positions + np.array([0.0, 0.0, z_m - z]),
                          state=truth.state)  # fmt: skip
    payload = sf.SessionPayload(session_id=str(uuid.uuid4()), raw=moved, filtered=moved,
                                created_at="2026-11-20T10:00:00Z")  # fmt: skip
    return sf.encode(payload)


def make_processed_khs(exercise: str = "squat", reps: int = 3, *, seed: int = 0) -> bytes:
    """Returns the session file the home agent makes of a simulated set: raw, filtered by the pipeline, angle SDs."""
    from kinect_agent.capture import make_payload

    measured, _, _ = simulate(exercise, reps, seed=seed)
    return sf.encode(make_payload(measured, created_at="2026-11-20T10:00:00Z"))


def split(data: bytes) -> tuple[int, dict[str, Any], list[bytes]]:
    """Returns (version, JSON header, compressed blocks) of a valid file."""
    _, version, _, header_len, _ = _FIXED.unpack_from(data)
    header = json.loads(data[_FIXED.size : _FIXED.size + header_len])
    pos, end, blocks = _FIXED.size + header_len, len(data) - 32, []
    while pos < end:
        (n,) = _LEN.unpack_from(data, pos)
        blocks.append(data[pos + 4 : pos + 4 + n])
        pos += 4 + n
    return version, header, blocks


def join(header: dict[str, Any], blocks: list[bytes], version: int = sf.VERSION) -> bytes:
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


# ---------------------------------------------------------------------------------------------- defects


def _bad_version(data):
    return data[:8] + (3).to_bytes(2, "little") + data[10:]


def _flip(data):
    i = len(data) // 2
    return data[:i] + bytes([data[i] ^ 0xFF]) + data[i + 1 :]


def _joints(data):
    return with_header(data, lambda h: h.__setitem__("joints", h["joints"][:19]))


def _non_finite(data):
    t = np.arange(n_frames(data)) / 30.0  # version-2 positions are integers: only times can be non-finite
    t[7] = np.inf
    return with_time(data, t)


def _non_monotonic(data):
    n = n_frames(data)
    t = np.arange(n) / 30.0
    t[10] = t[8]
    return with_time(data, t)


def _no_frames(data):
    return with_header(data, lambda h: h["recordings"]["raw"].__setitem__("n_frames", 0))


def _zlib_bomb(data):
    return with_block(data, 2, bytes(40 * 2**20))


def _not_uuid(data):
    return with_header(data, lambda h: h.__setitem__("session_id", "abc"))


def _raw_meta(key, value):
    def change(h):
        h["recordings"]["raw"].setdefault("meta", {})
        if key is None:
            h["recordings"]["raw"]["meta"] = value
        else:
            h["recordings"]["raw"]["meta"][key] = value

    return lambda data: with_header(data, change)


def _deep_params(data):
    """params nested 100 000 lists deep (JSON that makes a recursive parser overflow its stack)."""
    version, header, blocks = split(data)
    header["params"] = {"deep": "@@"}
    text = json.dumps(header, separators=(",", ":")).replace('"@@"', "[" * 100_000 + "]" * 100_000)
    return join_text(text, blocks, version)


def _far_joint(data):
    payload = sf.decode(data)
    payload.raw.positions[5, 3, 0] = 900.0  # within the format's range, 900 m from the camera
    return sf.encode(payload)


def _times(step_s):
    return lambda data: with_time(data, np.arange(n_frames(data)) * step_s)


# Every kind of defective file the server must refuse with 400 InvalidSessionFile, storing nothing:
# name -> (corrupt(valid file bytes) -> defective bytes, the start of the expected 'detail').
DEFECTS = {
    "meta_as_list": (_raw_meta(None, [1, 2]), "bad_header: recording 'raw' metadata must be an object"),
    "rate_as_text": (_raw_meta("rate_hz", "fast"), "bad_header: recording 'raw' metadata: rate_hz"),
    "rate_of_a_billionth_hz": (
        _raw_meta("rate_hz", 1e-9),
        "bad_header: recording 'raw' metadata: rate_hz must be a finite number in [1, 1000] Hz",
    ),
    "exercise_as_list": (_raw_meta("exercise", ["squat"]), "bad_header: recording 'raw' metadata: exercise"),
    "params_100000_deep": (_deep_params, "bad_header: JSON header is nested too deeply"),
    "nan_in_header": (
        lambda d: with_header(d, lambda h: h["params"].__setitem__("x", float("nan"))),
        "bad_header: JSON header holds NaN",
    ),
    "created_at_not_a_time": (
        lambda d: with_header(d, lambda h: h.__setitem__("created_at", "yesterday")),
        "bad_header: created_at 'yesterday' is not an ISO 8601 time",
    ),
    "created_at_without_zone": (
        lambda d: with_header(d, lambda h: h.__setitem__("created_at", "2026-11-20T10:00:00")),
        "bad_header: created_at '2026-11-20T10:00:00' has no time zone",
    ),
    "frames_1e-7_s_apart": (_times(1e-7), "implausible_timing: recording 'raw': frames 1e-07 s apart"),
    "frames_10_s_apart": (_times(10.0), "implausible_timing: recording 'raw': frames 10 s apart"),
    "joint_900_m_away": (_far_joint, "implausible_position: recording 'raw': frame 5 joint HEAD at x = 900"),
    "bad_magic": (lambda d: b"NOT A KHS FILE" + d[14:], "bad_magic: "),
    "unsupported_version": (_bad_version, "unsupported_version: file version 3"),
    "checksum_mismatch": (_flip, "checksum_mismatch: "),
    "truncated": (lambda d: d[:-100], "truncated: "),
    "wrong_joint_count": (_joints, "wrong_joint_count: joint list has 19 joints"),
    "non_finite": (_non_finite, "non_finite: recording 'raw'"),
    "non_monotonic_time": (_non_monotonic, "non_monotonic_time: recording 'raw': frame 10"),
    "no_frames": (_no_frames, "no_frames: recording 'raw' has 0 frames"),
    "zlib_bomb": (_zlib_bomb, "too_large: a block decodes to more than"),
    "empty_body": (lambda d: b"", "bad_magic: "),
    "gzipped": (lambda d: gzip.compress(d), "bad_magic: expected magic"),
    "line_ends_converted_to_crlf": (lambda d: d.replace(b"\n", b"\r\n"), "bad_magic: expected magic"),
    "line_ends_converted_to_lf": (lambda d: d.replace(b"\r\n", b"\n"), "bad_magic: expected magic"),
    "utf8_bom_before": (lambda d: codecs.BOM_UTF8 + d, "bad_magic: expected magic"),
    "skeleton_csv_sent_as_khs": (lambda d: b"time,ROOT_x,ROOT_y,ROOT_z\n0.0,0.1,0.2,2.0\n", "bad_magic: "),
    "random_bytes": (lambda d: np.random.default_rng(7).bytes(4096), "bad_magic: "),
    "session_id_not_uuid": (_not_uuid, "bad_header: session_id 'abc' is not a UUID"),
}
