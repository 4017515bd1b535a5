"""viser's client as the app serves it (frontend.replay_viewer): the pinned file, its bundle unchanged, with the
reader's language, title and no-script text, and the scripts that put viser's words in that language."""

from __future__ import annotations

import re

import pytest

from backend.i18n import translator
from frontend.pages import VISER_CLIENT
from frontend.replay_viewer import NO_SCRIPT, ViewerChanged, viewer_html


def _scripts(html: str) -> list[str]:
    return re.findall(r"<script\b[^>]*>.*?</script>", html, flags=re.S)


@pytest.mark.parametrize("locale", ["de", "es", "fr"])
def test_the_viewer_is_visers_file_in_the_readers_language(locale):
    html = viewer_html(VISER_CLIENT, locale, False, "")
    t = translator(locale)
    assert f'<html lang="{locale}">' in html and f"<title>{t.gettext('Session replay')}</title>" in html
    assert f"<noscript>{t.gettext(NO_SCRIPT)}</noscript>" in html and t.gettext(NO_SCRIPT) != NO_SCRIPT
    original = VISER_CLIENT.read_text(encoding="utf-8")
    added = [s for s in _scripts(html) if s not in _scripts(original)]
    assert [s for s in _scripts(original) if s not in html] == [], "viser's own scripts are served unchanged"
    assert added[1:] == ['<script src="/static/i18n.js"></script>', '<script src="/static/replay_viewer.js"></script>']
    assert added[0].startswith('<script type="application/json" id="i18n-messages">'), added[0][:80]
    assert t.gettext("Playback speed") in added[0] and "</" not in added[0][len("<script ") : -len("</script>")]


def test_a_viser_without_a_text_the_app_replaces_is_named(tmp_path):
    changed = tmp_path / "index.html"
    changed.write_text(VISER_CLIENT.read_text(encoding="utf-8").replace("<title>Viser</title>", "<title>V</title>"))
    with pytest.raises(ViewerChanged, match="<title>Viser</title>"):
        viewer_html(changed, "de", False, "")
