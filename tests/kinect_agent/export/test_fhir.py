"""FHIR export: a Bundle the fhir.resources R4B models accept, with the codes, units and references promised."""

from __future__ import annotations

import json
from typing import Any

import pytest

fhir_bundle = pytest.importorskip("fhir.resources.R4B.bundle", reason="fhir.resources is in the test extra")

from kinect_agent.export import fhir  # noqa: E402
from tests.kinect_agent.export.conftest import session  # noqa: E402

CONTEXT = fhir.SessionContext(session_id="abc", start="2026-11-20T10:00:00Z", patient_id=7, device_id=3)


def _observations(bundle: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {
        e["resource"]["code"]["coding"][0]["code"]: e["resource"]
        for e in bundle["entry"]
        if e["resource"]["resourceType"] == "Observation"
    }


@pytest.mark.parametrize(("exercise", "seed"), [("squat", 1), ("elbow_flexion", 2), ("sit_to_stand", 3)])
def test_bundle_validates_against_the_r4b_models(exercise, seed):
    _, doc = session(exercise, 3, seed)
    data = fhir.bundle(doc, CONTEXT)
    parsed = fhir_bundle.Bundle.model_validate(json.loads(json.dumps(data, allow_nan=False)))
    assert parsed.type == "collection"
    kinds = [e.resource.__resource_type__ for e in parsed.entry]
    assert kinds[0] == "Device" and set(kinds[1:]) == {"Observation"}


def test_observations_carry_patient_device_units_and_body_sites(squat_session):
    _, doc = squat_session
    data = fhir.bundle(doc, CONTEXT)
    device_url = data["entry"][0]["fullUrl"]
    obs = _observations(data)
    assert all(o["subject"] == {"reference": "Patient/7"} for o in obs.values())
    assert all(o["device"] == {"reference": device_url} for o in obs.values())
    duration = obs["55411-3"]
    assert duration["code"]["coding"][0]["system"] == fhir.LOINC
    assert duration["valueQuantity"] == {"value": doc.duration_s, "unit": "s", "system": fhir.UCUM, "code": "s"}
    assert obs["repetitions"]["valueQuantity"]["value"] == doc.repetitions == 3
    knee = obs["range-of-motion.knee_flexion_L"]
    assert knee["valueQuantity"]["code"] == "deg" and knee["valueQuantity"]["system"] == fhir.UCUM
    assert knee["valueQuantity"]["value"] == doc.range_of_motion["knee_flexion_L"].range_deg
    knee_site = {"system": fhir.SNOMED, "code": "49076000", "display": "Knee joint structure"}
    assert knee["bodySite"]["coding"][0] == knee_site
    assert "left" in knee["bodySite"]["text"]
    assert "bodySite" not in obs["range-of-motion.trunk_flexion"]
    for name in fhir.INDICATORS:
        indicator = obs[f"indicator.{name}"]
        assert 0 <= indicator["valueQuantity"]["value"] <= 100, name
        assert indicator["valueQuantity"]["value"] == getattr(doc.indicators, name).score


def test_without_patient_or_device_the_bundle_has_neither(squat_session):
    _, doc = squat_session
    data = fhir.bundle(doc, fhir.SessionContext(session_id="abc", start="2026-11-20T10:00:00Z"))
    fhir_bundle.Bundle.model_validate(data)
    assert all(e["resource"]["resourceType"] == "Observation" for e in data["entry"])
    assert not any("subject" in e["resource"] or "device" in e["resource"] for e in data["entry"])
