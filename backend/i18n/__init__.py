"""Languages of the patient's side: gettext catalogues (one .po per locale, compiled in memory at first use), the
locale of a request, and dates and numbers formatted per locale with Babel.

One catalogue per locale holds every message: the server's (Python, marked with `_`/`ngettext` or, where the text is
chosen before the locale is known, `N_`), the templates' (Jinja's i18n extension) and the page scripts' (`I18n.t`/
`I18n.nt` in frontend/static, handed to the page as JSON by `js_messages`). English is the source language: its
messages are the msgids. `python -m backend.i18n.catalogues extract|update|check` keeps the catalogues in step with
the code; tests/backend/test_i18n.py holds them complete.

Placeholders: `%(name)s`/`%(name)d` in Python and templates, `{name}` in scripts; a translation has exactly the
placeholders of its msgid.

Two domains: `messages` (the patient's side and whatever patient and therapist pages share, English plus every locale
of LOCALES, complete) and `therapist` (the texts only the therapist pages show: extracted into therapist.pot, English
only for now). A therapist page is in a locale once `locale/<locale>/LC_MESSAGES/therapist.po` exists (found at
start, no code change): `therapist_locales`. The pages look a message up in `therapist` first, then in `messages`.
"""

from __future__ import annotations

import datetime as dt
import gettext
import io
import os
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from babel import Locale, UnknownLocaleError
from babel.dates import format_date as _babel_format_date
from babel.dates import format_skeleton
from babel.messages.catalog import Catalog
from babel.messages.mofile import write_mo
from babel.messages.pofile import read_po
from babel.numbers import format_decimal, format_percent

# the catalogues: the shipped ones, or a copy named by COACH_LOCALE_DIR (a clinic's own therapist.po, a test's)
LOCALE_DIR = Path(os.environ.get("COACH_LOCALE_DIR") or Path(__file__).resolve().parent / "locale")
DOMAIN = "messages"
THERAPIST_DOMAIN = "therapist"  # texts only the therapist pages show; a locale's therapist.po is optional
DOMAINS = (DOMAIN, THERAPIST_DOMAIN)
DEFAULT_LOCALE = "en"
LOCALES = ("en", "de", "es", "fr")  # English is the source language; the others have a catalogue each
LANGUAGE_NAMES = {"en": "English", "de": "Deutsch", "es": "Español", "fr": "Français"}  # each in its own language
SCRIPT_SUFFIXES = (".js",)  # messages found in these files are handed to the page scripts


def N_(message: str) -> str:  # noqa: N802 (the gettext convention)
    """Marks a message for extraction without translating it (the text is translated where it is shown)."""
    return message


def po_path(locale: str, domain: str = DOMAIN) -> Path:
    """Returns the .po file of one locale and domain (not English: its msgids are the text)."""
    return LOCALE_DIR / locale / "LC_MESSAGES" / f"{domain}.po"


@lru_cache(maxsize=2 * len(LOCALES))
def _catalog(locale: str, domain: str = DOMAIN) -> Catalog:
    with po_path(locale, domain).open("rb") as f:
        return read_po(f, locale=locale, domain=domain)


def _compiled(locale: str, domain: str) -> gettext.GNUTranslations:
    buf = io.BytesIO()
    write_mo(buf, _catalog(locale, domain), use_fuzzy=False)
    buf.seek(0)
    return gettext.GNUTranslations(buf)


@lru_cache(maxsize=len(LOCALES))
def translations(locale: str) -> gettext.NullTranslations:
    """Returns the compiled translations of a locale (the .po compiled to .mo in memory); English: the msgids."""
    if locale == DEFAULT_LOCALE:
        return gettext.NullTranslations()
    return _compiled(locale, DOMAIN)


@lru_cache(maxsize=1)
def therapist_locales() -> tuple[str, ...]:
    """Returns the locales the therapist pages come in: English and each locale of LOCALES with a therapist.po."""
    return (DEFAULT_LOCALE,) + tuple(loc for loc in LOCALES[1:] if po_path(loc, THERAPIST_DOMAIN).exists())


@lru_cache(maxsize=len(LOCALES))
def therapist_translations(locale: str) -> gettext.NullTranslations:
    """Returns the translations of the therapist pages: the locale's therapist.po, falling back to its messages.po
    (the texts the pages share with the patient's side); English, or a locale without therapist.po: its messages."""
    if locale == DEFAULT_LOCALE or locale not in therapist_locales():
        return translations(locale)
    found = _compiled(locale, THERAPIST_DOMAIN)
    found.add_fallback(_compiled(locale, DOMAIN))
    return found


def forget_catalogues() -> None:
    """Forgets the catalogues read so far and the therapist locales found (read again at next use: after the
    catalogues or LOCALE_DIR changed)."""
    for cache in (_catalog, translations, therapist_locales, therapist_translations, js_messages):
        cache.cache_clear()


@dataclass(frozen=True)
class Translator:
    """The messages, dates and numbers of one locale (therapist: the therapist pages' catalogue first)."""

    locale: str
    therapist: bool = False

    def _source(self) -> gettext.NullTranslations:
        return therapist_translations(self.locale) if self.therapist else translations(self.locale)

    def gettext(self, message: str, **params: object) -> str:
        """Returns the translation of message, with %(name)s placeholders filled from params when given."""
        text = self._source().gettext(message)
        return text % params if params else text

    def ngettext(self, singular: str, plural: str, n: int, **params: object) -> str:
        """Returns the singular or plural translation for n; %(num)d is n unless params says otherwise."""
        text = self._source().ngettext(singular, plural, n)
        return text % ({"num": n} | params)

    def format_date(self, value: dt.date | dt.datetime, format: str = "long") -> str:  # noqa: A002 (Babel's name)
        """Returns a date the way this locale writes it ("long": 27 November 2026 / 27. November 2026)."""
        return _babel_format_date(value, format=format, locale=self.locale)

    def format_day_month(self, value: dt.date) -> str:
        """Returns a day and short month the way this locale writes them (CLDR skeleton dMMM: 24 Nov, 24. Nov.,
        24 nov.); English the British way, as the page scripts write dates (en-GB)."""
        return format_skeleton("dMMM", value, locale="en_GB" if self.locale == DEFAULT_LOCALE else self.locale)

    def format_number(self, value: float, decimals: int = 0) -> str:
        """Returns a number with this locale's decimal sign, rounded to `decimals` places."""
        fmt = "#,##0" + ("." + "0" * decimals if decimals else "")
        return format_decimal(round(value, decimals), format=fmt, locale=self.locale)

    def format_percent(self, fraction: float) -> str:
        """Returns a fraction as a whole percentage the way this locale writes it (0.85: 85% / 85 %)."""
        return format_percent(fraction, locale=self.locale)


def translator(locale: str | None) -> Translator:
    """Returns the Translator of a supported locale (anything else: English)."""
    return Translator(locale if locale in LOCALES else DEFAULT_LOCALE)


ENGLISH = translator("en")  # the patients' catalogue in English: stored texts, commands, reports, jobs' words


def therapist_translator(accept_language: str | None) -> Translator:
    """Returns the Translator of a therapist's request: the locale of its Accept-Language among the therapist pages'
    locales (therapist_locales; English until a therapist.po exists)."""
    return Translator(negotiate(accept_language, therapist_locales()), therapist=True)


def reader_translator(accept_language: str | None, *, role: str, locale: str | None = None) -> Translator:
    """Returns the Translator of an API reader: a patient's (the locale their page asks for in Accept-Language, else
    their chosen one), a therapist's or admin's (the same among the therapist pages' locales, therapist catalogue
    first), anyone else's (a device) English."""
    if role == "patient":
        return translator(asked_locale(accept_language) or locale)
    if role in ("therapist", "admin"):
        chosen = locale if locale in therapist_locales() else None
        return Translator(asked_locale(accept_language, therapist_locales()) or chosen or DEFAULT_LOCALE,
                          therapist=True)  # fmt: skip
    return Translator(DEFAULT_LOCALE)


def normalise(tag: str | None) -> str | None:
    """Returns the supported locale of a language tag ("de-AT" -> "de", "fr_CA" -> "fr"), or None."""
    if not tag:
        return None
    try:
        language = Locale.parse(tag.strip().replace("-", "_")).language
    except (ValueError, UnknownLocaleError):
        return None
    return language if language in LOCALES else None


def negotiate(accept_language: str | None, supported: Sequence[str] = LOCALES) -> str:
    """Returns the locale of `supported` a browser's Accept-Language header prefers most, else English."""
    return asked_locale(accept_language, supported) or DEFAULT_LOCALE


def asked_locale(accept_language: str | None, supported: Sequence[str] = LOCALES) -> str | None:
    """Returns the locale of `supported` an Accept-Language header prefers most, or None when it names none."""
    choices = []
    for position, part in enumerate((accept_language or "").split(",")[:20]):
        tag, _, params = part.strip().partition(";")
        q = 1.0
        if params.strip().startswith("q="):
            try:
                q = float(params.strip()[2:])
            except ValueError:
                q = 0.0
        locale = normalise(tag) if tag and tag != "*" else None
        if locale is not None and locale in supported and q > 0:
            choices.append((-q, position, locale))
    return min(choices)[2] if choices else None


def is_script_message(locations: Sequence[tuple[str, int | None]]) -> bool:
    """Returns whether a message is used by a page script (one of its locations is a .js file)."""
    return any(path.endswith(SCRIPT_SUFFIXES) for path, _ in locations)


@lru_cache(maxsize=4 * len(LOCALES))
def js_messages(locale: str, therapist: bool = False, scripts: tuple[str, ...] | None = None) -> dict[str, Any]:
    """Returns the page scripts' messages of a locale, the JSON that frontend/static/i18n.js reads:
    {"locale", "plural": "n != 1" | "n > 1", "messages": {msgid: msgstr, "singular\\u0004plural": [forms]}}.

    Only messages used in a .js file and translated (not fuzzy) are sent; a missing one shows its English msgid.
    A therapist page gets the messages domain's and, where the locale has one, its therapist.po's. scripts: only the
    messages used in these files (paths from the repository's root, "frontend/static/replay_viewer.js"), for a page
    that loads no other script with messages; None: every script's.
    """
    if locale not in LOCALES or locale == DEFAULT_LOCALE:
        return {"locale": DEFAULT_LOCALE, "plural": "n != 1", "messages": {}}
    messages = _script_messages(_catalog(locale), scripts)
    if therapist and locale in therapist_locales():
        messages |= _script_messages(_catalog(locale, THERAPIST_DOMAIN), scripts)
    return {"locale": locale, "plural": plural_rule(locale), "messages": messages}


def _script_messages(catalog: Catalog, scripts: tuple[str, ...] | None = None) -> dict[str, str | list[str]]:
    messages: dict[str, str | list[str]] = {}
    for message in catalog:
        if not message.id or message.fuzzy or not is_script_message(message.locations):
            continue
        if scripts is not None and not any(path in scripts for path, _ in message.locations):
            continue
        if isinstance(message.id, str):
            if isinstance(message.string, str) and message.string:
                messages[message.id] = message.string
        elif isinstance(message.string, tuple | list) and all(message.string):  # plural: one string per form
            messages[message.id[0] + "\u0004" + message.id[1]] = list(message.string)
    return messages


def plural_rule(locale: str) -> str:
    """Returns the plural rule of a locale's catalogue as the scripts know it: "n != 1" or "n > 1" (two forms)."""
    if locale == DEFAULT_LOCALE:
        return "n != 1"
    expr = _catalog(locale).plural_expr.replace(" ", "").strip("()")
    return {"n!=1": "n != 1", "n>1": "n > 1"}[expr]
