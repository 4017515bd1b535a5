"""A viser scene that listens on no socket, for building `.viser` recordings on the server.

viser 1.1.1 records a scene only through a ViserServer, whose constructor starts an infra.WebsockServer: a thread
with an event loop serving viser's client and a websocket on a TCP port, which anyone on the machine could connect
to while a build runs and receive the scene (the patient's joints). `recording_server()` gives a ViserServer whose
WebsockServer is a SocketlessServer: its start() makes the message buffer the scene API and the recording need on
an event loop that is closed at once, so no thread, no port, no connection exists; the scene's messages go only to
the recording (StateSerializer). One such server is made at a time (the swap of viser.infra.WebsockServer is
guarded by a lock), and only this module makes ViserServers in the app.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from viser import ViserServer
    from viser.infra import WebsockServer

_LOCK = threading.Lock()


def _socketless_class() -> type[WebsockServer]:
    from viser import infra
    from viser.infra._async_message_buffer import AsyncMessageBuffer

    class SocketlessServer(infra.WebsockServer):
        """An infra.WebsockServer that binds nothing and runs nothing: messages are buffered and recorded only."""

        def start(self) -> None:
            """Makes the broadcast buffer on a closed event loop (viser's pushes skip a closed loop)."""
            loop = asyncio.new_event_loop()
            loop.close()
            self._background_event_loop = loop
            self._broadcast_buffer = AsyncMessageBuffer(loop, persistent_messages=True)

        def stop(self) -> None:
            """Marks the buffer done; there is no thread or socket to end."""
            self._broadcast_buffer.set_done()

    return SocketlessServer


@contextlib.contextmanager
def recording_server() -> Iterator[ViserServer]:
    """Yields a viser.ViserServer that listens on nothing, stopped on exit (one at a time per process)."""
    import viser
    from viser import infra

    with _LOCK:
        real = infra.WebsockServer
        # a deliberate swap of viser's server class (module doc), which mypy forbids for any class attribute
        infra.WebsockServer = _socketless_class()  # type: ignore[misc]
        try:
            with contextlib.redirect_stdout(io.StringIO()):  # no banner: there is no address to print
                server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
        finally:
            infra.WebsockServer = real  # type: ignore[misc]
        try:
            yield server
        finally:
            server.stop()
