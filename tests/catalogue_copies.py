"""A copy of the shipped catalogues with therapist catalogues started for some locales (what
`python -m backend.i18n.catalogues init LOCALE` and a translator make), for servers started with COACH_LOCALE_DIR."""

from __future__ import annotations

import shutil
from pathlib import Path

from babel.messages.catalog import Catalog
from babel.messages.pofile import read_po, write_po

from backend.i18n import LOCALE_DIR, THERAPIST_DOMAIN
from backend.i18n.catalogues import PLURAL_FORMS


def copy_with_therapist_catalogues(dest: Path, words: dict[str, dict[str, str]]) -> Path:
    """Copies the catalogues to dest/locale and writes, per locale of words, a therapist.po with those translations
    (msgid -> msgstr, each a message of therapist.pot, with its locations there: the page scripts get those used in a
    script; the others fall back to the locale's messages.po, then English); returns dest/locale."""
    locale_dir = dest / "locale"
    shutil.copytree(LOCALE_DIR, locale_dir)
    with (LOCALE_DIR / f"{THERAPIST_DOMAIN}.pot").open("rb") as f:
        template = read_po(f, domain=THERAPIST_DOMAIN)
    for locale, table in words.items():
        catalog = Catalog(locale=locale, domain=THERAPIST_DOMAIN)
        catalog.mime_headers = [("Plural-Forms", PLURAL_FORMS[locale])]
        for msgid, msgstr in table.items():
            found = template.get(msgid)
            if found is None:
                raise KeyError(f"{msgid!r} is no message of {THERAPIST_DOMAIN}.pot")
            catalog.add(msgid, msgstr, locations=found.locations)
        with (locale_dir / locale / "LC_MESSAGES" / f"{THERAPIST_DOMAIN}.po").open("wb") as f:
            write_po(f, catalog)
    return locale_dir
