"""`coach-server`: migrate, create-user, and one-line errors with exit status 2."""

from __future__ import annotations

import pytest

from backend import cli
from backend.config import get_settings
from backend.database import get_engine, get_sessionmaker
from backend.migrate import head_revision


@pytest.fixture
def cli_db(tmp_path, monkeypatch):
    """Points COACH_DATABASE_URL at an empty SQLite file for the CLI."""
    monkeypatch.setenv("COACH_DATABASE_URL", f"sqlite:///{tmp_path / 'cli.db'}")
    for cached in (get_settings, get_engine, get_sessionmaker):
        cached.cache_clear()
    yield
    get_engine().dispose()
    for cached in (get_settings, get_engine, get_sessionmaker):
        cached.cache_clear()


def test_create_user_before_migrate_fails_with_hint(cli_db, capsys):
    assert cli.main(["create-user", "--email", "a@b.org", "--password", "0123456789", "--role", "admin"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("coach-server: error:") and "coach-server migrate" in err and "\n" not in err


def test_migrate_then_create_user_then_duplicate(cli_db, capsys):
    assert cli.main(["migrate"]) == 0
    assert f"at revision {head_revision()} (head)" in capsys.readouterr().out
    assert cli.main(["create-user", "--email", "A@b.org", "--password", "0123456789", "--role", "admin"]) == 0
    assert "created admin a@b.org" in capsys.readouterr().out
    assert cli.main(["create-user", "--email", "a@b.org", "--password", "0123456789"]) == 2
    assert "a user with email a@b.org exists" in capsys.readouterr().err
    assert cli.main(["migrate", "--down", "base"]) == 0
    assert "base (empty)" in capsys.readouterr().out


def test_short_password_is_a_user_error(cli_db, capsys):
    assert cli.main(["migrate"]) == 0
    assert cli.main(["create-user", "--email", "a@b.org", "--password", "short"]) == 2
    assert "password" in capsys.readouterr().err


def test_every_subcommand_has_help(capsys):
    for command in ("serve", "migrate", "create-user", "seed-demo", "analyze"):
        assert cli.main([command, "--help"]) == 0
        assert "usage: coach-server" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["reanalyze", "--patient", "999"], "no patient with id 999"),
        (["reanalyze", "--exercise", "squats"], "no exercise 'squats' in the library (known: "),
        (["retention", "--days", "-5"], "--days must be at least 1, got -5"),
        (["retention", "--days", "0"], "--days must be at least 1, got 0"),
        (["storage", "move-out", "--batch", "0"], "--batch must be at least 1, got 0"),
    ],
)
def test_records_commands_refuse_bad_input_in_one_line(cli_db, capsys, argv, says):
    assert cli.main(["migrate"]) == 0
    capsys.readouterr()
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("coach-server: error:") and says in err and "\n" not in err, err
