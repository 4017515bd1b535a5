"""The analysis' reasons in the reader's language: why a session's quality check failed (quality.assess), why an
angle's 95 % interval is withheld (intervals.withheld_reason) and why balance was not measured
(balance.missing_reason).

The metrics document stores each reason as a message id and its numbers (kinect_agent.analysis.reasons.Reason,
document schema 3; an older document's English text is read back as one when it matches a message, else kept as a
text). The indicators' bases (how each was scored, kinect_agent.analysis.reasons.BASES, document schema 4) are
stored and written the same way, an angle in the reader's words (session_detail.ANGLE_WORDS). `written` writes a
reason or a basis in a Translator's language with the locale's numbers; `with_texts` fills the `text` of every
reason and basis of a document for an API answer, a page or an export.
"""

from __future__ import annotations

from typing import TypeVar

from backend.i18n import Translator
from backend.session_texts.session_detail import angle_label
from kinect_agent.analysis.document import INDICATOR_NAMES, AnalysisDocument, AnalysisReport, Indicators
from kinect_agent.analysis.reasons import MESSAGES, Kind, Reason, UnknownReason, message_of

__all__ = ["MESSAGES", "indicators_with_text", "with_text", "with_texts", "written"]
D = TypeVar("D", bound=AnalysisReport)
R = TypeVar("R", bound=Reason)


def _number(value: float | str, kind: Kind, t: Translator) -> str:
    """Returns one value of a reason as t's locale writes it: a number with the locale's digits, an angle in words."""
    if isinstance(value, str) or kind == "angle":
        return angle_label(str(value), t)
    if kind == "percent":
        return t.format_percent(value)
    if kind == "general":
        decimals = min(len(f"{value:g}".partition(".")[2]), 3)
        return t.format_number(value, decimals)
    return t.format_number(value, 1 if kind == "decimal1" else 0)


def written(reason: Reason, t: Translator) -> str:
    """Returns a reason (or a basis) in t's language: its message with the locale's numbers, or a stored text as it
    is (raises UnknownReason for an id no message has: a document validates its ids, so only a reason built
    unchecked)."""
    if reason.id is None:
        return reason.text or ""
    message = message_of(reason.id)
    if message is None:
        raise UnknownReason(f"unknown reason id {reason.id!r}")
    kinds = dict(message.kinds)
    return t.gettext(message.message, **{k: _number(v, kinds[k], t) for k, v in reason.params.items()})


def with_text(reason: R, t: Translator) -> R:
    """Returns a reason with its text in t's language (id and params as stored)."""
    return reason.model_copy(update={"text": written(reason, t)})


def with_texts(doc: D, t: Translator) -> D:
    """Returns a metrics document with the text of each reason in t's language: the quality check's, the withheld
    ranges', intervals', repetitions' and median amplitude's, and why balance is missing (the document's and, in an
    AnalysisDocument, its balance indicator's)."""
    withheld, ranges = doc.range_of_motion_95_withheld, doc.range_of_motion_withheld
    reps = [r if r.withheld is None else r.model_copy(update={"withheld": with_text(r.withheld, t)})
            for r in doc.repetition_list]  # fmt: skip
    update: dict[str, object] = {
        "repetition_list": reps,
        "rom_deg_withheld": None if doc.rom_deg_withheld is None else with_text(doc.rom_deg_withheld, t),
        "quality": doc.quality.model_copy(update={"reasons": [with_text(r, t) for r in doc.quality.reasons]}),
        "range_of_motion_withheld": None if ranges is None else {k: with_text(v, t) for k, v in ranges.items()},
        "range_of_motion_95_withheld": None if withheld is None else {k: with_text(v, t) for k, v in withheld.items()},
        "balance_missing": None if doc.balance_missing is None else with_text(doc.balance_missing, t),
    }
    if isinstance(doc, AnalysisDocument):
        update["indicators"] = indicators_with_text(doc.indicators, t)
    return doc.model_copy(update=update)


def indicators_with_text(indicators: Indicators, t: Translator) -> Indicators:
    """Returns the indicators with the texts of their bases and of why balance is missing in t's language."""
    update = {}
    for name in INDICATOR_NAMES:
        item = getattr(indicators, name)
        update[name] = item.model_copy(update={"basis": with_text(item.basis, t)})
    balance = update["balance"]
    if indicators.balance.missing is not None:
        update["balance"] = balance.model_copy(update={"missing": with_text(indicators.balance.missing, t)})
    return indicators.model_copy(update=update)
