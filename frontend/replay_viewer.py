"""viser's web client as the replay page's iframe opens it (/replay/viewer/): the file of the pinned viser wheel, in
the reader's language where the app can say it.

The client is one HTML file whose application is a compressed inline bundle: its own words are English and cannot be
changed in the file (docs/languages.md names them). Served here, the file gets, per reader: `<html lang>` of the
reader's language, its `<title>` and `<noscript>` text from the catalogues, and before `</head>` the messages of
static/replay_viewer.js only (JSON, as every page carries its scripts' messages; the player needs a few dozen, not
every page's) with two scripts of this origin: static/i18n.js and static/replay_viewer.js, which puts viser's
playback-bar words in the reader's language as they appear and names the controls viser leaves unnamed. The bundle
and its inline script are not changed, so the viewer's policy (backend/security_headers.py: scripts of this origin,
connections to this origin only) is the same.
"""

from __future__ import annotations

import json
from functools import lru_cache
from html import escape
from pathlib import Path

from backend.i18n import LOCALES, N_, Translator, js_messages

REPLAY_TITLE = N_("Session replay")
NO_SCRIPT = N_("The 3D replay needs JavaScript. Please turn it on in your browser and open this page again.")
# what viser 1.1.1's index.html says, each exactly once (ViewerChanged names the one a new viser no longer has)
_LANG = '<html lang="en">'
_TITLE = "<title>Viser</title>"
_NO_SCRIPT = "<noscript>You need to enable JavaScript to run this app.</noscript>"
_HEAD_END = "</head>"
# the scripts the viewer loads that say something (i18n.js says nothing itself): the page carries their messages only
VIEWER_SCRIPTS = ("frontend/static/replay_viewer.js",)


class ViewerChanged(RuntimeError):
    """viser's index.html no longer holds a text the app replaces (a viser upgrade changed it)."""


@lru_cache(maxsize=2)
def _client(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def _once(html: str, old: str, new: str) -> str:
    """Returns html with its one `old` replaced by `new`; raises ViewerChanged when it has none or several."""
    count = html.count(old)
    if count != 1:
        raise ViewerChanged(f"viser's client holds {old!r} {count} times, not once: update frontend/replay_viewer.py")
    return html.replace(old, new)


@lru_cache(maxsize=4 * len(LOCALES))
def viewer_html(client: Path, locale: str, therapist: bool, root: str) -> str:
    """Returns viser's client page (the file `client`) for a reader of `locale` (a therapist's: their pages'
    catalogues), its scripts under the app's path `root` (the public URL's prefix, "" at the origin's root)."""
    t = Translator(locale, therapist=therapist)
    messages = json.dumps(js_messages(locale, therapist, VIEWER_SCRIPTS), ensure_ascii=False).replace("<", "\\u003c")
    scripts = (f'<script type="application/json" id="i18n-messages">{messages}</script>'
               f'<script src="{escape(root)}/static/i18n.js"></script>'
               f'<script src="{escape(root)}/static/replay_viewer.js"></script>')  # fmt: skip
    html = _once(_client(client), _LANG, f'<html lang="{escape(locale)}">')
    html = _once(html, _TITLE, f"<title>{escape(t.gettext(REPLAY_TITLE))}</title>")
    html = _once(html, _NO_SCRIPT, f"<noscript>{escape(t.gettext(NO_SCRIPT))}</noscript>")
    return _once(html, _HEAD_END, scripts + _HEAD_END)
