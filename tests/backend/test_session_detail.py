"""GET /api/v1/sessions/{id}/detail: the evidence behind a session's numbers, its access rules and its errors."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

import numpy as np
import pytest
from sqlalchemy import select

from backend.audit.models import AuditEvent
from backend.exercises.models import Exercise
from kinect_agent.formats import session_file as sf
from kinect_agent.skeleton import INDEX, JOINTS
from kinect_agent.sources.simulator import simulate
from tests.backend.khs_files import make_khs, make_processed_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)


def _detail(client, session_id: int, headers: dict[str, Any]):
    return client.get(f"/api/v1/sessions/{session_id}/detail", headers=headers)


def _prepared(client, run_jobs, session_id: int, headers: dict[str, Any]):
    """Asks for a stored row's detail (not uploaded: nothing queued yet), lets a worker build it, asks again."""
    first = _detail(client, session_id, headers)
    assert first.status_code == 202 and first.json()["state"] == "preparing", first.text
    assert run_jobs() == 1
    return _detail(client, session_id, headers)


def _khs_with_bad_wrist(exercise: str, reps: int, seed: int) -> bytes:
    """A session of the simulator's truth plus 1 cm sensor noise whose raw right wrist jumps 0.6 m sideways for
    0.5 s in the middle (a tracking error); the filtered recording is the truth."""
    _, truth, _ = simulate(exercise, reps, seed=seed)
    rng = np.random.default_rng(seed)
    positions = truth.positions + rng.normal(0.0, 0.01, truth.positions.shape)
    mid = truth.n_frames // 2
    positions[mid : mid + 15, INDEX["WRI_R"], 0] += 0.6
    raw = truth.replace(step="test: noise, wrist corrupted", positions=positions, state=truth.state)
    payload = sf.SessionPayload(
        session_id=str(uuid.uuid4()), raw=raw, filtered=truth, created_at="2026-11-20T10:00:00Z"
    )
    return sf.encode(payload)


def test_detail_has_raw_and_filtered_curves_of_each_defining_angle(client, upload, auth_headers):
    session_id, _, therapist = upload(make_khs("squat", 3, seed=1), "squat")
    response = _detail(client, session_id, auth_headers(therapist))
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["angles"] == ["knee_flexion_L", "knee_flexion_R"]
    kinds = [(c["angle"], c["kind"]) for c in body["curves"]]
    assert kinds == [(a, k) for a in body["angles"] for k in ("raw", "filtered")]
    for c in body["curves"]:
        assert len(c["t_s"]) == len(c["deg"]) > 100, c["label"]
        assert c["t_s"] == sorted(c["t_s"]) and c["t_s"][0] == 0.0
        assert c["t_s"][-1] == pytest.approx(body["duration_s"], abs=0.05)
    filtered = np.array(body["curves"][1]["deg"], dtype=float)
    assert 30 < np.nanmax(filtered) - np.nanmin(filtered) < 140, "a squat bends the knee"


def test_repetition_marks_match_the_stored_metrics_document(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 4, seed=2), "squat")
    headers = auth_headers(patient)
    stored = client.get(f"/api/v1/sessions/{session_id}", headers=headers).json()["metrics"]["repetition_list"]
    body = _detail(client, session_id, headers).json()
    assert body["repetition_count"] == len(stored) == 4
    for row, rep in zip(body["repetitions"], stored, strict=True):
        assert (row["start_s"], row["end_s"], row["rom_deg"], row["side"]) == (
            rep["start_s"],
            rep["end_s"],
            rep["amplitude_deg"],
            rep["side"],
        )
        assert 10 < row["peak_speed_deg_s"] < 500, row
    assert body["processing"]["analysis"] == "stored"


def test_quality_score_is_within_0_and_100_with_its_three_parts(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("seated_knee_extension", 3, seed=3), "seated_knee_extension")
    quality = _detail(client, session_id, auth_headers(patient)).json()["quality"]
    assert 0 <= quality["score"] <= 100
    assert [p["name"] for p in quality["parts"]] == ["tracked_fraction", "outlier_fraction", "segment_spread_mm"]
    assert all(0 <= p["score"] <= 100 for p in quality["parts"])
    strip = quality["outlier_strip"]
    assert strip["joints"] == list(JOINTS) and len(strip["prob"]) == len(JOINTS)
    assert all(len(row) == len(strip["t_s"]) <= 400 for row in strip["prob"])


def test_outlier_strip_flags_the_joint_corrupted_on_purpose(client, upload, auth_headers):
    session_id, patient, _ = upload(_khs_with_bad_wrist("elbow_flexion", 4, seed=4), "elbow_flexion")
    strip = _detail(client, session_id, auth_headers(patient)).json()["quality"]["outlier_strip"]
    prob = np.array(strip["prob"], dtype=float)
    t = np.array(strip["t_s"])
    flagged = prob[INDEX["WRI_R"]] > strip["threshold"]
    assert flagged.any() and np.all(np.abs(t[flagged] - t[-1] / 2) < 1.0), t[flagged]
    others = np.delete(prob, INDEX["WRI_R"], axis=0)
    assert np.nanmax(others) < strip["threshold"], [JOINTS[j] for j in np.flatnonzero(np.nanmax(prob, axis=1) > 0.5)]


def test_arm_exercise_has_a_workspace_with_hand_paths(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("shoulder_abduction", 3, seed=5), "shoulder_abduction")
    workspace = _detail(client, session_id, auth_headers(patient)).json()["workspace"]
    for side in ("left", "right"):
        arm = workspace[side]
        assert len(arm["outward"]) == len(arm["up"]) == len(arm["forward"]) > 50
        assert max(arm["up"]) > 0.5, "raised sideways, the hand rises above the shoulder"
        assert 0 < arm["area_ratio"] < 1


def test_leg_exercise_has_no_workspace(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 2, seed=6), "squat")
    assert _detail(client, session_id, auth_headers(patient)).json()["workspace"] is None


def test_reading_the_detail_is_audited(client, db_session, upload, auth_headers):
    session_id, _, therapist = upload(make_khs("squat", 2, seed=7), "squat")
    assert _detail(client, session_id, auth_headers(therapist)).status_code == 200
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.object_id == str(session_id))).all()
    assert "session.detail.read" in actions


def test_another_patient_gets_404(client, upload, make_user, auth_headers):
    session_id, _, _ = upload(make_khs("squat", 2, seed=8), "squat")
    response = _detail(client, session_id, auth_headers(make_user("patient")))
    assert response.status_code == 404, response.text
    assert response.json()["error"] == "SessionNotFound"


def test_unassigned_therapist_gets_404(client, upload, make_user, auth_headers):
    session_id, _, _ = upload(make_khs("squat", 2, seed=8), "squat")
    assert _detail(client, session_id, auth_headers(make_user("therapist"))).status_code == 404


def test_unknown_session_is_404(client, make_user, auth_headers):
    response = _detail(client, 10**9, auth_headers(make_user("admin")))
    assert response.status_code == 404
    assert response.json() == {"error": "SessionNotFound", "detail": f"session {10**9} does not exist"}


def test_anonymous_gets_401(client, upload):
    session_id, _, _ = upload(make_khs("squat", 2, seed=9), "squat")
    assert _detail(client, session_id, {}).status_code == 401


def test_corrupt_stored_file_is_a_typed_400(client, make_patient_with_therapist, auth_headers, exercise, store,
                                            run_jobs):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    data = bytearray(make_khs("squat", 2, seed=10))
    data[100] ^= 0xFF  # the SHA-256 trailer no longer matches
    row = store(patient, exercise, T0, data=bytes(data), metrics=False)
    response = _prepared(client, run_jobs, row.id, auth_headers(therapist))
    assert response.status_code == 400, response.text
    assert response.json()["error"] == "InvalidSessionFile"
    assert "checksum_mismatch" in response.json()["detail"]


def test_session_without_metrics_is_analysed_from_its_file(
    client, db_session, store, make_patient_with_therapist, auth_headers, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    squat = db_session.scalar(select(Exercise).where(Exercise.slug == "squat"))
    row = store(patient, squat, T0, data=make_khs("squat", 3, seed=11), metrics=False)
    body = _prepared(client, run_jobs, row.id, auth_headers(therapist)).json()
    assert body["processing"]["analysis"] == "recomputed"
    assert body["repetition_count"] == 3


@pytest.mark.parametrize("seed", (1, 2, 3))
def test_detail_shows_the_95_percent_intervals_of_an_agent_made_file(client, upload, auth_headers, seed):
    session_id, patient, _ = upload(make_processed_khs("squat", 4, seed=seed), "squat")
    body = _detail(client, session_id, auth_headers(patient)).json()
    unc = body["uncertainty"]
    assert unc is not None, body["uncertainty_note"]
    for angle in body["angles"]:
        a = unc["angles"][angle]
        if a["withheld"]:  # too wide to show (a squat's peak: the simulated Kinect's bias at the turning point)
            assert a["max_ci95"] is None and "95 % interval would span" in a["withheld"], f"seed {seed}: {a}"
            continue
        for key in ("min", "max", "range"):
            lo, hi = a[f"{key}_ci95"]
            assert lo <= a[f"{key}_deg"] <= hi and hi - lo > 0, f"seed {seed}: {angle} {key}: {a}"
    reps = unc["repetitions"]
    assert reps["low"] <= body["repetition_count"] <= reps["high"], f"seed {seed}: {reps}"
    stored = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()["metrics"]
    defining = body["defining_angle"]
    assert (stored["range_of_motion_95"][defining] or {}).get("max_deg") == unc["angles"][defining]["max_ci95"], (
        "the intervals are stored with the session's metrics at ingest"
    )
    withheld = stored["range_of_motion_95_withheld"].get(defining)  # the same reason, written for the same reader
    assert withheld == unc["angles"][defining]["withheld_reason"], f"seed {seed}"
    assert (withheld or {}).get("text") == unc["angles"][defining]["withheld"], f"seed {seed}"


def test_a_file_without_angle_sds_has_no_intervals(client, upload, auth_headers):
    session_id, patient, _ = upload(make_khs("squat", 3, seed=1), "squat")
    body = _detail(client, session_id, auth_headers(patient)).json()
    assert body["uncertainty"] is None
    assert "no per-frame uncertainty" in body["uncertainty_note"]


def test_agent_made_standing_session_shows_its_balance_with_an_interval(client, upload, auth_headers):
    session_id, patient, _ = upload(make_processed_khs("shoulder_abduction", 4, seed=3), "shoulder_abduction")
    body = _detail(client, session_id, auth_headers(patient)).json()
    b = body["balance"]
    assert b is not None and body["balance_missing"] is None, body["balance_missing"]
    lo, hi = b["sway_velocity_95"]
    assert 0 < lo <= b["sway_velocity_m_s"] <= hi < 0.06
    assert b["standing_s"] > 0.8 * body["duration_s"]


def test_seated_session_says_why_balance_is_missing(client, upload, auth_headers):
    session_id, patient, _ = upload(make_processed_khs("seated_knee_extension", 3, seed=3), "seated_knee_extension")
    body = _detail(client, session_id, auth_headers(patient)).json()
    assert body["balance"] is None
    assert body["balance_missing"] == "the patient was seated or crouching: balance is measured while standing"


def _khs_bent_past_anatomy() -> bytes:
    """A seated elbow flexion bent 165° from its rest (about 8°): the curve passes what an elbow bends (170°)."""
    from kinect_agent.sources.simulator import simulate_truth

    truth = simulate_truth("elbow_flexion", 3, seed=2, amplitude_deg=165.0)
    payload = sf.SessionPayload(session_id=str(uuid.uuid4()), raw=truth, filtered=truth,
                                created_at="2026-11-20T10:00:00Z")  # fmt: skip
    return sf.encode(payload)


def test_repetitions_past_what_the_joint_bends_are_withheld_with_the_reason(client, upload, auth_headers):
    session_id, patient, therapist = upload(_khs_bent_past_anatomy(), "elbow_flexion")
    english = _detail(client, session_id, auth_headers(therapist)).json()  # the therapist pages are in English
    assert "more than the joint can bend (170°)" in english["repetitions"][0]["withheld"], english["repetitions"]
    body = _detail(client, session_id, auth_headers(patient) | {"Accept-Language": "de"}).json()
    assert body["repetition_count"] == 3 and body["rom_deg"] is None, body["rom_deg"]
    assert body["rom_deg_withheld_reason"]["id"] == "repetitions_beyond_anatomy", body["rom_deg_withheld_reason"]
    assert body["rom_deg_withheld"].startswith("in 3 von 3 Wiederholungen"), body["rom_deg_withheld"]
    for row in body["repetitions"]:
        assert row["peak_deg"] is None and row["rom_deg"] is None and row["peak_speed_deg_s"] is None, row
        assert row["withheld_reason"]["id"] == "beyond_anatomy" and row["withheld_reason"]["params"]["limit"] == 170
        assert "mehr als das Gelenk beugen kann (170°)" in row["withheld"], row["withheld"]
    stored = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(patient)).json()
    assert stored["rom_deg"] is None and stored["metrics"]["rom_deg"] is None, stored["rom_deg"]
    reps = stored["metrics"]["repetition_list"]
    assert all(r["peak_deg"] is None and "more than the joint can bend" in r["withheld"]["text"] for r in reps), reps
    flexibility = stored["metrics"]["indicators"]["flexibility"]
    assert flexibility["value"] is None and flexibility["score"] is None, flexibility  # not scored from a lost limb
