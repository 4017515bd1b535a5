"""A real SMTP server (aiosmtpd) on a free local port whose received e-mails the tests read, and the settings of a
server that sends reminders through it."""

from __future__ import annotations

import email
import email.policy
import socket
import threading
import time
from collections.abc import Iterator
from email.message import EmailMessage

import pytest
from aiosmtpd.controller import Controller

from backend.config import Settings

PUBLIC_URL = "https://coach.example.org/clinic"


class Inbox:
    """The e-mails an aiosmtpd server received (its DATA handler), parsed; thread-safe."""

    def __init__(self) -> None:
        self.messages: list[EmailMessage] = []
        self.recipients: list[list[str]] = []
        self._lock = threading.Lock()

    async def handle_DATA(self, server, session, envelope) -> str:  # noqa: N802 (aiosmtpd's hook name)
        parsed = email.message_from_bytes(envelope.content, policy=email.policy.default)
        with self._lock:
            self.messages.append(parsed)
            self.recipients.append(list(envelope.rcpt_tos))
        return "250 OK"

    def wait_for(self, n: int, timeout_s: float = 10.0) -> list[EmailMessage]:
        """Returns the messages once n have arrived; fails after timeout_s."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            with self._lock:
                if len(self.messages) >= n:
                    return list(self.messages)
            time.sleep(0.05)
        raise AssertionError(f"expected {n} e-mail(s) within {timeout_s} s, got {len(self.messages)}")


def free_port() -> int:
    """Returns a TCP port nothing listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def smtp() -> Iterator[tuple[Inbox, int]]:
    """A running SMTP server on 127.0.0.1: (its inbox, its port)."""
    inbox, port = Inbox(), free_port()
    controller = Controller(inbox, hostname="127.0.0.1", port=port)
    controller.start()
    yield inbox, port
    controller.stop()


def mail_settings(port: int, **more) -> Settings:
    """Settings of a server that sends reminder e-mails to 127.0.0.1:port (no TLS: a local test server)."""
    return Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", EVENTS_STREAM_MAX_S=0.0,
                    LIVE_OFFLINE_GRACE_S=0.0, SMTP_HOST="127.0.0.1", SMTP_PORT=port, SMTP_STARTTLS=False,
                    SMTP_FROM="Home Coach <coach@example.org>", PUBLIC_URL=PUBLIC_URL, **more)  # fmt: skip
