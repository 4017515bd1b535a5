"""Settings: COACH_ prefix, secrets refused at their defaults outside local."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from backend.config import Settings


def test_default_secret_refused_outside_local(monkeypatch):
    monkeypatch.setenv("COACH_ENVIRONMENT", "production")
    monkeypatch.delenv("COACH_SECRET_KEY", raising=False)
    with pytest.raises(ValidationError, match="COACH_SECRET_KEY must be set"):
        Settings()


def test_environment_variables_are_read(monkeypatch):
    monkeypatch.setenv("COACH_ENVIRONMENT", "staging")
    monkeypatch.setenv("COACH_SECRET_KEY", "s" * 40)
    monkeypatch.setenv("COACH_LOGIN_MAX_FAILURES", "7")
    settings = Settings()
    assert settings.LOGIN_MAX_FAILURES == 7 and settings.cookie_secure is True


def test_local_defaults(monkeypatch):
    for name in ("COACH_DATABASE_URL", "COACH_ENVIRONMENT", "COACH_COOKIE_SECURE"):
        monkeypatch.delenv(name, raising=False)
    settings = Settings(_env_file=None)
    assert settings.DATABASE_URL == "sqlite:///./var/coach.db" and settings.cookie_secure is False
