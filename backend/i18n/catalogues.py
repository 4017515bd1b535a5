"""Keeps the message catalogues in step with the code: `python -m backend.i18n.catalogues extract|update|check`.

- extract: writes backend/i18n/locale/messages.pot and therapist.pot from the marked texts of the server (Python),
  the analysis' reasons (kinect_agent/analysis/reasons.py), the templates (Jinja) and the page scripts
  (JavaScript), with Babel's extractors. A message goes to therapist.pot
  when every place it is used is a file of THERAPIST_FILES (the pages only therapists see), else to messages.pot.
- update: merges each template into each locale's .po of its domain (new messages empty, changed ones fuzzy, gone
  ones dropped): messages.po of every locale, therapist.po of the locales that have one.
- init LOCALE: starts the therapist pages' catalogue of a locale (therapist.po from therapist.pot, to translate);
  from then on the therapist pages come in that locale (for a browser that asks for it) and check holds it complete.
- check: exits 1, naming each problem, when a template is not what the code marks today, a therapist template shows
  text that is not marked, or a locale's .po misses a translation, has a fuzzy one, or a translation's placeholders
  differ from its msgid's, or a French one puts a plain space (or none) before : ; ! ? (French typography: a
  no-break space, U+00A0 or the narrow U+202F). English-only is complete for the therapist domain: it has only its
  template until a locale's therapist.po is started, and then that .po is checked like messages.po.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path

from babel.messages.catalog import Catalog
from babel.messages.extract import extract_from_dir
from babel.messages.jslexer import tokenize
from babel.messages.pofile import read_po, write_po

from backend.i18n import DOMAIN, DOMAINS, LOCALE_DIR, LOCALES, THERAPIST_DOMAIN, po_path

ROOT = Path(__file__).resolve().parents[2]
# the files of the pages only therapists (and admins) see: their messages form the therapist domain (the replay page
# is not one: a patient opens it too, in their language)
THERAPIST_FILES = frozenset(
    {
        "frontend/templates/therapist.html",
        "frontend/templates/patient_detail.html",
        "frontend/templates/session.html",
        "frontend/templates/admin_jobs.html",
        "frontend/static/therapist.js",
        "frontend/static/patient_detail.js",
        "frontend/static/session.js",
        "frontend/static/admin_jobs.js",
        "frontend/static/records.js",
        "frontend/static/replies_view.js",
        "frontend/static/feeling_view.js",
        "frontend/static/versions.js",
        "frontend/static/voice_setting.js",
        "frontend/static/downloads.js",
        "frontend/static/report_period.js",
        "backend/sessions/triage.py",  # the dashboard's attention reasons and indicator trends
    }
)  # fmt: skip (the session detail's notes, quality labels and curve labels are not: a patient reads them in the API)
PLURAL_FORMS = {"de": "nplurals=2; plural=(n != 1);", "es": "nplurals=2; plural=(n != 1);",
                "fr": "nplurals=2; plural=(n > 1);"}  # fmt: skip
# (directory, Babel method map, keywords); the Python keywords are gettext's own plus N_ for lazy marks
SOURCES = (
    ("backend", [("**.py", "python")], {"_": None, "gettext": None, "ngettext": (1, 2), "N_": None}),
    ("kinect_agent/analysis", [("reasons.py", "python")], {"N_": None}),  # the analysis' reasons (no server import)
    ("frontend", [("**.py", "python")], {"_": None, "gettext": None, "ngettext": (1, 2), "N_": None}),
    ("frontend/templates", [("**.html", "jinja2")], {"_": None, "gettext": None, "ngettext": (1, 2)}),
    ("frontend/static", [("**.js", "javascript")], {"I18n.t": None, "I18n.nt": (1, 2), "I18n.N_": None}),
)
JINJA_OPTIONS = {"extensions": "jinja2.ext.i18n", "trimmed": "true"}
PLURAL_COUNTS = {"n", "num"}  # the count of a plural message: {n} in scripts, %(num)d in Python
PLACEHOLDER = re.compile(r"%\((\w+)\)[sdif]|\{(\w+)\}")
# French puts a no-break space (U+00A0) or a narrow one (U+202F) before : ; ! ? used as punctuation (followed by a
# space, the end, a closing mark or a tag: not 10:30, https:// or Plotly's %{y:.1f}); a plain or no space is a fault
FRENCH_TIGHT = re.compile(r"(?P<before>.?)(?P<mark>[:;!?])(?=$|[\s»”’\"')…<])", re.S)
FRENCH_SPACES = ("\u00a0", "\u202f")


def pot_path(domain: str = DOMAIN) -> Path:
    """Returns the template (.pot) of a domain."""
    return LOCALE_DIR / f"{domain}.pot"


def extract_all() -> dict[str, Catalog]:
    """Returns each domain's catalogue of the messages marked in the code today (locations relative to the
    repository): therapist, the messages used only in THERAPIST_FILES; messages, every other."""
    every = Catalog(project="Kinect Home Coach", domain=DOMAIN, charset="utf-8", fuzzy=False)
    for directory, method_map, keywords in SOURCES:
        options = {"**.html": JINJA_OPTIONS}
        found = extract_from_dir(ROOT / directory, method_map, options_map=options, keywords=keywords,
                                 comment_tags=("TRANSLATORS:",), strip_comment_tags=True)  # fmt: skip
        for filename, lineno, message, comments, context in found:
            every.add(message, None, [(f"{directory}/{filename}", lineno)], auto_comments=comments, context=context)
    domains = {d: Catalog(project="Kinect Home Coach", domain=d, charset="utf-8", fuzzy=False) for d in DOMAINS}
    for found_message in every:
        if not found_message.id:
            continue
        therapist_only = all(path in THERAPIST_FILES for path, _ in found_message.locations)
        domains[THERAPIST_DOMAIN if therapist_only else DOMAIN].add(
            found_message.id,
            None,
            found_message.locations,
            auto_comments=found_message.auto_comments,
            context=found_message.context,
        )
    return domains


def extract(domain: str = DOMAIN) -> Catalog:
    """Returns the catalogue of one domain's messages marked in the code today."""
    return extract_all()[domain]


def _write(catalog: Catalog, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        write_po(f, catalog, width=120, omit_header=False, sort_output=True, ignore_obsolete=True,
                 include_previous=False)  # fmt: skip


def _read(path: Path, locale: str | None = None, domain: str = DOMAIN) -> Catalog:
    with path.open("rb") as f:
        return read_po(f, locale=locale, domain=domain)


def write_templates() -> dict[str, Catalog]:
    """Writes each domain's .pot from the code; returns them."""
    templates = extract_all()
    for domain, template in templates.items():
        _write(template, pot_path(domain))
    return templates


def domain_locales(domain: str) -> tuple[str, ...]:
    """Returns the locales (not English) whose .po of a domain the check holds complete: every one for messages,
    those with a therapist.po for therapist (English-only until a locale's catalogue is started with init)."""
    if domain == DOMAIN:
        return LOCALES[1:]
    return tuple(locale for locale in LOCALES[1:] if po_path(locale, domain).exists())


def update(started: tuple[str, ...] = ()) -> None:
    """Merges each .pot into the .po files of its domain (making messages.po of a new locale, and therapist.po of
    the locales in `started`)."""
    for domain in DOMAINS:
        template = _read(pot_path(domain), domain=domain)
        for locale in sorted(set(domain_locales(domain)) | (set(started) if domain == THERAPIST_DOMAIN else set())):
            path = po_path(locale, domain)
            if path.exists():
                catalog = _read(path, locale, domain)
            else:
                catalog = Catalog(locale=locale, domain=domain, project="Kinect Home Coach", fuzzy=False)
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


def check(templates: dict[str, Catalog] | None = None) -> list[Problem]:
    """Returns the problems of the catalogues: each domain's .pot against the code, each .po against the code, and
    the words of the pages (templates and scripts, the patient's too) that are not marked for translation."""
    problems: list[Problem] = []
    code = extract_all() if templates is None else templates
    for domain in DOMAINS:
        problems.extend(check_template(domain, code[domain]))
        for locale in domain_locales(domain):
            problems.extend(check_locale(locale, code[domain], domain=domain))
    for script in sorted((ROOT / "frontend/static").glob("*.js")):
        where = str(script.relative_to(ROOT))
        problems.extend(marks_in_template_literals(where, script.read_text(encoding="utf-8")))
    for path in sorted(THERAPIST_FILES):
        if not (ROOT / path).is_file():
            problems.append(Problem("backend/i18n/catalogues.py", f"THERAPIST_FILES names {path}, which is not there"))
    return problems + unmarked_page_text(ROOT)


def unmarked_page_text(root: Path) -> list[Problem]:
    """Returns the words of every page's templates and scripts under root (frontend/templates, frontend/static),
    the patient's as the therapist's, that are not marked for translation: each would stay English in every locale."""
    pages = sorted((root / "frontend/templates").glob("*.html")) + sorted((root / "frontend/static").glob("*.js"))
    problems: list[Problem] = []
    for page in pages:
        where = str(page.relative_to(root))
        find = unmarked_template_text if where.endswith(".html") else unmarked_script_text
        problems.extend(find(where, page.read_text(encoding="utf-8")))
    return problems


def check_template(domain: str, code: Catalog, pot: Catalog | None = None) -> Iterable[Problem]:
    """Yields the differences between a domain's .pot (read unless given) and the messages of the code."""
    where = str(pot_path(domain).relative_to(ROOT))
    if pot is None:
        pot = _read(pot_path(domain), domain=domain) if pot_path(domain).exists() else Catalog(domain=domain)
    for msgid, _ in sorted(_ids(code) - _ids(pot), key=str):
        yield Problem(where, f"misses {msgid!r}: run extract and update")
    for msgid, _ in sorted(_ids(pot) - _ids(code), key=str):
        yield Problem(where, f"still has {msgid!r}, no longer in the code: run extract")


# Jinja's parts that are no text: comments, {% trans %} blocks, expressions, tags, and the blocks that fill a class or
# attributes (body_class, main_attrs)
_JINJA = re.compile(
    r"\{#.*?#\}|\{%-?\s*trans\b.*?\{%-?\s*endtrans\s*-?%\}"
    r"|\{%\s*block\s+(?:body_class|main_attrs)\s*%\}.*?\{%\s*endblock\s*%\}|\{\{.*?\}\}|\{%.*?%\}",
    re.S,
)
_WORD = re.compile(r"[^\W\d_]{2,}")  # two letters in a row: a word someone reads
_READ_ATTRIBUTES = ("title", "placeholder", "aria-label", "alt", "aria-description")


class _TextFinder(HTMLParser):
    """Collects the words a reader sees in an HTML page: text outside <script>/<style>, and attributes read out."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.found: list[tuple[int, str]] = []
        self._skip = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in ("script", "style"):
            self._skip += 1
        for name, value in attrs:
            if name in _READ_ATTRIBUTES and value and _WORD.search(value):
                self.found.append((self.getpos()[0], value))

    def handle_endtag(self, tag: str) -> None:
        if tag in ("script", "style"):
            self._skip = max(0, self._skip - 1)

    def handle_data(self, data: str) -> None:
        if not self._skip and _WORD.search(data):
            self.found.append((self.getpos()[0], " ".join(data.split())))


def unmarked_template_text(where: str, source: str) -> list[Problem]:
    """Returns the words of a Jinja template that are not marked for translation ({{ _("...") }} or a
    {% trans %} block): each would stay English in every locale."""
    # blank out the Jinja parts, keeping the line breaks so the line numbers stay right
    plain = _JINJA.sub(lambda m: "\n" * m.group(0).count("\n"), source)
    for name in _NOT_TEXT:
        plain = plain.replace(name, " ")
    finder = _TextFinder()
    finder.feed(plain)
    finder.close()
    return [Problem(f"{where}:{line}", f"text not marked for translation: {text!r}") for line, text in finder.found]


# a script string that reads as words: two words in a row, or one capitalised word ("Approve"); not code-like
# (CSS classes, ids, URLs, Plotly's %{x} templates, HTML) and not the product's name
_PROSE = re.compile(r"[^\W\d_]{2,}[ ’'][^\W\d_]{2,}|^[A-Z][a-z]{2,}$")
_CODE = re.compile(r"[-_#/=<>\[\]{}]|%\{|^\w+\.\w+$")
_NOT_TEXT = ("Kinect Home Coach", "use strict")
_SCRIPT_MARKS = ("I18n.t", "I18n.nt", "I18n.N_")
NOT_SHOWN = "i18n: not shown"  # a script line's comment: its strings go to the console or compare, never to a page


def unmarked_script_text(where: str, source: str) -> list[Problem]:
    """Returns the strings of a page script that read as words but are not marked (I18n.t, I18n.nt, I18n.N_, or
    joined with + to a marked string): each would stay English in every locale. A heuristic for the therapist
    scripts: CSS classes (after `class:` or `className =`), ids, URLs and Plotly templates are not text, nor the strings
    of a line that says NOT_SHOWN in a comment (console messages, English-only comparisons)."""
    lines = source.splitlines()
    tokens = [t for t in tokenize(source, jsx=False, template_string=True) if "comment" not in t.type]
    marked: set[int] = set()
    found = []
    for i, token in enumerate(tokens):
        if token.type not in ("string", "template_string"):
            continue
        before = [t.value for t in tokens[max(0, i - 4) : i]]
        if (
            before[-2:-1]
            and before[-2] in _SCRIPT_MARKS
            and before[-1] == "("  # I18n.t("...")
            or len(before) == 4
            and before[0] == "I18n.nt"
            and before[1] == "("
            and before[3] == ","  # its plural
            or before[-1:] == ["+"]
            and i - 2 in marked  # "..." + "..." inside a mark
        ):
            marked.add(i)
            continue
        text = re.sub(r"\$\{.*?\}", " ", token.value[1:-1])
        for name in _NOT_TEXT:
            text = text.replace(name, " ")
        if not _PROSE.search(text) or _CODE.search(text):
            continue
        if before[-2:-1] and (before[-2] == "class" or before[-2].endswith("className")):
            continue
        if NOT_SHOWN in lines[token.lineno - 1]:
            continue
        found.append(Problem(f"{where}:{token.lineno}", f"text not marked for translation: {token.value[1:-1]!r}"))
    return found


_MARK_IN_LITERAL = re.compile(r"\$\{\s*I18n\.(?:t|nt|N_)\(")


def marks_in_template_literals(where: str, source: str) -> list[Problem]:
    """Returns the I18n marks inside a template literal (`${I18n.t("...")}`) of a page script: Babel's extractor
    does not look inside template literals, so such a message would be in no catalogue and stay English."""
    return [
        Problem(f"{where}:{source.count(chr(10), 0, m.start()) + 1}",
                "I18n mark inside a template literal (not extracted): join with + instead")
        for m in _MARK_IN_LITERAL.finditer(source)
    ]  # fmt: skip


def check_locale(locale: str, code: Catalog, catalog: Catalog | None = None, domain: str = DOMAIN) -> Iterable[Problem]:
    """Yields the problems of one locale's catalogue of a domain (its .po unless given) against the messages of the
    code."""
    where = str(po_path(locale, domain).relative_to(ROOT))
    if catalog is None:
        catalog = _read(po_path(locale, domain), locale, domain)
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
            if locale == "fr":
                yield from (Problem(where, f"{ids[0]!r}: {bad}") for bad in french_spacing(string))


def french_spacing(text: str) -> list[str]:
    """Returns what French typography finds wrong in a translation: each : ; ! ? used as punctuation without a
    no-break space (U+00A0 or the narrow U+202F) before it, said with the words around it."""
    return [
        f"no no-break space before {m['mark']!r} in {text[max(0, m.start() - 20) : m.end() + 10]!r}"
        for m in FRENCH_TIGHT.finditer(text)
        if m["before"] not in FRENCH_SPACES and m.start("mark") > 0
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m backend.i18n.catalogues", description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("extract", "update", "init", "check"))
    parser.add_argument("locale", nargs="?", choices=LOCALES[1:], help="init: the locale of the new therapist.po")
    args = parser.parse_args(argv)
    if args.command == "extract":
        for domain, template in write_templates().items():
            print(f"{pot_path(domain).relative_to(ROOT)}: {len(template)} messages")
    elif args.command in ("update", "init"):
        if args.command == "init" and not args.locale:
            parser.error("init needs a locale, e.g. init de")
        update(started=(args.locale,) if args.command == "init" else ())
        paths = [po_path(loc, d) for d in DOMAINS for loc in domain_locales(d)]
        print("updated " + ", ".join(str(p.relative_to(ROOT)) for p in paths))
    else:
        problems = check()
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            print(f"{len(problems)} problems", file=sys.stderr)
            return 1
        therapist = ", ".join(("en",) + domain_locales(THERAPIST_DOMAIN))
        print(f"catalogues complete: {', '.join(LOCALES)} (therapist pages: {therapist})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
