"""The replay is built by the job queue, off the request path: the page says it is being prepared, then plays it;
many requests at once queue one build."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import httpx
import pytest
import sqlalchemy as sa
from playwright.sync_api import expect

from backend.demo import ADMIN
from backend.jobs.models import Job
from backend.replay.jobs import job_key
from backend.replay.models import SessionReplay
from tests.frontend.conftest import api_client, login, shot, upload_session

pytestmark = pytest.mark.browser
WALTER = "walter@demo.clinic"  # elbow_flexion; sessions of his are uploaded only by this module and test_jobs_page


def test_the_page_says_the_replay_is_being_prepared_then_plays_it(page, live_server):
    sid = upload_session(live_server.url, WALTER, "elbow_flexion", 2, seed=311,
                         created_at="2026-11-19T08:00:00Z")["id"]  # fmt: skip
    login(page, ADMIN[0])
    page.wait_for_url("**/therapist")  # admins start on the dashboard too
    page.goto(f"/therapist/sessions/{sid}/replay")
    expect(page.locator("#replay-state")).to_contain_text("The 3D replay is being prepared.")
    expect(page.locator("#viewer")).to_be_hidden()
    shot(page, "replay_preparing")
    viewer = page.frame_locator("#viewer")
    viewer.locator("canvas").first.wait_for(state="visible", timeout=30_000)
    expect(page.locator("#replay-state")).to_be_hidden()
    assert not page.js_errors, page.js_errors


def test_many_requests_at_once_queue_one_build(live_server):
    sid = upload_session(live_server.url, WALTER, "elbow_flexion", 1, seed=312,
                         created_at="2026-11-18T08:00:00Z")["id"]  # fmt: skip
    clients = [api_client(live_server.url, ADMIN[0]) for _ in range(8)]

    def ask(pair: tuple[httpx.Client, dict[str, Any]]) -> int:
        return pair[0].get(f"/api/v1/sessions/{sid}/replay").status_code

    try:
        with ThreadPoolExecutor(len(clients)) as pool:
            codes = list(pool.map(ask, clients))
    finally:
        for c, _ in clients:
            c.close()
    assert set(codes) <= {200, 202} and 202 in codes, codes
    engine = sa.create_engine(live_server.database_url)
    try:
        with engine.connect() as conn:
            jobs = conn.scalar(sa.select(sa.func.count()).select_from(Job).where(Job.key == job_key(sid)))
            assert jobs == 1, f"{jobs} builds queued for one replay"
        client, _ = api_client(live_server.url, ADMIN[0])
        try:
            for _ in range(300):
                if client.get(f"/api/v1/sessions/{sid}/replay/state").json()["state"] == "ready":
                    break
                time.sleep(0.1)
            assert client.get(f"/api/v1/sessions/{sid}/replay").status_code == 200
        finally:
            client.close()
        with engine.connect() as conn:
            built = sa.select(sa.func.count()).select_from(SessionReplay).where(SessionReplay.session_id == sid)
            assert conn.scalar(built) == 1
    finally:
        engine.dispose()
