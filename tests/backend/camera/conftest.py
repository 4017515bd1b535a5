"""Fixtures of camera-set tests: a patient with a plan and consent, and helpers to start sets and send batches."""

from __future__ import annotations

import datetime as dt
import uuid

import pytest

from backend.camera.limits import CONSENT_VERSION
from backend.camera.models import CameraSet
from backend.database import utcnow
from backend.plans.models import Plan, PlanItem


@pytest.fixture
def camera_home(db_session, make_patient_with_therapist, auth_headers, exercise):
    """A patient with a plan of one exercise (target 3), API headers of the patient and of another patient."""
    patient, therapist = make_patient_with_therapist()
    other, _ = make_patient_with_therapist()
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
    plan.items.append(PlanItem(exercise_id=exercise.id, sets=2, repetitions=3, frequency_per_week=3))
    db_session.add(plan)
    db_session.flush()
    return {"patient": patient, "therapist": therapist, "item": plan.items[0], "headers": auth_headers(patient),
            "other_headers": auth_headers(other), "therapist_headers": auth_headers(therapist)}  # fmt: skip


@pytest.fixture
def started(client, db_session, camera_home):
    """Factory: started(seconds_ago=60) -> set id of a set the patient started (consent given), its start moved
    seconds_ago into the past so that frame times up to then are in real time."""

    def start(seconds_ago: float = 60.0) -> str:
        h = camera_home["headers"]
        r = client.post("/api/v1/camera/consent", json={"consent_version": CONSENT_VERSION}, headers=h)
        assert r.status_code == 200, r.text
        r = client.post("/api/v1/camera/sets", json={"plan_item_id": camera_home["item"].id,
                                                     "model": "pose_landmarker_lite"}, headers=h)  # fmt: skip
        assert r.status_code == 201, r.text
        set_id = r.json()["set_id"]
        row = db_session.get(CameraSet, uuid.UUID(set_id))
        row.started_at = utcnow() - dt.timedelta(seconds=seconds_ago)
        db_session.flush()
        return set_id

    return start
