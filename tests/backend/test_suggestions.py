"""Suggestions API: who sees what, therapist-written advice, approve/dismiss, audit, and storing rule drafts."""

from __future__ import annotations

import datetime as dt
import uuid

import pytest
from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.database import utcnow
from backend.sessions.models import ExerciseSession
from backend.suggestions.models import Suggestion
from backend.suggestions.rules import AdviceParams, SuggestionDraft, evaluate
from backend.suggestions.service import add_system_suggestions, is_visible_to_patient
from tests.backend.session_rows import report

MONDAY = dt.date(2026, 11, 23)


@pytest.fixture
def care(make_patient_with_therapist, auth_headers, device_headers):
    """A patient with an assigned therapist; headers of the patient, the therapist and the patient's device."""
    patient, therapist = make_patient_with_therapist()
    _, device_hdr = device_headers(patient)
    return {
        "patient": patient,
        "therapist": therapist,
        "patient_hdr": auth_headers(patient),
        "therapist_hdr": auth_headers(therapist),
        "device_hdr": device_hdr,
    }


@pytest.fixture
def make_suggestion(db_session):
    """Factory: make_suggestion(patient, source='system', status='pending', minutes_ago=0) -> Suggestion."""

    def make(patient, source="system", status="pending", minutes_ago=0, session_id=None) -> Suggestion:
        row = Suggestion(
            patient_id=patient.id,
            session_id=session_id,
            source=source,
            rule="too_fast" if source == "system" else "therapist",
            metric="tempo_s_per_rep" if source == "system" else "",
            comparison="<" if source == "system" else "",
            threshold=1.5 if source == "system" else None,
            value=1.1 if source == "system" else None,
            text=f"{source} {status}",
            status=status,
            created_at=utcnow() - dt.timedelta(minutes=minutes_ago),
        )
        db_session.add(row)
        db_session.flush()
        return row

    return make


def _exercise_session(db_session, patient) -> ExerciseSession:
    row = ExerciseSession(
        client_session_id=uuid.uuid4(),
        patient_id=patient.id,
        started_at=utcnow(),
        duration_s=30.0,
        n_frames=900,
        file_bytes=b"",
        content_hash="0" * 64,
    )
    db_session.add(row)
    db_session.flush()
    return row


def _mixed(care, make_suggestion) -> dict[str, Suggestion]:
    p = care["patient"]
    return {
        "pending": make_suggestion(p, status="pending", minutes_ago=4),
        "approved": make_suggestion(p, status="approved", minutes_ago=3),
        "dismissed": make_suggestion(p, status="dismissed", minutes_ago=2),
        "therapist": make_suggestion(p, source="therapist", status="approved", minutes_ago=1),
    }


def _url(patient) -> str:
    return f"/api/v1/patients/{patient.id}/suggestions"


# --- listing ---


@pytest.mark.parametrize("who", ["patient_hdr", "device_hdr"])
def test_patient_and_device_see_approved_and_therapist_written_only(client, care, make_suggestion, who):
    rows = _mixed(care, make_suggestion)
    response = client.get(_url(care["patient"]), headers=care[who])
    assert response.status_code == 200, response.text
    body = response.json()
    assert [s["id"] for s in body["items"]] == [rows["therapist"].id, rows["approved"].id]
    assert body["total"] == 2


def test_therapist_sees_all_newest_first(client, care, make_suggestion):
    rows = _mixed(care, make_suggestion)
    body = client.get(_url(care["patient"]), headers=care["therapist_hdr"]).json()
    assert [s["id"] for s in body["items"]] == [rows[k].id for k in ("therapist", "dismissed", "approved", "pending")]


def test_therapist_filters_by_status(client, care, make_suggestion):
    rows = _mixed(care, make_suggestion)
    body = client.get(_url(care["patient"]), params={"status": "pending"}, headers=care["therapist_hdr"]).json()
    assert [s["id"] for s in body["items"]] == [rows["pending"].id]
    assert body["items"][0] | {"created_at": None} == {
        "id": rows["pending"].id,
        "patient_id": care["patient"].id,
        "session_id": None,
        "session_started_at": None,
        "source": "system",
        "author_id": None,
        "rule": "too_fast",
        "metric": "tempo_s_per_rep",
        "comparison": "<",
        "threshold": 1.5,
        "value": 1.1,
        "text": "system pending",
        "locale": None,  # a row without params: its text as stored
        "status": "pending",
        "created_at": None,
        "decided_at": None,
        "decided_by_id": None,
    }


def test_patient_asking_for_pending_gets_nothing(client, care, make_suggestion):
    _mixed(care, make_suggestion)
    body = client.get(_url(care["patient"]), params={"status": "pending"}, headers=care["patient_hdr"]).json()
    assert body == {"items": [], "total": 0, "limit": 50, "offset": 0}


def test_list_filters_by_session(client, db_session, care, make_suggestion):
    session = _exercise_session(db_session, care["patient"])
    row = make_suggestion(care["patient"], session_id=session.id)
    make_suggestion(care["patient"])
    body = client.get(_url(care["patient"]), params={"session_id": session.id}, headers=care["therapist_hdr"]).json()
    assert [s["id"] for s in body["items"]] == [row.id]


def test_list_paginates(client, care, make_suggestion):
    rows = [make_suggestion(care["patient"], minutes_ago=m) for m in range(5)]
    body = client.get(_url(care["patient"]), params={"limit": 2, "offset": 1}, headers=care["therapist_hdr"]).json()
    assert [s["id"] for s in body["items"]] == [rows[1].id, rows[2].id]
    assert (body["total"], body["limit"], body["offset"]) == (5, 2, 1)


def test_list_rejects_unknown_status(client, care):
    response = client.get(_url(care["patient"]), params={"status": "maybe"}, headers=care["therapist_hdr"])
    assert response.status_code == 422
    assert response.json()["detail"].startswith("query.status:")


def test_list_unknown_patient_is_404(client, care):
    response = client.get("/api/v1/patients/2147483000/suggestions", headers=care["therapist_hdr"])
    assert response.status_code == 404
    assert response.json() == {"error": "PatientNotFound", "detail": "patient 2147483000 does not exist"}


def test_list_is_audited(client, db_session, care):
    client.get(_url(care["patient"]), headers=care["patient_hdr"])
    event = db_session.scalar(select(AuditEvent).where(AuditEvent.action == "suggestion.list"))
    assert (event.actor_user_id, event.patient_id) == (care["patient"].id, care["patient"].id)


# --- therapist-written ---


def test_therapist_writes_a_suggestion_the_patient_sees(client, db_session, care):
    response = client.post(
        _url(care["patient"]), json={"text": "  Hold each squat for 2 s. "}, headers=care["therapist_hdr"]
    )
    assert response.status_code == 201, response.text
    out = response.json()
    assert (out["source"], out["status"], out["author_id"], out["text"]) == (
        "therapist",
        "approved",
        care["therapist"].id,
        "Hold each squat for 2 s.",
    )
    listed = client.get(_url(care["patient"]), headers=care["patient_hdr"]).json()["items"]
    assert [s["id"] for s in listed] == [out["id"]]
    event = db_session.scalar(select(AuditEvent).where(AuditEvent.action == "suggestion.create"))
    assert (event.object_id, event.actor_user_id) == (str(out["id"]), care["therapist"].id)


def test_therapist_suggestion_about_a_session(client, db_session, care):
    session = _exercise_session(db_session, care["patient"])
    body = {"text": "Good set.", "session_id": session.id}
    response = client.post(_url(care["patient"]), json=body, headers=care["therapist_hdr"])
    assert response.status_code == 201, response.text
    assert response.json()["session_id"] == session.id


def test_therapist_suggestion_refuses_another_patients_session(client, db_session, care, make_user):
    session = _exercise_session(db_session, make_user("patient"))
    body = {"text": "Good set.", "session_id": session.id}
    response = client.post(_url(care["patient"]), json=body, headers=care["therapist_hdr"])
    assert response.status_code == 422
    assert response.json() == {
        "error": "InvalidInput",
        "detail": f"body.session_id: session {session.id} is not a session of patient {care['patient'].id}",
    }


@pytest.mark.parametrize(
    ("body", "detail"),
    [
        ({"text": "   "}, "body.text: Value error, text must not be blank"),
        ({"text": ""}, "body.text: String should have at least 1 character"),
        ({"text": "x" * 2001}, "body.text: String should have at most 2000 characters"),
        ({"text": "a\x00b"}, "text fields may not contain NUL characters (\\u0000)"),  # backend/request_limits.py
        ({"text": "x", "status": "pending"}, "body.status: Extra inputs are not permitted"),
    ],
)
def test_therapist_suggestion_bad_body(client, care, body, detail):
    response = client.post(_url(care["patient"]), json=body, headers=care["therapist_hdr"])
    assert response.status_code == 422
    assert response.json()["detail"] == detail


def test_patient_cannot_write_a_suggestion(client, care):
    response = client.post(_url(care["patient"]), json={"text": "x"}, headers=care["patient_hdr"])
    assert response.status_code == 403
    assert response.json()["error"] == "Forbidden"


# --- approve / dismiss ---


def _decide(client, care, suggestion_id: int, action: str):
    return client.post(f"/api/v1/suggestions/{suggestion_id}/{action}", headers=care["therapist_hdr"])


def test_approve_makes_it_visible_to_the_patient(client, db_session, care, make_suggestion):
    row = make_suggestion(care["patient"])
    response = _decide(client, care, row.id, "approve")
    assert response.status_code == 200, response.text
    out = response.json()
    assert (out["status"], out["decided_by_id"]) == ("approved", care["therapist"].id)
    assert out["decided_at"] is not None
    listed = client.get(_url(care["patient"]), headers=care["patient_hdr"]).json()["items"]
    assert [s["id"] for s in listed] == [row.id]
    event = db_session.scalar(select(AuditEvent).where(AuditEvent.action == "suggestion.approve"))
    assert (event.object_id, event.patient_id) == (str(row.id), care["patient"].id)


def test_dismiss_hides_it_from_the_patient(client, care, make_suggestion):
    row = make_suggestion(care["patient"])
    response = _decide(client, care, row.id, "dismiss")
    assert response.status_code == 200, response.text
    assert response.json()["status"] == "dismissed"
    assert client.get(_url(care["patient"]), headers=care["patient_hdr"]).json()["items"] == []


@pytest.mark.parametrize("action", ["approve", "dismiss"])
@pytest.mark.parametrize("status", ["approved", "dismissed"])
def test_decided_suggestion_is_409(client, care, make_suggestion, action, status):
    row = make_suggestion(care["patient"], status=status)
    response = _decide(client, care, row.id, action)
    assert response.status_code == 409
    assert response.json() == {
        "error": "SuggestionNotPending",
        "detail": f"suggestion {row.id} is already {status}; only pending suggestions can be decided",
    }


def test_therapist_written_suggestion_cannot_be_dismissed(client, care, make_suggestion):
    row = make_suggestion(care["patient"], source="therapist", status="approved")
    response = _decide(client, care, row.id, "dismiss")
    assert response.status_code == 409
    assert response.json()["detail"] == (
        f"suggestion {row.id} was written by a therapist; only pending system suggestions can be decided"
    )


def test_unknown_suggestion_is_404(client, care):
    response = _decide(client, care, 2147483000, "approve")
    assert response.status_code == 404
    assert response.json() == {"error": "SuggestionNotFound", "detail": "suggestion 2147483000 does not exist"}


def test_unassigned_therapist_cannot_approve(client, care, make_suggestion, make_user, auth_headers):
    row = make_suggestion(care["patient"])
    response = client.post(f"/api/v1/suggestions/{row.id}/approve", headers=auth_headers(make_user("therapist")))
    assert response.status_code == 404
    assert response.json()["detail"] == f"suggestion {row.id} does not exist"


# --- storing rule drafts ---


def test_rule_drafts_are_stored_pending_and_reviewable(client, db_session, care):
    session = _exercise_session(db_session, care["patient"])
    doc = report(exercise="sit_to_stand", repetitions=6, rom_deg=80.0, tempo_s_per_rep=1.0, quality={"ok": True})
    saturday = dt.datetime(2026, 11, 21, 18, 30, tzinfo=dt.UTC)
    drafts = evaluate(doc, prescribed_reps=10, history=[], expected_per_week=None, now=saturday, today=MONDAY)
    rows = add_system_suggestions(drafts, patient_id=care["patient"].id, session_id=session.id, db_session=db_session)
    assert [r.rule for r in rows] == ["fewer_reps", "too_fast"]
    assert all(r.id is not None for r in rows), "add_system_suggestions must flush"
    body = client.get(_url(care["patient"]), params={"status": "pending"}, headers=care["therapist_hdr"]).json()
    by_rule = {s["rule"]: s for s in body["items"]}
    fewer = by_rule["fewer_reps"]
    assert (fewer["metric"], fewer["value"], fewer["comparison"], fewer["threshold"]) == ("repetitions", 6.0, "<", 10.0)
    assert by_rule["fewer_reps"]["session_id"] == session.id
    assert fewer["text"] == (
        "On Saturday you did 6 of the 10 sit-to-stands in your plan. Next time, try to do all 10. "
        "Rest for a moment between them if you need to."
    )
    assert by_rule["too_fast"]["text"].startswith("On Saturday you did your sit-to-stands quickly")
    assert client.get(_url(care["patient"]), headers=care["patient_hdr"]).json()["total"] == 0


def test_rule_drafts_are_not_repeated_for_the_same_session(db_session, care):
    session = _exercise_session(db_session, care["patient"])
    params = AdviceParams(session_on=MONDAY, written_on=MONDAY, tempo_s_per_rep=1.0, advised_s_per_rep=2)
    draft = SuggestionDraft("too_fast", "tempo_s_per_rep", "<", 1.5, 1.0, params, "Slow down.")
    kwargs = {"patient_id": care["patient"].id, "session_id": session.id, "db_session": db_session}
    assert len(add_system_suggestions([draft, draft], **kwargs)) == 1
    assert add_system_suggestions([draft], **kwargs) == []
    count = db_session.scalar(select(Suggestion.id).where(Suggestion.session_id == session.id).limit(2).offset(1))
    assert count is None, "only one stored suggestion per rule and session"


def test_no_drafts_store_nothing(db_session, care):
    assert add_system_suggestions([], patient_id=care["patient"].id, session_id=None, db_session=db_session) == []


# --- documentation ---


def test_openapi_documents_errors_and_examples(client):
    schema = client.get("/openapi.json").json()
    approve = schema["paths"]["/api/v1/suggestions/{suggestion_id}/approve"]["post"]["responses"]
    assert set(approve["409"]["content"]["application/json"]["examples"]) == {"SuggestionNotPending"}
    assert set(approve["404"]["content"]["application/json"]["examples"]) == {"SuggestionNotFound"}
    out = schema["components"]["schemas"]["SuggestionOut"]
    assert out["examples"][0]["rule"] == "fewer_reps"


def test_is_visible_to_patient_matches_the_list_filter(client, care, make_suggestion):
    rows = _mixed(care, make_suggestion)
    listed = {s["id"] for s in client.get(_url(care["patient"]), headers=care["patient_hdr"]).json()["items"]}
    assert {r.id for r in rows.values() if is_visible_to_patient(r)} == listed


@pytest.mark.parametrize(
    "draft",
    [{"rule": "too_fast"}, SuggestionDraft("made_up", "x", "<", 1.0, 0.0, AdviceParams(), "text")],
    ids=["dict", "rule"],
)
def test_add_system_suggestions_rejects_bad_drafts(db_session, care, draft):
    with pytest.raises(ValueError, match=r"drafts\[0\] must be a SuggestionDraft of a known rule"):
        add_system_suggestions([draft], patient_id=care["patient"].id, session_id=None, db_session=db_session)


def test_decided_pages_and_each_suggestion_names_its_sessions_start(
    client, db_session, make_patient_with_therapist, auth_headers, exercise
):
    import datetime as dt
    import uuid

    from backend.sessions.models import ExerciseSession
    from backend.suggestions.models import Suggestion

    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    started = dt.datetime(2026, 11, 2, 9, 30, tzinfo=dt.UTC)
    session = ExerciseSession(client_session_id=uuid.uuid4(), patient_id=patient.id, exercise_id=exercise.id,
                              started_at=started, duration_s=30.0, n_frames=900, file_bytes=b"",
                              content_hash=uuid.uuid4().hex * 2)  # fmt: skip
    db_session.add(session)
    db_session.flush()
    for k in range(7):
        db_session.add(Suggestion(patient_id=patient.id, source="system", rule="r", text=f"t{k}", status="approved",
                                  session_id=session.id if k == 6 else None))  # fmt: skip
    db_session.add(Suggestion(patient_id=patient.id, source="system", rule="r", text="waiting", status="pending"))
    db_session.flush()
    url = f"/api/v1/patients/{patient.id}/suggestions?decided=true&limit=5"
    first = client.get(url, headers=headers).json()
    rest = client.get(url + "&offset=5", headers=headers).json()
    assert (first["total"], len(first["items"]), len(rest["items"])) == (7, 5, 2)
    assert all(s["status"] != "pending" for s in first["items"] + rest["items"])
    about = [s for s in first["items"] + rest["items"] if s["session_id"] == session.id]
    assert len(about) == 1 and about[0]["session_started_at"].startswith("2026-11-02T09:30"), about
    assert all(s["session_started_at"] is None for s in first["items"] + rest["items"] if s["session_id"] is None)
