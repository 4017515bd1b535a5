"""A plausible long session still ingests under the server's default limits: two hours at 30 Hz."""

from __future__ import annotations

import uuid

import numpy as np

from backend.config import Settings
from kinect_agent.formats import session_file as sf
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate

TWO_HOURS_AT_30_HZ = 2 * 60 * 60 * 30


def _repeat(rec: Recording, n: int) -> Recording:
    """Returns rec's frames repeated back to back up to n frames at 30 Hz (t (n,) s, positions (n, J, 3) m)."""
    k = -(-n // rec.n_frames)
    positions, state = np.concatenate([rec.positions] * k)[:n], np.concatenate([rec.state] * k)[:n]
    return Recording(np.arange(n) / 30.0, positions, state, rec.meta)


def test_a_two_hour_session_at_30_hz_ingests_with_the_default_limits(client, db_session, make_user, device_headers):
    assert Settings().SESSION_MAX_FRAMES >= TWO_HOURS_AT_30_HZ
    measured, truth, _ = simulate("squat", 10, seed=4)
    payload = sf.SessionPayload(
        session_id=str(uuid.uuid4()),
        raw=_repeat(measured, TWO_HOURS_AT_30_HZ),
        filtered=_repeat(truth, TWO_HOURS_AT_30_HZ),
        created_at="2026-11-20T08:00:00Z",
    )
    _, headers = device_headers(make_user("patient"))
    db_session.commit()
    r = client.post("/api/v1/sessions", content=sf.encode(payload),
                    headers={**headers, "Content-Type": "application/octet-stream"})  # fmt: skip
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["n_frames"] == TWO_HOURS_AT_30_HZ and body["status"] == "processed", body["error"]
    assert body["metrics"]["repetitions"] > 100
