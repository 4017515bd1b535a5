"""Account tables: users, personal API tokens, browser login sessions and login attempts."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import JSON, Boolean, CheckConstraint, ForeignKey, Index, SmallInteger, String
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow

ROLES = ("admin", "therapist", "patient")


class User(Base):
    """One person: an admin, a therapist or a patient (patients are users with role 'patient')."""

    __tablename__ = "user"
    __table_args__ = (CheckConstraint("role IN ('admin', 'therapist', 'patient')", name="role"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    email: Mapped[str] = mapped_column(String(320), unique=True)
    full_name: Mapped[str] = mapped_column(String(200), default="")
    role: Mapped[str] = mapped_column(String(16))
    password_hash: Mapped[str | None] = mapped_column(String(255))
    is_active: Mapped[bool] = mapped_column(Boolean, default=True)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    deactivated_at: Mapped[dt.datetime | None] = mapped_column()
    # the language of the patient's pages ("en", "de", "es", "fr": backend.i18n.LOCALES); None: the browser's
    locale: Mapped[str | None] = mapped_column(String(16))
    # IANA time zone of the patient's reminder times ("Europe/Berlin"); None: the server's COACH_TIME_ZONE
    time_zone: Mapped[str | None] = mapped_column(String(64))
    # when the patient stopped e-mail reminders (the unsubscribe link of a reminder); None: reminders are sent
    reminder_emails_off_at: Mapped[dt.datetime | None] = mapped_column()
    # a patient's pain said after a set (0-10) above this raises their attention score (backend.sessions.triage);
    # set by their therapist; None: triage.PAIN_ALERT_ABOVE
    pain_alert_above: Mapped[int | None] = mapped_column(SmallInteger)


class ApiToken(Base):
    """A personal API token (sent as `Authorization: Bearer khc_...`); only its sha256 is stored.

    A token expires at expires_at; a token made with another token (parent_id) expires no later than its parent
    and is revoked with it.
    """

    __tablename__ = "api_token"

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    name: Mapped[str] = mapped_column(String(100))
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    scopes: Mapped[list[str]] = mapped_column(JSON, default=list)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    last_used_at: Mapped[dt.datetime | None] = mapped_column()
    revoked_at: Mapped[dt.datetime | None] = mapped_column()
    expires_at: Mapped[dt.datetime] = mapped_column()
    parent_id: Mapped[int | None] = mapped_column(ForeignKey("api_token.id", ondelete="CASCADE"), index=True)


class LoginSession(Base):
    """A browser login: the cookie holds the token, the table its sha256 and the CSRF secret."""

    __tablename__ = "login_session"

    id: Mapped[int] = mapped_column(primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    csrf_secret: Mapped[str] = mapped_column(String(64))
    ip: Mapped[str | None] = mapped_column(String(64))
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    expires_at: Mapped[dt.datetime] = mapped_column()
    revoked_at: Mapped[dt.datetime | None] = mapped_column()


class LoginAttempt(Base):
    """One attempt at a secret, kept for throttling (backend.users.throttle): a password login (kind 'password',
    with the e-mail tried) or a pairing code (kind 'pairing', email empty). Recorded as failed before the secret is
    checked, so that attempts in flight count too; marked succeeded after."""

    __tablename__ = "login_attempt"
    __table_args__ = (
        Index("ix_login_attempt_email_ip_at", "email", "ip", "at"),
        Index("ix_login_attempt_ip_at", "ip", "at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    kind: Mapped[str] = mapped_column(String(16), default="password", server_default="password")
    email: Mapped[str] = mapped_column(String(320))
    ip: Mapped[str] = mapped_column(String(64))
    succeeded: Mapped[bool] = mapped_column(Boolean)
    at: Mapped[dt.datetime] = mapped_column(default=utcnow)
