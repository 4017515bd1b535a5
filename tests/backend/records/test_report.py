"""The PDF progress report: A4 and Letter, the patient's sessions, plan, notes, who and when."""

from __future__ import annotations

import datetime as dt
import os
import re
import subprocess
from pathlib import Path

import pytest
from reportlab.graphics import renderPDF
from reportlab.lib.pagesizes import A4, LETTER
from sqlalchemy import select

from backend.exercises.models import Exercise
from backend.records.report import _chart
from tests.backend.khs_files import make_khs

SHOTS = Path(os.environ.get("COACH_SHOTS_DIR", "/tmp/shots"))


def _pdf_text(data: bytes, tmp_path) -> str:
    path = tmp_path / "r.pdf"
    path.write_bytes(data)
    return subprocess.run(["pdftotext", "-layout", str(path), "-"], capture_output=True, text=True, check=True).stdout


def _page_sizes(data: bytes, tmp_path) -> set[tuple[int, int]]:
    """Returns the (width, height) in points, rounded, of every page (pdfinfo)."""
    path = tmp_path / "sizes.pdf"
    path.write_bytes(data)
    out = subprocess.run(["pdfinfo", "-f", "1", "-l", "999", str(path)], capture_output=True, text=True,
                         check=True).stdout  # fmt: skip
    found = re.findall(r"Page +\d+ size: +([\d.]+) x ([\d.]+) pts", out)
    assert found, out
    return {(round(float(w)), round(float(h))) for w, h in found}


@pytest.mark.parametrize(("paper", "size"), [("a4", A4), ("letter", LETTER)])
def test_report_lists_sessions_plan_and_notes(client, db_session, make_patient_with_therapist, auth_headers, tmp_path,
                                              paper, size):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    th = auth_headers(therapist)
    plan = {"title": "Knees", "start_date": "2026-11-01", "notes": "Slowly, no pain.",
            "items": [{"exercise_slug": "squat", "sets": 1, "repetitions": 5, "frequency_per_week": 3}]}  # fmt: skip
    assert client.post(f"/api/v1/patients/{patient.id}/plans", json=plan, headers=th).status_code == 201
    mine = auth_headers(patient)
    for seed, pain, effort in ((91, 2, 3.5), (92, 6, None)):
        r = client.post("/api/v1/sessions", content=make_khs("squat", 3, seed=seed), params={"exercise": "squat"},
                        headers={"Content-Type": "application/octet-stream", **mine})  # fmt: skip
        assert r.status_code == 201, r.text
        felt = client.put(f"/api/v1/sessions/{r.json()['id']}/feeling", json={"pain": pain, "effort": effort},
                          headers=mine)  # fmt: skip
        assert felt.status_code == 200, felt.text
    assert client.post(f"/api/v1/patients/{patient.id}/suggestions", json={"text": "Deeper squats."}, headers=th)
    today = dt.datetime.now(dt.UTC).date()
    response = client.get(f"/api/v1/patients/{patient.id}/report.pdf", headers=th,
                          params={"from": "2026-11-01", "to": str(today), "paper": paper})  # fmt: skip
    assert response.status_code == 200 and response.headers["content-type"] == "application/pdf"
    assert response.content.startswith(b"%PDF")
    text = _pdf_text(response.content, tmp_path)
    assert _page_sizes(response.content, tmp_path) == {(round(size[0]), round(size[1]))}, f"every page on {paper}"
    assert "Progress report" in text and patient.email in text
    assert "Plan and adherence" in text and "Knees" in text and "Slowly, no pain." in text
    assert "Deeper squats." in text and "Not recorded" not in text
    assert "Said after 2 of 2 set(s)" in text and "Pain: highest 6, last 6 of 10." in text, text
    assert "Borg CR10" in text and "3.5" in text and "skipped" in text
    name = db_session.scalar(select(Exercise.name).where(Exercise.slug == "squat"))
    assert f"{name}: 2 session(s)." in text and "MDC95" in text
    (SHOTS / f"report-{paper}.pdf").parent.mkdir(parents=True, exist_ok=True)
    (SHOTS / f"report-{paper}.pdf").write_bytes(response.content)  # for pdftoppm renders


def test_a_backwards_period_is_a_clear_422(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    response = client.get(f"/api/v1/patients/{patient.id}/report.pdf", headers=auth_headers(therapist),
                          params={"from": "2026-11-20", "to": "2026-11-01"})  # fmt: skip
    assert response.status_code == 422 and "must run forwards" in response.json()["detail"]


def test_a_period_nobody_chose_is_the_last_4_weeks_as_on_the_page(client, make_patient_with_therapist, auth_headers,
                                                                   tmp_path):  # fmt: skip
    """The API (and the CLI, which reads its period the same way) and the patient page's form start from the same
    period: the 28 days up to today, both included."""
    patient, therapist = make_patient_with_therapist()
    response = client.get(f"/api/v1/patients/{patient.id}/report.pdf", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    today = dt.datetime.now(dt.UTC).date()
    first = today - dt.timedelta(days=27)
    text = " ".join(_pdf_text(response.content, tmp_path).split())
    assert f"Period {first:%d %b %Y} to {today:%d %b %Y} (4.0 weeks)" in text, text
    page = client.get(f"/therapist/patients/{patient.id}", headers=auth_headers(therapist))
    assert page.status_code == 200 and f'value="{first.isoformat()}"' in page.text, "the page's form starts there too"


def test_a_chart_labels_its_days_with_dates_each_once(tmp_path):
    """The x axis ticks whole days from the period's first, each labelled with its date once ("day 22" twice, or
    22 Nov labelled "day 21", said nothing a doctor could read)."""
    series = {"range of motion, degrees": [(21.0, 81.0), (25.0, 79.0)], "repetitions": [(21.0, 7.0), (25.0, 7.0)]}
    drawing = _chart("Seated knee extension", series, "value", 400.0, dt.date(2026, 11, 1))
    labels = re.findall(r"\d\d [A-Z][a-z]{2}", _pdf_text(renderPDF.drawToString(drawing), tmp_path))
    assert labels == ["22 Nov", "23 Nov", "24 Nov", "25 Nov", "26 Nov"], labels


def test_a_balance_not_measured_says_why(client, make_patient_with_therapist, auth_headers, tmp_path):
    patient, therapist = make_patient_with_therapist()
    seated = make_khs("seated_knee_extension", 3, seed=93, created_at="2026-11-20T10:00:00Z")
    r = client.post("/api/v1/sessions", content=seated,
                    params={"exercise": "seated_knee_extension"},
                    headers={"Content-Type": "application/octet-stream", **auth_headers(patient)})  # fmt: skip
    assert r.status_code == 201, r.text
    why = r.json()["metrics"]["balance_missing"]
    assert why is not None and why["text"], r.json()["metrics"]["balance"]  # seated: no standing phase
    today = dt.datetime.now(dt.UTC).date()
    response = client.get(f"/api/v1/patients/{patient.id}/report.pdf", headers=auth_headers(therapist),
                          params={"from": "2026-11-01", "to": str(today)})  # fmt: skip
    assert response.status_code == 200, response.text
    text = " ".join(_pdf_text(response.content, tmp_path).split())
    assert "not measured" in text and f"Balance not measured: {why['text']}" in text, text
