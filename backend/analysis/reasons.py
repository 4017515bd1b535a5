"""The analysis' reasons in words: why a session's quality check failed (quality.assess), why an angle's 95 %
interval is withheld (intervals.withheld_reason) and why balance was not measured (balance.missing_reason).

Each reason is one catalogue message with placeholders (`messages` domain: a patient reads them through the API).
The analysis writes it into the metrics document in English (`english`), as every stored document holds it;
`in_language` finds which message a stored English text is (each message read back as a pattern, its numbers
parsed) and writes it in the reader's language with the locale's numbers. A text that is none of them (written by
an older analysis) stays as stored.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

from backend.i18n import N_, Translator
from kinect_agent.analysis.document import AnalysisDocument

Kind = Literal["int", "percent", "decimal0", "decimal1", "general"]
# how each kind of number is written in the English document, and read back from it
_ENGLISH = {"int": "{:d}", "percent": "{:.0%}", "decimal0": "{:.0f}", "decimal1": "{:.1f}", "general": "{:g}"}
_PATTERN = {"int": r"-?\d+", "percent": r"-?\d+%", "decimal0": r"-?\d+", "decimal1": r"-?\d+\.\d",
            "general": r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?"}  # fmt: skip
_PLACEHOLDER = re.compile(r"%\((\w+)\)s")


@dataclass(frozen=True)
class Reason:
    """One reason: its message (%(name)s placeholders) and the kind of number each placeholder holds."""

    message: str
    kinds: tuple[tuple[str, Kind], ...] = ()

    def english(self, **values: float) -> str:
        """Returns the reason in English as the document stores it (values: one number per placeholder)."""
        kinds = dict(self.kinds)
        if set(values) != set(kinds):
            raise ValueError(f"{self.message!r} needs {sorted(kinds)}, got {sorted(values)}")
        return self.message % {k: _ENGLISH[kinds[k]].format(int(v) if kinds[k] == "int" else v)
                                for k, v in values.items()}  # fmt: skip

    @cached_property
    def pattern(self) -> re.Pattern[str]:
        """Returns the pattern of the English text: the message with a named group per placeholder."""
        kinds = dict(self.kinds)
        parts, last = [], 0
        for m in _PLACEHOLDER.finditer(self.message):
            parts += [_literal(self.message[last : m.start()]), f"(?P<{m[1]}>{_PATTERN[kinds[m[1]]]})"]
            last = m.end()
        return re.compile("".join([*parts, _literal(self.message[last:])]))

    def written(self, text: str, t: Translator) -> str | None:
        """Returns text, this reason in English, in t's language; None when text is not this reason."""
        found = self.pattern.fullmatch(text)
        if found is None:
            return None
        kinds = dict(self.kinds)
        return t.gettext(self.message, **{k: _number(v, kinds[k], t) for k, v in found.groupdict().items()})


def _literal(text: str) -> str:
    """Returns the pattern of a message's text between placeholders ("%%" is one "%" once formatted)."""
    return re.escape(text.replace("%%", "%"))


def _number(text: str, kind: Kind, t: Translator) -> str:
    """Returns a number of the English text as t's locale writes it."""
    if kind == "percent":
        return t.format_percent(float(text[:-1]) / 100)
    decimals = {"decimal1": 1, "general": len(text.partition(".")[2])}.get(kind, 0)
    return t.format_number(float(text), decimals)


# quality.assess: why a session is not ok
TOO_FEW_FRAMES = Reason(N_("only %(frames)s frames (at least %(needed)s needed)"),
                        (("frames", "int"), ("needed", "int")))  # fmt: skip
TOO_SHORT = Reason(N_("only %(seconds)s s recorded (at least %(needed)s s needed)"),
                   (("seconds", "decimal1"), ("needed", "decimal0")))  # fmt: skip
TOO_LITTLE_TRACKED = Reason(N_("the body was tracked in %(tracked)s of the samples (at least %(needed)s needed)"),
                            (("tracked", "percent"), ("needed", "percent")))  # fmt: skip
TOO_MANY_ERRORS = Reason(N_("%(errors)s of the samples were tracking errors (at most %(allowed)s allowed)"),
                         (("errors", "percent"), ("allowed", "percent")))  # fmt: skip
GAPS = Reason(N_("the measured positions have gaps"))
# intervals.withheld_reason: why an angle's 95 % interval is not shown
ROTATION_UNDEFINED = Reason(N_("shoulder rotation is undefined while the elbow is straight, so it has no interval"))
OUT_OF_PLANE = Reason(N_("the angle is defined in only %(defined)s of the frames (the limb was out of its plane)"),
                      (("defined", "percent"),))  # fmt: skip
JOINTS_UNTRACKED = Reason(N_("the joints of this angle were tracked in only %(tracked)s of the frames"),
                          (("tracked", "percent"),))  # fmt: skip
UNKNOWN_ANGLE = Reason(N_("the angle or its uncertainty is unknown in every frame, or it spun through a full turn"))
TOO_UNCERTAIN = Reason(
    N_("the tracking is too uncertain: a 95 %% interval would span %(width)s° (at most %(most)s° is shown)"),
    (("width", "decimal0"), ("most", "decimal0")),
)
# balance.missing_reason: why balance was not measured
RECORDING_TOO_SHORT = Reason(N_("the recording is too short"))
NOT_STANDING = Reason(N_("the patient was seated or crouching: balance is measured while standing"))
NEVER_STILL = Reason(
    N_(
        "the patient never stood still with both feet down for %(seconds)s s in total (steps, a raised leg or a bent "
        "trunk do not count)"
    ),
    (("seconds", "general"),),
)
REASONS = (TOO_FEW_FRAMES, TOO_SHORT, TOO_LITTLE_TRACKED, TOO_MANY_ERRORS, GAPS, ROTATION_UNDEFINED, OUT_OF_PLANE,
           JOINTS_UNTRACKED, UNKNOWN_ANGLE, TOO_UNCERTAIN, RECORDING_TOO_SHORT, NOT_STANDING, NEVER_STILL)  # fmt: skip


def in_language(text: str, t: Translator) -> str:
    """Returns a reason the document stores in English in t's language (as stored when it is none of REASONS)."""
    if t.locale == "en" and not t.therapist:
        return text
    for reason in REASONS:
        written = reason.written(text, t)
        if written is not None:
            return written
    return text


def document_in_language(doc: AnalysisDocument, t: Translator) -> AnalysisDocument:
    """Returns a metrics document with its reasons in t's language: the quality check's, the withheld intervals',
    and why balance is missing (the document and its balance indicator)."""
    if t.locale == "en" and not t.therapist:
        return doc
    balance = doc.indicators.balance
    withheld = doc.range_of_motion_95_withheld
    shown_withheld = None if withheld is None else {k: in_language(v, t) for k, v in withheld.items()}
    return doc.model_copy(update={
        "quality": doc.quality.model_copy(update={"reasons": [in_language(r, t) for r in doc.quality.reasons]}),
        "range_of_motion_95_withheld": shown_withheld,
        "balance_missing": None if doc.balance_missing is None else in_language(doc.balance_missing, t),
        "indicators": doc.indicators.model_copy(update={"balance": balance.model_copy(update={
            "missing": None if balance.missing is None else in_language(balance.missing, t)})}),
    })  # fmt: skip
