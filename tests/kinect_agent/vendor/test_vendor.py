"""The pinned pose assets: reproducible `.task` bundles with the input metadata MediaPipe needs, hash-checked."""

from __future__ import annotations

import hashlib
import zipfile
from typing import Any

import pytest

from kinect_agent import vendor
from kinect_agent.vendor import install
from kinect_agent.vendor.tflite_metadata import ZIP_ALIGNMENT, ImageInput, pack_task, tensor_names, with_image_metadata


@pytest.fixture(scope="module")
def lock() -> dict[str, Any]:
    lk = vendor.load_lock()
    if not install.is_installed(lk):
        pytest.fail(f"the pose assets are not installed: {vendor.INSTALL_HINT}")
    return lk


def _read_metadata(tflite: bytes):
    """Returns the ModelMetadata table of a TFLite model's TFLITE_METADATA buffer."""
    from kinect_agent.vendor.tflite_metadata import schema_module

    fb = schema_module("schema")
    model = fb.Model.GetRootAsModel(tflite, 0)
    entries = {model.Metadata(i).Name().decode(): model.Metadata(i).Buffer() for i in range(model.MetadataLength())}
    data = model.Buffers(entries["TFLITE_METADATA"]).DataAsNumpy().tobytes()
    md = schema_module("metadata")
    return md, md.ModelMetadata.GetRootAsModelMetadata(data, 0)


def test_task_members_are_stored_aligned_and_the_bytes_repeat() -> None:
    members = {"pose_detector.tflite": b"a" * 1001, "pose_landmarks_detector.tflite": b"bc" * 777}
    first, second = pack_task(members), pack_task(dict(members))
    assert first == second
    with zipfile.ZipFile(__import__("io").BytesIO(first)) as zf:
        assert zf.namelist() == list(members)
        for info in zf.infolist():
            assert info.compress_type == zipfile.ZIP_STORED and info.date_time == (1980, 1, 1, 0, 0, 0)
            data_at = info.header_offset + 30 + len(info.filename.encode()) + len(info.extra)
            assert data_at % ZIP_ALIGNMENT == 0, (info.filename, data_at)
            assert zf.read(info) == members[info.filename]


def test_the_landmark_model_gets_its_normalisation_and_keeps_its_tensors(lock) -> None:
    raw = (vendor.package_dir("@mediapipe/pose") / "pose_landmark_lite.tflite").read_bytes()
    with_md = with_image_metadata(raw, name="pose_landmarks_detector", image=ImageInput(0.0, 255.0))
    assert tensor_names(with_md) == tensor_names(raw) == (
        ["input_1"], ["Identity", "Identity_1", "Identity_2", "Identity_3", "Identity_4"])  # fmt: skip
    md, meta = _read_metadata(with_md)
    graph = meta.SubgraphMetadata(0)
    assert graph.InputTensorMetadataLength() == 1 and graph.OutputTensorMetadataLength() == 5
    image = graph.InputTensorMetadata(0)
    assert image.Content().ContentPropertiesType() == md.ContentProperties.ImageProperties
    unit = image.ProcessUnits(0)
    assert unit.OptionsType() == md.ProcessUnitOptions.NormalizationOptions
    options = md.NormalizationOptions()
    options.Init(unit.Options().Bytes, unit.Options().Pos)
    assert options.MeanAsNumpy().tolist() == [0.0] and options.StdAsNumpy().tolist() == [255.0]
    # adding it twice replaces the first: one metadata entry, the same bytes
    again = with_image_metadata(with_md, name="pose_landmarks_detector", image=ImageInput(0.0, 255.0))
    assert again == with_md


def test_every_task_rebuilds_to_its_pinned_sha256(lock) -> None:
    for task in lock["tasks"]:
        built = install.build_task(task)
        assert hashlib.sha256(built).hexdigest() == task["sha256"], task["file"]
        installed = vendor.FILES / "models" / task["file"]
        assert installed.read_bytes() == built


def test_the_lock_pins_exact_versions_and_sha512_integrity(lock) -> None:
    for package in lock["npm"]:
        assert package["version"].replace(".", "").isdigit(), package  # an exact version, no range
        assert package["integrity"].startswith("sha512-") and package["license"] in ("Apache-2.0", "MIT")
        marker = vendor.package_dir(package["name"]) / ".integrity"
        assert marker.read_text().strip() == package["integrity"]


def test_a_second_install_only_reads_the_stamp(lock, monkeypatch) -> None:
    def no_npm(*args, **kwargs):
        raise AssertionError("npm must not run when everything is installed")

    monkeypatch.setattr(install, "npm_pack", no_npm)
    assert install.main(["--quiet"]) == 0


def test_without_npm_the_error_says_what_to_install(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(vendor.VendorError, match="npm is needed .*apt-get install npm"):
        install.npm_pack("@mediapipe/pose", "0.5.1675469404", tmp_path)


def test_model_info_names_the_pinned_bundle(lock) -> None:
    info = vendor.model_info("full")
    assert info.name == "pose_landmarker_full.task" and info.source == "@mediapipe/pose@0.5.1675469404"
    assert info.sha256 == next(t["sha256"] for t in lock["tasks"] if t["file"] == info.name)
    assert vendor.task_path("lite").is_file()
    with pytest.raises(ValueError, match="lite, full"):
        vendor.model_info("heavy")


@pytest.mark.parametrize("model", vendor.MODELS)
def test_the_python_runtime_finds_the_33_landmarks_on_a_real_frame(lock, model) -> None:
    cv2 = pytest.importorskip("cv2")
    import mediapipe as mp
    from mediapipe.tasks.python import BaseOptions, vision

    from tests.media import sports2d_demo

    capture = cv2.VideoCapture(str(sports2d_demo()))  # one person standing on a hut, small in a wide image
    options = vision.PoseLandmarkerOptions(base_options=BaseOptions(model_asset_path=str(vendor.task_path(model))),
                                           running_mode=vision.RunningMode.VIDEO)  # fmt: skip
    with vision.PoseLandmarker.create_from_options(options) as landmarker:
        for i in range(31):  # the first second: found within a few frames, then tracked
            ok, frame = capture.read()
            assert ok
            image = mp.Image(image_format=mp.ImageFormat.SRGB, data=cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
            result = landmarker.detect_for_video(image, round(i * 1000 / 30))
    capture.release()
    assert len(result.pose_landmarks) == 1 and len(result.pose_world_landmarks[0]) == 33
    points = result.pose_landmarks[0]
    nose, heel_l = points[0], points[29]
    # the person stands on the roof of the hut, left of centre: head near the top, heels lower, all in the image
    assert 0.25 < nose.x < 0.5 and 0.0 < nose.y < heel_l.y < 0.6, (nose, heel_l)
    world = result.pose_world_landmarks[0]
    height = max(p.y for p in world) - min(p.y for p in world)  # world y points down, metres, hips origin
    assert 1.2 < height < 2.0, height
