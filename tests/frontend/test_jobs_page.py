"""The admin's re-analysis page end to end: an admin starts the re-analysis of one patient's sessions, the
server's worker runs it (COACH_EMBEDDED_WORKER: the loop of `coach-server worker`), the page follows the progress by
itself and says a failure in words; a therapist gets the 403 page; a session whose recording the retention period
removed says so on its page; a session re-analysed with the pipeline names the pipeline of each version. Screenshots
at 1366 and 390 px, axe-core 0 serious/critical."""

from __future__ import annotations

import datetime as dt
import os
import re
import subprocess
import sys

import pytest
import sqlalchemy as sa
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect
from sqlalchemy.engine import CursorResult
from sqlalchemy.orm import Session

from backend.demo import ADMIN
from backend.jobs.models import Job
from backend.records.reanalysis import KIND
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage.local import LocalStore
from tests.frontend.conftest import ROOT, THERAPIST, open_page, shot, sign_in, upload_session

pytestmark = pytest.mark.browser
WALTER = "walter@demo.clinic"  # elbow_flexion; no other browser test uses his sessions
REMOVED = re.compile(rf"^This session was removed on .*{dt.date.today().year}.* under the clinic's retention policy\.$")


def _axe_blocking(page) -> list[str]:
    found = Axe().run(page).response["violations"]
    return [f"{v['id']}: {v['help']}" for v in found if v["impact"] in ("serious", "critical")]


def _env(live_server) -> dict[str, str]:
    return os.environ | {"COACH_DATABASE_URL": live_server.database_url, "COACH_ENVIRONMENT": "local",
                         "COACH_STORAGE_DIR": live_server.storage_dir, "PYTHONPATH": str(ROOT)}  # fmt: skip


def test_an_admin_reanalyses_one_patient_and_follows_it(browser, live_server):
    engine = sa.create_engine(live_server.database_url)
    kept = upload_session(live_server.url, WALTER, "elbow_flexion", 3, seed=301, created_at="2026-11-21T09:00:00Z")
    lost = upload_session(live_server.url, WALTER, "elbow_flexion", 3, seed=302, created_at="2026-11-22T09:00:00Z")
    with Session(engine) as db, db.begin():
        walter = db.scalar(sa.select(ExerciseSession.patient_id).where(ExerciseSession.id == kept["id"]))
        for metric in db.scalars(sa.select(SessionMetric).join(ExerciseSession)
                                 .where(ExerciseSession.patient_id == walter)):  # fmt: skip
            doc = dict(metric.document)
            doc.pop("analysis_version", None), doc.pop("schema_version", None)  # made before versions (schema 1)
            metric.document = doc
        lost_key = db.scalar(sa.select(ExerciseSession.file_key).where(ExerciseSession.id == lost["id"]))
    assert lost_key is not None
    LocalStore(live_server.storage_dir).delete(lost_key)  # its file is gone from the store: that job fails

    try:
        with open_page(browser, live_server.url, 1366, 900) as page:
            sign_in(page, ADMIN[0])
            page.goto("/therapist")
            page.get_by_role("link", name="Re-analysis and jobs").click()
            page.wait_for_url("**/admin/jobs")
            expect(page.locator("#version")).not_to_have_text("…")
            # the newest jobs of every kind: an upload's session-details job says what it did, not a re-analysis's
            # words ("Already analysed with this version" was said of every finished job of another kind)
            built = page.locator(f'#jobs tr[data-status="done"]:has(a[href$="/sessions/{kept["id"]}"])').first
            expect(built).to_contain_text("Session details built.", timeout=30_000)
            page.select_option("#scope", label="Walter Young's sessions")
            page.click("#start-btn")
            expect(page.locator("#start-msg")).to_contain_text("queued for analysis version")
            row = page.locator("#batches tbody tr").first
            expect(row).to_contain_text("Walter Young")
            expect(page.locator("#live")).to_contain_text("every 2 seconds")
            # the server's embedded worker runs the jobs; the lost file's job is retried after 5 s (then 30 s)
            retrying = page.locator(f'#jobs tr:has(a[href$="/sessions/{lost["id"]}"])')
            expect(retrying).to_contain_text("Will try again: The session's file is missing from the object store",
                                             timeout=20_000)  # fmt: skip
            shot(page, "admin_jobs_retrying_1366")
            # two tries instead of three for this job (its own max_attempts column, as a job's row allows): it fails
            # after the 5 s retry, not 30 s later; the delays and the attempt limit are tests/backend/records' part
            with Session(engine) as db, db.begin():
                two = db.execute(sa.update(Job).where(Job.key.like(f"{KIND}:{lost['id']}:%")).values(max_attempts=2))
            assert isinstance(two, CursorResult)  # an UPDATE's result
            assert two.rowcount == 1, f"{two.rowcount} jobs of session {lost['id']}"
            expect(row).to_contain_text("Finished, 1 failed", timeout=90_000)  # the page polled by itself
            failed = page.locator(f'#jobs tr[data-status="failed"]:has(a[href$="/sessions/{lost["id"]}"])')
            expect(failed).to_contain_text("The session's file is missing from the object store")
            expect(failed).not_to_contain_text("Traceback")
            done = page.locator(f'#jobs tr[data-status="done"]:has(a[href$="/sessions/{kept["id"]}"])')
            expect(done).to_contain_text("New metrics stored; the old ones are kept.")
            expect(page.locator("#live")).to_contain_text("Up to date")
            shot(page, "admin_jobs_1366")
            assert _axe_blocking(page) == []
            page.set_viewport_size({"width": 390, "height": 844})
            shot(page, "admin_jobs_390")
            assert _axe_blocking(page) == []
            width = page.evaluate("[document.documentElement.scrollWidth, document.documentElement.clientWidth]")
            assert width[0] <= width[1], f"the page scrolls sideways at 390 px: {width}"
            assert not page.js_errors, page.js_errors
    finally:
        engine.dispose()


def test_a_therapist_gets_the_403_page(page, live_server):
    sign_in(page, THERAPIST)
    response = page.goto("/admin/jobs")
    assert response.status == 403
    expect(page.locator("main")).to_contain_text("This page is for the clinic's administrators.")


def test_a_removed_session_says_when_and_why(browser, live_server):
    old = upload_session(live_server.url, WALTER, "elbow_flexion", 2, seed=303, created_at="2019-03-01T09:00:00Z")
    retention = subprocess.run(
        [sys.executable, "-m", "backend.cli", "retention"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        env=_env(live_server) | {"COACH_RETENTION_DAYS": "2000"},
    )
    assert retention.returncode == 0, retention.stderr + retention.stdout
    with open_page(browser, live_server.url, 1366, 900) as page:
        sign_in(page, ADMIN[0])
        page.goto(f"/therapist/sessions/{old['id']}")
        notice = page.locator("#removed")
        expect(notice).to_be_visible()
        expect(page.locator("#removed-text")).to_have_text(REMOVED)
        expect(page.locator("#removed-numbers")).to_contain_text("Repetitions")
        expect(page.locator("#session-body")).to_be_hidden()
        expect(page.locator("#error")).to_be_hidden()
        shot(page, "session_removed_1366")
        assert _axe_blocking(page) == []
        page.set_viewport_size({"width": 390, "height": 844})
        shot(page, "session_removed_390")
        assert _axe_blocking(page) == []
        assert not page.js_errors, page.js_errors


def test_the_session_page_says_which_pipeline_filtered_each_version(browser, live_server):
    """A session of a file filtered by no known pipeline, re-analysed with today's pipeline (the job a worker runs):
    its page's table shows today's pipeline beside the earlier file's "not recorded", and why it was filtered again."""
    from backend.records.reanalysis import reanalyze_session
    from backend.storage import use_store
    from kinect_agent.processing.pipeline import VERSION

    stored = upload_session(live_server.url, WALTER, "elbow_flexion", 3, seed=304, created_at="2026-11-23T09:00:00Z")
    engine = sa.create_engine(live_server.database_url)
    use_store(LocalStore(live_server.storage_dir))
    try:
        with Session(engine) as db, db.begin():
            result = reanalyze_session(db_session=db, session_id=stored["id"], max_frames=108_000,
                                       max_decoded_bytes=64 * 2**20, pipeline=True)  # fmt: skip
        assert result["refiltered"] == "filtered by an unnamed pipeline", result
        with open_page(browser, live_server.url, 1366, 900) as page:
            sign_in(page, ADMIN[0])
            page.goto(f"/therapist/sessions/{stored['id']}")
            card = page.locator("#versions-card")
            expect(card).to_be_visible()
            rows = page.locator("#versions tbody tr")
            expect(rows).to_have_count(2)
            expect(rows.nth(0)).to_contain_text(f"{VERSION}, settings ")
            expect(rows.nth(0)).to_contain_text("(filtered again by the server: filtered by an unnamed pipeline)")
            expect(rows.nth(1)).to_contain_text("not recorded · file ")
            # in words: the file's "filtered" recording was the simulator's truth (make_khs), 116° against the
            # pipeline's 98° of the same raw recording (tests/backend/records/test_refilter.py)
            why = page.locator("#versions-why")
            expect(why).to_contain_text("Filtered again by the server with pipeline " + VERSION)
            expect(why).to_contain_text("range of motion 116° → 98°, repetitions 3 → 3")
            expect(why).to_contain_text("does not say which filter made its filtered recording")
            card.scroll_into_view_if_needed()
            shot(page, "session_versions_pipeline_1366")
            assert _axe_blocking(page) == []
            assert not page.js_errors, page.js_errors
    finally:
        use_store(None)
        engine.dispose()
