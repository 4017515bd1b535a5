"""PostgreSQL LISTEN for the events of every worker and replica: one thread per server process.

It holds one connection of its own (outside the pool), LISTENs on hub.CHANNEL and hands each notification to this
process's HUB; when the connection drops it reconnects with backoff (1 s doubling to 30 s). Notifications sent
while it was away are lost, which the pages tolerate: they also load their data on opening and on reconnecting.
"""

from __future__ import annotations

import logging
import threading

import psycopg
from sqlalchemy.engine import URL

from backend.events.hub import CHANNEL, HUB, Event, Hub

log = logging.getLogger(__name__)


def conninfo(url: URL) -> str:
    """Returns the libpq connection string of an SQLAlchemy PostgreSQL URL (driver name dropped, query kept)."""
    return url.set(drivername="postgresql").render_as_string(hide_password=False)


class Listener:
    """Runs LISTEN in a daemon thread until stop()."""

    def __init__(self, url: URL, hub: Hub = HUB) -> None:
        self.conninfo = conninfo(url)
        self.hub = hub
        self._stop = threading.Event()
        self.ready = threading.Event()  # set once LISTEN is in place (tests wait for it)
        self._thread = threading.Thread(target=self._run, name="events-listener", daemon=True)

    def start(self) -> Listener:
        """Starts the thread; returns self."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Asks the thread to end (within about a second)."""
        self._stop.set()
        self._thread.join(timeout=5)

    def _run(self) -> None:
        delay = 1.0
        while not self._stop.is_set():
            try:
                with psycopg.connect(self.conninfo, autocommit=True) as conn:
                    conn.execute(f"LISTEN {CHANNEL}")
                    self.ready.set()
                    delay = 1.0
                    while not self._stop.is_set():
                        for note in conn.notifies(timeout=1.0):
                            self._deliver(note.payload)
            except psycopg.Error as exc:
                self.ready.clear()
                log.warning("event listener lost PostgreSQL (%s); retrying in %.0f s", exc, delay)
                self._stop.wait(delay)
                delay = min(delay * 2, 30.0)

    def _deliver(self, payload: str) -> None:
        try:
            ev = Event.from_json(payload)
        except ValueError:
            log.warning("event listener ignored a notification that is not an event: %.200s", payload)
            return
        self.hub.deliver(ev)
