"""Replays a recording file (any format kinect_agent.formats reads) as a live source."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

from kinect_agent import formats
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources.base import Frame, Pacer, SourceBase


class ReplaySource(SourceBase):
    """Yields the frames of a file at real-time pace (realtime=True) or as fast as possible."""

    name = "replay"

    def __init__(self, path: str | Path, *, realtime: bool = True, format: str | None = None) -> None:
        self.path = Path(path)
        self.realtime = realtime
        self.format = format
        self._rec: Recording | None = None
        self.device = "unknown"

    def open(self) -> None:
        """Reads the whole file (raises FormatError naming the file and line when it cannot)."""
        self._rec = formats.read(self.path, self.format)
        self.device = self._rec.meta.device

    def frames(self) -> Iterator[Frame]:
        """Yields each frame of the file once, in order."""
        if self._rec is None:
            raise RuntimeError("ReplaySource.frames() called before open()")
        pacer = Pacer(self.realtime)
        rec = self._rec
        for i in range(rec.n_frames):
            pacer.wait(float(rec.t[i]))
            yield Frame(float(rec.t[i]), rec.positions[i].copy(), rec.state[i].copy())

    def metadata(self) -> Metadata:
        """Returns the file's metadata, with the replay noted as its source."""
        if self._rec is None:
            return Metadata(source=str(self.path))
        m = self._rec.meta
        return dataclasses.replace(m, history=list(m.history), extra=dict(m.extra), source=str(self.path))
