"""Adds the TFLite model metadata that MediaPipe Tasks needs (input normalisation) and packs `.task` bundles.

MediaPipe's own metadata writer in the `mediapipe` wheel (1.2.x) does not import (its native version helper,
`mediapipe.tasks.cc.metadata.python`, is not shipped), so this module writes the same metadata with the FlatBuffers
object API generated from the TFLite and TFLite-metadata schemas; those two generated modules ship inside the wheel
and need only the `flatbuffers` package, so they are loaded by file path without importing `mediapipe` itself (no
native library is loaded). The output is a pure function of the input bytes: the bundles are reproducible and their
SHA-256 is pinned in lock.json.
"""

from __future__ import annotations

import importlib.util
import io
import zipfile
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

METADATA_NAME = "TFLITE_METADATA"  # the model's metadata entry that MediaPipe reads
METADATA_IDENTIFIER = b"M001"  # FlatBuffers file identifier of the metadata buffer
TFLITE_IDENTIFIER = b"TFL3"
MIN_PARSER_VERSION = "1.0.0"  # image properties and normalisation options: the schema's first version
ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # fixed member time stamps: the same inputs give the same bytes
ZIP_ALIGNMENT = 4  # MediaPipe maps the stored members in place: each starts at a multiple of 4 bytes


class MetadataError(RuntimeError):
    """The schema modules are missing or a model does not have the expected inputs."""


@dataclass(frozen=True)
class ImageInput:
    """Normalisation of a model's float image input: value = (pixel - mean) / std, pixel in 0..255 (RGB)."""

    mean: float
    std: float


def _schema_dir() -> Path:
    spec = importlib.util.find_spec("mediapipe")
    if spec is None or not spec.submodule_search_locations:
        raise MetadataError(
            "packing the pose models needs the 'mediapipe' wheel (its TFLite schema modules) and 'flatbuffers': "
            "pip install '.[webcam]' (or the pins in requirements/vendor.lock)"
        )
    return Path(next(iter(spec.submodule_search_locations))) / "tasks" / "metadata"


_LOADED: dict[str, ModuleType] = {}


def schema_module(name: str) -> ModuleType:
    """Returns one generated schema module of the mediapipe wheel, loaded from its file ("schema", "metadata")."""
    if name not in _LOADED:
        file = _schema_dir() / {"schema": "schema_py_generated.py", "metadata": "metadata_schema_py_generated.py"}[name]
        if not file.is_file():
            raise MetadataError(f"{file} is missing from the mediapipe wheel")
        spec = importlib.util.spec_from_file_location(f"_kinect_vendor_{name}_fb", file)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        _LOADED[name] = module
    return _LOADED[name]


def tensor_names(model: bytes) -> tuple[list[str], list[str]]:
    """Returns (input names, output names) of the first subgraph of a TFLite model."""
    fb = schema_module("schema")
    m = fb.Model.GetRootAsModel(model, 0)
    graph = m.Subgraphs(0)
    inputs = [graph.Tensors(graph.Inputs(i)).Name().decode() for i in range(graph.InputsLength())]
    outputs = [graph.Tensors(graph.Outputs(i)).Name().decode() for i in range(graph.OutputsLength())]
    return inputs, outputs


def with_image_metadata(model: bytes, *, name: str, image: ImageInput, description: str = "") -> bytes:
    """Returns the TFLite model with a metadata buffer describing its one RGB image input and its outputs.

    Any metadata buffer already named TFLITE_METADATA is replaced. Raises MetadataError when the model does not
    have exactly one input.
    """
    fb, md = schema_module("schema"), schema_module("metadata")
    import flatbuffers

    inputs, outputs = tensor_names(model)
    if len(inputs) != 1:
        raise MetadataError(f"{name}: expected one image input, got {len(inputs)} ({inputs})")
    image_md = md.TensorMetadataT()
    image_md.name = "image"
    image_md.description = "RGB image, pixel values normalised as (value - mean) / std"
    image_md.content = md.ContentT()
    image_md.content.contentPropertiesType = md.ContentProperties.ImageProperties
    image_md.content.contentProperties = md.ImagePropertiesT()
    image_md.content.contentProperties.colorSpace = md.ColorSpaceType.RGB
    unit = md.ProcessUnitT()
    unit.optionsType = md.ProcessUnitOptions.NormalizationOptions
    unit.options = md.NormalizationOptionsT()
    unit.options.mean = [float(image.mean)]
    unit.options.std = [float(image.std)]
    image_md.processUnits = [unit]
    image_md.stats = md.StatsT()
    image_md.stats.min = [(0.0 - image.mean) / image.std]
    image_md.stats.max = [(255.0 - image.mean) / image.std]
    output_mds = []
    for out in outputs:
        tensor = md.TensorMetadataT()
        tensor.name = out
        output_mds.append(tensor)
    graph = md.SubGraphMetadataT()
    graph.inputTensorMetadata = [image_md]
    graph.outputTensorMetadata = output_mds
    meta = md.ModelMetadataT()
    meta.name = name
    meta.description = description
    meta.subgraphMetadata = [graph]
    meta.minParserVersion = MIN_PARSER_VERSION
    builder = flatbuffers.Builder(0)
    builder.Finish(meta.Pack(builder), METADATA_IDENTIFIER)
    meta_bytes = bytes(builder.Output())

    tflite = fb.ModelT.InitFromObj(fb.Model.GetRootAsModel(model, 0))
    buffer = fb.BufferT()
    buffer.data = list(meta_bytes)
    tflite.buffers = list(tflite.buffers or [])
    tflite.metadata = list(tflite.metadata or [])
    existing = [m for m in tflite.metadata if m.name.decode() == METADATA_NAME]
    if existing:  # replaced in place: adding the metadata twice gives the same model
        tflite.buffers[existing[0].buffer] = buffer
    else:
        tflite.buffers.append(buffer)
        entry = fb.MetadataT()
        entry.name = METADATA_NAME
        entry.buffer = len(tflite.buffers) - 1
        tflite.metadata.append(entry)
    builder = flatbuffers.Builder(0)
    builder.Finish(tflite.Pack(builder), TFLITE_IDENTIFIER)
    return bytes(builder.Output())


class _AlignedZip(zipfile.ZipFile):
    """A zip writer that pads before each stored member's local header so that its data starts at a multiple of
    ZIP_ALIGNMENT bytes (as MediaPipe's own bundler does; readers skip bytes between members)."""

    def _writecheck(self, zinfo: zipfile.ZipInfo) -> None:  # called after the writer has moved to the member's start
        assert self.fp is not None
        offset = self.fp.tell()
        pad = (-(offset + len(zinfo.FileHeader()))) % ZIP_ALIGNMENT
        if pad:
            self.fp.write(b"\0" * pad)
            zinfo.header_offset = offset + pad
        super()._writecheck(zinfo)  # type: ignore[misc]


def pack_task(members: dict[str, bytes]) -> bytes:
    """Returns a MediaPipe `.task` bundle: an uncompressed zip of the members, in the given order, each member's
    data aligned to ZIP_ALIGNMENT bytes, fixed time stamps and permissions."""
    out = io.BytesIO()
    with _AlignedZip(out, "w", compression=zipfile.ZIP_STORED) as zf:
        for member, data in members.items():
            info = zipfile.ZipInfo(member, date_time=ZIP_DATE)
            info.compress_type = zipfile.ZIP_STORED
            info.create_system = 3
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    return out.getvalue()
