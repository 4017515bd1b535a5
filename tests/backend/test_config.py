"""Settings: COACH_ prefix, environment variables, no server secret."""

from __future__ import annotations

from backend.config import Settings


def test_production_needs_no_server_secret(monkeypatch):
    """The server keeps no secret of its own: login sessions, CSRF secrets and tokens are random values (tokens
    stored as SHA-256 hashes), so a COACH_SECRET_KEY would protect nothing and is not asked for."""
    monkeypatch.setenv("COACH_ENVIRONMENT", "production")
    monkeypatch.setenv("COACH_SECRET_KEY", "short")  # left over from an older .env: ignored, not refused
    settings = Settings()
    assert settings.ENVIRONMENT == "production" and not hasattr(settings, "SECRET_KEY")


def test_environment_variables_are_read(monkeypatch):
    monkeypatch.setenv("COACH_ENVIRONMENT", "staging")
    monkeypatch.setenv("COACH_LOGIN_MAX_FAILURES", "7")
    settings = Settings()
    assert settings.LOGIN_MAX_FAILURES == 7 and settings.cookie_secure is True


def test_local_defaults(monkeypatch):
    for name in ("COACH_DATABASE_URL", "COACH_ENVIRONMENT", "COACH_COOKIE_SECURE"):
        monkeypatch.delenv(name, raising=False)
    settings = Settings(_env_file=None)
    assert settings.DATABASE_URL == "sqlite:///./var/coach.db" and settings.cookie_secure is False
