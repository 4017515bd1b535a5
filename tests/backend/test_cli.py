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


def _admin_and_patient(capsys) -> int:
    """Migrates, creates the admin boss@clinic.org and the patient pat@home.org; returns the patient's id."""
    import sqlalchemy as sa

    from backend.users.models import User

    assert cli.main(["migrate"]) == 0
    for email, role in (("boss@clinic.org", "admin"), ("pat@home.org", "patient")):
        assert cli.main(["create-user", "--email", email, "--password", "0123456789", "--role", role]) == 0
    with get_sessionmaker()() as s:
        pid = s.scalar(sa.select(User.id).where(User.email == "pat@home.org"))
    capsys.readouterr()
    assert pid is not None
    return pid


def test_patient_data_archive_report_and_erasure_from_the_command_line(cli_db, capsys, tmp_path):
    import io
    import zipfile

    import sqlalchemy as sa

    from backend.audit.models import AuditEvent
    from backend.users.models import User

    pid = _admin_and_patient(capsys)
    admin = ["--admin", "boss@clinic.org"]
    zip_path, pdf_path = tmp_path / "p.zip", tmp_path / "p.pdf"
    assert cli.main(["patient-data", "archive", str(pid), *admin, "--out", str(zip_path)]) == 0
    z = zipfile.ZipFile(io.BytesIO(zip_path.read_bytes()))
    assert (
        f"patient {pid} (pat@home.org)" in z.read("README.txt").decode()
        and "admin boss@clinic.org" in z.read("README.txt").decode()
    )
    assert cli.main(["patient-data", "archive", str(pid), *admin, "--out", str(zip_path)]) == 2
    assert "exists already" in capsys.readouterr().err
    assert cli.main(["patient-data", "report", str(pid), *admin, "--out", str(pdf_path), "--paper", "letter"]) == 0
    assert pdf_path.read_bytes().startswith(b"%PDF")
    for argv, says in (
        (["archive", "99999", *admin, "--out", str(tmp_path / "x.zip")], "patient 99999 does not exist"),
        (["archive", str(pid), "--admin", "pat@home.org", "--out", str(tmp_path / "x.zip")], "no active admin"),
        (["report", str(pid), *admin, "--out", str(tmp_path / "x.pdf"), "--from", "2026-02-01", "--to", "2026-01-01"],
         "must run forwards"),
        (["erase", str(pid), *admin], "erase needs --confirm-email"),
        (["erase", str(pid), *admin, "--confirm-email", "other@home.org"], "nothing erased"),
    ):  # fmt: skip
        capsys.readouterr()
        assert cli.main(["patient-data", *argv]) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.startswith("coach-server: error:") and says in err and "\n" not in err, err
    assert not (tmp_path / "x.zip").exists() and not (tmp_path / "x.pdf").exists()
    assert cli.main(["patient-data", "erase", str(pid), *admin, "--confirm-email", "PAT@home.org"]) == 0
    assert f"patient {pid} erased" in capsys.readouterr().out
    with get_sessionmaker()() as s:
        assert s.get(User, pid) is None
        assert s.scalar(sa.select(sa.func.count()).select_from(AuditEvent).where(AuditEvent.patient_id == pid)) == 0
        erased = s.scalars(sa.select(AuditEvent).where(AuditEvent.action == "patient.erase")).one()
        boss = s.scalar(sa.select(User.id).where(User.email == "boss@clinic.org"))
        assert erased.actor_user_id == boss and erased.patient_id is None


def test_patient_data_archive_keeps_what_it_builds_and_reuses_the_kept_one(cli_db, capsys, tmp_path, monkeypatch):
    import sqlalchemy as sa

    from backend.records import prepared_archive
    from backend.records.models import PatientArchive
    from backend.users.models import User

    pid = _admin_and_patient(capsys)
    argv = ["patient-data", "archive", str(pid), "--admin", "boss@clinic.org", "--out"]
    assert cli.main([*argv, str(tmp_path / "first.zip")]) == 0
    assert "(made now)" in capsys.readouterr().out
    with get_sessionmaker()() as s:
        kept = s.scalars(sa.select(PatientArchive).where(PatientArchive.patient_id == pid)).one()
        patient = s.get(User, pid)
        assert patient is not None
        state = prepared_archive.archive_state(db_session=s, patient=patient)
        assert state.state == "ready" and state.current, "the page's next ask gets it without a build"
        assert (tmp_path / "first.zip").stat().st_size == kept.size

    def no_build(**kw):
        raise AssertionError("the kept archive covers today's data: nothing to build")

    monkeypatch.setattr(prepared_archive, "build_archive", no_build)
    assert cli.main([*argv, str(tmp_path / "second.zip")]) == 0
    assert "still current" in capsys.readouterr().out
    assert (tmp_path / "second.zip").read_bytes() == (tmp_path / "first.zip").read_bytes()


def test_a_reanalysis_queued_from_the_command_line_is_listed_with_its_patient(cli_db, capsys):
    """The admin page's batch list says whose sessions a batch re-analyses; a batch of `reanalyze --patient ID`
    said "every patient" before the command audited it as POST /reanalysis does."""
    import datetime as dt

    import sqlalchemy as sa

    from backend.exercises.models import Exercise
    from backend.jobs.listing import list_batches
    from backend.users.models import User
    from tests.backend.session_rows import store_session

    pid = _admin_and_patient(capsys)
    with get_sessionmaker()() as s:
        exercise = s.scalars(sa.select(Exercise).order_by(Exercise.id)).first()
        store_session(s, s.get(User, pid), exercise, dt.datetime(2026, 11, 1, tzinfo=dt.UTC))
        s.commit()
    assert cli.main(["reanalyze", "--patient", str(pid)]) == 0
    assert "session(s) queued for re-analysis" in capsys.readouterr().out
    assert cli.main(["reanalyze", "--pipeline"]) == 0  # every patient (a job of its own: another key)
    with get_sessionmaker()() as s:
        rows = list_batches(db_session=s, kind="reanalyze", limit=10)
    assert [r.patient_id for r in rows] == [None, pid], rows


def test_analyze_reports_a_diverged_filter_as_an_internal_fault(tmp_path, monkeypatch, capsys):
    # a raw recording (no filtered part): `analyze` runs the agent's pipeline, whose filter diverges here
    from kinect_agent import formats
    from kinect_agent.processing import pipeline
    from kinect_agent.sources.simulator import simulate
    from tests.kinect_agent.processing.test_processing_errors import diverging

    src = tmp_path / "raw.csv"
    formats.write(simulate("squat", 2, seed=0)[0], src)
    monkeypatch.setattr(pipeline, "smooth", diverging(pipeline.smooth))
    assert cli.main(["analyze", str(src), "--exercise", "squat"]) == 1
    err = capsys.readouterr().err
    assert "internal fault (FilterDiverged)" in err and "first: frame 10" in err, err
    assert "error:" not in err, "an internal fault is not the user's error"
