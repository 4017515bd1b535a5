"""Camera sets over HTTP: consent, start, batches (hostile values refused naming the field, idempotent by number,
rate-limited), patients only and their own sets only."""

from __future__ import annotations

import json
import uuid
from typing import Any

from sqlalchemy import func, select

from backend.camera.limits import CONSENT_VERSION, MAX_FRAMES_PER_BATCH
from backend.camera.models import CameraBatch
from tests.backend.camera.landmarks import batch, frame

LITE = "pose_landmarker_lite"


def _batch(seq: int, t0: float = 0.0, n: int = 3) -> dict[str, Any]:
    return batch(seq, [frame(t0 + k / 30) for k in range(n)])


def _post(client, set_id, body, headers):
    return client.post(f"/api/v1/camera/sets/{set_id}/batches", json=body, headers=headers)


def _batches(db_session, set_id) -> int:
    return db_session.scalar(
        select(func.count()).select_from(CameraBatch).where(CameraBatch.set_id == uuid.UUID(set_id))
    )


def test_consent_is_asked_then_recorded_then_withdrawn(client, camera_home):
    h = camera_home["headers"]
    assert client.get("/api/v1/camera/consent", headers=h).json()["given"] is False
    r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id, "model": LITE}, headers=h)
    assert r.status_code == 409 and r.json()["error"] == "ConsentMissing", r.text
    r = client.post("/api/v1/camera/consent", json={"consent_version": "2001-01-01"}, headers=h)
    assert r.status_code == 422 and "body.consent_version" in r.json()["detail"], r.text
    r = client.post("/api/v1/camera/consent", json={"consent_version": CONSENT_VERSION}, headers=h)
    assert r.status_code == 200 and r.json()["given"] is True, r.text
    r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id, "model": LITE}, headers=h)
    assert r.status_code == 201, r.text
    assert r.json()["target_reps"] == 3 and r.json()["status"] == "recording" and r.json()["last_seq"] == -1
    assert client.delete("/api/v1/camera/consent", headers=h).json()["given"] is False
    r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id, "model": LITE}, headers=h)
    assert r.status_code == 409, r.text


def test_only_the_patient_starts_a_set_of_their_own_plan(client, camera_home):
    for who in ("other_headers", "therapist_headers"):
        h = camera_home[who]
        client.post("/api/v1/camera/consent", json={"consent_version": CONSENT_VERSION}, headers=h)
        r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id, "model": LITE}, headers=h)
        assert r.status_code in (403, 404), (who, r.text)


def test_an_unknown_model_is_refused(client, camera_home, started):
    started()
    r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id, "model": "yolo"},
                    headers=camera_home["headers"])  # fmt: skip
    assert r.status_code == 422 and "model" in r.json()["detail"], r.text


def test_another_patients_set_and_a_set_the_server_did_not_start_are_not_found(client, camera_home, started):
    set_id = started()
    for set_ref, h in ((set_id, camera_home["other_headers"]), (str(uuid.uuid4()), camera_home["headers"])):
        r = _post(client, set_ref, _batch(0), h)
        assert r.status_code == 404 and r.json()["error"] == "CameraSetNotFound", r.text
        r = client.post(f"/api/v1/camera/sets/{set_ref}/end", json={"last_seq": -1}, headers=h)
        assert r.status_code == 404, r.text
    r = client.get(f"/api/v1/camera/sets/{set_id}", headers=camera_home["therapist_headers"])
    assert r.status_code == 403, r.text


def test_a_cookie_login_needs_the_csrf_header(client, camera_home, started):
    from backend.security import hash_password
    from tests.backend.conftest import PASSWORD

    set_id = started()
    patient = camera_home["patient"]
    patient.password_hash = hash_password(PASSWORD)
    r = client.post("/api/v1/auth/login", json={"email": patient.email, "password": PASSWORD})
    assert r.status_code == 200, r.text
    r = _post(client, set_id, _batch(0), {})
    assert r.status_code == 403 and r.json()["error"] == "CsrfFailed", r.text
    client.cookies.clear()


def _hostile(client, set_id, headers, raw: str) -> dict[str, Any]:
    r = client.post(f"/api/v1/camera/sets/{set_id}/batches", content=raw,
                    headers=headers | {"Content-Type": "application/json"})  # fmt: skip
    assert 400 <= r.status_code < 500, r.text
    return r.json()


def test_hostile_values_are_refused_naming_the_field(client, db_session, camera_home, started):
    set_id, h = started(), camera_home["headers"]
    good = _batch(0)
    cases = []
    nan = json.loads(json.dumps(good))
    nan["frames"][1]["world"][12][1] = 0.123456789  # a sentinel replaced by NaN in the JSON text
    cases.append((json.dumps(nan).replace("0.123456789", "NaN"), "frames[1].world[12][1]"))
    far = json.loads(json.dumps(good))
    far["frames"][2]["world"][25][2] = 1e6
    cases.append((json.dumps(far), "frames[2].world[25][2]"))
    img = json.loads(json.dumps(good))
    img["frames"][0]["image"][0][0] = -50
    cases.append((json.dumps(img), "frames[0].image[0][0]"))
    vis = json.loads(json.dumps(good))
    vis["frames"][1]["visibility"][3] = 1.5
    cases.append((json.dumps(vis), "frames[1].visibility[3]"))
    back = json.loads(json.dumps(good))
    back["frames"][2]["t"] = 0.0
    cases.append((json.dumps(back), "frames[2].t"))
    short = json.loads(json.dumps(good))
    short["frames"][0]["world"] = short["frames"][0]["world"][:20]
    cases.append((json.dumps(short), "frames.0.world"))
    negative = json.loads(json.dumps(good))
    negative["frames"][0]["t"] = -1
    cases.append((json.dumps(negative), "frames[0].t"))
    huge = batch(0, [frame(k / 30) for k in range(MAX_FRAMES_PER_BATCH + 1)])
    cases.append((json.dumps(huge), "frames"))
    inf = json.loads(json.dumps(good))
    inf["frames"][0]["image"][5][1] = 0.123456789
    cases.append((json.dumps(inf).replace("0.123456789", "Infinity"), "frames[0].image[5][1]"))
    for raw, field in cases:
        body = _hostile(client, set_id, h, raw)
        assert field in body["detail"], (field, body)
    assert _batches(db_session, set_id) == 0  # nothing stored, not even part of a batch


def test_time_going_back_across_batches_is_refused(client, camera_home, started, db_session):
    set_id, h = started(), camera_home["headers"]
    assert _post(client, set_id, _batch(0, t0=1.0), h).status_code == 201
    r = _post(client, set_id, _batch(1, t0=0.5), h)
    assert r.status_code == 422 and "frames[0].t" in r.json()["detail"], r.text
    assert _batches(db_session, set_id) == 1


def test_frames_under_a_millisecond_apart_are_refused_as_a_session_file_would_refuse_them(client, camera_home, started,
                                                                                           db_session):  # fmt: skip
    """No session file holds frames closer than 1 ms (over 1000 Hz), so no batch does: a set of such frames could
    never be stored. Frames 1 ms apart (the page's clock rounds to 1 ms) are taken, within and across batches."""
    set_id, h = started(), camera_home["headers"]
    close = batch(0, [frame(1.0), frame(1.0004), frame(1.1)])
    r = _post(client, set_id, close, h)
    assert r.status_code == 422 and "body.frames[1].t: 1.0004 s does not come 0.001 s" in r.json()["detail"], r.text
    assert _post(client, set_id, batch(0, [frame(1.123), frame(1.124), frame(1.2)]), h).status_code == 201
    r = _post(client, set_id, batch(1, [frame(1.2005), frame(1.3)]), h)
    assert r.status_code == 422 and "body.frames[0].t: 1.2005 s" in r.json()["detail"], r.text
    assert _post(client, set_id, batch(1, [frame(1.201), frame(1.3)]), h).status_code == 201
    assert _batches(db_session, set_id) == 2


def test_a_repeated_batch_is_stored_once_and_a_different_one_with_its_number_conflicts(client, camera_home, started,
                                                                                       db_session):  # fmt: skip
    set_id, h = started(), camera_home["headers"]
    first = _post(client, set_id, _batch(0), h)
    assert first.status_code == 201 and first.json()["repeated"] is False, first.text
    again = _post(client, set_id, _batch(0), h)
    assert again.status_code == 200 and again.json()["repeated"] is True, again.text
    assert again.json()["n_frames"] == 3
    r = _post(client, set_id, _batch(0, t0=0.5), h)
    assert r.status_code == 409 and r.json()["error"] == "BatchConflict", r.text
    r = _post(client, set_id, _batch(2, t0=1.0), h)
    assert r.status_code == 409 and r.json()["error"] == "BatchOutOfOrder" and "batch 1" in r.json()["detail"]
    assert _batches(db_session, set_id) == 1


def test_frames_ahead_of_the_sets_clock_are_refused(client, camera_home, started):
    set_id, h = started(seconds_ago=0), camera_home["headers"]
    r = _post(client, set_id, _batch(0, t0=30.0), h)
    assert r.status_code == 422 and "ahead of the set's clock" in r.json()["detail"], r.text


def test_more_frames_than_real_time_allows_are_rate_limited(client, camera_home, started, monkeypatch):
    monkeypatch.setattr("backend.camera.limits.MAX_FPS", 10.0)  # 10 s of allowance: 100 frames at the start
    set_id, h = started(seconds_ago=0), camera_home["headers"]
    r = _post(client, set_id, batch(0, [frame(k * 0.001) for k in range(90)]), h)
    assert r.status_code == 201, r.text
    r = _post(client, set_id, batch(1, [frame(0.1 + k * 0.001) for k in range(MAX_FRAMES_PER_BATCH)]), h)
    assert r.status_code == 429 and r.json()["error"] == "CameraRateLimited", r.text
    assert r.headers.get("retry-after") == "1"
