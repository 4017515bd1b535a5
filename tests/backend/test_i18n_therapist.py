"""The therapist pages are ready for catalogues (issue 23, point 2): their texts are marked and extracted into their own
domain (therapist.pot, English only), the check fails on a therapist text that is not marked or not extracted and
holds a started therapist.po to the same placeholders rule as messages.po, and a therapist.po dropped into the locale
folder turns the therapist pages into its language without a code change."""

from __future__ import annotations

import shutil

import pytest
from babel.messages.catalog import Catalog

import backend.i18n as i18n
from backend.i18n import THERAPIST_DOMAIN, js_messages, therapist_locales
from backend.i18n.catalogues import (
    ROOT,
    THERAPIST_FILES,
    check_locale,
    check_template,
    extract_all,
    unmarked_script_text,
    unmarked_template_text,
)

HTML = {"Accept": "text/html"}


@pytest.fixture(scope="module")
def domains() -> dict[str, Catalog]:
    return extract_all()


def _ids(catalog: Catalog) -> set[str]:
    return {m.id if isinstance(m.id, str) else m.id[0] for m in catalog if m.id}


def test_therapist_texts_are_extracted_into_their_own_domain(domains):
    therapist, messages = _ids(domains["therapist"]), _ids(domains["messages"])
    assert {"My patients", "Suggestions to review", "Key numbers"} <= therapist  # templates
    assert {"Approve", "{n} new reply", "Because {what} ({value}) was {compared} {limit}."} <= therapist  # scripts
    assert "My patients" not in messages and "Sign out" in messages and "Sign out" not in therapist
    # a text the patient pages use too stays in messages (translated for every locale), used from both
    (done,) = [m for m in domains["messages"] if m.id == "Done"]
    assert {"frontend/static/advice_reply.js", "frontend/static/replies_view.js"} <= {p for p, _ in done.locations}
    for message in domains["therapist"]:
        assert all(path in THERAPIST_FILES for path, _ in message.locations), message.locations


def test_the_check_names_a_therapist_text_missing_from_therapist_pot(domains):
    code = domains["therapist"]
    pot = Catalog(domain=THERAPIST_DOMAIN)
    for message in code:
        if message.id and message.id != "My patients":
            pot.add(message.id, None, message.locations, context=message.context)
    pot.add("A text the code no longer has")
    found = [str(p) for p in check_template(THERAPIST_DOMAIN, code, pot)]
    assert found == [
        "backend/i18n/locale/therapist.pot: misses 'My patients': run extract and update",
        "backend/i18n/locale/therapist.pot: still has 'A text the code no longer has', no longer in the code: "
        "run extract",
    ]


def test_the_check_names_therapist_template_text_that_is_not_marked():
    path = "frontend/templates/patient_detail.html"
    source = (ROOT / path).read_text(encoding="utf-8")
    assert unmarked_template_text(path, source) == []
    unmarked = source.replace('{{ _("Suggestions to review") }}', "Suggestions to review", 1)
    unmarked = unmarked.replace("placeholder=\"{{ _('e.g. Europe/Berlin') }}\"", 'placeholder="e.g. Europe/Berlin"')
    found = [str(p) for p in unmarked_template_text(path, unmarked)]
    assert len(found) == 2, found
    line = next(n for n, text in enumerate(source.splitlines(), 1) if "e.g. Europe/Berlin" in text)
    assert found[0] == f"{path}:{line}: text not marked for translation: 'e.g. Europe/Berlin'"
    assert found[1].startswith(f"{path}:") and found[1].endswith(
        ": text not marked for translation: 'Suggestions to review'"
    )


def test_the_check_names_therapist_script_text_that_is_not_marked():
    source = """
      el("button", { class: "btn btn-good", id: "approve-1" }, I18n.t("Approve"));
      el("p", {}, I18n.nt("{n} new reply", "{n} new replies", n), I18n.t("Because it was " + "below the limit."));
      api(`/patients/${pid}/suggestions?status=pending`);  msg.className = "small alert";
      box.append(el("li", { class: "muted" }, "Nothing to review."));
      const LEVELS = { now: ["high", "Now"] };
      document.title = `${name} · Kinect Home Coach`;
    """
    found = [str(p) for p in unmarked_script_text("x.js", source)]
    assert found == ["x.js:5: text not marked for translation: 'Nothing to review.'",
                     "x.js:6: text not marked for translation: 'Now'"]  # fmt: skip


def test_a_started_therapist_catalogue_is_held_to_the_placeholders_rule(domains):
    code = domains["therapist"]
    po = Catalog(locale="de", domain=THERAPIST_DOMAIN)
    po.mime_headers = [("Plural-Forms", "nplurals=2; plural=(n != 1);")]
    for message in code:
        if message.id:
            po.add(
                message.id, message.id if isinstance(message.id, str) else tuple(message.id), context=message.context
            )
    po["Because {what} ({value}) was {compared} {limit}."].string = "Weil {what} ({value}) {compared} war."
    del po["My patients"]
    found = sorted(str(p) for p in check_locale("de", code, po, domain=THERAPIST_DOMAIN))
    assert found == [
        "backend/i18n/locale/de/LC_MESSAGES/therapist.po: 'Because {what} ({value}) was {compared} {limit}.': "
        "placeholders ['compared', 'value', 'what'] != ['compared', 'limit', 'value', 'what']",
        "backend/i18n/locale/de/LC_MESSAGES/therapist.po: no translation of 'My patients'",
    ]


def _clear_caches() -> None:
    from frontend.pages import templates_for

    for cached in (i18n._catalog, i18n.translations, i18n.therapist_locales, i18n.therapist_translations,
                   i18n.js_messages, templates_for):  # fmt: skip
        cached.cache_clear()


@pytest.fixture
def german_therapist_catalogue(tmp_path, monkeypatch, domains):
    """A copy of the locale folder with a German therapist.po (two texts translated, one of them a script's), as
    `python -m backend.i18n.catalogues init de` starts it and a translator fills it."""
    folder = tmp_path / "locale"
    shutil.copytree(i18n.LOCALE_DIR, folder)
    po = Catalog(locale="de", domain=THERAPIST_DOMAIN)
    for message in domains["therapist"]:
        if message.id in ("My patients", "No unread replies."):
            po.add(message.id, {"My patients": "Meine Patienten", "No unread replies.": "Keine ungelesenen Antworten."}[
                message.id], message.locations)  # fmt: skip
    from babel.messages.pofile import write_po

    with (folder / "de" / "LC_MESSAGES" / "therapist.po").open("wb") as f:
        write_po(f, po)
    monkeypatch.setattr(i18n, "LOCALE_DIR", folder)
    _clear_caches()
    yield
    monkeypatch.undo()
    _clear_caches()


def test_without_a_therapist_catalogue_the_therapist_pages_are_english(client, make_patient_with_therapist,
                                                                       auth_headers):  # fmt: skip
    assert therapist_locales() == ("en",)
    _, therapist = make_patient_with_therapist()
    page = client.get("/therapist", headers=HTML | auth_headers(therapist) | {"Accept-Language": "de"})
    assert '<html lang="en">' in page.text and '<h1 id="patients-h">My patients</h1>' in page.text


@pytest.mark.usefixtures("german_therapist_catalogue")
def test_a_therapist_po_turns_the_therapist_pages_german_without_a_code_change(
    client, make_patient_with_therapist, auth_headers
):
    assert therapist_locales() == ("en", "de")
    patient, therapist = make_patient_with_therapist()
    headers = HTML | auth_headers(therapist)
    page = client.get("/therapist", headers=headers | {"Accept-Language": "de-DE,de;q=0.9,en;q=0.5"})
    assert page.status_code == 200 and '<html lang="de">' in page.text
    assert '<h1 id="patients-h">Meine Patienten</h1>' in page.text
    assert "Abmelden" in page.text  # base.html's "Sign out": the shared messages.po, the fallback
    assert "New replies from patients" in page.text  # not translated yet: its English msgid
    assert '"No unread replies.": "Keine ungelesenen Antworten."' in page.text  # the scripts' messages
    assert js_messages("de", therapist=True)["messages"]["No unread replies."] == "Keine ungelesenen Antworten."
    assert "No unread replies." not in js_messages("de")["messages"]  # the patient pages do not get them
    french = client.get("/therapist", headers=headers | {"Accept-Language": "fr"})
    assert '<html lang="en">' in french.text  # no French therapist catalogue: English
    assert '<html lang="de">' in client.get("/patient", headers=HTML | auth_headers(patient) | {
        "Accept-Language": "de"}).text  # fmt: skip


def test_the_dashboard_reasons_format_numbers_and_dates_with_babel_in_the_readers_locale():
    import datetime as dt

    from backend.i18n import Translator, therapist_translator
    from backend.sessions.triage import RecentSession, RunningPlan, attention

    now = dt.datetime(2026, 11, 27, 12, tzinfo=dt.UTC)

    def said(days: int, pain: int) -> RecentSession:
        return RecentSession(started_at=now - dt.timedelta(days=days), exercise_slug="squat", repetitions=10,
                             rom_deg=60.0, quality_ok=True, indicator_scores=None, pain_nrs=pain)  # fmt: skip

    sessions = [said(20, 2), said(15, 3), said(2, 6)]  # the median pain rose from 2.5 to 6
    plan = RunningPlan(per_week=3, started_on=dt.date(2026, 11, 24))  # new: "no session yet" names its first day

    def reasons(t: Translator, last_session_at: dt.datetime | None) -> list[str]:
        return attention(now=now, plan=plan, sessions_this_week=0, last_session_at=last_session_at, sessions=sessions,
                         pending_suggestions=1, pain_alert_above=9, t=t).reasons  # fmt: skip

    english = reasons(therapist_translator("de"), now)  # no German therapist catalogue: English
    assert "Pain after sets rose from 2.5 to 6 of 10 (median of the last 7 days against the 4 weeks before)" in english
    assert "1 suggestion to review" in english
    assert reasons(therapist_translator(None), None)[-1] == "New plan since 24 Nov; no session yet"
    german_numbers = reasons(Translator("de", therapist=True), None)
    assert any("from 2,5 to 6 of 10" in r for r in german_numbers), german_numbers
    assert german_numbers[-1] == "New plan since 24. Nov.; no session yet"
