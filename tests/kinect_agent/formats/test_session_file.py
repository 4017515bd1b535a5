"""Tests of the session file (.khs): round trip, size budget, every error code, CLI conversion."""

from __future__ import annotations

import hashlib
import json
import struct
import uuid
import zlib
from datetime import datetime, timedelta

import numpy as np
import pytest

from kinect_agent import cli, formats, skeleton
from kinect_agent.formats import session_file as sf
from kinect_agent.recording import Metadata, Recording

GRID = 2.0**-13


def realistic(rng: np.random.Generator, n_frames: int, noise_m: float = 0.015) -> tuple[Recording, Recording]:
    """Returns (raw, filtered) at 30 Hz: smooth sinusoidal motion, raw adds AR(1) noise and NaN bursts."""
    t = np.arange(n_frames) / 30.0
    base = rng.uniform(-0.5, 0.5, (1, skeleton.J, 3)) + np.array([0.0, 0.0, 2.5])
    amp = rng.uniform(0.02, 0.3, (1, skeleton.J, 3))
    freq = rng.uniform(0.1, 0.6, (1, skeleton.J, 3))
    phase = rng.uniform(0, 2 * np.pi, (1, skeleton.J, 3))
    smooth = base + amp * np.sin(2 * np.pi * freq * t[:, None, None] + phase)
    phi = 0.9
    shocks = rng.normal(0.0, noise_m * np.sqrt(1 - phi**2), smooth.shape)
    noise = np.zeros_like(smooth)
    noise[0] = rng.normal(0.0, noise_m, smooth.shape[1:])
    for i in range(1, n_frames):
        noise[i] = phi * noise[i - 1] + shocks[i]
    positions = smooth + noise
    for _ in range(max(1, n_frames // 3000)):
        start, j = int(rng.integers(0, max(1, n_frames - 30))), int(rng.integers(0, skeleton.J))
        positions[start : start + int(rng.integers(5, 30)), j] = np.nan
    raw = Recording.from_positions(t, positions, Metadata(device="kinect2", rate_hz=30.0, subject="s01"))
    raw.state[(raw.state == 2) & (rng.random(raw.state.shape) < 0.02)] = 1
    filtered = Recording.from_positions(t, smooth, Metadata(device="kinect2", rate_hz=30.0, history=["ukf"]))
    return raw, filtered


def header_of(data: bytes) -> dict:
    _, _, _, n, _ = struct.unpack_from("<8sHHIQ", data)
    return json.loads(data[24 : 24 + n])


def rebuild(header: dict, blocks: list[bytes], version: int = 1) -> bytes:
    """Builds session bytes by hand from a header dict and compressed blocks, with a correct checksum."""
    head = json.dumps(header).encode()
    body = b"".join(struct.pack("<I", len(b)) + b for b in blocks)
    total = 24 + len(head) + len(body) + 32
    data = struct.pack("<8sHHIQ", sf.MAGIC, version, 0, len(head), total) + head + body
    return data + hashlib.sha256(data).digest()


def blocks_of(data: bytes) -> list[bytes]:
    _, _, _, n, _ = struct.unpack_from("<8sHHIQ", data)
    pos, out = 24 + n, []
    while pos < len(data) - 32:
        (k,) = struct.unpack_from("<I", data, pos)
        out.append(data[pos + 4 : pos + 4 + k])
        pos += 4 + k
    return out


def small_payload(rng: np.random.Generator, n_frames: int = 60) -> sf.SessionPayload:
    raw, filtered = realistic(rng, n_frames)
    return sf.SessionPayload("abc", raw, filtered, params={"q": 0.01, "steps": ["a"]})


def expect(code: str, data: bytes, **kwargs) -> None:
    with pytest.raises(sf.SessionFileError) as info:
        sf.decode(data, **kwargs)
    assert info.value.code == code, str(info.value)


def test_round_trip_within_grid(rng):
    payload = small_payload(rng, 300)
    back = sf.decode(sf.encode(payload))
    assert (back.session_id, back.params, back.created_at) == ("abc", payload.params, payload.created_at)
    for a, b in ((payload.raw, back.raw), (payload.filtered, back.filtered)):
        np.testing.assert_allclose(b.t, a.t, rtol=0, atol=1e-9)
        np.testing.assert_array_equal(b.state, a.state)
        np.testing.assert_array_equal(np.isnan(b.positions), np.isnan(a.positions))
        np.testing.assert_allclose(b.positions, a.positions, rtol=0, atol=GRID / 2 + 1e-12, equal_nan=True)
        assert b.meta == a.meta
    assert np.isnan(back.raw.positions).any(), "test data must contain untracked joints"
    assert (back.raw.state == 1).any()


def test_round_trip_real_recording(data_dir, tmp_path):
    table = np.loadtxt(data_dir / "utkinect" / "joints_s01_e01.txt")  # frame id + 20 joints x (x y z) m, SDK v1 order
    _, first = np.unique(table[:, 0], return_index=True)
    table = table[np.sort(first)]
    table = table[np.concatenate([[True], np.diff(table[:, 0]) > 0])]
    rec = Recording.from_positions(table[:, 0] / 30.0, table[:, 1:].reshape(-1, 20, 3), Metadata(device="kinect1"))
    out = tmp_path / "real.khs"
    sf.write(rec, out)
    assert formats.detect(out) is sf
    back = formats.read(out)
    assert back.meta.device == "kinect1"
    np.testing.assert_array_equal(back.state, rec.state)
    np.testing.assert_allclose(back.t, rec.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.positions, rec.positions, rtol=0, atol=GRID / 2 + 1e-12, equal_nan=True)
    assert out.stat().st_size < rec.positions.nbytes / 4, out.stat().st_size


def test_ten_minutes_raw_and_filtered_under_2mb(rng):
    raw, filtered = realistic(rng, 18000)
    data = sf.encode(sf.SessionPayload("s", raw, filtered, params={"filter": "ukf", "q": [0.1] * 20}))
    assert len(data) < 2 * 2**20, f"{len(data)} bytes"
    assert sf.decode(data).raw.n_frames == 18000


def test_file_round_trip_and_hash(rng, tmp_path):
    payload = small_payload(rng)
    path = tmp_path / "s.khs"
    sf.write_payload(payload, path)
    assert sf.sniff(path, path.read_bytes()[:16])
    assert sf.content_hash(path.read_bytes()) == hashlib.sha256(path.read_bytes()).hexdigest()
    assert sf.read_payload(path).session_id == "abc"
    assert sf.read(path).n_frames == 60


def test_error_names_file(tmp_path):
    path = tmp_path / "bad.khs"
    path.write_bytes(b"not a session file at all, just text" * 3)
    with pytest.raises(sf.SessionFileError) as info:
        sf.read_payload(path)
    assert info.value.code == "bad_magic" and str(path) in str(info.value)


def test_bad_magic():
    expect("bad_magic", b"garbage garbage garbage garbage garbage garbage garbage")


def test_truncated(rng):
    data = sf.encode(small_payload(rng))
    expect("truncated", data[: len(data) // 2])
    expect("truncated", data[:30])
    expect("truncated", sf.MAGIC[:5])


def test_checksum_mismatch(rng):
    data = bytearray(sf.encode(small_payload(rng)))
    data[len(data) // 2] ^= 0x01
    expect("checksum_mismatch", bytes(data))


def test_unsupported_version(rng):
    data = sf.encode(small_payload(rng))
    expect("unsupported_version", rebuild(header_of(data), blocks_of(data), version=99))


def test_wrong_joint_count(rng):
    data = sf.encode(small_payload(rng))
    header = header_of(data)
    header["recordings"]["raw"]["n_joints"] = 25
    expect("wrong_joint_count", rebuild(header, blocks_of(data)))


def test_bad_header_json(rng):
    data = sf.encode(small_payload(rng))
    body = b"{not json"
    blob = struct.pack("<8sHHIQ", sf.MAGIC, 1, 0, len(body), 24 + len(body) + 32) + body
    expect("bad_header", blob + hashlib.sha256(blob).digest())
    header = header_of(data)
    del header["session_id"]
    expect("bad_header", rebuild(header, blocks_of(data)))


def _one_recording(t: np.ndarray, positions: np.ndarray, state: np.ndarray) -> bytes:
    """Hand-built session bytes: float64 t deltas, int8 state, float32 position deltas (shuffled)."""
    n = len(t)
    header = {
        "format": "kinect-home-session",
        "session_id": "x",
        "created_at": "2026-01-01T00:00:00Z",
        "params": {},
        "joints": list(skeleton.JOINTS),
        "grid_m": GRID,
        "codec": "zlib",
        "recordings": {"raw": {"n_frames": n, "n_joints": 20, "meta": {}}, "filtered": None},
    }
    dt = np.concatenate([t[:1], np.diff(t)]).astype("<f8")
    deltas = np.diff(positions.transpose(1, 2, 0), axis=-1, prepend=0.0).astype("<f4")
    blocks = [sf._shuffle(dt), state.astype(np.int8).tobytes(), sf._shuffle(deltas)]
    return rebuild(header, [zlib.compress(b) for b in blocks])


def test_hand_built_file_decodes():
    t = np.arange(4) / 30.0
    positions = np.full((4, 20, 3), 0.5)
    back = sf.decode(_one_recording(t, positions, np.full((4, 20), 2)))
    np.testing.assert_allclose(back.raw.positions, positions)


def test_non_finite():
    t = np.arange(4) / 30.0
    positions = np.full((4, 20, 3), 0.5)
    positions[2, 3, 1] = np.nan
    expect("non_finite", _one_recording(t, positions, np.full((4, 20), 2)))


def test_non_monotonic_time():
    t = np.array([0.0, 0.1, 0.05, 0.2])
    expect("non_monotonic_time", _one_recording(t, np.zeros((4, 20, 3)), np.full((4, 20), 2)))


def test_no_frames(rng):
    data = sf.encode(small_payload(rng))
    header = header_of(data)
    header["recordings"]["raw"]["n_frames"] = 0
    expect("no_frames", rebuild(header, blocks_of(data)))


def test_too_long(rng):
    data = sf.encode(small_payload(rng, 100))
    expect("too_long", data, max_frames=99)


def test_too_large_declared(rng):
    data = sf.encode(small_payload(rng, 100))
    expect("too_large", data, max_decoded_bytes=1000)


def test_zlib_bomb_refused(rng):
    data = sf.encode(small_payload(rng, 10))
    blocks = blocks_of(data)
    blocks[2] = zlib.compress(b"\0" * (256 * 2**20), 9)  # 256 MiB of zeros where 2400 bytes are declared
    expect("too_large", rebuild(header_of(data), blocks))


def test_cli_convert_csv_to_session_and_back(rng, tmp_path):
    raw, _ = realistic(rng, 90)
    csv_in, khs, csv_out = tmp_path / "in.csv", tmp_path / "out.khs", tmp_path / "back.csv"
    formats.write(raw, csv_in)
    assert cli.main(["convert", str(csv_in), "-o", str(khs)]) == 0
    assert khs.read_bytes().startswith(sf.MAGIC)
    assert cli.main(["convert", str(khs), "-o", str(csv_out)]) == 0
    a, b = formats.read(csv_in), formats.read(csv_out)
    np.testing.assert_array_equal(b.state, a.state)
    np.testing.assert_allclose(b.positions, a.positions, atol=GRID / 2 + 1e-5, equal_nan=True)


def test_write_makes_new_session_without_filtered(rng, tmp_path):
    raw, _ = realistic(rng, 40)
    path = tmp_path / "w.khs"
    sf.write(raw, path)
    back = sf.read_payload(path)
    assert uuid.UUID(back.session_id).version == 4
    assert back.filtered is None and back.params == {}
    assert datetime.fromisoformat(back.created_at).utcoffset() == timedelta(0)


def test_encode_refuses_positions_off_the_grid_range(rng):
    raw, _ = realistic(rng, 40)
    raw.positions[3, 2, 0] = 5000.0
    with pytest.raises(ValueError, match="within"):
        sf.encode(sf.SessionPayload("x", raw))


def _reference_positions(data: bytes, index: int, n_frames: int, state: np.ndarray) -> np.ndarray:
    """The first decoder's definition: float32 deltas to float64, cumulative sum over time, NaN where untracked."""
    raw = zlib.decompress(blocks_of(data)[3 * index + 2])
    deltas = sf._unshuffle(raw, "<f4").reshape(skeleton.J, 3, n_frames).astype(np.float64)
    positions = np.cumsum(deltas, axis=-1).transpose(2, 0, 1).copy()
    positions[state == skeleton.NOT_TRACKED] = np.nan
    return positions


def test_decode_equals_reference_on_simulated_session():
    from kinect_agent.sources.simulator import simulate

    measured, truth, _ = simulate("squat", 3, seed=4)
    data = sf.encode(sf.SessionPayload(str(uuid.uuid4()), measured, truth))
    back = sf.decode(data)
    for index, rec in enumerate((back.raw, back.filtered)):
        expected = _reference_positions(data, index, rec.n_frames, rec.state)
        np.testing.assert_array_equal(rec.positions, expected, err_msg=f"recording {index}")
        assert rec.positions.flags.c_contiguous


def test_decode_equals_reference_on_deltas_off_the_grid(rng):
    t = np.arange(50) / 30.0
    positions = rng.normal(0.0, 1.0, (50, skeleton.J, 3))  # float32 deltas, not multiples of the grid
    state = np.where(rng.random((50, skeleton.J)) < 0.1, 0, 2)
    data = _one_recording(t, positions, state)
    back = sf.decode(data)
    np.testing.assert_array_equal(back.raw.positions, _reference_positions(data, 0, 50, back.raw.state))


def test_non_finite_delta_of_untracked_last_frame_decodes_as_nan():
    t = np.arange(4) / 30.0
    positions = np.full((4, 20, 3), 0.5)
    positions[3, 5, 0] = np.inf
    state = np.full((4, 20), 2)
    state[3, 5] = 0
    back = sf.decode(_one_recording(t, positions, state))
    assert np.all(np.isnan(back.raw.positions[3, 5]))
    np.testing.assert_allclose(back.raw.positions[:3], 0.5)
