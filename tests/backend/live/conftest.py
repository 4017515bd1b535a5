"""Fixtures of the live loop's tests: the events the live routes publish, and a patient's home."""

from __future__ import annotations

import pytest

from backend.database import utcnow
from backend.plans.models import Plan, PlanItem


@pytest.fixture
def events(monkeypatch):
    """Returns the list of events the live routes and service publish."""
    seen = []

    def capture(_db_session, ev):
        seen.append(ev)

    monkeypatch.setattr("backend.live.service.publish", capture)
    monkeypatch.setattr("backend.live.router.publish", capture)
    return seen


@pytest.fixture
def home(db_session, make_patient_with_therapist, device_headers, auth_headers, exercise):
    """A patient with a plan of one exercise, their therapist and a paired (not yet connected) device."""
    patient, therapist = make_patient_with_therapist()
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
    plan.items.append(PlanItem(exercise_id=exercise.id, sets=2, repetitions=8, frequency_per_week=3))
    db_session.add(plan)
    device, device_hdr = device_headers(patient)
    db_session.flush()
    return {
        "patient": patient,
        "therapist": therapist,
        "item": plan.items[0],
        "device": device,
        "device_hdr": device_hdr,
        "patient_hdr": auth_headers(patient),
        "therapist_hdr": auth_headers(therapist),
    }
