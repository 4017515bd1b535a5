"""Keeps the message catalogues in step with the code: `python -m backend.i18n.catalogues extract|update|check`.

- extract: writes backend/i18n/locale/messages.pot from the marked texts of the server (Python), the templates
  (Jinja) and the page scripts (JavaScript), with Babel's extractors.
- update: merges the template into each locale's .po (new messages empty, changed ones fuzzy, gone ones dropped).
- check: exits 1, naming each problem, when the template is not what the code marks today, or a locale misses a
  translation, has a fuzzy one, or a translation's placeholders differ from its msgid's.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from babel.messages.catalog import Catalog
from babel.messages.extract import extract_from_dir
from babel.messages.pofile import read_po, write_po

from backend.i18n import DOMAIN, LOCALE_DIR, LOCALES, po_path

ROOT = Path(__file__).resolve().parents[2]
POT = LOCALE_DIR / f"{DOMAIN}.pot"
PLURAL_FORMS = {"de": "nplurals=2; plural=(n != 1);", "es": "nplurals=2; plural=(n != 1);",
                "fr": "nplurals=2; plural=(n > 1);"}  # fmt: skip
# (directory, Babel method map, keywords); the Python keywords are gettext's own plus N_ for lazy marks
SOURCES = (
    ("backend", [("**.py", "python")], {"_": None, "gettext": None, "ngettext": (1, 2), "N_": None}),
    ("frontend", [("**.py", "python")], {"_": None, "gettext": None, "ngettext": (1, 2), "N_": None}),
    ("frontend/templates", [("**.html", "jinja2")], {"_": None, "gettext": None, "ngettext": (1, 2)}),
    ("frontend/static", [("**.js", "javascript")], {"I18n.t": None, "I18n.nt": (1, 2), "I18n.N_": None}),
)
JINJA_OPTIONS = {"extensions": "jinja2.ext.i18n", "trimmed": "true"}
PLURAL_COUNTS = {"n", "num"}  # the count of a plural message: {n} in scripts, %(num)d in Python
PLACEHOLDER = re.compile(r"%\((\w+)\)[sdif]|\{(\w+)\}")


def extract() -> Catalog:
    """Returns the catalogue of every message marked in the code today (locations relative to the repository)."""
    catalog = Catalog(project="Kinect Home Coach", domain=DOMAIN, charset="utf-8", fuzzy=False)
    for directory, method_map, keywords in SOURCES:
        options = {"**.html": JINJA_OPTIONS}
        found = extract_from_dir(ROOT / directory, method_map, options_map=options, keywords=keywords,
                                 comment_tags=("TRANSLATORS:",), strip_comment_tags=True)  # fmt: skip
        for filename, lineno, message, comments, context in found:
            catalog.add(message, None, [(f"{directory}/{filename}", lineno)], auto_comments=comments, context=context)
    return catalog


def _write(catalog: Catalog, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        write_po(f, catalog, width=120, omit_header=False, sort_output=True, ignore_obsolete=True,
                 include_previous=False)  # fmt: skip


def _read(path: Path, locale: str | None = None) -> Catalog:
    with path.open("rb") as f:
        return read_po(f, locale=locale, domain=DOMAIN)


def write_template() -> Catalog:
    """Writes messages.pot from the code; returns it."""
    template = extract()
    _write(template, POT)
    return template


def update() -> None:
    """Merges messages.pot into each locale's .po (making the .po of a new locale)."""
    template = _read(POT)
    for locale in LOCALES[1:]:
        path = po_path(locale)
        if path.exists():
            catalog = _read(path, locale)
        else:
            catalog = Catalog(locale=locale, domain=DOMAIN, project="Kinect Home Coach", fuzzy=False)
        catalog.update(template, no_fuzzy_matching=True)
        catalog.mime_headers = [("Plural-Forms", PLURAL_FORMS[locale])]  # two forms, as the page scripts count
        _write(catalog, path)


def placeholders(text: str) -> set[str]:
    """Returns the names of the placeholders in a message: %(name)s and {name}."""
    return {a or b for a, b in PLACEHOLDER.findall(text)}


@dataclass(frozen=True)
class Problem:
    """One thing the check found wrong, said so a translator can find it."""

    where: str
    what: str

    def __str__(self) -> str:
        return f"{self.where}: {self.what}"


def _ids(catalog: Catalog) -> set[tuple[str | tuple[str, ...], str | None]]:
    return {(m.id if isinstance(m.id, str) else tuple(m.id), m.context) for m in catalog if m.id}


def check(template: Catalog | None = None) -> list[Problem]:
    """Returns the problems of the catalogues: messages.pot against the code, each .po against messages.pot."""
    problems: list[Problem] = []
    code = extract() if template is None else template
    pot = _read(POT)
    for msgid, _ in sorted(_ids(code) - _ids(pot), key=str):
        problems.append(Problem(str(POT.relative_to(ROOT)), f"misses {msgid!r}: run extract and update"))
    for msgid, _ in sorted(_ids(pot) - _ids(code), key=str):
        problems.append(Problem(str(POT.relative_to(ROOT)), f"still has {msgid!r}, no longer in the code: run extract"))
    for locale in LOCALES[1:]:
        problems.extend(check_locale(locale, code))
    return problems


def check_locale(locale: str, code: Catalog, catalog: Catalog | None = None) -> Iterable[Problem]:
    """Yields the problems of one locale's catalogue (its .po unless given) against the messages of the code."""
    where = str(po_path(locale).relative_to(ROOT))
    if catalog is None:
        catalog = _read(po_path(locale), locale)
    if catalog.num_plurals != 2 or PLURAL_FORMS[locale].split("plural=")[1].rstrip(";") != catalog.plural_expr:
        yield Problem(where, f"Plural-Forms must be {PLURAL_FORMS[locale]!r}")
    for message in code:
        if not message.id:
            continue
        found = catalog.get(message.id, context=message.context)
        ids = (message.id,) if isinstance(message.id, str) else tuple(message.id)
        if found is None or not found.string or (isinstance(found.string, tuple) and not all(found.string)):
            yield Problem(where, f"no translation of {ids[0]!r}")
            continue
        if found.fuzzy:
            yield Problem(where, f"fuzzy translation of {ids[0]!r}")
        strings = (found.string,) if isinstance(found.string, str) else tuple(found.string)
        expected = set().union(*(placeholders(i) for i in ids))
        # a plural form may leave out the count ("once a week" for n = 1), never anything else
        optional = PLURAL_COUNTS if isinstance(message.id, tuple) else set()
        for string in strings:
            has = placeholders(string)
            if not (expected - optional <= has <= expected):
                yield Problem(where, f"{ids[0]!r}: placeholders {sorted(has)} != {sorted(expected)}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m backend.i18n.catalogues", description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("extract", "update", "check"))
    args = parser.parse_args(argv)
    if args.command == "extract":
        template = write_template()
        print(f"{POT.relative_to(ROOT)}: {len(template)} messages")
    elif args.command == "update":
        update()
        print("updated " + ", ".join(str(po_path(locale).relative_to(ROOT)) for locale in LOCALES[1:]))
    else:
        problems = check()
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            print(f"{len(problems)} problems", file=sys.stderr)
            return 1
        print("catalogues complete: " + ", ".join(LOCALES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
