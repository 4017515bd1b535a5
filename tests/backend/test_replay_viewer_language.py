"""The replay viewer's page (frontend.pages.replay_viewer) in the reader's language: a patient's chosen one, a
therapist's pages' (English until a therapist.po exists)."""

from __future__ import annotations

from urllib.parse import quote


def test_a_german_patient_gets_the_viewer_in_german_and_a_therapist_in_english(
    client, db_session, make_patient_with_therapist, auth_headers
):
    patient, therapist = make_patient_with_therapist()
    patient.locale = "de"
    db_session.flush()
    query = "/replay/viewer/?playbackPath=" + quote("/api/v1/sessions/12/replay", safe="")
    german = client.get(query, headers=auth_headers(patient) | {"Accept": "text/html"})
    english = client.get(query, headers=auth_headers(therapist) | {"Accept": "text/html", "Accept-Language": "de"})
    assert german.status_code == english.status_code == 200
    assert '<html lang="de">' in german.text and "<title>Wiedergabe der Sitzung</title>" in german.text
    assert '<html lang="en">' in english.text, "the therapist pages are English until a therapist.po exists"
    assert german.headers["cache-control"] == "private, no-cache"


def test_the_viewer_carries_only_its_own_script_messages(client, db_session, make_user, auth_headers):
    import json
    import re

    from babel.messages.extract import extract_from_file

    from backend.i18n import js_messages
    from backend.i18n.catalogues import ROOT, SOURCES

    patient = make_user("patient")
    patient.locale = "fr"
    db_session.flush()
    query = "/replay/viewer/?playbackPath=" + quote("/api/v1/sessions/12/replay", safe="")
    page = client.get(query, headers=auth_headers(patient) | {"Accept": "text/html"}).text
    found = re.search(r'<script type="application/json" id="i18n-messages">(.*?)</script>', page)
    assert found is not None
    carried = set(json.loads(found.group(1))["messages"])
    keywords = SOURCES[-1][2]  # the page scripts' marks: I18n.t, I18n.nt, I18n.N_
    used = {m[1] for m in extract_from_file("javascript", ROOT / "frontend/static/replay_viewer.js", keywords)}
    assert carried == used, f"carried but unused: {carried - used}; used but missing: {used - carried}"
    every = js_messages("fr")["messages"]
    assert len(carried) < len(every) / 10, (len(carried), len(every))
