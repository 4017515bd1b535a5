"""Replies to advice: the patient answers, therapists read; access, validation, audit, unread to read, dashboard."""

from __future__ import annotations

import pytest
from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.replies.models import AdviceReply
from backend.suggestions.models import Suggestion


@pytest.fixture
def care(make_patient_with_therapist, make_user, auth_headers, device_headers, db_session):
    """A patient with an assigned therapist, advice they see (therapist-written) and advice they do not (pending)."""
    patient, therapist = make_patient_with_therapist()
    other_patient, other_therapist, admin = make_user("patient"), make_user("therapist"), make_user("admin")
    seen = Suggestion(patient_id=patient.id, source="therapist", rule="therapist", text="Hold each squat.",
                      status="approved", author_id=therapist.id)  # fmt: skip
    pending = Suggestion(patient_id=patient.id, source="system", rule="too_fast", text="Slow down.", status="pending")
    elsewhere = Suggestion(patient_id=other_patient.id, source="therapist", rule="therapist", text="Walk daily.",
                           status="approved")  # fmt: skip
    db_session.add_all([seen, pending, elsewhere])
    out = {
        "patient": patient,
        "therapist": therapist,
        "seen": seen,
        "pending": pending,
        "elsewhere": elsewhere,
        "patient_hdr": auth_headers(patient),
        "other_patient_hdr": auth_headers(other_patient),
        "therapist_hdr": auth_headers(therapist),
        "other_therapist_hdr": auth_headers(other_therapist),
        "admin_hdr": auth_headers(admin),
        "device_hdr": device_headers(patient)[1],
    }
    db_session.commit()  # a refused request rolls back to here, not further
    return out


def _url(care, tail: str = "") -> str:
    return f"/api/v1/patients/{care['patient'].id}/replies{tail}"


def _reply(client, care, **body):
    return client.post(_url(care), json={"suggestion_id": care["seen"].id, **body}, headers=care["patient_hdr"])


def test_patient_answers_with_a_preset_and_with_words(client, care):
    hurt = _reply(client, care, preset="hurt")
    words = _reply(client, care, text="  Done, but slowly.  ")
    assert (hurt.status_code, words.status_code) == (201, 201), (hurt.text, words.text)
    assert (hurt.json()["preset"], hurt.json()["text"], hurt.json()["read_at"]) == ("hurt", None, None)
    assert (words.json()["preset"], words.json()["text"]) == (None, "Done, but slowly.")
    assert hurt.json()["suggestion_text"] == "Hold each squat."
    listed = client.get(_url(care), headers=care["patient_hdr"]).json()
    assert [r["id"] for r in listed["items"]] == [words.json()["id"], hurt.json()["id"]]  # newest first
    assert listed["total"] == 2


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({}, "body: Value error, give a preset, a text, or both"),
        ({"text": "   "}, "body.text: Value error, text must not be blank"),
        ({"text": "x" * 501}, "body.text: String should have at most 500 characters"),
        ({"preset": "great"}, "body.preset: Input should be 'done', 'hurt' or 'call_me'"),
        ({"preset": "done", "mood": 3}, "body.mood: Extra inputs are not permitted"),
    ],
)
def test_invalid_replies_are_refused_with_the_field_named(client, care, body, field):
    response = _reply(client, care, **body)
    assert response.status_code == 422
    assert response.json()["error"] == "ValidationError"
    assert field in response.json()["detail"]


def test_only_the_patient_answers_and_only_advice_they_see(client, care):
    body = {"suggestion_id": care["seen"].id, "preset": "done"}
    assert client.post(_url(care), json=body, headers=care["therapist_hdr"]).json()["error"] == "Forbidden"
    assert client.post(_url(care), json=body, headers=care["device_hdr"]).status_code == 403
    assert client.post(_url(care), json=body, headers=care["other_patient_hdr"]).json()["error"] == "PatientNotFound"
    for hidden in ("pending", "elsewhere"):  # not yet approved, or another patient's: as if it did not exist
        response = _reply(client, care, suggestion_id=care[hidden].id, preset="done")
        assert response.status_code == 404
        assert response.json() == {
            "error": "SuggestionNotFound",
            "detail": f"suggestion {care[hidden].id} does not exist",
        }


def test_who_reads_the_replies(client, care):
    _reply(client, care, preset="call_me")
    for who in ("patient_hdr", "therapist_hdr", "admin_hdr", "device_hdr"):
        assert client.get(_url(care), headers=care[who]).json()["total"] == 1, who
    for who in ("other_patient_hdr", "other_therapist_hdr"):
        assert client.get(_url(care), headers=care[who]).json()["error"] == "PatientNotFound", who
    assert client.get(_url(care)).status_code == 401
    assert client.get("/api/v1/replies", headers=care["other_therapist_hdr"]).json()["total"] == 0
    assert client.get("/api/v1/replies", headers=care["patient_hdr"]).status_code == 403


def test_unread_until_the_therapist_marks_what_they_saw(client, db_session, care):
    first = _reply(client, care, preset="hurt").json()
    second = _reply(client, care, text="Call me please").json()
    unread = client.get("/api/v1/replies?unread=true", headers=care["therapist_hdr"]).json()
    assert [r["id"] for r in unread["items"]] == [second["id"], first["id"]]
    read = client.post(_url(care, "/read"), json={"reply_ids": [first["id"]]}, headers=care["therapist_hdr"])
    assert read.status_code == 200, read.text
    assert read.json() == {"marked": 1}
    again = client.post(_url(care, "/read"), json={"reply_ids": [first["id"]]}, headers=care["therapist_hdr"])
    assert again.json() == {"marked": 0}  # already read: its first reader and time stay
    left = client.get(_url(care, "?unread=true"), headers=care["therapist_hdr"]).json()["items"]
    assert [r["id"] for r in left] == [second["id"]]  # the one not yet seen stays unread
    row = db_session.get(AdviceReply, first["id"])
    assert row.read_by_id == care["therapist"].id and row.read_at is not None


def test_marking_read_is_for_the_care_team_and_their_own_replies(client, care):
    reply = _reply(client, care, preset="done").json()
    body = {"reply_ids": [reply["id"]]}
    assert client.post(_url(care, "/read"), json=body, headers=care["patient_hdr"]).status_code == 403
    assert client.post(_url(care, "/read"), json=body, headers=care["other_therapist_hdr"]).status_code == 404
    unknown = client.post(_url(care, "/read"), json={"reply_ids": [reply["id"], 2**31 - 1]},
                          headers=care["therapist_hdr"])  # fmt: skip
    assert unknown.status_code == 404
    assert unknown.json() == {"error": "ReplyNotFound", "detail": f"reply {2**31 - 1} does not exist"}
    empty = client.post(_url(care, "/read"), json={"reply_ids": []}, headers=care["therapist_hdr"])
    assert (empty.status_code, empty.json()["error"]) == (422, "ValidationError")
    assert client.get(_url(care, "?unread=true"), headers=care["admin_hdr"]).json()["total"] == 1  # nothing marked


def test_replies_are_audited_without_their_words(client, db_session, care):
    reply = _reply(client, care, preset="hurt", text="My knee").json()
    client.get(_url(care), headers=care["therapist_hdr"])
    client.post(_url(care, "/read"), json={"reply_ids": [reply["id"]]}, headers=care["therapist_hdr"])
    rows = db_session.scalars(select(AuditEvent).where(AuditEvent.object_type == "reply").order_by(AuditEvent.id))
    seen = [(e.action, e.actor_user_id, e.patient_id, e.detail) for e in rows]
    pid, tid = care["patient"].id, care["therapist"].id
    assert seen == [
        ("reply.create", pid, pid, {"suggestion_id": care["seen"].id, "preset": "hurt"}),
        ("reply.list", tid, pid, None),
        ("reply.read", tid, pid, {"reply_ids": [reply["id"]], "marked": 1}),
    ]


def test_dashboard_counts_unread_replies_per_patient(client, care):
    first = _reply(client, care, preset="hurt").json()
    _reply(client, care, preset="done")

    def unread() -> int:
        rows = client.get("/api/v1/dashboard", headers=care["therapist_hdr"]).json()["items"]
        return next(r["unread_replies"] for r in rows if r["patient_id"] == care["patient"].id)

    assert unread() == 2
    client.post(_url(care, "/read"), json={"reply_ids": [first["id"]]}, headers=care["therapist_hdr"])
    assert unread() == 1
