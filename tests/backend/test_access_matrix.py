"""Every API route x every kind of caller: allowed callers get 2xx, everyone else 401/403/404.

ROUTES must list every route of the app (a new route without an entry fails the test), with the callers it
allows and a request body. Each call runs in a SAVEPOINT that is rolled back, so calls do not affect each other.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from typing import Any

import pytest
from fastapi.routing import iter_route_contexts

from backend.camera.limits import CONSENT_VERSION
from backend.camera.models import CameraConsent, CameraSet
from backend.database import utcnow
from backend.devices.service import create_pairing_code
from backend.plans.models import Plan, PlanItem
from backend.replies.models import AdviceReply
from backend.sessions.models import ExerciseSession
from backend.suggestions.models import Suggestion
from tests.backend.conftest import PASSWORD
from tests.backend.khs_files import make_khs

CALLERS = ("anonymous", "patient_own", "patient_other", "therapist_assigned", "therapist_other", "admin", "device")
PUBLIC = set(CALLERS)
AUTHED = PUBLIC - {"anonymous"}
USERS = AUTHED - {"device"}
CARE = {"patient_own", "therapist_assigned", "admin"}  # may see and manage the own patient
CARE_DEV = CARE | {"device"}
PRESCRIBE = {"therapist_assigned", "admin"}
STAFF = {"therapist_assigned", "therapist_other", "admin"}  # sees only the patients they may see
ADMIN = {"admin"}
PATIENTS = {"patient_own", "patient_other"}


LIVE_SET_ID = str(uuid.uuid4())  # the set the server started on the world's device (progress is only for it)


def _progress_body():
    return {"set_id": LIVE_SET_ID, "exercise_slug": "squat", "state": "recording", "count": 2, "target": 5}


def _camera_start(w):
    return {"plan_item_id": w["params"]["plan_item_id"], "model": "pose_landmarker_lite"}


def _camera_batch():
    from tests.backend.camera.landmarks import batch, frame

    return batch(0, [frame(k / 30) for k in range(3)])


def _plan_body(w):
    return {
        "title": "p",
        "start_date": "2026-11-23",
        "items": [{"exercise_slug": w["exercise_slug"], "sets": 1, "repetitions": 5, "frequency_per_week": 2}],
    }


@dataclass
class Raw:
    """A non-JSON request body (e.g. a session file) and its query parameters."""

    content: bytes
    params: dict[str, Any]


# (method, path) -> (allowed callers, body factory or None); a factory returns JSON data or a Raw
ROUTES = {
    ("GET", "/healthz"): (PUBLIC, None),
    ("GET", "/api/v1/version"): (PUBLIC, None),
    ("POST", "/api/v1/auth/login"): (PUBLIC, lambda w: {"email": w["own_email"], "password": PASSWORD}),
    ("POST", "/api/v1/auth/logout"): (AUTHED, None),
    ("GET", "/api/v1/auth/csrf"): (set(), None),  # bearer callers have no CSRF token; cookie case in test_auth
    ("POST", "/api/v1/tokens"): (USERS, lambda w: {"name": "m", "scopes": ["read"]}),
    ("GET", "/api/v1/tokens"): (USERS, None),
    ("DELETE", "/api/v1/tokens/{token_id}"): (ADMIN, None),  # token_id is the admin's own token
    ("GET", "/api/v1/users/me"): (USERS, None),
    ("GET", "/api/v1/users"): (ADMIN, None),
    ("POST", "/api/v1/users"): (
        ADMIN,
        lambda w: {"email": "new-matrix@example.org", "role": "patient", "password": "0123456789"},
    ),
    ("GET", "/api/v1/users/{user_id}"): (ADMIN, None),
    ("PATCH", "/api/v1/users/{user_id}"): (ADMIN, lambda w: {"full_name": "Renamed"}),
    ("GET", "/api/v1/patients"): (AUTHED, None),
    ("GET", "/api/v1/patients/{patient_id}"): (CARE_DEV, None),
    ("GET", "/api/v1/patients/{patient_id}/therapists"): (CARE_DEV, None),
    ("PATCH", "/api/v1/patients/{patient_id}"): (CARE, lambda w: {"locale": "de"}),
    ("GET", "/api/v1/patients/{patient_id}/voice"): (CARE_DEV, None),
    ("PUT", "/api/v1/patients/{patient_id}/voice"): (CARE, lambda w: {"enabled": False, "volume": 0.5}),
    ("PUT", "/api/v1/patients/{patient_id}/therapists/{therapist_id}"): (ADMIN, None),
    ("DELETE", "/api/v1/patients/{patient_id}/therapists/{therapist_id}"): (ADMIN, None),
    ("POST", "/api/v1/patients/{patient_id}/pairing-codes"): (CARE, None),
    ("POST", "/api/v1/devices/pair"): (PUBLIC, lambda w: {"code": w["pairing_code"], "name": "m"}),
    ("GET", "/api/v1/devices/me"): ({"device"}, None),
    ("GET", "/api/v1/patients/{patient_id}/devices"): (CARE, None),
    ("DELETE", "/api/v1/devices/{device_id}"): (CARE, None),  # device_id is ANOTHER device of the own patient
    ("GET", "/api/v1/exercises"): (AUTHED, None),
    ("GET", "/api/v1/exercises/{slug}"): (AUTHED, None),
    ("GET", "/api/v1/exercises/{slug}/demonstration"): (AUTHED, None),
    ("GET", "/api/v1/patients/{patient_id}/plans"): (CARE_DEV, None),
    ("POST", "/api/v1/patients/{patient_id}/plans"): (PRESCRIBE, _plan_body),
    ("GET", "/api/v1/plans/{plan_id}"): (CARE_DEV, None),
    ("PUT", "/api/v1/plans/{plan_id}"): (PRESCRIBE, _plan_body),
    ("DELETE", "/api/v1/plans/{plan_id}"): (PRESCRIBE, None),
    ("GET", "/api/v1/patients/{patient_id}/suggestions"): (CARE_DEV, None),
    ("POST", "/api/v1/patients/{patient_id}/suggestions"): (PRESCRIBE, lambda w: {"text": "Keep going."}),
    ("POST", "/api/v1/suggestions/{suggestion_id}/approve"): (PRESCRIBE, None),  # a pending system suggestion
    ("POST", "/api/v1/suggestions/{suggestion_id}/dismiss"): (PRESCRIBE, None),
    ("GET", "/api/v1/patients/{patient_id}/replies"): (CARE_DEV, None),
    ("POST", "/api/v1/patients/{patient_id}/replies"): (  # only the patient answers, and only advice they see
        {"patient_own"},
        lambda w: {"suggestion_id": w["advice_id"], "preset": "hurt"},
    ),
    ("POST", "/api/v1/patients/{patient_id}/replies/read"): (PRESCRIBE, lambda w: {"reply_ids": [w["reply_id"]]}),
    ("GET", "/api/v1/replies"): (STAFF, None),  # therapists: the replies of their assigned patients only
    ("GET", "/api/v1/audit"): (ADMIN, None),
    ("POST", "/api/v1/sessions"): (CARE_DEV, lambda w: Raw(w["khs"], {"patient_id": w["params"]["patient_id"]})),
    ("GET", "/api/v1/sessions"): (AUTHED, None),  # lists only what the caller may see
    ("GET", "/api/v1/sessions/{session_id}"): (CARE_DEV, None),
    ("GET", "/api/v1/sessions/{session_id}/file"): (CARE_DEV, None),
    ("GET", "/api/v1/sessions/{session_id}/feeling"): (CARE_DEV, None),
    ("PUT", "/api/v1/sessions/{session_id}/feeling"): ({"patient_own"}, lambda w: {"pain": 2, "effort": 3.5}),
    ("GET", "/api/v1/sessions/{session_id}/detail"): (CARE, None),  # people only: devices do not read it
    ("GET", "/api/v1/sessions/{session_id}/export"): (CARE, lambda w: Raw(b"", {"format": "trc"})),  # as detail
    ("GET", "/api/v1/sessions/{session_id}/replay"): (CARE_DEV, None),
    ("GET", "/api/v1/sessions/{session_id}/replay/state"): (CARE_DEV, None),
    ("GET", "/api/v1/events"): (AUTHED, None),  # each caller gets the events of the patients they may see
    ("GET", "/api/v1/live/agent"): ({"device"}, None),
    ("POST", "/api/v1/live/progress"): ({"device"}, lambda w: _progress_body()),
    ("GET", "/api/v1/live/status"): ({"patient_own", "patient_other", "device"}, None),  # without patient_id: own
    ("POST", "/api/v1/live/start"): ({"patient_own"}, lambda w: {"plan_item_id": w["params"]["plan_item_id"]}),
    ("POST", "/api/v1/live/stop"): ({"patient_own", "patient_other"}, lambda w: {"set_id": str(uuid.uuid4())}),
    ("GET", "/api/v1/patients/{patient_id}/progress"): (CARE_DEV, None),
    ("GET", "/api/v1/patients/{patient_id}/summary"): (CARE_DEV, None),
    ("GET", "/api/v1/dashboard"): (STAFF, None),  # therapists: assigned patients only
    ("GET", "/api/v1/camera/consent"): (PATIENTS, None),  # each patient their own
    ("POST", "/api/v1/camera/consent"): (PATIENTS, lambda w: {"consent_version": CONSENT_VERSION}),
    ("DELETE", "/api/v1/camera/consent"): (PATIENTS, None),
    ("POST", "/api/v1/camera/sets"): ({"patient_own"}, lambda w: _camera_start(w)),
    ("GET", "/api/v1/camera/sets/{set_id}"): ({"patient_own"}, None),  # only the set's patient
    ("POST", "/api/v1/camera/sets/{set_id}/batches"): ({"patient_own"}, lambda w: _camera_batch()),
    ("POST", "/api/v1/camera/sets/{set_id}/end"): ({"patient_own"}, lambda w: {"last_seq": -1}),
    ("GET", "/api/v1/patients/{patient_id}/archive"): ({"patient_own", "admin"}, None),  # the patient, or an admin
    ("POST", "/api/v1/patients/{patient_id}/archive"): ({"patient_own", "admin"}, None),
    ("GET", "/api/v1/patients/{patient_id}/archive/status"): ({"patient_own", "admin"}, None),
    ("POST", "/api/v1/patients/{patient_id}/erasure"): (ADMIN, lambda w: {"confirm_email": w["own_email"]}),
    ("GET", "/api/v1/patients/{patient_id}/report.pdf"): (CARE, None),
    ("POST", "/api/v1/reanalysis"): (ADMIN, lambda w: {"patient_id": w["params"]["patient_id"]}),
    ("GET", "/api/v1/reanalysis/{batch}"): (ADMIN, None),  # a batch queued in the world below
    ("GET", "/api/v1/reanalysis"): (ADMIN, None),
    ("GET", "/api/v1/jobs"): (ADMIN, None),
    ("GET", "/api/v1/sessions/{session_id}/metric-versions"): (CARE, None),
    ("GET", "/api/v1/patients/{patient_id}/reminders"): (CARE_DEV, None),
    ("POST", "/api/v1/reminders/unsubscribe/{token}"): (PUBLIC, None),  # the e-mail's token is the authority
}


@pytest.fixture
def world(db_session, make_user, make_patient_with_therapist, auth_headers, device_headers, exercise):
    """Own patient with an assigned therapist, another patient and therapist, an admin, devices, a plan, a code."""
    own, therapist = make_patient_with_therapist()
    own.password_hash = __import__("backend.security", fromlist=["x"]).hash_password(PASSWORD)
    other, other_therapist, admin = make_user("patient"), make_user("therapist"), make_user("admin")
    device, device_hdr = device_headers(own)
    second_device, _ = device_headers(own)
    plan = Plan(patient_id=own.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
    plan.items.append(PlanItem(exercise_id=exercise.id, sets=1, repetitions=5, frequency_per_week=2))
    db_session.add(plan)
    device.live_stream_id, device.last_seen_at = str(uuid.uuid4()), utcnow()  # the home agent is connected
    device.live_set_id = LIVE_SET_ID
    suggestion = Suggestion(patient_id=own.id, source="system", rule="too_fast", text="Slow down.", status="pending")
    advice = Suggestion(patient_id=own.id, source="therapist", rule="therapist", text="Well done.", status="approved")
    db_session.add_all([suggestion, advice])
    db_session.flush()
    reply = AdviceReply(suggestion_id=advice.id, patient_id=own.id, preset="done")
    db_session.add(reply)
    session = ExerciseSession(
        client_session_id=uuid.uuid4(),
        patient_id=own.id,
        exercise_id=exercise.id,
        started_at=utcnow(),
        duration_s=1.0,
        n_frames=30,
        file_bytes=make_khs("squat", 1, seed=12),  # a real file: detail and replay decode it
        content_hash="0" * 64,
    )
    db_session.add(session)
    db_session.flush()
    db_session.add(CameraConsent(patient_id=own.id, consent_version=CONSENT_VERSION, given_at=utcnow()))
    camera_set = CameraSet(id=uuid.uuid4(), patient_id=own.id, plan_item_id=plan.items[0].id, exercise_id=exercise.id,
                           target_reps=5, model_name="pose_landmarker_lite", started_at=utcnow())  # fmt: skip
    db_session.add(camera_set)
    db_session.flush()
    _, code = create_pairing_code(db_session=db_session, patient_id=own.id, created_by_id=own.id, minutes=15)
    from backend.users.service import create_api_token

    admin_token, _ = create_api_token(db_session=db_session, user=admin, name="victim", scopes=["read"], days=1)
    from backend.jobs.queue import enqueue

    enqueue(db_session=db_session, kind="reanalyze", items=[("matrix", {"session_id": session.id})], batch="matrix")
    from backend.reminders.service import DueReminder, claim

    claimed = claim(db_session=db_session, reminder=DueReminder(plan.id, own.id, utcnow().date(), "08:00", utcnow()))
    assert claimed is not None
    _, unsubscribe_token = claimed
    headers = {
        "anonymous": {},
        "patient_own": auth_headers(own),
        "patient_other": auth_headers(other),
        "therapist_assigned": auth_headers(therapist),
        "therapist_other": auth_headers(other_therapist),
        "admin": auth_headers(admin),
        "device": device_hdr,
    }
    params = {
        "patient_id": own.id,
        "therapist_id": other_therapist.id,
        "user_id": own.id,
        "device_id": second_device.id,
        "plan_id": plan.id,
        "plan_item_id": plan.items[0].id,
        "suggestion_id": suggestion.id,
        "token_id": admin_token.id,
        "slug": exercise.slug,
        "session_id": session.id,
        "set_id": str(camera_set.id),
        "batch": "matrix",
        "token": unsubscribe_token,
    }
    return {
        "headers": headers,
        "params": params,
        "own_email": own.email,
        "pairing_code": code,
        "exercise_slug": exercise.slug,
        "khs": make_khs("squat", 2, seed=11),
        "advice_id": advice.id,
        "reply_id": reply.id,
    }


DOC_PATHS = {"/openapi.json", "/docs", "/docs/oauth2-redirect", "/redoc"}


def _api_routes(app) -> list[tuple[str, str]]:
    """Returns (method, path) of every route of the app, included routers flattened, docs and HTML pages left out."""
    out = []
    for ctx in iter_route_contexts(app.routes):
        assert ctx.path is not None, ctx
        if ctx.path in DOC_PATHS or not ctx.methods or not getattr(ctx.route, "include_in_schema", True):
            continue
        out += [(m, ctx.path) for m in sorted(set(ctx.methods) - {"HEAD"})]
    return out


def test_every_route_is_in_the_table(app):
    missing = [r for r in _api_routes(app) if r not in ROUTES]
    assert not missing, f"routes without an access expectation in ROUTES: {missing}"
    stale = [r for r in ROUTES if r not in _api_routes(app)]
    assert not stale, f"ROUTES lists routes the app does not have: {stale}"


def test_access_matrix(app, client, world, db_connection, db_session):
    failures = []
    db_session.commit()  # release the session's SAVEPOINT so ours below is not nested inside it
    for method, path in _api_routes(app):
        allowed, body = ROUTES[(method, path)]
        url = path.format(**{k: v for k, v in world["params"].items() if "{" + k + "}" in path})
        for caller in CALLERS:
            savepoint = db_connection.begin_nested()
            kwargs = {"headers": world["headers"][caller]}
            if body is not None:
                made = body(world)
                kwargs.update(
                    {"content": made.content, "params": made.params} if isinstance(made, Raw) else {"json": made}
                )
            response = client.request(method, url, **kwargs)
            client.cookies.clear()
            savepoint.rollback()
            db_session.expire_all()
            ok = 200 <= response.status_code < 300
            expected_denial = (401,) if caller == "anonymous" else (403, 404)
            if caller in allowed and not ok:
                failures.append(f"{caller} {method} {url}: expected 2xx, got {response.status_code} {response.text}")
            if caller not in allowed and response.status_code not in expected_denial:
                failures.append(f"{caller} {method} {url}: expected {expected_denial}, got {response.status_code}")
    assert not failures, "\n".join(failures)
