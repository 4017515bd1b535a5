"""Malformed and hostile session-file uploads against the real app: each must be a 4xx within 2 s, storing nothing.

Replays the fixed catalogue of defective files (DEFECTS, tests/backend/khs_files.py) and randomised attack families
(truncation, bit flips, wrong checksums, non-finite or backward times, absurd counts and frame intervals, oversized
bodies, compression bombs, wrong JSON types, garbage, a file recorded for another patient) through
POST /api/v1/sessions with FastAPI's TestClient, on a migrated empty database holding two patients, each with a
paired device. After every case the exercise_session rows of both patients are counted (must stay 0; a case that
stored something is a failure and its rows are deleted so the next case starts clean). At the end one valid file
is uploaded: it must be 201 and stored, which shows that the harness can store. Then the family "file chooses the
work" (bench/attack_work.py): accepted files whose params["config"], frame rate or duration would set the server's
work; each request (upload, detail, replay) is measured against the CPU and memory budget of
backend.session_texts.work_budget and fails above it or on a 5xx.

    python bench/attack.py [--quick] [--json OUT] [--db URL ...] [--seeds N] [--first-seed S] [--families F]

--db: may be given several times; default an embedded SQLite file in a temp folder, plus PostgreSQL at
DEFAULT_PG (in a schema of its own, dropped at the end) if it answers. Case generation is deterministic per seed
(seeds S .. S+N-1, default 0, 1, 2; --quick: seed S only and fewer random cases per family). The compression bombs
are made once and cached in the temp folder. Exit status 1 if any case failed (not 4xx, over 2 s, or anything
stored) or the valid file was not stored, else 0.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import lzma
import random
import sys
import tempfile
import time
import uuid
import zlib
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import httpx
    from fastapi.testclient import TestClient
    from sqlalchemy import Engine

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/attack.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from bench.attack_work import jobs_runner, print_work, run_work_case, work_cases  # noqa: E402
from bench.ingest import db_label, make_app, open_engine  # noqa: E402
from kinect_agent.formats import session_file as sf  # noqa: E402
from tests.backend import khs_files  # noqa: E402
from tests.backend.khs_files import DEFECTS, join, join_text, make_khs, n_frames, split, with_header  # noqa: E402

DEFAULT_PG = "postgresql+psycopg://postgres@127.0.0.1:5432/test"
URL = "/api/v1/sessions"
LIMIT_S = 2.0  # every case must be answered within this
BOMB_BYTES = 200 * 2**20  # the xz bomb inflates to this (its blocks declare a few kB)
ZLIB_BOMB_BYTES = 64 * 2**20  # the version-1 (zlib) bomb
BIG_DICT_MIB = (48, 64)  # xz dictionaries whose decoder needs more than the server's 32 MiB memory limit
TEN_GB = 10 * 10**9
CREATED_AT = "2025-06-01T10:00:00Z"  # base files: a valid start time (after 2000, before tomorrow)
BASE_EXERCISES = ("squat", "sit_to_stand", "elbow_flexion", "shoulder_abduction")  # in simulator and library
BLOCK_NAMES = ("raw t", "raw state", "raw positions", "filtered t", "filtered state", "filtered positions")
FAMILIES = (
    "defects",
    "truncated",
    "bit_flip",
    "block_bit_flip",
    "wrong_checksum",
    "nan_inf_time",
    "declared_counts",
    "frame_interval",
    "time_backwards",
    "oversized_body",
    "compression_bomb",
    "header_types",
    "garbage",
    "wrong_owner",
    "late_defect",
)
RANDOM_CASES = 12  # per randomised family (truncated, bit flips, garbage) and seed (--quick: 2)
INVALID = "InvalidSessionFile"
Users = dict[str, tuple[int, int, dict[str, str]]]  # "A" and "B": (device id, patient id, upload headers)


@dataclass
class Case:
    """One upload: body (bytes, or a callable making the bytes or an iterator of chunks, streamed without a
    Content-Length), extra headers and query, the device that sends it ("A" or "B"), and what the answer should
    name (informative: any 4xx within LIMIT_S storing nothing passes): error names or detail prefixes."""

    family: str
    name: str
    body: bytes | Callable[[], bytes | Iterator[bytes]]
    headers: dict[str, str] = field(default_factory=dict)
    params: dict[str, int | str] = field(default_factory=dict)
    device: str = "A"
    expect: tuple[str, ...] = ()
    seed: int | None = None

    def fingerprint(self) -> str:
        """Returns a digest of what is sent (lazy bodies: their name, which holds their random parameters)."""
        body = self.body if isinstance(self.body, bytes) else self.name.encode()
        return hashlib.sha256(self.family.encode() + b"\0" + body + repr(self.headers).encode()).hexdigest()


@dataclass(frozen=True)
class Context:
    """What case generation needs: the ids of device and patient A (wrong_owner: files recorded by A, sent by
    B), the server's upload and frame limits, and the folder caching the compression bombs."""

    device_a: int
    patient_a: int
    device_b: int
    patient_b: int
    max_upload_bytes: int
    max_frames: int
    cache_dir: Path


# ---------------------------------------------------------------------------------------------- building blocks


def base_file(seed: int) -> bytes:
    """Returns the seed's valid file: a simulated set (exercise, reps, noise, session id drawn from the seed)."""
    rng = random.Random(f"base-{seed}")
    sid = str(uuid.UUID(int=rng.getrandbits(128), version=4))
    return make_khs(rng.choice(BASE_EXERCISES), rng.randint(2, 4), seed=seed, session_id=sid, created_at=CREATED_AT)


def _cached(cache_dir: Path, name: str, make: Callable[[], bytes]) -> bytes:
    path = cache_dir / name
    if path.exists() and path.stat().st_size > 0:
        return path.read_bytes()
    data = make()
    tmp = path.with_suffix(f".{uuid.uuid4().hex}.tmp")
    tmp.write_bytes(data)
    tmp.replace(path)
    return data


def xz_bomb(cache_dir: Path) -> bytes:
    """Returns one xz stream (no check, as the format's) of BOMB_BYTES zero bytes: about 30 kB; cached."""
    make = lambda: lzma.compress(bytes(BOMB_BYTES), format=lzma.FORMAT_XZ, check=lzma.CHECK_NONE, preset=1)  # noqa: E731
    return _cached(cache_dir, f"khc-bench-attack-xz-{BOMB_BYTES >> 20}MiB-zeros.xz", make)


def zlib_bomb(cache_dir: Path) -> bytes:
    """Returns one zlib stream of ZLIB_BOMB_BYTES zero bytes (about 64 kB); cached."""
    make = lambda: zlib.compress(bytes(ZLIB_BOMB_BYTES), 9)  # noqa: E731
    return _cached(cache_dir, f"khc-bench-attack-zlib-{ZLIB_BOMB_BYTES >> 20}MiB-zeros.z", make)


def _raw_blocks(data: bytes) -> list[bytes]:
    """Returns the decompressed blocks of a valid version-2 file."""
    return [lzma.decompress(b, format=lzma.FORMAT_XZ) for b in split(data)[2]]


def _flip_bit(data: bytes, index: int, bit: int) -> bytes:
    return data[:index] + bytes([data[index] ^ (1 << bit)]) + data[index + 1 :]


def _time_block(t: np.ndarray) -> bytes:
    """Returns the uncompressed time block of times t (T,) s: byte-shuffled float64 deltas."""
    t = np.asarray(t, dtype="<f8")
    return sf._shuffle(np.concatenate([t[:1], np.diff(t)]).astype("<f8"))


def _times(data: bytes, t: np.ndarray, recording: str = "raw") -> bytes:
    """Returns the file with the times of one recording replaced by t (checksum recomputed)."""
    index = 0 if recording == "raw" else 3
    return khs_files.with_block(data, index, _time_block(t))


def _header_set(path: tuple[str, ...], value: object) -> Callable[[dict[str, Any]], None]:
    """Returns a change setting header[path[0]][path[1]]... = value."""

    def change(header: dict[str, Any]) -> None:
        node = header
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value

    return change


def _region(data: bytes, index: int) -> str:
    """Names the part of a valid file that byte `index` lies in."""
    header_len = sf._FIXED.unpack_from(data)[3]
    regions = (
        (8, "magic"),
        (10, "version"),
        (12, "flags"),
        (16, "header length"),
        (24, "total length"),
        (24 + header_len, "JSON header"),
        (len(data) - 32, "blocks"),
        (len(data), "trailer"),
    )
    return next(name for end, name in regions if index < end)


# ---------------------------------------------------------------------------------------------- families


def defect_cases(ctx: Context) -> list[Case]:
    """The fixed catalogue DEFECTS applied to one valid file (3 simulated squats, as the upload tests use)."""
    data = make_khs("squat", 3, seed=1, created_at=CREATED_AT)
    return [Case("defects", name, corrupt(data), expect=(detail,)) for name, (corrupt, detail) in DEFECTS.items()]


def _truncated(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Cut at random points, the first ones in distinct parts of the file (magic, fixed header, JSON, blocks...)."""
    header_len = sf._FIXED.unpack_from(data)[3]
    spans = [(0, 8), (8, 24), (24, 24 + header_len), (24 + header_len, len(data) - 32), (len(data) - 32, len(data))]
    rng.shuffle(spans)
    cuts = [rng.randrange(*spans[i]) if i < len(spans) else rng.randrange(len(data)) for i in range(n)]
    return [
        Case(
            "truncated",
            f"first {k} of {len(data)} bytes (cut in the {_region(data, k)})",
            data[:k],
            expect=("truncated", "bad_magic"),
        )
        for k in cuts
    ]


def _bit_flip_expect(data: bytes, index: int, bit: int) -> tuple[str, ...]:
    region = _region(data, index)
    if region == "magic":
        return ("bad_magic",)
    if region == "version":
        return ("unsupported_version",)
    if region == "total length":
        return ("truncated", "bad_header")  # longer or shorter than declared: found before the checksum
    return ("checksum_mismatch",)


def _bit_flip(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """One bit flipped anywhere; the SHA-256 trailer (or the envelope checks before it) must catch it."""
    cases = []
    for _ in range(n):
        index, bit = rng.randrange(len(data)), rng.randrange(8)
        cases.append(
            Case(
                "bit_flip",
                f"byte {index} bit {bit} ({_region(data, index)})",
                _flip_bit(data, index, bit),
                expect=_bit_flip_expect(data, index, bit),
            )
        )
    return cases


def _block_bit_flip(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """One bit flipped inside a compressed block, trailer recomputed: the decoder must find the damage."""
    version, header, blocks = split(data)
    cases = []
    for _ in range(n):
        k = rng.randrange(len(blocks))
        index, bit = rng.randrange(len(blocks[k])), rng.randrange(8)
        changed = list(blocks)
        changed[k] = _flip_bit(blocks[k], index, bit)
        name = f"block {k} ({BLOCK_NAMES[k]}) byte {index} of {len(blocks[k])} bit {bit}"
        cases.append(Case("block_bit_flip", name, join(header, changed, version), expect=(INVALID,)))
    return cases


def _wrong_checksum(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Trailers that are not the SHA-256 of the content."""
    body, digest = data[:-32], data[-32:]
    bit = rng.randrange(256)
    other = base_file(rng.randrange(10**6, 2 * 10**6))[-32:]
    variants = {
        "random trailer": rng.randbytes(32),
        "zero trailer": bytes(32),
        f"digest with bit {bit} flipped": _flip_bit(digest, bit // 8, bit % 8),
        "another file's trailer": other,
        "SHA-256 of the content after the fixed header": hashlib.sha256(body[24:]).digest(),
        "SHA-256 as hex text (first 32 characters)": hashlib.sha256(body).hexdigest()[:32].encode(),
        "SHA-256 of the whole file incl. trailer": hashlib.sha256(data).digest(),
    }
    return [
        Case("wrong_checksum", name, body + trailer, expect=("checksum_mismatch",))
        for name, trailer in variants.items()
    ]


def _nan_inf_time(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """NaN or infinite time stamps (version-2 positions are integers: only times can be non-finite)."""
    frames = n_frames(data)
    t = np.arange(frames) / 30.0
    k = rng.randrange(frames)

    def at(value: float, index: int = k, recording: str = "raw") -> bytes:
        changed = t.copy()
        changed[index] = value
        return _times(data, changed, recording)

    variants = {
        f"NaN at frame {k}": at(np.nan),
        f"+inf at frame {k}": at(np.inf),
        f"-inf at frame {k}": at(-np.inf),
        "NaN at frame 0": at(np.nan, 0),
        f"+inf at the last frame {frames - 1}": at(np.inf, frames - 1),
        "all NaN": _times(data, np.full(frames, np.nan)),
        f"NaN at frame {k} of the filtered recording": at(np.nan, recording="filtered"),
        "deltas of 1e308 (sum overflows to inf)": khs_files.with_block(
            data, 0, sf._shuffle(np.full(frames, 1e308, dtype="<f8"))
        ),
    }
    return [Case("nan_inf_time", name, body, expect=("non_finite",)) for name, body in variants.items()]


def _declared_counts(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Declared frame and joint counts that are absurd or do not match the blocks."""
    frames = n_frames(data)
    other = rng.choice([f for f in range(1, 3 * frames) if f != frames])

    def raw(key: str, value: object) -> bytes:
        return with_header(data, _header_set(("recordings", "raw", key), value))

    variants = {
        "n_frames 10**9": (raw("n_frames", 10**9), ("too_long",)),
        "n_frames 2**64": (raw("n_frames", 2**64), ("too_long",)),
        "n_frames -1": (raw("n_frames", -1), ("no_frames",)),
        "n_frames 0": (raw("n_frames", 0), ("no_frames",)),
        "n_frames true": (raw("n_frames", True), ("bad_header",)),
        "n_frames '100' (text)": (raw("n_frames", "100"), ("bad_header",)),
        f"n_frames {frames}.0 (float)": (raw("n_frames", float(frames)), ("bad_header",)),
        "n_joints 25": (raw("n_joints", 25), ("wrong_joint_count",)),
        "n_joints 0": (raw("n_joints", 0), ("wrong_joint_count",)),
        f"n_frames {frames + 1} for {frames} in the blocks": (raw("n_frames", frames + 1), ("bad_header",)),
        f"n_frames {frames - 1} for {frames} in the blocks": (raw("n_frames", frames - 1), ("too_large",)),
        f"n_frames {other} for {frames} in the blocks": (raw("n_frames", other), ("bad_header", "too_large")),
        "filtered n_frames 10**9": (
            with_header(data, _header_set(("recordings", "filtered", "n_frames"), 10**9)),
            ("too_long",),
        ),
        "filtered n_joints 25": (
            with_header(data, _header_set(("recordings", "filtered", "n_joints"), 25)),
            ("wrong_joint_count",),
        ),
    }
    return [Case("declared_counts", name, body, expect=expect) for name, (body, expect) in variants.items()]


def _frame_interval(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Frame intervals no camera makes: far over 1000 Hz, or seconds apart."""
    frames = n_frames(data)
    fast, slow = 10 ** rng.uniform(-9, -3.1), rng.uniform(1.2, 120.0)
    k = rng.randrange(1, frames)
    one_close = np.arange(frames) / 30.0
    one_close[k:] -= 1 / 30.0 - 1e-6
    variants = {
        "frames 1e-7 s apart": np.arange(frames) * 1e-7,
        "frames 1e-5 s apart": np.arange(frames) * 1e-5,
        "frames 5 s apart": np.arange(frames) * 5.0,
        f"frames {fast:.3g} s apart": np.arange(frames) * fast,
        f"frames {slow:.3g} s apart": np.arange(frames) * slow,
        f"30 Hz, but frame {k} 1e-6 s after the previous": one_close,
    }
    return [
        Case("frame_interval", name, _times(data, t), expect=("implausible_timing",)) for name, t in variants.items()
    ]


def _time_backwards(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Times that go back or stand still."""
    frames = n_frames(data)
    t = np.arange(frames) / 30.0
    k = rng.randrange(1, frames)
    step_back, duplicate, jump_back = t.copy(), t.copy(), t.copy()
    step_back[k] = t[k - 1] - 1 / 30.0
    duplicate[k] = t[k - 1]
    jump_back[k:] -= 1000.0
    variants = {
        "reversed": t[::-1].copy(),
        f"one step back at frame {k}": step_back,
        f"frame {k} duplicates frame {k - 1}": duplicate,
        "all frames at the same time": np.zeros(frames),
        f"1000 s back at frame {k}": jump_back,
    }
    cases = [
        Case("time_backwards", name, _times(data, t), expect=("non_monotonic_time",)) for name, t in variants.items()
    ]
    cases.append(
        Case(
            "time_backwards",
            "filtered recording reversed",
            _times(data, t[::-1].copy(), "filtered"),
            expect=("non_monotonic_time",),
        )
    )
    return cases


def _oversized_body(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Bodies over the upload limit: declared by Content-Length, announced (10 GB) or streamed without it."""
    size = ctx.max_upload_bytes + 1
    fill = rng.randrange(256)

    def padded() -> bytes:
        return data + bytes([fill]) * (size - len(data))

    def streamed() -> Iterator[bytes]:
        sent, chunk = 0, bytes([fill]) * 2**20
        while sent < size:
            part = chunk[: size - sent]
            sent += len(part)
            yield part

    expect = ("SessionTooLarge",)
    return [
        Case("oversized_body", f"{size} bytes (file + fill 0x{fill:02x})", padded, expect=expect),
        Case(
            "oversized_body",
            "Content-Length: 10 GB over a valid file",
            data,
            headers={"Content-Length": str(TEN_GB)},
            expect=expect,
        ),
        Case(
            "oversized_body", f"{size} bytes streamed, no Content-Length (fill 0x{fill:02x})", streamed, expect=expect
        ),
    ]


def _version_1(data: bytes, bomb_at: int, bomb: bytes) -> bytes:
    """Returns the file as version 1 (zlib blocks, its codec and grid in the header) with block bomb_at replaced."""
    _, header, _ = split(data)
    header = {**header, "codec": "zlib", "grid_m": 2.0**-13}
    blocks = [khs_files.compress(raw, 1) for raw in _raw_blocks(data)]
    blocks[bomb_at] = bomb
    return join(header, blocks, 1)


def _compression_bomb(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Blocks that inflate far beyond their declared size, and xz streams needing too much decoder memory."""
    version, header, blocks = split(data)
    raws = _raw_blocks(data)
    bomb = xz_bomb(ctx.cache_dir)
    k, m = rng.randrange(len(blocks)), rng.randrange(3)  # m: in the raw recording, decoded first
    in_block, everywhere, two_streams = list(blocks), [bomb] * len(blocks), list(blocks)
    in_block[k] = bomb
    two_streams[m] = blocks[m] + blocks[m]
    mib = BOMB_BYTES >> 20
    cases = [
        Case(
            "compression_bomb",
            f"xz: {mib} MiB of zeros in block {k} ({BLOCK_NAMES[k]}, declares {len(raws[k])} B)",
            join(header, in_block, version),
            expect=("too_large",),
        ),
        Case(
            "compression_bomb",
            f"xz: {mib} MiB of zeros in every block",
            join(header, everywhere, version),
            expect=("too_large",),
        ),
        Case(
            "compression_bomb",
            f"zlib (version 1): {ZLIB_BOMB_BYTES >> 20} MiB of zeros in block {m}",
            _version_1(data, m, zlib_bomb(ctx.cache_dir)),
            expect=("too_large",),
        ),
        Case(
            "compression_bomb",
            f"block {m} holds its xz stream twice",
            join(header, two_streams, version),
            expect=("bad_header",),
        ),
    ]
    for dict_mib in BIG_DICT_MIB:
        filters = [{"id": lzma.FILTER_LZMA2, "preset": 1, "dict_size": dict_mib * 2**20}]
        big = list(blocks)
        big[k] = lzma.compress(raws[k], format=lzma.FORMAT_XZ, check=lzma.CHECK_NONE, filters=filters)
        cases.append(
            Case(
                "compression_bomb",
                f"xz dictionary {dict_mib} MiB in block {k} (decoder limit 32 MiB)",
                join(header, big, version),
                expect=("too_large",),
            )
        )
    return cases


def _deep(data: bytes, key: str, depth: int) -> bytes:
    """Returns the file with header[key]['deep'] (params) or the raw meta nested `depth` lists deep."""
    version, header, blocks = split(data)
    if key == "params":
        header["params"] = {"deep": "@@"}
    else:
        header["recordings"]["raw"]["meta"] = {"deep": "@@"}
    text = json.dumps(header, separators=(",", ":")).replace('"@@"', "[" * depth + "]" * depth)
    return join_text(text, blocks, version)


def _header_types(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """JSON header fields of the wrong type or value, and headers that are no JSON object."""
    version, header, blocks = split(data)
    rec = rng.choice(["raw", "filtered"])
    depth = rng.randint(10_000, 1_000_000)

    def meta(key: str, value: object) -> bytes:
        return with_header(data, _header_set(("recordings", rec, "meta", key), value))

    def top(key: str, value: object) -> bytes:
        return with_header(data, _header_set((key,), value))

    bad = ("bad_header",)
    variants = {
        f"{rec} meta as list": (with_header(data, _header_set(("recordings", rec, "meta"), [1, 2])), bad),
        f"{rec} rate_hz as text": (meta("rate_hz", "fast"), bad),
        f"{rec} exercise as list": (meta("exercise", ["squat"]), bad),
        "params nested 100000 deep": (_deep(data, "params", 100_000), bad),
        f"params nested {depth} deep": (_deep(data, "params", depth), bad),
        f"raw meta nested {depth} deep": (_deep(data, "meta", depth), bad),
        "created_at 9999-12-31": (top("created_at", "9999-12-31T23:59:59Z"), bad),
        "created_at 1970-01-01": (top("created_at", "1970-01-01T00:00:00Z"), bad),
        "created_at without time zone": (top("created_at", "2025-06-01T10:00:00"), bad),
        "created_at not a time": (top("created_at", "yesterday"), bad),
        "created_at as number": (top("created_at", 1_700_000_000), bad),
        "session_id not a UUID": (top("session_id", "not-a-uuid"), bad),
        "session_id of 100000 characters": (top("session_id", "x" * 100_000), bad),
        "session_id as number": (top("session_id", 12345), bad),
        "recordings not an object": (top("recordings", [1, 2]), bad),
        "recordings.raw as text": (with_header(data, _header_set(("recordings", "raw"), "raw")), bad),
        "recordings.raw null": (with_header(data, _header_set(("recordings", "raw"), None)), bad),
        "params as list": (top("params", [1, 2]), bad),
        "joints as object": (top("joints", {"ROOT": 0}), bad),
        "joints shuffled": (top("joints", rng.sample(header["joints"], len(header["joints"]))), ("wrong_joint_count",)),
        "format name wrong": (top("format", "zip"), bad),
        "codec zlib in a version-2 file": (top("codec", "zlib"), bad),
        "grid_m 0.001": (top("grid_m", 0.001), bad),
        "recorded_by ids as text": (top("recorded_by", {"device_id": "1", "patient_id": "1"}), bad),
        "recorded_by ids 0 and -1": (top("recorded_by", {"device_id": 0, "patient_id": -1}), bad),
        "recorded_by with an extra key": (top("recorded_by", {"device_id": 1, "patient_id": 1, "x": 1}), bad),
        "header is a JSON list": (join_text(json.dumps([header]), blocks, version), bad),
        "header is a JSON number": (join_text("1e999", blocks, version), bad),
        "header is not JSON": (join_text("{'session_id': 1}", blocks, version), bad),
    }
    cases = [Case("header_types", name, body, expect=expect) for name, (body, expect) in variants.items()]
    text = json.dumps(header, separators=(",", ":")).encode()
    cut = rng.randrange(1, len(text))
    not_utf8 = text[:cut] + b"\xff\xfe" + text[cut:]
    cases.append(
        Case(
            "header_types",
            f"header not UTF-8 (bytes ff fe at {cut})",
            _join_bytes(not_utf8, blocks, version),
            expect=bad,
        )
    )
    return cases


def _join_bytes(head: bytes, blocks: list[bytes], version: int) -> bytes:
    """Like khs_files.join_text, for header bytes that are not text."""
    body = b"".join(len(b).to_bytes(4, "little") + b for b in blocks)
    data = sf._FIXED.pack(sf.MAGIC, version, 0, len(head), sf._FIXED.size + len(head) + len(body) + 32) + head + body
    return data + hashlib.sha256(data).digest()


def _garbage(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Random bytes, random bytes behind the magic or behind a whole fixed header (with a correct trailer), and
    an empty body."""
    cases = [Case("garbage", "empty body", b"", expect=("bad_magic",))]
    kinds = ("random", "magic + random", "fixed header + random + trailer", "JSON text")
    for i in range(n):
        kind = kinds[i % len(kinds)]
        size = rng.choice([rng.randint(1, 64), rng.randint(65, 4096), rng.randint(4097, 200_000)])
        noise = rng.randbytes(size)
        expect: tuple[str, ...]
        if kind == "random":
            body, expect = noise, ("bad_magic", "truncated")
        elif kind == "magic + random":
            body, expect = sf.MAGIC + noise, ("truncated", "unsupported_version", "bad_header", "checksum_mismatch")
        elif kind == "fixed header + random + trailer":
            head_len = rng.randint(0, size)
            body = sf._FIXED.pack(sf.MAGIC, 2, 0, head_len, 24 + size + 32) + noise
            body, expect = body + hashlib.sha256(body).digest(), ("bad_header",)
        else:
            body, expect = (
                json.dumps({"session_id": str(uuid.UUID(int=rng.getrandbits(128))), "noise": noise.hex()}).encode(),
                ("bad_magic",),
            )
        cases.append(Case("garbage", f"{kind}, {len(body)} bytes", body, expect=expect))
    return cases


def _wrong_owner(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Files recorded by device A for patient A (or mixed ids), sent with patient B's device token."""
    a, b = (ctx.device_a, ctx.patient_a), (ctx.device_b, ctx.patient_b)

    def owned(device: int, patient: int) -> bytes:
        return with_header(data, _header_set(("recorded_by",), {"device_id": device, "patient_id": patient}))

    mismatch = ("SessionOwnerMismatch",)
    unknown = 10**6 + rng.randrange(10**6)
    # (what the file says, device id, patient id, query, expected answer), all sent by device B
    variants: list[tuple[str, int, int, dict[str, int | str], tuple[str, ...]]] = [
        ("recorded by device A for patient A", *a, {}, mismatch),
        ("recorded by device B for patient A", b[0], a[1], {}, mismatch),
        ("recorded by device A for patient B", a[0], b[1], {}, mismatch),
        (f"recorded by unknown device {unknown} for patient B", unknown, b[1], {}, mismatch),
        ("recorded by device A for patient A", *a, {"patient_id": a[1]}, ("PatientNotFound",)),
    ]
    return [
        Case(
            "wrong_owner",
            f"{what}, sent by device B" + (" with ?patient_id=A" if query else ""),
            owned(device, patient),
            params=query,
            device="B",
            expect=expect,
        )  # fmt: skip
        for what, device, patient, query, expect in variants
    ]


def _late_defect(rng: random.Random, data: bytes, n: int, ctx: Context) -> list[Case]:
    """Files of the largest accepted length (ctx.max_frames frames at 30 Hz, a still pose, raw recording only)
    with their one defect in the last frame or at the end of a stream: everything is decompressed and summed
    before the refusal, the dearest refusal the decoder makes."""
    frames, last = ctx.max_frames, ctx.max_frames - 1
    _, header, _ = split(data)
    header["recordings"] = {**header["recordings"], "filtered": None}
    header["recordings"]["raw"] = {**header["recordings"]["raw"], "n_frames": frames}
    pose = sf.decode(data).raw.positions[0]  # (J, 3) m, NaN = untracked
    units = np.rint(np.nan_to_num(pose) / sf.GRID_M).astype(np.int64)
    t = np.arange(frames) / 30.0
    state = np.full((frames, len(header["joints"])), 2, dtype=np.int8)
    joint, axis = rng.randrange(state.shape[1]), rng.randrange(3)

    def positions(far: bool = False) -> bytes:
        deltas = np.zeros((state.shape[1], 3, frames), dtype="<i4")
        deltas[:, :, 0] = units
        if far:
            deltas[joint, axis, last] = int(np.rint(900.0 / sf.GRID_M)) - units[joint, axis]
        return sf._shuffle(deltas)

    def pack(raw: bytes) -> bytes:
        return khs_files.compress(raw, sf.VERSION)

    good = [pack(_time_block(t)), pack(state.tobytes()), pack(positions())]
    late_t, nan_t, bad_state = t.copy(), t.copy(), state.copy()
    late_t[last] = t[last - 1] - 1 / 30.0
    nan_t[last] = np.nan
    bad_state[last, joint] = 3
    byte = len(good[2]) - 1 - rng.randrange(1, 48)
    variants = {
        f"last frame 1/30 s before the previous, {frames} frames": (0, pack(_time_block(late_t)), "non_monotonic_time"),
        f"NaN time in the last frame, {frames} frames": (0, pack(_time_block(nan_t)), "non_finite"),
        f"state 3 in the last frame, {frames} frames": (1, pack(bad_state.tobytes()), "bad_header"),
        f"joint {joint} 900 m away in the last frame, {frames} frames": (
            2,
            pack(positions(far=True)),
            "implausible_position",
        ),
        f"bit flipped at byte {byte} of {len(good[2])} of the positions stream, {frames} frames": (
            2,
            _flip_bit(good[2], byte, rng.randrange(8)),
            "bad_header",
        ),
    }
    cases = []
    for name, (index, block, expect) in variants.items():
        blocks = list(good)
        blocks[index] = block
        cases.append(Case("late_defect", name, join(header, blocks, sf.VERSION), expect=(expect,)))
    return cases


_GENERATORS: dict[str, Callable[[random.Random, bytes, int, Context], list[Case]]] = {
    "truncated": _truncated,
    "bit_flip": _bit_flip,
    "block_bit_flip": _block_bit_flip,
    "wrong_checksum": _wrong_checksum,
    "nan_inf_time": _nan_inf_time,
    "declared_counts": _declared_counts,
    "frame_interval": _frame_interval,
    "time_backwards": _time_backwards,
    "oversized_body": _oversized_body,
    "compression_bomb": _compression_bomb,
    "header_types": _header_types,
    "garbage": _garbage,
    "wrong_owner": _wrong_owner,
    "late_defect": _late_defect,
}


def attack_cases(seed: int, ctx: Context, *, quick: bool = False) -> list[Case]:
    """Returns the randomised families' cases for one seed (deterministic: same seed, same cases)."""
    data = base_file(seed)
    n = 2 if quick else RANDOM_CASES
    cases = []
    for family, generate in _GENERATORS.items():
        for case in generate(random.Random(f"{family}-{seed}"), data, n, ctx):
            case.seed = seed
            cases.append(case)
    return cases


# ---------------------------------------------------------------------------------------------- running


def _patients_with_devices(engine: Engine) -> Users:
    """Creates patients A and B (unique e-mails), each with a paired device; returns
    {"A": (device id, patient id, upload headers), "B": ...}."""
    from sqlalchemy.orm import Session

    from backend.devices.models import Device
    from backend.security import DEVICE_TOKEN_PREFIX, new_token, token_hash
    from backend.users.service import create_user

    made: Users = {}
    with Session(engine) as session, session.begin():
        for who in ("A", "B"):
            token = new_token(DEVICE_TOKEN_PREFIX)
            email = f"bench-attack-{who.lower()}-{uuid.uuid4().hex[:12]}@example.org"
            patient = create_user(db_session=session, email=email, password=None, role="patient", full_name="")
            device = Device(patient_id=patient.id, name=f"bench attack device {who}", token_hash=token_hash(token))
            session.add(device)
            session.flush()
            headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/octet-stream"}
            made[who] = (device.id, patient.id, headers)
    return made


def _reader_headers(engine: Engine, patient_id: int) -> dict[str, str]:
    """Returns the headers of a read token of the patient (the family "file chooses the work" reads with it)."""
    from sqlalchemy.orm import Session

    from backend.users.models import User
    from backend.users.service import create_api_token

    with Session(engine) as session, session.begin():
        user = session.get(User, patient_id)
        if user is None:
            raise LookupError(f"patient {patient_id} was not created")
        _, token = create_api_token(db_session=session, user=user, name="bench attack", scopes=["read"], days=1)
    return {"Authorization": f"Bearer {token}"}


def _stored(engine: Engine, patient_ids: list[int], purge: bool = False) -> int:
    """Returns the number of exercise_session rows of the patients; purge: then deletes them (and their metrics)."""
    from sqlalchemy import func, select
    from sqlalchemy.orm import Session

    from backend.sessions.models import ExerciseSession

    with Session(engine) as session, session.begin():
        where = ExerciseSession.patient_id.in_(patient_ids)
        count = session.execute(select(func.count()).select_from(ExerciseSession).where(where)).scalar_one()
        if purge and count:
            for row in session.scalars(select(ExerciseSession).where(where)):
                session.delete(row)
    return count


def _answer(response: httpx.Response) -> tuple[str, str]:
    try:
        body = response.json()
    except ValueError:
        return "", response.text[:300]
    if isinstance(body, dict):
        return str(body.get("error") or ""), str(body.get("detail") or "")
    return "", json.dumps(body)[:300]


def run_case(client: TestClient, engine: Engine, case: Case, users: Users, patient_ids: list[int]) -> dict[str, Any]:
    """Sends one case; returns its record (status, error, detail, elapsed_s, stored, failures, as_expected)."""
    body = case.body() if callable(case.body) else case.body
    headers = {**users[case.device][2], **case.headers}
    status, error, detail = None, "", ""
    start = time.perf_counter()
    try:
        response = client.post(URL, content=body, headers=headers, params=case.params)
        elapsed = time.perf_counter() - start
        status = response.status_code
        error, detail = _answer(response)
    except Exception as exc:  # noqa: BLE001 - a crash of the client or app is a failed case, not the end of the run
        elapsed = time.perf_counter() - start
        error, detail = type(exc).__name__, str(exc)[:300]
    stored = _stored(engine, patient_ids)
    if stored:
        _stored(engine, patient_ids, purge=True)
    failures = []
    if status is None or not 400 <= status < 500:
        failures.append(f"status {status}")
    if elapsed > LIMIT_S:
        failures.append(f"{elapsed:.2f} s")
    if stored:
        failures.append(f"stored {stored} session(s)")
    as_expected = any(detail.startswith(p) or error == p for p in case.expect) if case.expect else None
    return {
        "family": case.family,
        "name": case.name,
        "seed": case.seed,
        "status": status,
        "error": error,
        "detail": detail[:500],
        "elapsed_s": elapsed,
        "stored": stored,
        "as_expected": as_expected,
        "expected": list(case.expect),
        "failures": failures,
    }


def _valid_upload(client: TestClient, engine: Engine, users: Users, patient_ids: list[int]) -> dict[str, Any]:
    """Uploads one valid file with device A: it must be 201 and stored (the harness can store)."""
    created_at = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(time.time() - 3600))
    data = make_khs("squat", 3, seed=12345, session_id=str(uuid.uuid4()), created_at=created_at)
    start = time.perf_counter()
    response = client.post(URL, content=data, headers=users["A"][2])
    elapsed = time.perf_counter() - start
    stored = _stored(engine, patient_ids)
    error, detail = _answer(response)
    ok = response.status_code == 201 and stored == 1
    return {
        "status": response.status_code,
        "error": error,
        "detail": detail[:300],
        "elapsed_s": elapsed,
        "stored": stored,
        "ok": ok,
    }


def run_database(url: str, seeds: list[int], quick: bool, cache_dir: Path, families: str = "all") -> dict[str, Any]:
    """Runs every case against the real app on a fresh database at `url`; returns the database's report.

    families: "all", "uploads" (the 4xx families only) or "work" (family "file chooses the work" only).
    """
    from fastapi.testclient import TestClient

    engine, cleanup = open_engine(url)
    try:
        users = _patients_with_devices(engine)
        patient_ids = [users["A"][1], users["B"][1]]
        app = make_app(engine)
        settings = app.state.settings
        ids = (users["A"][0], users["A"][1], users["B"][0], users["B"][1])
        ctx = Context(*ids, settings.MAX_UPLOAD_BYTES, settings.SESSION_MAX_FRAMES, cache_dir)
        records = []
        with TestClient(app, raise_server_exceptions=False) as client:
            client.post(URL, content=b"warm-up", headers=users["A"][2])  # first request: lazy imports, connection
            groups = [defect_cases(ctx)] + [attack_cases(seed, ctx, quick=quick) for seed in seeds]
            for cases in groups if families != "work" else []:
                records += [run_case(client, engine, case, users, patient_ids) for case in cases]
            valid = _valid_upload(client, engine, users, patient_ids)
            work = []
            if families != "uploads":
                reader = _reader_headers(engine, users["A"][1])
                run_jobs = jobs_runner(engine, settings)
                for case in work_cases(settings.SESSION_MAX_FRAMES, cache_dir, quick=quick):
                    work.append(run_work_case(client, case, users["A"][2], reader, run_jobs))
                    _stored(engine, patient_ids, purge=True)
    finally:
        cleanup()
    return summarise(db_label(url), records, valid) | {"work": work}


def summarise(db: str, records: list[dict[str, Any]], valid: dict[str, Any]) -> dict[str, Any]:
    """Returns the database's report: per family counts, slowest case and statuses; the failed cases."""
    families = []
    for family in FAMILIES:
        rows = [r for r in records if r["family"] == family]
        if not rows:
            continue
        checked = [r for r in rows if r["as_expected"] is not None]
        families.append(
            {
                "family": family,
                "cases": len(rows),
                "passed": sum(not r["failures"] for r in rows),
                "slowest_s": max(r["elapsed_s"] for r in rows),
                "statuses": dict(sorted(Counter(str(r["status"]) for r in rows).items())),
                "as_expected": sum(bool(r["as_expected"]) for r in checked),
                "checked": len(checked),
            }
        )
    failed = [r for r in records if r["failures"]]
    return {
        "db": db,
        "cases": len(records),
        "passed": len(records) - len(failed),
        "slowest_s": max((r["elapsed_s"] for r in records), default=0.0),
        "limit_s": LIMIT_S,
        "families": families,
        "failed": failed,
        "unexpected_answer": [r for r in records if r["as_expected"] is False],
        "valid_upload": valid,
        "records": records,
    }


def print_report(report: dict[str, Any], seeds: list[int]) -> None:
    """Prints the database's table, its failures and the answers that named another defect than expected."""
    print(
        f"\nMalformed and hostile uploads, POST {URL}, db {report['db']}, seeds {seeds}: "
        f"{report['cases']} cases, limit {LIMIT_S:g} s"
    )
    print(f"{'family':<18}{'cases':>6}{'4xx ≤ 2 s':>11}{'slowest':>10}  {'as expected':>11}  statuses")
    for f in report["families"]:
        statuses = ", ".join(f"{s}×{n}" for s, n in f["statuses"].items())
        print(
            f"{f['family']:<18}{f['cases']:>6}{f['passed']:>11}{f['slowest_s']:>9.3f}s  "
            f"{f['as_expected']:>5}/{f['checked']:<5}  {statuses}"
        )
    print(f"{'all':<18}{report['cases']:>6}{report['passed']:>11}{report['slowest_s']:>9.3f}s")
    v = report["valid_upload"]
    verdict = "ok" if v["ok"] else f"FAILED ({v['error']}: {v['detail']})"
    print(f"valid file: {v['status']}, {v['stored']} session stored, {v['elapsed_s']:.3f} s: {verdict}")
    if report["failed"]:
        print(f"FAILED cases ({len(report['failed'])}):")
        for r in report["failed"]:
            print(
                f"  [{r['family']}] seed {r['seed']}: {r['name']}: {'; '.join(r['failures'])}; "
                f"{r['status']} {r['error']}: {r['detail'][:200]}"
            )
    else:
        print("failed cases: none")
    for r in report["unexpected_answer"]:
        print(
            f"  note: [{r['family']}] {r['name']}: {r['status']} {r['error']}: {r['detail'][:160]} "
            f"(expected {' or '.join(r['expected'])})"
        )


def _reachable(url: str) -> bool:
    from sqlalchemy import create_engine, text

    engine = create_engine(url, connect_args={"connect_timeout": 3})
    try:
        with engine.connect() as conn:
            conn.execute(text("SELECT 1"))
        return True
    except Exception:  # noqa: BLE001 - any failure means: not there
        return False
    finally:
        engine.dispose()


def main(argv: list[str] | None = None) -> int:
    """Runs the cases on each database; prints the tables (and writes --json); returns 1 if any case failed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one seed and 2 random cases per randomised family")
    parser.add_argument("--json", type=Path, help="also write the report (every case) to this JSON file")
    parser.add_argument(
        "--db",
        action="append",
        help=f"database URL, may be repeated (default: SQLite in a temp folder, plus {DEFAULT_PG} if it answers)",
    )
    parser.add_argument("--seeds", type=int, help="number of seeds (default 3, --quick 1)")
    parser.add_argument("--families", choices=("all", "uploads", "work"), default="all",
                        help='"uploads": the 4xx families only; "work": "file chooses the work" only')  # fmt: skip
    parser.add_argument("--first-seed", type=int, default=0, help="first seed (default 0)")
    args = parser.parse_args(argv)
    count = args.seeds if args.seeds is not None else (1 if args.quick else 3)
    seeds = list(range(args.first_seed, args.first_seed + count))
    cache_dir = Path(tempfile.gettempdir())
    started = time.perf_counter()
    reports = []
    with tempfile.TemporaryDirectory() as tmp:
        urls = args.db
        if not urls:
            urls = [f"sqlite:///{tmp}/attack.db"]
            if _reachable(DEFAULT_PG):
                urls.append(DEFAULT_PG)
            else:
                print(f"note: PostgreSQL at {DEFAULT_PG} does not answer; SQLite only", file=sys.stderr)
        for url in urls:
            db_started = time.perf_counter()
            report = run_database(url, seeds, args.quick, cache_dir, args.families)
            report["run_s"] = time.perf_counter() - db_started
            print_report(report, seeds)
            print_work(report["db"], report["work"])
            reports.append(report)
    failed = sum(
        len(r["failed"]) + (not r["valid_upload"]["ok"]) + sum(bool(w["failures"]) for w in r["work"]) for r in reports
    )
    total = time.perf_counter() - started
    print(
        f"\n{sum(r['cases'] for r in reports)} cases on {len(reports)} database(s) in {total:.1f} s: "
        f"{'all answered 4xx within 2 s, nothing stored' if not failed else f'{failed} FAILED'}"
    )
    if args.json:
        out = {
            "seeds": seeds,
            "quick": args.quick,
            "limit_s": LIMIT_S,
            "total_s": total,
            "failed": failed,
            "databases": reports,
        }
        args.json.write_text(json.dumps(out, indent=2, default=str))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
