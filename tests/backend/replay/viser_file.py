"""Reads a viser scene recording (`.viser`) back, as viser's client does, for tests to look inside."""

from __future__ import annotations

from typing import Any

import msgspec
import numpy as np
import zstandard


def read_viser(data: bytes) -> dict[str, Any]:
    """Returns the recording's document with binary placeholders replaced by numpy arrays.

    Layout (viser.infra.StateSerializer.serialize): u64 inner size, then zstd of [u64 msgpack length, msgpack,
    8-byte aligned binary buffers].
    """
    inner_size = int.from_bytes(data[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=inner_size)
    n = int.from_bytes(inner[:8], "little")
    doc = msgspec.msgpack.decode(inner[8 : 8 + n])
    buffers, offset = [], 8 + n
    for length in doc["binaryBufferLengths"]:
        offset += (8 - offset % 8) % 8
        buffers.append(inner[offset : offset + length])
        offset += length
    doc["messages"] = [(t, _resolve(m, buffers)) for t, m in doc["messages"]]
    return doc


def _resolve(value: Any, buffers: list[bytes]) -> Any:
    if isinstance(value, dict):
        if "__binary_index" in value:
            return np.frombuffer(buffers[value["__binary_index"]], dtype=np.dtype(value["dtype"]))
        return {k: _resolve(v, buffers) for k, v in value.items()}
    if isinstance(value, list):
        return [_resolve(v, buffers) for v in value]
    return value


def node_points(doc: dict[str, Any], name: str) -> list[tuple[float, np.ndarray]]:
    """Returns (time s, points (N, 3) float, or (N, 2, 3) for line segments) each time node `name` is shown with
    new points: its creation and its point updates while visible."""
    out: list[tuple[float, np.ndarray]] = []
    visible = True
    latest: np.ndarray | None = None
    for t, m in doc["messages"]:
        if m.get("name") != name:
            continue
        if m["type"] == "SetSceneNodeVisibilityMessage":
            visible = m["visible"]
            if visible and latest is not None:
                out.append((t, latest))
            continue
        points = m.get("props", m.get("updates", {})).get("points")
        if points is None:
            continue
        latest = np.asarray(points, dtype=float).reshape(-1, 3)
        if "LineSegments" in m["type"] or name.endswith("/bones"):
            latest = latest.reshape(-1, 2, 3)
        if visible:
            out.append((t, latest))
    return out
