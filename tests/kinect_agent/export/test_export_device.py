"""The CSV and FHIR exports name the device that recorded the session (a webcam with its pose model and hash)."""

from __future__ import annotations

import csv
import io
import json
import zipfile

import pytest

from kinect_agent.export import files
from kinect_agent.vendor import model_info
from tests.kinect_agent.export.conftest import session

fhir_bundle = pytest.importorskip("fhir.resources.R4B.bundle", reason="fhir.resources is in the test extra")
WEBCAM = {"model": model_info("lite").to_dict(), "runtime": "mediapipe 1.2.3 (Python)", "fps_achieved": 12.0}


@pytest.fixture(scope="module")
def webcam_session():
    payload, doc = session("squat", 3, seed=12)
    payload.raw.meta.device = "webcam"
    payload.raw.meta.extra["webcam"] = WEBCAM
    return payload, doc


def _tables(data: bytes) -> dict[str, list[list[str]]]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {n: list(csv.reader(io.StringIO(z.read(n).decode()))) for n in z.namelist()}


def test_the_csv_export_names_the_device_and_the_model(webcam_session) -> None:
    payload, doc = webcam_session
    tables = _tables(files.export("csv", payload, document=doc).data)
    assert tables["metrics.csv"][1] == ["device", "webcam", ""]
    recording = dict(tables["recording.csv"][1:])
    assert recording["device"] == "webcam" and recording["label"] == "ordinary camera (webcam)"
    assert recording["model"] == "pose_landmarker_lite.task" and recording["model_sha256"] == model_info("lite").sha256
    assert float(recording["fps_achieved"]) == 12.0


def test_the_fhir_export_has_a_device_naming_the_camera_and_model(webcam_session) -> None:
    payload, doc = webcam_session
    data = json.loads(files.export("fhir", payload, document=doc).data)
    fhir_bundle.Bundle.model_validate(data)
    device = data["entry"][0]["resource"]
    assert device["resourceType"] == "Device" and device["type"]["coding"][0]["code"] == "webcam"
    assert {"name": "ordinary camera (webcam)", "type": "model-name"} in device["deviceName"]
    assert device["version"][0]["value"] == f"pose_landmarker_lite.task sha256:{model_info('lite').sha256}"
    observations = [e["resource"] for e in data["entry"][1:]]
    assert all(o["device"] == {"reference": data["entry"][0]["fullUrl"]} for o in observations)


def test_a_kinect_session_is_named_as_such(webcam_session) -> None:
    payload, doc = session("squat", 3, seed=13)
    payload.raw.meta.device = "kinect2"
    tables = _tables(files.export("csv", payload, document=doc).data)
    assert tables["metrics.csv"][1] == ["device", "kinect2", ""]
    device = json.loads(files.export("fhir", payload, document=doc).data)["entry"][0]["resource"]
    assert device["type"]["text"].startswith("Depth camera (Kinect)") and "version" not in device
