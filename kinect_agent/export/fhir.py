"""FHIR R4 Bundle (type collection) of one session's Observations, as JSON-ready dicts (stdlib only).

Entries: the Device that recorded the session (when known: the paired agent's id, the recording device, e.g. a
Kinect or an ordinary camera with its pose model and hash), then Observations, each with status final, the patient
as subject (`Patient/<id>`, a reference to the clinic's server), the Device as device, the session's period as
effectivePeriod:
    exercise duration      LOINC 55411-3 "Exercise duration", s
    repetitions            project code `repetitions`, {repetitions} (UCUM annotation: a count)
    range of motion        one per clinical angle with a value: project code `range-of-motion.<angle>`, value the
                           range (p98 − p2), components min and max, UCUM `deg`, bodySite the SNOMED CT joint
                           structure (BODY_SITES; trunk angles have none) with laterality in its text
    indicators             project codes `indicator.<flexibility|endurance|strength|balance>`, score 0-100
                           (UCUM `1`), the measured value as a component
    how the set felt       what the patient answered after the set (backend.feeling), category survey, the patient
                           as performer, issued when answered: pain LOINC 72514-3 "Pain severity - 0-10 verbal
                           numeric rating [Score] - Reported" (an integer 0-10, UCUM `{score}`); effort on the Borg
                           CR10 scale (0-10 in halves, UCUM `{score}`) under FEELING_CODE_SYSTEM `effort-borg-cr10`:
                           LOINC has no Borg CR10 term (its 82289-0 "Rating of perceived exertion [Score]" is the
                           0-10 scale of the 2008 US Physical Activity Guidelines, docs/fhir.md). A skipped question
                           gives no Observation.
Project codes live in CODE_SYSTEM and FEELING_CODE_SYSTEM, documented in docs/fhir.md. SNOMED CT codes (body
structures) were checked in published mappings (DICOM anatomic region tables, HL7 examples): 16953009 elbow joint
structure, 49076000 knee joint structure, 85537004 glenohumeral (shoulder) joint structure, 24136001 hip joint
structure.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

from kinect_agent.analysis.document import AnalysisDocument, AnalysisReport, Indicator

CODE_SYSTEM = "https://kinect-home-coach.example/fhir/CodeSystem/metrics"
FEELING_CODE_SYSTEM = "https://kinect-home-coach.example/fhir/CodeSystem/patient-reported"
PAIN_LOINC = ("72514-3", "Pain severity - 0-10 verbal numeric rating [Score] - Reported")
EFFORT_CODE = ("effort-borg-cr10", "Perceived exertion after the set, Borg CR10 scale (0-10) - Reported")
DEVICE_ID_SYSTEM = "https://kinect-home-coach.example/fhir/NamingSystem/device-id"
DEVICE_CODE_SYSTEM = "https://kinect-home-coach.example/fhir/CodeSystem/recording-device"  # recording.DEVICES
SESSION_ID_SYSTEM = "https://kinect-home-coach.example/fhir/NamingSystem/session-id"
LOINC = "http://loinc.org"
SNOMED = "http://snomed.info/sct"
UCUM = "http://unitsofmeasure.org"
CATEGORY = "http://terminology.hl7.org/CodeSystem/observation-category"
MEDIA_TYPE = "application/fhir+json"
INDICATORS = ("flexibility", "endurance", "strength", "balance")
BODY_SITES: dict[str, tuple[str, str]] = {
    "elbow": ("16953009", "Elbow joint structure"),
    "knee": ("49076000", "Knee joint structure"),
    "shoulder": ("85537004", "Glenohumeral joint structure"),
    "hip": ("24136001", "Hip joint structure"),
}
_SIDES = {"L": "left", "R": "right"}


@dataclass(frozen=True)
class Feeling:
    """How the set felt to the patient: pain_nrs 0-10 (integer), effort_cr10 0-10 in halves (Borg CR10), None =
    skipped; answered_at: ISO 8601 UTC time of the answer."""

    pain_nrs: int | None
    effort_cr10: float | None
    answered_at: str | None = None


@dataclass(frozen=True)
class SessionContext:
    """Who and what a bundle describes: ids on the clinic's server (None when unknown) and the session's start.

    start: ISO 8601 UTC time the session started (e.g. the file's created_at); session_id: the session's id.
    """

    session_id: str
    start: str
    patient_id: int | None = None
    device_id: int | None = None
    recorded_with: dict[str, Any] | None = None  # kinect_agent.analysis.validity.recorded_with of the recording
    feeling: Feeling | None = None  # the patient's answers after the set (the server's sessions only)


def _urn() -> str:
    return f"urn:uuid:{uuid.uuid4()}"


def _quantity(value: float, unit: str, code: str) -> dict[str, Any]:
    return {"value": value, "unit": unit, "system": UCUM, "code": code}


def _concept(system: str, code: str, display: str) -> dict[str, Any]:
    return {"coding": [{"system": system, "code": code, "display": display}], "text": display}


def _period(context: SessionContext, duration_s: float | None) -> dict[str, str]:
    start = datetime.fromisoformat(context.start.replace("Z", "+00:00"))
    if start.tzinfo is None:
        start = start.replace(tzinfo=UTC)
    end = start + timedelta(seconds=duration_s or 0.0)
    fmt = "%Y-%m-%dT%H:%M:%S%z"
    return {"start": _iso(start.strftime(fmt)), "end": _iso(end.strftime(fmt))}


def _iso(text: str) -> str:
    return text[:-2] + ":" + text[-2:] if text[-5] in "+-" else text


def _label(angle: str) -> str:
    return angle.replace("_", " ")


def body_site(angle: str) -> dict[str, Any] | None:
    """Returns the bodySite CodeableConcept of a clinical angle (e.g. knee_flexion_L), or None (trunk angles)."""
    joint = angle.split("_")[0]
    if joint not in BODY_SITES:
        return None
    code, display = BODY_SITES[joint]
    side = _SIDES.get(angle.rsplit("_", 1)[-1])
    concept = _concept(SNOMED, code, display)
    concept["text"] = f"{display} ({side})" if side else display
    return concept


def _observation(common: dict[str, Any], code: dict[str, Any], category: str, **fields: Any) -> dict[str, Any]:
    obs = {
        "resourceType": "Observation",
        "status": "final",
        "category": [{"coding": [{"system": CATEGORY, "code": category}]}],
        "code": code,
        **common,
        **fields,
    }
    return obs


def _rom_observations(document: AnalysisReport, common: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for angle, rom in document.range_of_motion.items():
        if rom.range_deg is None:
            continue
        code = _concept(CODE_SYSTEM, f"range-of-motion.{angle}", f"Range of motion, {_label(angle)}")
        fields: dict[str, Any] = {"valueQuantity": _quantity(rom.range_deg, "deg", "deg")}
        site = body_site(angle)
        if site is not None:
            fields["bodySite"] = site
        ends = (("min", rom.min_deg), ("max", rom.max_deg))
        fields["component"] = [
            {
                "code": _concept(CODE_SYSTEM, f"range-of-motion.{key}", f"{key.capitalize()}imum angle"),
                "valueQuantity": _quantity(value, "deg", "deg"),
            }
            for key, value in ends
            if value is not None
        ]
        out.append(_observation(common, code, "exam", **fields))
    return out


def _indicator_observations(document: AnalysisReport, common: dict[str, Any]) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    if not isinstance(document, AnalysisDocument):
        return out
    for name in INDICATORS:
        item: Indicator = getattr(document.indicators, name)
        if item.score is None:
            continue
        code = _concept(CODE_SYSTEM, f"indicator.{name}", f"{name.capitalize()} indicator (0-100)")
        fields: dict[str, Any] = {"valueQuantity": _quantity(item.score, "score", "1")}
        if item.value is not None:
            fields["component"] = [
                {
                    "code": _concept(CODE_SYSTEM, f"indicator.{name}.value", f"{name.capitalize()} measured value"),
                    "valueQuantity": {"value": item.value},
                }
            ]
        if item.basis.text:  # written by the server (English in its exports); a document read unwritten has none
            fields["note"] = [{"text": item.basis.text}]
        out.append(_observation(common, code, "exam", **fields))
    return out


def _feeling_observations(
    feeling: Feeling | None, common: dict[str, Any], patient_id: int | None
) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    if feeling is None:
        return out
    fields: dict[str, Any] = {}
    if feeling.answered_at is not None:
        fields["issued"] = feeling.answered_at
    if patient_id is not None:
        fields["performer"] = [{"reference": f"Patient/{patient_id}"}]
    plain = {k: v for k, v in common.items() if k != "device"}  # the patient said it, no device measured it
    if feeling.pain_nrs is not None:
        code = _concept(LOINC, *PAIN_LOINC)
        value = _quantity(int(feeling.pain_nrs), "score", "{score}")
        out.append(_observation(plain, code, "survey", valueQuantity=value, **fields))
    if feeling.effort_cr10 is not None:
        code = _concept(FEELING_CODE_SYSTEM, *EFFORT_CODE)
        value = _quantity(float(feeling.effort_cr10), "score", "{score}")
        method = {"text": "Borg CR10 scale: 0 nothing at all, 10 maximal"}
        out.append(_observation({**plain, "method": method}, code, "survey", valueQuantity=value, **fields))
    return out


DEVICE_TYPES = {"webcam": "Ordinary camera (webcam) with BlazePose landmark model",
                "simulator": "Simulated depth camera"}  # fmt: skip


def _device(context: SessionContext) -> dict[str, Any]:
    recorded = context.recorded_with or {}
    code = recorded.get("device")
    names = [{"name": "Kinect Home Coach home agent", "type": "user-friendly-name"}]
    if recorded.get("label"):
        names.append({"name": recorded["label"], "type": "model-name"})
    device: dict[str, Any] = {
        "resourceType": "Device",
        "deviceName": names,
        "type": {"text": DEVICE_TYPES.get(str(code), "Depth camera (Kinect) with skeleton tracking")},
    }
    if code is not None:
        device["type"]["coding"] = [{"system": DEVICE_CODE_SYSTEM, "code": code, "display": recorded.get("label")}]
    if context.device_id is not None:
        device["identifier"] = [{"system": DEVICE_ID_SYSTEM, "value": str(context.device_id)}]
    if recorded.get("model"):
        version = f"{recorded['model']} sha256:{recorded.get('model_sha256') or '?'}"
        device["version"] = [{"type": {"text": "pose model"}, "value": version}]
    if context.patient_id is not None:
        device["patient"] = {"reference": f"Patient/{context.patient_id}"}
    return device


def bundle(document: AnalysisReport, context: SessionContext) -> dict[str, Any]:
    """Returns the Bundle of a session's analysis document (an AnalysisDocument: its indicators too)."""
    entries: list[dict[str, Any]] = []
    common: dict[str, Any] = {
        "identifier": [{"system": SESSION_ID_SYSTEM, "value": context.session_id}],
        "effectivePeriod": _period(context, document.duration_s),
    }
    if document.exercise:
        common["method"] = {"text": f"Kinect Home Coach exercise {document.exercise}"}
    if context.patient_id is not None:
        common["subject"] = {"reference": f"Patient/{context.patient_id}"}
    if context.device_id is not None or context.recorded_with is not None:
        device_url = _urn()
        entries.append({"fullUrl": device_url, "resource": _device(context)})
        common["device"] = {"reference": device_url}
    observations = []
    if document.duration_s is not None:
        code = _concept(LOINC, "55411-3", "Exercise duration")
        value = _quantity(document.duration_s, "s", "s")
        observations.append(_observation(common, code, "activity", valueQuantity=value))
    if document.repetitions is not None:
        code = _concept(CODE_SYSTEM, "repetitions", "Repetitions of the exercise")
        value = _quantity(document.repetitions, "repetitions", "{repetitions}")
        observations.append(_observation(common, code, "activity", valueQuantity=value))
    observations += _rom_observations(document, common)
    observations += _indicator_observations(document, common)
    observations += _feeling_observations(context.feeling, common, context.patient_id)
    entries += [{"fullUrl": _urn(), "resource": obs} for obs in observations]
    return {
        "resourceType": "Bundle",
        "type": "collection",
        "timestamp": datetime.now(UTC).isoformat(timespec="seconds"),
        "identifier": {"system": SESSION_ID_SYSTEM, "value": context.session_id},
        "entry": entries,
    }
