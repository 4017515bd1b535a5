"""A session file says whose it is: the home agent writes the device and patient it is paired to into the header
(`recorded_by`), and the server refuses to store the file for anyone else or through another device."""

from __future__ import annotations

import pytest
from sqlalchemy import func, select

from backend.sessions.models import ExerciseSession
from tests.backend.khs_files import make_khs, with_header

URL = "/api/v1/sessions"
OCTET = {"Content-Type": "application/octet-stream"}


@pytest.fixture
def post(client, db_session):
    def send(data, headers, **params):
        db_session.commit()
        return client.post(URL, content=data, headers={**OCTET, **headers}, params=params)

    return send


@pytest.fixture
def homes(make_patient_with_therapist, make_user, device_headers):
    """Patient A with a device and a therapist, patient B with a device, and A's file as A's device wrote it."""
    a, therapist = make_patient_with_therapist()
    b = make_user("patient")
    device_a, headers_a = device_headers(a)
    _, headers_b = device_headers(b)
    recorded = {"device_id": device_a.id, "patient_id": a.id}
    data = with_header(make_khs("squat", 2, seed=3), lambda h: h.update(recorded_by=recorded))
    return {"a": a, "b": b, "therapist": therapist, "headers_a": headers_a, "headers_b": headers_b, "file": data}


def _count(db_session, patient_id: int) -> int:
    db_session.expire_all()
    query = select(func.count()).select_from(ExerciseSession).where(ExerciseSession.patient_id == patient_id)
    return db_session.scalar(query)


def test_a_file_of_patient_a_sent_with_patient_bs_login_is_refused(post, db_session, homes, auth_headers):
    r = post(homes["file"], auth_headers(homes["b"]))
    assert r.status_code == 403 and r.json()["error"] == "SessionOwnerMismatch", r.text
    assert "recorded_by.patient_id" in r.json()["detail"]
    assert _count(db_session, homes["b"].id) == 0


def test_a_file_of_patient_a_sent_by_patient_bs_device_is_refused(post, db_session, homes):
    r = post(homes["file"], homes["headers_b"])
    assert r.status_code == 403 and r.json()["error"] == "SessionOwnerMismatch", r.text
    assert _count(db_session, homes["b"].id) == 0


def test_a_file_sent_through_another_device_of_the_same_patient_is_refused(post, db_session, homes, device_headers):
    _, second = device_headers(homes["a"])
    r = post(homes["file"], second)
    assert r.status_code == 403 and "recorded_by.device_id" in r.json()["detail"], r.text
    assert _count(db_session, homes["a"].id) == 0


def test_the_recording_device_and_the_patients_therapist_may_store_it(post, homes, auth_headers):
    assert post(homes["file"], homes["headers_a"]).status_code == 201
    r = post(homes["file"], auth_headers(homes["therapist"]), patient_id=homes["a"].id)  # relayed: the same session
    assert r.status_code == 200, r.text


@pytest.mark.parametrize("recorded_by", [[], {"device_id": "3", "patient_id": 1}, {"patient_id": 0, "device_id": 1},
                                         {"device_id": 1}])  # fmt: skip
def test_a_malformed_recorded_by_is_400(post, db_session, homes, recorded_by):
    data = with_header(make_khs("squat", 2, seed=3), lambda h: h.update(recorded_by=recorded_by))
    r = post(data, homes["headers_a"])
    assert r.status_code == 400 and "recorded_by" in r.json()["detail"], r.text
    assert _count(db_session, homes["a"].id) == 0
