"""The analysis document of one session as pydantic models (versioned), and reading stored documents of any version.

The analysis (kinect_agent.analysis.report.analyze_recording) builds an AnalysisReport; at ingest the server adds
the four indicators (kinect_agent.analysis.indicators) and the analysis version (backend.sessions.metrics) and
stores the AnalysisDocument as `model_dump(mode="json")`. Storage, the API, the pages and the exports read it
through `read_document` (or `read_report`, `read_if_readable`, `read_indicators`), which upgrade an older stored
shape first (`upgrade`).
The models live beside the agent's analysis because the agent's exports (kinect_agent.export) read the same
document.

Schema versions (`schema_version`; a document without it is version 1):
    1  2026-11-23 to 2026-11-27, before versions were recorded: no range_of_motion_95, range_of_motion_95_withheld,
       repetitions_95, peak_end, balance_missing, analysis_version; repetitions without peak_s; balance without
       sway_velocity_95, n_windows, method; the balance indicator without interval and missing. Documents of
       2026-11-25 to 2026-11-27 already hold range_of_motion_95 and repetitions_95.
    2  2026-11-27: every key present, None where it does not apply; the reasons (quality.reasons,
       range_of_motion_95_withheld, balance_missing, indicators.balance.missing) in English words.
    3  2026-11-27: each reason a Reason (kinect_agent.analysis.reasons): a message id and its numbers, written in
       the reader's language by the server; an English text of schema 1 or 2 that no message matches stays a text.
       The indicators' basis in English words.
    4  2026-11-28: each indicator's basis a Basis (kinect_agent.analysis.reasons.BASES): a message id, its numbers
       and angle, written in the reader's language by the server; an English basis of schema 1 to 3 that no message
       matches (the wordings before 2026-11-24) stays a text.
    5  2026-11-28: range_of_motion_withheld, {angle: why its range of motion is withheld}: a range the raw data
       does not support (intervals.beyond_raw) has its numbers None and its reason there; None in documents of
       schema 1-4 (not checked).
    6  today: a repetition measured on a flexion past what the joint bends (kinect_agent.analysis.anatomy: knee
       and elbow; hip too since ANALYSIS_VERSION 2026.11.28-hip-limit, same keys) has amplitude_deg and peak_deg
       None and why in its "withheld" (beyond_anatomy); rom_deg is then None too, why in "rom_deg_withheld"
       (repetitions_beyond_anatomy), and fatigue's amplitude trend None. A document
       of schema 1-5 is checked on read on what it holds, the peaks alone (the curves are not in it): a peak past
       its defining angle's limit is withheld so, and rom_deg with it.
Raise SCHEMA_VERSION and add one step to `upgrade` whenever a key is added, removed or changes its meaning.
"""

from __future__ import annotations

import math
import re
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from kinect_agent.analysis import reasons
from kinect_agent.analysis.anatomy import limit_reason, rom_beyond_anatomy
from kinect_agent.analysis.reasons import MESSAGES, Basis, Kind, Message, Reason

SCHEMA_VERSION = 6


class _Part(BaseModel):
    """A part of the document: exactly the keys the analysis writes (an unknown key is an error)."""

    model_config = ConfigDict(extra="forbid")


class RepetitionItem(_Part):
    """One counted repetition of the defining angle."""

    index: int = Field(description="0-based position in the session")
    start_s: float = Field(description="start, s from the recording's first frame (1 ms)")
    end_s: float = Field(description="end, s from the recording's first frame (1 ms)")
    duration_s: float = Field(description="end_s − start_s, s (1 ms)")
    amplitude_deg: float | None = Field(
        description="excursion of the counting angle, degrees (0.1); None: withheld (why in withheld)"
    )
    peak_deg: float | None = Field(
        description="the measured defining angle at the peak, degrees (0.1); None: withheld (why in withheld)"
    )
    side: str = Field(description="'left', 'right', 'both' or 'center'")
    peak_s: float | None = Field(description="time of the peak, s from the first frame (1 ms); None: schema 1")
    withheld: Reason | None = Field(
        description="why amplitude_deg and peak_deg are None: the curve passed what the joint bends "
        "(beyond_anatomy); None when they are shown"
    )


class AngleRange(_Part):
    """One angle's range of motion over the session (1st to 99th percentile); None where the angle is undefined."""

    min_deg: float | None = Field(description="lowest angle, degrees (0.1)")
    max_deg: float | None = Field(description="highest angle, degrees (0.1)")
    range_deg: float | None = Field(description="max_deg − min_deg, degrees (0.1)")


class AngleRangeInterval(_Part):
    """95 % intervals [low, high] of one angle's range, degrees (0.1)."""

    min_deg: list[float] = Field(description="[low, high] of min_deg, degrees", min_length=2, max_length=2)
    max_deg: list[float] = Field(description="[low, high] of max_deg, degrees", min_length=2, max_length=2)
    range_deg: list[float] = Field(description="[low, high] of range_deg, degrees", min_length=2, max_length=2)


class CountInterval(_Part):
    """95 % interval of the repetition count."""

    low: int = Field(description="fewest repetitions")
    high: int = Field(description="most repetitions")
    ambiguous: bool = Field(description="low != high")


class MovingJoint(_Part):
    """One joint's path length over the session."""

    joint: str = Field(description="joint name (kinect_agent.skeleton.JOINTS)")
    path_m: float = Field(description="length of the smoothed path, metres (1 mm)")


class Workspace(_Part):
    """The reachable range of one hand, relative to its arm's length."""

    arm_length_m: float = Field(description="median shoulder-to-hand length, metres (1 mm)")
    area_ratio: float = Field(description="share of the front hemisphere's directions reached, 0..1")
    volume_ratio: float = Field(description="share of the front half-sphere of radius arm length reached, 0..1")
    quadrants: dict[str, float] = Field(
        description="{upper_lateral, upper_medial, lower_medial, lower_lateral}: share of each quadrant reached, 0..1"
    )


class ReachableRange(_Part):
    """The reachable range of both hands; None for a hand that was not tracked."""

    left: Workspace | None
    right: Workspace | None


class Fatigue(_Part):
    """Trends over the repetitions; None with fewer than 3 repetitions."""

    amplitude_slope_pct_per_rep: float | None = Field(
        description="amplitude trend, % of the mean per repetition; None also when rom_deg is withheld"
    )
    duration_slope_pct_per_rep: float | None = Field(description="duration trend, % of the mean per repetition")


class Balance(_Part):
    """Trunk-and-hips centre-of-mass sway in standing phases."""

    sway_path_m: float = Field(description="path of the centre of mass on the floor, metres")
    sway_area_m2: float = Field(description="95 % ellipse area of the centre of mass on the floor, m²")
    sway_velocity_m_s: float = Field(description="sway_path_m / standing_s, m/s")
    sway_velocity_95: list[float] | None = Field(description="95 % interval [low, high] m/s; None: schema 1")
    standing_s: float = Field(description="time standing still, s")
    n_windows: int | None = Field(description="windows of the interval's bootstrap; None: schema 1")
    method: str | None = Field(description="what was measured, in words; None: schema 1")


class SitToStand(_Part):
    """The rises of a sit-to-stand session."""

    mean_s: float = Field(description="mean 20-80 % rise time, s (1 ms)")
    count: int = Field(description="rises measured")


class Quality(_Part):
    """The analysis' own quality check."""

    ok: bool = Field(description="no reason found")
    tracked_fraction: float = Field(description="share of the defining joints' samples tracked, 0..1")
    outlier_fraction: float = Field(description="share of tracked samples far from the filtered body, 0..1")
    reasons: list[Reason] = Field(description="why the session is not ok")


class Indicator(_Part):
    """One of the four indicators (kinect_agent.analysis.indicators)."""

    score: float | None = Field(description="0..100; None when it cannot be scored")
    value: int | float | None = Field(description="the measured number it scores (unit in basis); None: missing")
    basis: Basis = Field(
        description="how it was scored: a message id and its numbers; in an API answer with its text "
        "in the reader's language"
    )
    quality_ok: bool = Field(description="the document's quality ok and the value present")
    previous: float | None = Field(description="median value of the patient's earlier sessions; None: none")


class BalanceIndicator(Indicator):
    """The balance indicator, with the sway interval and why it is missing."""

    interval: list[float] | None = Field(description="balance.sway_velocity_95, [low, high] m/s; None: none")
    missing: Reason | None = Field(description="balance_missing when there is no value")


class Indicators(_Part):
    """The four indicators of the paper."""

    flexibility: Indicator
    endurance: Indicator
    strength: Indicator
    balance: BalanceIndicator


class AnalysisReport(_Part):
    """What analyze_recording measures in one session (every key present, None where it does not apply)."""

    schema_version: int = Field(default=SCHEMA_VERSION, description="the shape of this document (module doc)")
    exercise: str = Field(description="exercise slug")
    duration_s: float = Field(description="recording length, s (1 ms)")
    n_frames: int = Field(description="frames recorded")
    rate_hz: float = Field(description="mean frame rate, Hz")
    measured_on: Literal["filtered", "params", "raw"] = Field(description="the positions the metrics measured")
    repetitions: int = Field(description="repetitions counted")
    repetition_list: list[RepetitionItem]
    defining_angle: str | None = Field(description="the angle that counted the repetitions; None: none moved")
    peak_end: Literal["min", "max"] = Field(
        description="the end of the defining angle's range its repetitions reach ('max' in schema 1)"
    )
    range_of_motion: dict[str, AngleRange] = Field(description="{angle: range}, degrees")
    range_of_motion_withheld: dict[str, Reason] | None = Field(
        description="{angle: why its range (numbers None) is withheld}; None: schema 1-4, or measured on raw positions"
    )
    range_of_motion_95: dict[str, AngleRangeInterval | None] | None = Field(
        description="{angle: 95 % intervals or None (withheld)}; None without the agent's angle SDs"
    )
    range_of_motion_95_withheld: dict[str, Reason] | None = Field(
        description="{angle: why its interval is withheld}; None without the agent's angle SDs"
    )
    repetitions_95: CountInterval | None = Field(description="None without the agent's angle SDs")
    rom_deg: float | None = Field(
        description="median repetition amplitude, degrees (0.1); None: no repetition, or withheld (rom_deg_withheld)"
    )
    rom_deg_withheld: Reason | None = Field(
        description="why rom_deg is None though repetitions were counted: some were measured past what the joint "
        "bends (repetitions_beyond_anatomy); None when shown or without repetitions"
    )
    most_moving_joints: list[MovingJoint] = Field(description="joints by path length, longest first")
    reachable_range: ReachableRange
    moving_time_s: float = Field(description="time moving, s (10 ms)")
    rest_time_s: float = Field(description="time at rest, s (10 ms)")
    tempo_s_per_rep: float | None = Field(description="median time between repetition starts, s; None: none")
    fatigue: Fatigue
    balance: Balance | None = Field(description="None when the patient did not stand still long enough")
    balance_missing: Reason | None = Field(description="why balance is None; None when measured")
    sit_to_stand: SitToStand | None = Field(description="the sit_to_stand exercise only")
    quality: Quality


class AnalysisDocument(AnalysisReport):
    """The stored metrics document of a session: the report, its indicators and the analysis version."""

    indicators: Indicators
    analysis_version: str | None = Field(
        description="the analysis that made it (backend.sessions.metrics.ANALYSIS_VERSION); None: schema 1"
    )


class UnreadableDocument(ValueError):
    """A stored document that no known schema version describes."""


_V1_DEFAULTS: dict[str, Any] = {
    "range_of_motion_95": None,
    "range_of_motion_95_withheld": None,
    "repetitions_95": None,
    "peak_end": "max",
    "balance_missing": None,
}


def _indicators_1_to_2(indicators: object) -> object:
    """Returns schema-1 indicators in schema 2: the balance indicator's interval and missing None when absent."""
    if isinstance(indicators, dict) and isinstance(indicators.get("balance"), dict):
        return {**indicators, "balance": {"interval": None, "missing": None, **indicators["balance"]}}
    return indicators


def _upgrade_1_to_2(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a schema-1 document in schema 2 (module doc): missing keys None ('max' for peak_end)."""
    out = {k: v for k, v in doc.items() if k != "schema_version"}
    for key, value in _V1_DEFAULTS.items():
        out.setdefault(key, value)
    out["repetition_list"] = [
        {"peak_s": None, **r} if isinstance(r, dict) else r for r in out.get("repetition_list") or []
    ]
    if isinstance(out.get("balance"), dict):
        out["balance"] = {"sway_velocity_95": None, "n_windows": None, "method": None, **out["balance"]}
    if "indicators" in out:
        out["indicators"] = _indicators_1_to_2(out["indicators"])
        out.setdefault("analysis_version", None)
    out["schema_version"] = 2
    return out


# Schema 2 to 3: each English reason text read back as its message (the message a pattern, a named group per number)
_PATTERN = {"int": r"-?\d+", "percent": r"-?\d+%", "decimal0": r"-?\d+", "decimal1": r"-?\d+\.\d",
            "general": r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?"}  # fmt: skip
_PLACEHOLDER = re.compile(r"%\((\w+)\)s")


def _english_pattern(message: Message) -> re.Pattern[str]:
    """Returns the pattern of a message as schema 1 and 2 wrote it in English: a named group per placeholder."""
    kinds = dict(message.kinds)
    parts, last = [], 0
    for m in _PLACEHOLDER.finditer(message.message):
        parts += [re.escape(message.message[last : m.start()].replace("%%", "%")),
                  f"(?P<{m[1]}>{_PATTERN[kinds[m[1]]]})"]  # fmt: skip
        last = m.end()
    return re.compile("".join([*parts, re.escape(message.message[last:].replace("%%", "%"))]))


_ENGLISH_PATTERNS = tuple((message, _english_pattern(message)) for message in MESSAGES)


def _english_number(text: str, kind: Kind) -> int | float:
    """Returns a number as schema 1 and 2 wrote it in a reason ("46%" is 0.46)."""
    if kind == "int":
        return int(text)
    return float(text[:-1]) / 100 if kind == "percent" else float(text)


def _message_of_text(text: object, patterns: tuple[tuple[Message, re.Pattern[str]], ...]) -> object:
    """Returns English words as a message's JSON: the first of `patterns` that matches them whole, with its numbers
    (an "angle" parameter stays a name); a text none matches stays a text (id None); anything else as it is."""
    if not isinstance(text, str):
        return text
    for message, pattern in patterns:
        found = pattern.fullmatch(text)
        if found is not None:
            kinds = dict(message.kinds)
            params = {
                k: v if kinds[k] == "angle" else _english_number(v, kinds[k]) for k, v in found.groupdict().items()
            }
            return {"id": message.id, "params": params}
    return {"id": None, "text": text}


def reason_of_text(text: object) -> object:
    """Returns a reason of schema 1 or 2 (English words) as a schema-3 Reason's JSON (_message_of_text)."""
    return _message_of_text(text, _ENGLISH_PATTERNS)


def _indicators_2_to_3(indicators: object) -> object:
    """Returns schema-2 indicators in schema 3: the balance indicator's missing a Reason."""
    if isinstance(indicators, dict) and isinstance(indicators.get("balance"), dict):
        balance = indicators["balance"]
        return {**indicators, "balance": {**balance, "missing": reason_of_text(balance.get("missing"))}}
    return indicators


def _upgrade_2_to_3(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a schema-2 document in schema 3 (module doc): each reason text a Reason."""
    out = dict(doc)
    if isinstance(out.get("quality"), dict) and isinstance(out["quality"].get("reasons"), list):
        out["quality"] = {**out["quality"], "reasons": [reason_of_text(r) for r in out["quality"]["reasons"]]}
    withheld = out.get("range_of_motion_95_withheld")
    if isinstance(withheld, dict):
        out["range_of_motion_95_withheld"] = {k: reason_of_text(v) for k, v in withheld.items()}
    out["balance_missing"] = reason_of_text(out.get("balance_missing"))
    if "indicators" in out:
        out["indicators"] = _indicators_2_to_3(out["indicators"])
    out["schema_version"] = 3
    return out


# Schema 3 to 4: each English basis read back as its message. The patterns are those of the English words
# kinect_agent.analysis.indicators wrote from 2026-11-24 to schema 3 (not the messages' words, which are new)
_NUMBER = r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?"
_RANGE = rf"against the normal range (?P<low>{_NUMBER})\.\.(?P<high>{_NUMBER}) deg"
_ENGLISH_BASES = tuple((message, re.compile(pattern)) for message, pattern in (
    (reasons.BASIS_FLEXIBILITY_NO_ANGLE,
     rf"median amplitude of None {_RANGE}"),
    (reasons.BASIS_FLEXIBILITY,
     rf"median amplitude of (?P<angle>[A-Za-z]\w*) {_RANGE}"),
    (reasons.BASIS_ENDURANCE_TARGET, r"repetitions against the target of (?P<target>\d+)"),
    (reasons.BASIS_ENDURANCE_USUAL, rf"repetitions against the usual (?P<usual>{_NUMBER}) of earlier sessions"),
    (reasons.BASIS_ENDURANCE_NONE, r"repetitions; no target and no earlier session to compare with"),
    (reasons.BASIS_STRENGTH_RISE,
     rf"sit-to-stand rise time \(20-80 %\), (?P<fast>{_NUMBER}) s scores 100, (?P<slow>{_NUMBER}) s scores 0"),
    (reasons.BASIS_STRENGTH_SPEED, r"movement speed \(deg/s\) against the best earlier session"),
    (reasons.BASIS_STRENGTH_SPEED_NONE, r"movement speed \(deg/s\); no earlier session to compare with"),
    (reasons.BASIS_BALANCE_SWAY,
     rf"trunk-and-hips sway while standing, (?P<good>{_NUMBER}) cm/s scores 100, (?P<poor>{_NUMBER}) cm/s 0"),
))  # fmt: skip


def basis_of_text(text: object) -> object:
    """Returns an indicator's basis of schema 1 to 3 (English words) as a schema-4 Basis' JSON (_message_of_text); a
    schema-4 basis stays as it is."""
    return _message_of_text(text, _ENGLISH_BASES)


INDICATOR_NAMES = ("flexibility", "endurance", "strength", "balance")


def _indicators_3_to_4(indicators: object) -> object:
    """Returns indicators of schema 1 to 3 in schema 4: each basis a Basis (a schema-4 basis stays as it is)."""
    if not isinstance(indicators, dict):
        return indicators
    return {name: {**item, "basis": basis_of_text(item.get("basis"))} if name in INDICATOR_NAMES
            and isinstance(item, dict) else item for name, item in indicators.items()}  # fmt: skip


def _upgrade_3_to_4(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a schema-3 document in schema 4 (module doc): each indicator's basis a Basis."""
    out = dict(doc)
    if "indicators" in out:
        out["indicators"] = _indicators_3_to_4(out["indicators"])
    out["schema_version"] = 4
    return out


def _upgrade_4_to_5(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a schema-4 document in schema 5 (module doc): range_of_motion_withheld None (not checked)."""
    return {**doc, "range_of_motion_withheld": None, "schema_version": 5}


def _checked_repetition(rep: object, defining: object) -> object:
    """Returns a schema-5 repetition in schema 6: withheld None, or, when its peak passes the flexion limit of the
    defining angle (anatomy.limit_reason), its peak and amplitude None and that reason."""
    if not isinstance(rep, dict):
        return rep
    peak, why = rep.get("peak_deg"), None
    if isinstance(peak, int | float) and not isinstance(peak, bool) and isinstance(defining, str):
        why = limit_reason(defining, float(peak))
    if why is None:
        return {**rep, "withheld": None}
    return {**rep, "peak_deg": None, "amplitude_deg": None, "withheld": why.model_dump(mode="json")}


def _upgrade_5_to_6(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a schema-5 document in schema 6 (module doc): its peaks checked against what the joint bends."""
    reps = doc.get("repetition_list")
    if not isinstance(reps, list):
        return {**doc, "rom_deg_withheld": None, "schema_version": 6}
    checked = [_checked_repetition(r, doc.get("defining_angle")) for r in reps]
    found = [Reason.model_validate(r["withheld"]) if isinstance(r, dict) and r.get("withheld") else None
             for r in checked]  # fmt: skip
    rom_why = rom_beyond_anatomy(found)
    out = {**doc, "repetition_list": checked, "rom_deg_withheld": None, "schema_version": 6}
    if rom_why is not None:
        out["rom_deg"], out["rom_deg_withheld"] = None, rom_why.model_dump(mode="json")
        if isinstance(out.get("fatigue"), dict):
            out["fatigue"] = {**out["fatigue"], "amplitude_slope_pct_per_rep": None}
    return out


def upgrade(doc: dict[str, Any]) -> dict[str, Any]:
    """Returns a stored document (JSON object) in today's schema; raises UnreadableDocument for an unknown version."""
    version = doc.get("schema_version", 1)
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= SCHEMA_VERSION:
        raise UnreadableDocument(f"unknown analysis document schema_version {version!r} (1..{SCHEMA_VERSION} known)")
    if version == 1:
        doc = _upgrade_1_to_2(doc)
    if version <= 2:
        doc = _upgrade_2_to_3(doc)
    if version <= 3:
        doc = _upgrade_3_to_4(doc)
    if version <= 4:
        doc = _upgrade_4_to_5(doc)
    if version <= 5:
        doc = _upgrade_5_to_6(doc)
    return doc


def read_document(doc: dict[str, Any]) -> AnalysisDocument:
    """Returns a stored metrics document of any schema version as today's model (pydantic.ValidationError or
    UnreadableDocument when it is malformed)."""
    return AnalysisDocument.model_validate(upgrade(doc))


def read_if_readable(stored: dict[str, Any] | None) -> AnalysisDocument | None:
    """Returns a stored metrics document of any schema version as today's model; None without one or when no
    schema reads it (for readers that show "not measured" rather than fail: reports, archives, comparisons)."""
    if stored is None:
        return None
    try:
        return read_document(stored)
    except (ValidationError, UnreadableDocument):
        return None


def read_indicators(stored: object) -> Indicators | None:
    """Returns the "indicators" part of a stored document of any schema version (the dashboard reads only that part);
    None without one or when no schema reads it."""
    if not isinstance(stored, dict):
        return None
    try:
        return Indicators.model_validate(_indicators_3_to_4(_indicators_2_to_3(_indicators_1_to_2(stored))))
    except ValidationError:
        return None


def read_report(doc: dict[str, Any]) -> AnalysisReport:
    """Returns a report (`coach-server analyze --json`, whose "source" is dropped) or a stored document of any
    schema version: an AnalysisDocument when it holds indicators, else an AnalysisReport (pydantic.ValidationError
    or UnreadableDocument when it is malformed)."""
    upgraded = {k: v for k, v in upgrade(doc).items() if k != "source"}
    if "indicators" in upgraded:
        return AnalysisDocument.model_validate(upgraded)
    return AnalysisReport.model_validate(upgraded)


def json_ready(value: Any) -> Any:
    """Returns value with numpy scalars and arrays turned into Python numbers and lists, NaN and inf into None."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):
        return json_ready(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
