"""GET /api/v1/exercises carries each exercise's minimal detectable change of the range of motion (bench/mdc.py)."""

from __future__ import annotations

from kinect_agent.analysis.mdc import MDC95_ROM_DEG


def test_every_measured_exercise_reports_its_mdc_and_the_others_null(client, make_user, auth_headers):
    response = client.get("/api/v1/exercises?limit=200", headers=auth_headers(make_user("therapist")))
    assert response.status_code == 200, response.text
    items = {e["slug"]: e for e in response.json()["items"]}
    assert set(MDC95_ROM_DEG) <= set(items), "every measured exercise is in the library"
    for slug, item in items.items():
        assert item["mdc95_rom_deg"] == MDC95_ROM_DEG.get(slug), slug
    assert all(0 < v < 90 for v in MDC95_ROM_DEG.values())
