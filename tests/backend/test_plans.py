"""Plans: therapists prescribe for assigned patients; patients read their own; every access is audited."""

from __future__ import annotations

from sqlalchemy import select

from backend.audit.models import AuditEvent


def _body(slug, **kw):
    body = {
        "title": "Knee rehab",
        "start_date": "2026-11-23",
        "end_date": "2026-12-21",
        "items": [{"exercise_slug": slug, "sets": 3, "repetitions": 10, "frequency_per_week": 3}],
    }
    body.update(kw)
    return body


def test_therapist_prescribes_and_patient_reads(
    client, make_patient_with_therapist, auth_headers, exercise, db_session
):
    patient, therapist = make_patient_with_therapist()
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=auth_headers(therapist))
    assert r.status_code == 201, r.text
    plan = r.json()
    assert plan["therapist_id"] == therapist.id and plan["items"][0]["exercise_slug"] == exercise.slug
    listed = client.get(f"/api/v1/patients/{patient.id}/plans", headers=auth_headers(patient)).json()
    assert listed["total"] == 1 and listed["items"][0]["id"] == plan["id"]
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.patient_id == patient.id)).all()
    assert {"plan.create", "plan.list"} <= set(actions)


def test_replace_and_delete(client, make_patient_with_therapist, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    plan = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=headers).json()
    r = client.put(f"/api/v1/plans/{plan['id']}", json=_body(exercise.slug, title="v2", items=[]), headers=headers)
    assert r.status_code == 200 and r.json()["title"] == "v2" and r.json()["items"] == []
    assert client.delete(f"/api/v1/plans/{plan['id']}", headers=headers).status_code == 204
    r = client.get(f"/api/v1/plans/{plan['id']}", headers=headers)
    assert r.status_code == 404 and r.json()["error"] == "PlanNotFound"


def test_patient_cannot_write_plans(client, make_user, auth_headers, exercise):
    patient = make_user("patient")
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=auth_headers(patient))
    assert r.status_code == 403


def test_end_before_start_is_a_validation_error(client, make_patient_with_therapist, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    body = _body(exercise.slug, end_date="2026-11-01")
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=body, headers=auth_headers(therapist))
    assert r.status_code == 422 and r.json()["error"] == "ValidationError"
    assert "end_date must not be before start_date" in r.json()["detail"]


def test_unknown_exercise_is_404(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body("no_such"), headers=auth_headers(therapist))
    assert r.status_code == 404 and r.json() == {
        "error": "ExerciseNotFound",
        "detail": "exercise 'no_such' does not exist",
    }


def test_target_range_of_motion_and_note_are_stored_and_edited(
    client, make_patient_with_therapist, auth_headers, exercise
):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    body = _body(exercise.slug, notes="Rest a minute between the sets.")
    body["items"][0]["target_rom_deg"] = 90
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=body, headers=headers)
    assert r.status_code == 201, r.text
    plan = r.json()
    assert plan["notes"] == "Rest a minute between the sets."
    assert plan["items"][0]["target_rom_deg"] == 90
    assert plan["therapist_name"] == (therapist.full_name or therapist.email)
    body["items"][0].update(target_rom_deg=75.5, repetitions=12)
    r = client.put(f"/api/v1/plans/{plan['id']}", json=body | {"notes": "Slowly."}, headers=headers)
    assert r.status_code == 200, r.text
    seen = client.get(f"/api/v1/patients/{patient.id}/plans", headers=auth_headers(patient)).json()["items"][0]
    assert seen["notes"] == "Slowly."
    assert seen["items"][0]["target_rom_deg"] == 75.5 and seen["items"][0]["repetitions"] == 12


def test_target_range_of_motion_is_optional(client, make_patient_with_therapist, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=auth_headers(therapist))
    assert r.status_code == 201 and r.json()["items"][0]["target_rom_deg"] is None


def test_target_range_of_motion_above_180_is_a_validation_error(
    client, make_patient_with_therapist, auth_headers, exercise
):
    patient, therapist = make_patient_with_therapist()
    body = _body(exercise.slug)
    body["items"][0]["target_rom_deg"] = 200
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=body, headers=auth_headers(therapist))
    assert r.status_code == 422 and r.json()["error"] == "ValidationError"
    assert r.json()["detail"] == "body.items.0.target_rom_deg: Input should be less than or equal to 180"


def test_zero_repetitions_is_a_validation_error_naming_the_row(
    client, make_patient_with_therapist, auth_headers, exercise
):
    patient, therapist = make_patient_with_therapist()
    body = _body(exercise.slug)
    body["items"].append(dict(body["items"][0], repetitions=0))
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=body, headers=auth_headers(therapist))
    assert r.status_code == 422
    assert r.json()["detail"] == "body.items.1.repetitions: Input should be greater than or equal to 1"


def test_another_therapist_cannot_edit_the_plan(client, make_patient_with_therapist, make_user, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    other = make_user("therapist")
    plan = client.post(
        f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=auth_headers(therapist)
    ).json()
    r = client.put(f"/api/v1/plans/{plan['id']}", json=_body(exercise.slug, notes="x"), headers=auth_headers(other))
    assert r.status_code == 404 and r.json() == {
        "error": "PlanNotFound",
        "detail": f"plan {plan['id']} does not exist",  # as for a plan that is not there: nothing leaks
    }
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_body(exercise.slug), headers=auth_headers(other))
    assert r.status_code == 404 and r.json()["error"] == "PatientNotFound"
    r = client.get(f"/api/v1/plans/{plan['id']}", headers=auth_headers(therapist))
    assert r.json()["notes"] == ""


def test_the_same_exercise_twice_in_a_plan_is_refused_naming_both_items(
    client, make_patient_with_therapist, auth_headers, exercise
):
    patient, therapist = make_patient_with_therapist()
    item = {"exercise_slug": exercise.slug, "sets": 1, "repetitions": 5, "frequency_per_week": 2}
    body = _body(exercise.slug, items=[item, item | {"sets": 2}])
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=body, headers=auth_headers(therapist))
    assert r.status_code == 422 and r.json()["error"] == "ValidationError", r.text
    detail = r.json()["detail"]
    assert f"body.items: Value error, exercise '{exercise.slug}' is in the plan twice (items 0 and 1)" in detail
