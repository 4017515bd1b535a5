"""A caller without any right to a patient cannot tell "not yours" from "not there": both answer the same 404.

Callers who may see a patient but not change something (a device writing what it may not) still get 403.
"""

from __future__ import annotations

import pytest

from backend.database import utcnow
from backend.plans.models import Plan
from backend.suggestions.models import Suggestion
from tests.backend.khs_files import make_khs
from tests.backend.session_rows import store_session

MISSING = 2**31 - 1  # an id no row has


@pytest.fixture
def other(db_session, make_patient_with_therapist, exercise):
    """Another patient with a session, a plan and a pending suggestion, and their therapist."""
    patient, therapist = make_patient_with_therapist()
    session = store_session(db_session, patient, exercise, utcnow(), data=make_khs("squat", 1, seed=3))
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
    suggestion = Suggestion(patient_id=patient.id, source="system", rule="too_fast", text="Slow.", status="pending")
    db_session.add_all([plan, suggestion])
    db_session.flush()
    return {"patient": patient, "session": session.id, "plan": plan.id, "suggestion": suggestion.id}


def _same_404(client, db_session, headers, method, template, real_id, missing_id, error):
    db_session.commit()  # an error answer rolls the request's transaction back: keep the set-up out of it
    real = client.request(method, template.format(id=real_id), headers=headers)
    gone = client.request(method, template.format(id=missing_id), headers=headers)
    assert real.status_code == gone.status_code == 404, (real.text, gone.text)
    assert real.json()["error"] == gone.json()["error"] == error
    assert real.json()["detail"].replace(str(real_id), "N") == gone.json()["detail"].replace(str(missing_id), "N")


@pytest.mark.parametrize(
    ("template", "key", "error"),
    [
        ("/api/v1/sessions/{id}", "session", "SessionNotFound"),
        ("/api/v1/sessions/{id}/file", "session", "SessionNotFound"),
        ("/api/v1/sessions/{id}/detail", "session", "SessionNotFound"),
        ("/api/v1/sessions/{id}/replay", "session", "SessionNotFound"),
        ("/api/v1/plans/{id}", "plan", "PlanNotFound"),
        ("/api/v1/patients/{id}/plans", "patient", "PatientNotFound"),
        ("/api/v1/patients/{id}/suggestions", "patient", "PatientNotFound"),
        ("/api/v1/patients/{id}/progress", "patient", "PatientNotFound"),
        ("/api/v1/patients/{id}", "patient", "PatientNotFound"),
    ],
)
def test_another_patients_data_is_404_like_missing_data(
    client, db_session, other, make_user, auth_headers, template, key, error
):
    stranger = auth_headers(make_user("patient"))
    real = other[key] if key != "patient" else other["patient"].id
    _same_404(client, db_session, stranger, "GET", template, real, MISSING, error)


def test_an_unassigned_therapist_cannot_tell_a_suggestion_exists(client, db_session, other, make_user, auth_headers):
    therapist = auth_headers(make_user("therapist"))
    template = "/api/v1/suggestions/{id}/approve"
    _same_404(client, db_session, therapist, "POST", template, other["suggestion"], MISSING, "SuggestionNotFound")


def test_a_device_of_another_patient_gets_404_too(client, db_session, other, make_user, device_headers):
    _, headers = device_headers(make_user("patient"))
    _same_404(client, db_session, headers, "GET", "/api/v1/sessions/{id}", other["session"], MISSING, "SessionNotFound")
