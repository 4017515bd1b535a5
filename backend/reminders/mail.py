"""One reminder e-mail: its text in the patient's language and its delivery through the configured SMTP server
(Python's smtplib; STARTTLS and login when configured)."""

from __future__ import annotations

import smtplib
import ssl
from dataclasses import dataclass
from email.message import EmailMessage
from email.utils import format_datetime, make_msgid

from backend.config import Settings
from backend.database import utcnow
from backend.i18n import translator


@dataclass(frozen=True)
class Reminder:
    """What one e-mail says: to whom, in which language, the plan's title and the local time, and where the
    unsubscribe link points."""

    to: str
    name: str
    locale: str | None
    plan_title: str
    local_time: str  # "HH:MM" in the patient's time zone
    unsubscribe_url: str


def message(reminder: Reminder, *, sender: str) -> EmailMessage:
    """Returns the reminder e-mail (plain text, in the patient's language) with List-Unsubscribe headers
    (RFC 2369, and RFC 8058's one-click POST to the same link)."""
    t = translator(reminder.locale)
    msg = EmailMessage()
    msg["Subject"] = t.gettext("Reminder: your exercises at %(time)s", time=reminder.local_time)
    msg["From"] = sender
    msg["To"] = reminder.to
    msg["Date"] = format_datetime(utcnow())
    msg["Message-ID"] = make_msgid(domain=sender.rpartition("@")[2].strip("> ") or None)
    msg["List-Unsubscribe"] = f"<{reminder.unsubscribe_url}>"
    msg["List-Unsubscribe-Post"] = "List-Unsubscribe=One-Click"
    msg["Auto-Submitted"] = "auto-generated"
    greeting = t.gettext("Hello %(name)s,", name=reminder.name) if reminder.name else t.gettext("Hello,")
    body = [
        greeting,
        "",
        t.gettext(
            "it is time for your exercises (%(time)s): %(plan)s.", time=reminder.local_time, plan=reminder.plan_title
        ),  # fmt: skip
        t.gettext("Open your exercise page when you are ready."),
        "",
        t.gettext("You get this e-mail because your therapist set reminder times in your plan."),
        t.gettext("To get no more e-mail reminders, open this link (no sign-in needed):"),
        reminder.unsubscribe_url,
    ]
    msg.set_content("\n".join(body) + "\n")
    msg["Content-Language"] = t.locale  # after set_content, which clears the Content-* headers
    return msg


def send(msg: EmailMessage, settings: Settings) -> None:
    """Delivers one e-mail through settings' SMTP server; raises smtplib.SMTPException or OSError when it fails."""
    with smtplib.SMTP(settings.SMTP_HOST, settings.SMTP_PORT, timeout=settings.SMTP_TIMEOUT_S) as smtp:
        if settings.SMTP_STARTTLS:
            smtp.starttls(context=ssl.create_default_context())
        if settings.SMTP_USER:
            smtp.login(settings.SMTP_USER, settings.SMTP_PASSWORD)
        smtp.send_message(msg)
