"""Session file (.khs): the compact, checksummed binary file used for storage and upload.

Byte layout (all integers little-endian; full description in docs/session-file.md):
    fixed header (24 bytes): MAGIC (8) | version u16 | flags u16 | header_len u32 | total_len u64
    JSON header (header_len bytes, UTF-8): session id, creation time, params, per-recording metadata
    blocks: for the raw recording, then the filtered one if present: t, state, positions; then, optional (header key
            "angle_sd"), one block of the per-frame SD of the filtered recording's clinical angles;
            each block is a u32 length followed by that many bytes of compressed data
    trailer (32 bytes): SHA-256 of every byte before it

Version 2 (written): positions rounded to a 2**-10 m grid (about 0.98 mm, far below Kinect's own error) and
stored as int32 time deltas in grid units, byte-shuffled; times are float64 deltas, byte-shuffled; states are
int8; every block is an xz stream (LZMA2, preset 6, no xz check: the SHA-256 trailer covers the file).
Version 1 (still read): the same layout with a 2**-13 m grid, float32 position deltas in metres and zlib blocks.
Angle SD block (optional, version 2; files without it read as before): uint16 (A, T) SDs in ANGLE_SD_STEP_DEG
units, byte-shuffled, xz; ANGLE_SD_MISSING = undefined (NaN); A = len(header["angle_sd"]["names"]), a subset of
kinect_agent.body.angles.ANGLE_NAMES, T = the filtered recording's frames.
No pickle anywhere.
"""

from __future__ import annotations

import hashlib
import json
import lzma
import struct
import uuid
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.angles import ANGLE_NAMES
from kinect_agent.clock import utc_now_iso
from kinect_agent.errors import FormatError
from kinect_agent.formats._atomic import atomic_open
from kinect_agent.recording import Metadata, Recording

NAME = "session"
DESCRIPTION = "Kinect Home Coach session file (.khs): raw + filtered recording, compressed, SHA-256 checked"
MAGIC = b"\x89KHS\r\n\x1a\n"
VERSION = 2  # written; versions 1 and 2 are read
GRID_M = 2.0**-10  # position quantum of version 2, metres (about 0.98 mm)
CODEC = "xz"
MAX_ABS_M = 1000.0  # encoder's position range; +-2**20 grid units, so time deltas fit int32 with room to spare
_FORMATS = {1: ("zlib", 2.0**-13), 2: (CODEC, GRID_M)}  # version -> (codec, grid_m) named in its JSON header
_XZ_PRESET = 6  # LZMA2, 8 MiB dictionary: the decoder needs about 9 MiB
_XZ_MEMLIMIT = 32 * 2**20  # decoder memory limit, bytes: refuses streams made with larger dictionaries
_FIXED = struct.Struct("<8sHHIQ")  # magic, version, flags, header_len, total_len
_BLOCK_LEN = struct.Struct("<I")
_DIGEST = 32
ERROR_CODES = frozenset(
    {
        "bad_magic",
        "unsupported_version",
        "checksum_mismatch",
        "truncated",
        "wrong_joint_count",
        "non_finite",
        "non_monotonic_time",
        "no_frames",
        "too_long",
        "too_large",
        "bad_header",
        "implausible_timing",
        "implausible_position",
    }
)
MIN_FRAME_INTERVAL_S = 1e-3  # frames closer than this (over 1000 Hz) are no camera or mocap recording
# a file's times are sums of float64 steps, so two times 1 ms apart on a millisecond clock (a browser's: 5.123 ->
# 5.124 s) read back 0.000999999999999 s apart in half the cases: such frames are MIN_FRAME_INTERVAL_S apart
TIME_ROUNDING_S = 1e-9
MAX_MEDIAN_INTERVAL_S = 1.0  # nor frames usually further apart than this (under 1 Hz)
ANGLE_SD_STEP_DEG = 0.1  # quantum of the stored angle SDs, degrees (0.01: 1.8x the bytes, 213 vs 118 kB on 10 min)
ANGLE_SD_MISSING = 65535  # stored code of an undefined SD; larger SDs are stored as the largest finite code
PLAUSIBLE_ABS_M = 50.0  # no depth camera (under 10 m) or motion-capture room puts a joint further from its origin


@dataclass
class SessionPayload:
    """One exercise session as uploaded: the raw recording, optionally the filtered one, and filter params.

    raw, filtered: Recording on the 20-joint model (t (T,) s, positions (T, J, 3) m camera frame, state (T, J)).
    params: JSON-ready dict (e.g. filter settings). created_at: ISO 8601 UTC.
    recorded_by: {"device_id": int, "patient_id": int} of the paired home agent that recorded the session (the
    server stores the file for that patient only, through that device or a user), or None for files of other origin.
    angle_sd: {angle of ANGLE_NAMES: (T,) degrees, NaN = undefined}, the per-frame SD of the filtered recording's
    clinical angles (pipeline.PipelineResult.angle_sd), stored to ANGLE_SD_STEP_DEG; None when not known.
    """

    session_id: str
    raw: Recording
    filtered: Recording | None = None
    params: dict[str, Any] = field(default_factory=dict)
    created_at: str = field(default_factory=utc_now_iso)
    recorded_by: dict[str, int] | None = None
    angle_sd: dict[str, np.ndarray] | None = None


class SessionFileError(FormatError):
    """A session file is invalid; `code` names the reason (one of ERROR_CODES)."""

    def __init__(self, code: str, message: str, path: str | Path | None = None) -> None:
        if code not in ERROR_CODES:
            raise ValueError(f"unknown session file error code {code!r}")
        self.code = code
        self.detail = message
        super().__init__(path, f"{code}: {message}")


def sniff(path: Path, head: bytes) -> bool:
    """True when the file starts with the session-file magic bytes."""
    return head.startswith(MAGIC)


def content_hash(data: bytes) -> str:
    """Returns the SHA-256 of `data` as 64 lowercase hex digits."""
    return hashlib.sha256(data).hexdigest()


# ---------------------------------------------------------------------------------------------- encode


def encode(payload: SessionPayload) -> bytes:
    """Returns the session file bytes for `payload`; raises ValueError for unstorable data."""
    recordings = {"raw": payload.raw, "filtered": payload.filtered}
    blocks: list[bytes] = []
    described: dict[str, Any] = {}
    for name, rec in recordings.items():
        if rec is None:
            described[name] = None
            continue
        described[name] = {"n_frames": rec.n_frames, "n_joints": skeleton.J, "meta": rec.meta.to_dict()}
        blocks += [_compress(b) for b in _recording_blocks(rec)]
    header = {
        "format": "kinect-home-session",
        "session_id": payload.session_id,
        "created_at": payload.created_at,
        "params": payload.params,
        "joints": list(skeleton.JOINTS),
        "grid_m": GRID_M,
        "codec": CODEC,
        "recordings": described,
    }
    if payload.recorded_by is not None:
        _check_recorded_by(payload.recorded_by)
        header["recorded_by"] = payload.recorded_by
    if payload.angle_sd is not None:
        names, block = _angle_sd_block(payload)
        header["angle_sd"] = {"names": names, "step_deg": ANGLE_SD_STEP_DEG}
        blocks.append(_compress(block))
    header_bytes = json.dumps(header, separators=(",", ":"), allow_nan=False).encode("utf-8")
    body = b"".join(_BLOCK_LEN.pack(len(b)) + b for b in blocks)
    total = _FIXED.size + len(header_bytes) + len(body) + _DIGEST
    data = _FIXED.pack(MAGIC, VERSION, 0, len(header_bytes), total) + header_bytes + body
    return data + hashlib.sha256(data).digest()


def _recording_blocks(rec: Recording) -> tuple[bytes, bytes, bytes]:
    """Returns the uncompressed (t, state, positions) blocks of one recording."""
    t = rec.t.astype("<f8")
    dt = np.concatenate([t[:1], np.diff(t)]).astype("<f8")
    state = rec.state.astype(np.int8)
    return _shuffle(dt), state.tobytes(), _shuffle(_position_deltas(rec.positions, state))


def _angle_sd_block(payload: SessionPayload) -> tuple[list[str], bytes]:
    """Returns the angle names (ANGLE_NAMES order) and the uncompressed SD block; ValueError for unstorable SDs."""
    sd = payload.angle_sd or {}
    if payload.filtered is None:
        raise ValueError("angle_sd describes the filtered recording, and the payload has none")
    unknown = sorted(set(sd) - set(ANGLE_NAMES))
    if unknown:
        raise ValueError(f"angle_sd has unknown angles {unknown}; known: {', '.join(ANGLE_NAMES)}")
    names = [n for n in ANGLE_NAMES if n in sd]
    T = payload.filtered.n_frames
    rows = []
    for name in names:
        v = np.asarray(sd[name], dtype=np.float64)
        if v.shape != (T,):
            raise ValueError(f"angle_sd[{name!r}] must have shape ({T},) like the filtered recording, got {v.shape}")
        if np.any(v < 0):
            raise ValueError(f"angle_sd[{name!r}] must be >= 0 degrees")
        with np.errstate(invalid="ignore"):
            code = np.rint(np.minimum(v, (ANGLE_SD_MISSING - 1) * ANGLE_SD_STEP_DEG) / ANGLE_SD_STEP_DEG)
        rows.append(np.where(np.isfinite(v), code, ANGLE_SD_MISSING).astype("<u2"))
    block = np.stack(rows) if rows else np.zeros((0, T), "<u2")
    return names, _shuffle(block)


def on_grid(positions: np.ndarray) -> np.ndarray:
    """Returns positions (any shape) m rounded to the grid a written file stores them on (NaN stays NaN): what a
    reader of the file gets back, for a live path that must see the same numbers as the stored file."""
    return np.rint(np.asarray(positions, dtype=np.float64) / GRID_M) * GRID_M


def as_stored(rec: Recording) -> Recording:
    """Returns the recording as a written file gives it back (decode of encode, without compressing): times (T,) s
    summed from their float64 deltas, positions (T, J, 3) m on the file's grid with untracked ones NaN, states and
    metadata as stored. A pipeline filters this, not the recording in memory, so the server filtering a stored
    file's raw recording again with the same settings gets the file's filtered recording bit for bit. Raises
    ValueError (encode's) for data no file can hold, SessionFileError for data no file may hold."""
    meta = Metadata.from_dict(json.loads(json.dumps(rec.meta.to_dict(), allow_nan=False)))
    return _build_recording("raw", rec.n_frames, list(_recording_blocks(rec)), meta, VERSION)


def _position_deltas(positions: np.ndarray, state: np.ndarray) -> np.ndarray:
    """Returns (J, 3, T) int32 time deltas of positions in grid units; untracked positions count as 0.

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked. state: (T, J) int8.
    """
    p = np.where((state != skeleton.NOT_TRACKED)[..., None], positions, 0.0)
    if not np.all(np.isfinite(p)):
        raise ValueError("positions must be finite wherever state is not 0")
    if np.any(np.abs(p) > MAX_ABS_M):
        raise ValueError(f"positions must lie within +-{MAX_ABS_M} m to be stored on the {GRID_M} m grid")
    units = np.rint(p / GRID_M).astype(np.int64)  # (T, J, 3) grid units, |units| <= 2**20
    series = np.ascontiguousarray(units.transpose(1, 2, 0))  # (J, 3, T)
    return np.diff(series, axis=-1, prepend=0).astype("<i4")  # |delta| <= 2**21


def _shuffle(a: np.ndarray) -> bytes:
    """Returns the bytes of `a` regrouped into planes: every element's byte 0, then byte 1, ..."""
    width = a.dtype.itemsize
    return np.ascontiguousarray(a).view(np.uint8).reshape(-1, width).T.tobytes()


def _unshuffle(raw: bytes, dtype: str) -> np.ndarray:
    width = np.dtype(dtype).itemsize
    planes = np.frombuffer(raw, dtype=np.uint8).reshape(width, -1)
    return np.ascontiguousarray(planes.T).view(dtype).ravel()


def _compress(raw: bytes) -> bytes:
    """Returns `raw` as one xz stream (LZMA2 at _XZ_PRESET, no integrity check: the trailer has SHA-256)."""
    return lzma.compress(raw, format=lzma.FORMAT_XZ, check=lzma.CHECK_NONE, preset=_XZ_PRESET)


# ---------------------------------------------------------------------------------------------- decode


def decode(data: bytes, *, max_frames: int = 30 * 60 * 60, max_decoded_bytes: int = 64 * 2**20) -> SessionPayload:
    """Checks and decodes session file bytes; raises SessionFileError with a `code` on any defect.

    Everything is validated before arrays are built; decompression never produces more than
    `max_decoded_bytes` in total, nor more than a block's declared size (compression bombs).
    """
    data = bytes(data)
    version, header_len = _check_envelope(data)
    header = _parse_header(data[_FIXED.size : _FIXED.size + header_len], version)
    specs = _recording_specs(header, max_frames, max_decoded_bytes)
    sd_names = _angle_sd_names(header, specs, max_decoded_bytes)
    blocks = _split_blocks(data, _FIXED.size + header_len, 3 * len(specs) + (sd_names is not None))
    budget = [max_decoded_bytes]
    inflate = _inflate_zlib if version == 1 else _inflate_xz
    recordings: dict[str, Recording] = {}
    for k, (name, n_frames, meta) in enumerate(specs):
        raw = [inflate(blocks[3 * k + i], size, budget) for i, size in enumerate(_block_sizes(n_frames))]
        recordings[name] = _build_recording(name, n_frames, raw, meta, version)
    angle_sd = None
    if sd_names is not None:
        T = recordings["filtered"].n_frames
        raw_sd = inflate(blocks[-1], 2 * len(sd_names) * T, budget)
        codes = _unshuffle(raw_sd, "<u2").reshape(len(sd_names), T) if sd_names else np.zeros((0, T), "<u2")
        values = np.where(codes == ANGLE_SD_MISSING, np.nan, codes * ANGLE_SD_STEP_DEG)
        angle_sd = {name: values[k] for k, name in enumerate(sd_names)}
    return SessionPayload(
        session_id=header["session_id"],
        raw=recordings["raw"],
        filtered=recordings.get("filtered"),
        params=header["params"],
        created_at=header["created_at"],
        recorded_by=header.get("recorded_by"),
        angle_sd=angle_sd,
    )


def _angle_sd_names(
    header: dict[str, Any], specs: list[tuple[str, int, Metadata]], max_decoded_bytes: int
) -> list[str] | None:
    """Returns the angle names of the optional angle SD block, or None without one, after checking its header."""
    desc = header.get("angle_sd")
    if desc is None:
        return None
    names = desc.get("names") if isinstance(desc, dict) else None
    if not isinstance(names, list) or not all(isinstance(n, str) and n in ANGLE_NAMES for n in names):
        raise SessionFileError("bad_header", f"angle_sd needs 'names', a list of angles among {', '.join(ANGLE_NAMES)}")
    if len(set(names)) != len(names) or desc.get("step_deg") != ANGLE_SD_STEP_DEG:
        raise SessionFileError("bad_header", f"angle_sd needs distinct names and step_deg {ANGLE_SD_STEP_DEG}")
    frames = {name: n for name, n, _ in specs}
    if "filtered" not in frames:
        raise SessionFileError("bad_header", "angle_sd describes the filtered recording, and the file has none")
    total = sum(sum(_block_sizes(n)) for n in frames.values()) + 2 * len(names) * frames["filtered"]
    if total > max_decoded_bytes:
        raise SessionFileError("too_large", f"the blocks decode to {total} bytes, the limit is {max_decoded_bytes}")
    return names


def _magic_hint(data: bytes) -> str:
    """Says what a file without the magic most likely is, when it can tell."""
    if data.startswith(b"\x1f\x8b"):
        return ": gzip data; send the .khs file itself, not compressed"
    if data.startswith((b"\x89KHS\r\r\n", b"\x89KHS\n")):
        return ": its line ends were converted (a text-mode transfer); copy the file as binary"
    if data.startswith(b"\xef\xbb\xbf") or data[:8].isascii():
        return ": text, not a session file (kinect-agent convert makes one from a recording)"
    return ""


def _check_envelope(data: bytes) -> tuple[int, int]:
    """Checks magic, version, length and checksum; returns the version and the JSON header length in bytes."""
    if len(data) < len(MAGIC):
        if MAGIC.startswith(data) and data:
            raise SessionFileError("truncated", f"file is {len(data)} bytes, shorter than the magic")
        raise SessionFileError("bad_magic", f"expected magic {MAGIC!r}, found {data[:8]!r}")
    if not data.startswith(MAGIC):
        raise SessionFileError("bad_magic", f"expected magic {MAGIC!r}, found {data[:8]!r}{_magic_hint(data)}")
    if len(data) < _FIXED.size + _DIGEST:
        raise SessionFileError("truncated", f"file is {len(data)} bytes, less than the {_FIXED.size + _DIGEST} minimum")
    _, version, _, header_len, total = _FIXED.unpack_from(data)
    if version not in _FORMATS:
        raise SessionFileError("unsupported_version", f"file version {version}, this reader knows versions 1 and 2")
    if len(data) < total:
        raise SessionFileError("truncated", f"file is {len(data)} bytes, its header declares {total}")
    if len(data) > total:
        raise SessionFileError("bad_header", f"file is {len(data)} bytes, its header declares only {total}")
    if hashlib.sha256(data[:-_DIGEST]).digest() != data[-_DIGEST:]:
        raise SessionFileError("checksum_mismatch", "SHA-256 trailer does not match the content")
    if _FIXED.size + header_len > total - _DIGEST:
        raise SessionFileError("bad_header", f"JSON header length {header_len} runs past the end of the file")
    return version, header_len


def _refuse_constant(name: str) -> None:
    raise SessionFileError("bad_header", f"JSON header holds {name}, which JSON does not allow")


def _parse_header(raw: bytes, version: int) -> dict[str, Any]:
    try:
        header = json.loads(raw.decode("utf-8"), parse_constant=_refuse_constant)
    except RecursionError:
        raise SessionFileError("bad_header", "JSON header is nested too deeply") from None
    except (UnicodeDecodeError, ValueError) as exc:
        if isinstance(exc, SessionFileError):
            raise
        raise SessionFileError("bad_header", f"JSON header is unreadable: {exc}") from None
    expected = {"session_id": str, "created_at": str, "params": dict, "recordings": dict, "joints": list}
    for key, kind in expected.items():
        if not isinstance(header, dict) or not isinstance(header.get(key), kind):
            raise SessionFileError("bad_header", f"JSON header needs {key!r} of type {kind.__name__}")
    codec, grid_m = _FORMATS[version]
    if header.get("format") != "kinect-home-session" or header.get("codec") != codec or header.get("grid_m") != grid_m:
        raise SessionFileError(
            "bad_header", f"version {version} needs format 'kinect-home-session', codec {codec!r}, grid_m {grid_m}"
        )
    if not isinstance(header["recordings"].get("raw"), dict):
        raise SessionFileError("bad_header", "JSON header lacks the 'raw' recording")
    _check_recorded_by(header.get("recorded_by", None))
    return header


def _check_recorded_by(value: Any) -> None:
    """Checks the optional recorded_by: absent, or exactly {"device_id": int >= 1, "patient_id": int >= 1}."""
    if value is None:
        return
    ok = isinstance(value, dict) and set(value) == {"device_id", "patient_id"}
    if not ok or not all(type(v) is int and v >= 1 for v in value.values()):
        raise SessionFileError(
            "bad_header", 'recorded_by must be {"device_id": <id>, "patient_id": <id>} with positive whole numbers'
        )


def _recording_specs(
    header: dict[str, Any], max_frames: int, max_decoded_bytes: int
) -> list[tuple[str, int, Metadata]]:
    """Returns (name, n_frames, metadata) of each stored recording after checking their sizes."""
    if len(header["joints"]) != skeleton.J or tuple(header["joints"]) != skeleton.JOINTS:
        raise SessionFileError("wrong_joint_count", f"joint list has {len(header['joints'])} joints, expected the 20")
    specs, total = [], 0
    for name in ("raw", "filtered"):
        desc = header["recordings"].get(name)
        if desc is None:
            continue
        if not isinstance(desc, dict) or type(desc.get("n_frames")) is not int:
            raise SessionFileError("bad_header", f"recording {name!r} needs an integer 'n_frames'")
        if desc.get("n_joints") != skeleton.J:
            raise SessionFileError("wrong_joint_count", f"recording {name!r} has {desc.get('n_joints')} joints, not 20")
        n = desc["n_frames"]
        if n <= 0:
            raise SessionFileError("no_frames", f"recording {name!r} has {n} frames")
        if n > max_frames:
            raise SessionFileError("too_long", f"recording {name!r} has {n} frames, the limit is {max_frames}")
        total += sum(_block_sizes(n))
        meta = desc.get("meta") or {}
        if not isinstance(meta, dict):
            raise SessionFileError("bad_header", f"recording {name!r} metadata must be an object")
        try:
            meta = Metadata.from_dict(meta)
        except (TypeError, ValueError) as exc:
            raise SessionFileError("bad_header", f"recording {name!r} metadata: {exc}") from None
        specs.append((name, n, meta))
    if total > max_decoded_bytes:
        raise SessionFileError("too_large", f"recordings decode to {total} bytes, the limit is {max_decoded_bytes}")
    return specs


def _block_sizes(n_frames: int) -> tuple[int, int, int]:
    """Decoded bytes of the t, state and positions blocks (4-byte position deltas in both versions)."""
    return 8 * n_frames, skeleton.J * n_frames, 4 * 3 * skeleton.J * n_frames


def _split_blocks(data: bytes, start: int, count: int) -> list[bytes]:
    """Returns the `count` length-prefixed blocks between the JSON header and the trailer."""
    end, pos, blocks = len(data) - _DIGEST, start, []
    for i in range(count):
        if pos + _BLOCK_LEN.size > end:
            raise SessionFileError("bad_header", f"block {i} length lies past the end of the data")
        (n,) = _BLOCK_LEN.unpack_from(data, pos)
        pos += _BLOCK_LEN.size
        if pos + n > end:
            raise SessionFileError("bad_header", f"block {i} of {n} bytes runs past the end of the data")
        blocks.append(data[pos : pos + n])
        pos += n
    if pos != end:
        raise SessionFileError("bad_header", f"{end - pos} unexpected bytes after the last block")
    return blocks


def _inflate_zlib(block: bytes, size: int, budget: list[int]) -> bytes:
    """Inflates one version-1 zlib block to exactly `size` bytes, never producing more than size+1 or the budget."""
    cap = min(size, budget[0])
    d = zlib.decompressobj()
    try:
        out = d.decompress(block, cap + 1)
    except zlib.error as exc:
        raise SessionFileError("bad_header", f"corrupt zlib block: {exc}") from None
    _check_inflated(out, size, cap, d.eof and not d.unconsumed_tail and not d.unused_data, budget)
    return out


def _inflate_xz(block: bytes, size: int, budget: list[int]) -> bytes:
    """Decompresses one version-2 xz block to exactly `size` bytes, never producing more than size+1 or the budget.

    The decoder's memory is capped at _XZ_MEMLIMIT (a stream asking for a larger dictionary is refused).
    """
    cap = min(size, budget[0])
    d = lzma.LZMADecompressor(format=lzma.FORMAT_XZ, memlimit=_XZ_MEMLIMIT)
    try:
        out = d.decompress(block, max_length=cap + 1)
    except lzma.LZMAError as exc:
        if "memory" in str(exc).lower():
            raise SessionFileError("too_large", f"xz block needs more than {_XZ_MEMLIMIT} bytes of memory") from None
        raise SessionFileError("bad_header", f"corrupt xz block: {exc}") from None
    _check_inflated(out, size, cap, d.eof and not d.unused_data, budget)
    return out


def _check_inflated(out: bytes, size: int, cap: int, complete: bool, budget: list[int]) -> None:
    """Refuses a block that inflated past `cap`, or that is not exactly `size` bytes of one complete stream."""
    if len(out) > cap:
        limit = "its declared size" if cap == size else "the remaining max_decoded_bytes budget"
        raise SessionFileError("too_large", f"a block decodes to more than {cap} bytes ({limit})")
    if len(out) != size:
        raise SessionFileError("bad_header", f"a block decodes to {len(out)} bytes, expected {size}")
    if not complete:
        raise SessionFileError("bad_header", "a block's compressed stream is cut short or followed by other data")
    budget[0] -= len(out)


def _build_recording(name: str, n_frames: int, raw: list[bytes], meta: Metadata, version: int) -> Recording:
    """Turns decoded t, state and position blocks into a Recording after checking them."""
    with np.errstate(invalid="ignore", over="ignore"):  # non-finite sums are refused just below
        t = np.cumsum(_unshuffle(raw[0], "<f8"))
    state = np.frombuffer(raw[1], dtype=np.int8).reshape(n_frames, skeleton.J).copy()
    if not np.all(np.isfinite(t)):  # times and states first: a bad file is refused before positions take memory
        raise SessionFileError("non_finite", f"recording {name!r}: time stamps are not finite")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise SessionFileError("non_monotonic_time", f"recording {name!r}: frame {i} t={t[i]} after t={t[i - 1]}")
    _check_timing(name, t)
    if np.any((state < 0) | (state > 2)):
        raise SessionFileError("bad_header", f"recording {name!r}: state values must be 0, 1 or 2")
    positions = _positions(raw[2], n_frames, version)
    tracked = state != skeleton.NOT_TRACKED
    if not np.isfinite(positions).all() and not np.all(np.isfinite(positions[tracked])):  # cheap check first
        f, j = np.argwhere(tracked & ~np.all(np.isfinite(positions), axis=-1))[0]
        raise SessionFileError("non_finite", f"recording {name!r}: frame {f} joint {skeleton.JOINTS[j]} not finite")
    positions[~tracked] = np.nan
    _check_positions(name, positions)
    return Recording(t, positions, state, meta)


def _check_positions(name: str, positions: np.ndarray) -> None:
    """Refuses joint positions (T, J, 3) m, NaN = untracked, further than PLAUSIBLE_ABS_M from the origin."""
    with np.errstate(invalid="ignore"):
        far = np.abs(positions) > PLAUSIBLE_ABS_M
    if far.any():
        f, j, axis = (int(i) for i in np.argwhere(far)[0])
        raise SessionFileError(
            "implausible_position",
            f"recording {name!r}: frame {f} joint {skeleton.JOINTS[j]} at {'xyz'[axis]} = {positions[f, j, axis]:.6g}"
            f" m; a depth camera or motion capture sees at most {PLAUSIBLE_ABS_M:g} m from its origin",
        )


def _check_timing(name: str, t: np.ndarray) -> None:
    """Refuses frame times no recording device makes: t (T,) s, strictly increasing. The analysis sizes its
    filters from the frame interval, so such files would also cost unbounded time."""
    if t.shape[0] < 2:
        return
    dt = np.diff(t)
    closest, median = float(dt.min()), float(np.median(dt))
    if closest < MIN_FRAME_INTERVAL_S - TIME_ROUNDING_S:
        raise SessionFileError("implausible_timing", f"recording {name!r}: frames {closest:.3g} s apart; a camera "
                               f"or motion capture gives at least {MIN_FRAME_INTERVAL_S:g} s (1000 Hz)")  # fmt: skip
    if median > MAX_MEDIAN_INTERVAL_S:
        raise SessionFileError("implausible_timing", f"recording {name!r}: frames {median:.3g} s apart (median); "
                               f"at most {MAX_MEDIAN_INTERVAL_S:g} s expected")  # fmt: skip


def _positions(raw: bytes, n_frames: int, version: int) -> np.ndarray:
    """Returns (T, J, 3) float64 positions, metres, C-contiguous, from a decoded positions block.

    Version 2: int32 grid-unit deltas, summed exactly in int64, then scaled by the grid.
    Version 1: float32 deltas in metres, summed in float64 (the version-1 definition).
    Sums run over frames with (J*3)-vectors as rows, which is fast; no per-frame Python loop.
    """
    if version == 1:
        deltas = _unshuffle(raw, "<f4").reshape(skeleton.J, 3, n_frames)  # (J, 3, T) float32 m
        positions = deltas.transpose(2, 0, 1).astype(np.float64, order="C")  # (T, J, 3) deltas
        np.cumsum(positions, axis=0, out=positions)
        return positions
    deltas = _unshuffle(raw, "<i4").reshape(skeleton.J, 3, n_frames)  # (J, 3, T) int32 grid units
    units = deltas.transpose(2, 0, 1).astype(np.int64, order="C")  # (T, J, 3) deltas; sums cannot overflow
    np.cumsum(units, axis=0, out=units)
    positions = units.astype(np.float64)
    positions *= GRID_M  # exact: |units| < 2**53
    return positions


# ---------------------------------------------------------------------------------------------- files


def read_payload(path: str | Path) -> SessionPayload:
    """Reads and checks a session file; errors name the file."""
    path = Path(path)
    try:
        return decode(path.read_bytes())
    except SessionFileError as exc:
        raise SessionFileError(exc.code, exc.detail, path) from None


def write_payload(payload: SessionPayload, path: str | Path) -> None:
    """Writes `payload` to `path` atomically."""
    data = encode(payload)
    with atomic_open(path, "wb") as f:
        f.write(data)


def read(path: Path) -> Recording:
    """Returns the raw recording of a session file."""
    return read_payload(path).raw


def write(rec: Recording, path: Path) -> None:
    """Writes `rec` as the raw recording of a new session (random uuid4 session id)."""
    write_payload(SessionPayload(session_id=str(uuid.uuid4()), raw=rec), path)
