"""The landmark wire contract: a batch reads back as written; every hostile batch is refused naming field and frame."""

from __future__ import annotations

import copy
import json
from typing import Any

import numpy as np
import pytest

from kinect_agent.sources.webcam.landmarks import MAX_FRAMES, LandmarkBatch, LandmarkError, parse_batch


def make_batch(rng: np.random.Generator, n: int = 5, t0: float = 100.0) -> LandmarkBatch:
    world = rng.normal(0.0, 0.3, (n, 33, 3))
    image = rng.uniform(0.1, 0.9, (n, 33, 3))
    visibility = rng.uniform(0.0, 1.0, (n, 33))
    return LandmarkBatch(t0 + np.arange(n) / 30.0, world, image, visibility, (640, 480))


@pytest.fixture
def doc(rng) -> dict[str, Any]:
    return json.loads(json.dumps(make_batch(rng).to_json()))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_batch_reads_back_as_written(seed) -> None:
    batch = make_batch(np.random.default_rng(seed), n=7)
    back = parse_batch(json.loads(json.dumps(batch.to_json())))
    for name in ("t", "world", "image", "visibility"):
        np.testing.assert_array_equal(getattr(back, name), getattr(batch, name), err_msg=name)
    assert back.image_size == (640, 480) and back.n_frames == 7


def _broken(doc: dict[str, Any], change) -> dict[str, Any]:
    bad = copy.deepcopy(doc)
    change(bad)
    return bad


def _set(path, value):
    def change(d):
        target = d
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value

    return change


HOSTILE = {
    "nan in world": (_set(["frames", 2, "world", 5, 1], float("nan")), "world", 2, "NaN"),
    "infinite time": (_set(["frames", 1, "t"], float("inf")), "t", 1, "NaN or infinite"),
    "absurd world coordinate": (_set(["frames", 3, "world", 15, 0], 42.0), "world", 3, "15 \\(left_wrist\\)"),
    "absurd image coordinate": (_set(["frames", 0, "image", 0, 1], 1e6), "image", 0, "0 \\(nose\\)"),
    "time going back": (_set(["frames", 3, "t"], 50.0), "t", 3, "must increase"),
    "time repeated": (_set(["frames", 1, "t"], 100.0), "t", 1, "must increase"),
    "32 landmarks": (lambda d: d["frames"][4]["world"].pop(), "world", 4, "33 landmarks, got 32"),
    "2 coordinates": (lambda d: d["frames"][1]["image"][7].pop(), "image", 1, "row of 3 numbers, got 2"),
    "text in a row": (_set(["frames", 0, "world", 0, 0], "1.0"), "world", 0, "numbers only, got str"),
    "boolean time": (_set(["frames", 0, "t"], True), "t", 0, "number, got bool"),
    "visibility above 1": (_set(["frames", 2, "visibility", 3], 1.5), "visibility", 2, "0..1"),
    "visibility of 32": (lambda d: d["frames"][2]["visibility"].pop(), "visibility", 2, "got 32"),
    "missing field": (lambda d: d["frames"][1].pop("image"), "image", 1, "missing"),
    "unknown field": (_set(["frames", 1, "jpeg"], "..."), "jpeg", 1, "unknown field"),
    "frame not an object": (_set(["frames", 2], [1, 2]), "frame", 2, "object"),
    "unknown top field": (_set(["patient_id"], 7), "patient_id", None, "unknown field"),
    "wrong version": (_set(["version"], 2), "version", None, "must be 1"),
    "image size zero": (_set(["image_size"], [0, 480]), "image_size", None, "16..8192"),
    "image size text": (_set(["image_size"], "640x480"), "image_size", None, "width, height"),
    "no frames": (_set(["frames"], []), "frames", None, "empty"),
    "frames not a list": (_set(["frames"], {"t": 1}), "frames", None, "must be a list"),
}


@pytest.mark.parametrize("case", list(HOSTILE))
def test_a_hostile_batch_is_refused_naming_field_and_frame(doc, case) -> None:
    change, field, frame, message = HOSTILE[case]
    with pytest.raises(LandmarkError, match=message) as info:
        parse_batch(_broken(doc, change))
    assert (info.value.field, info.value.frame) == (field, frame)
    assert str(info.value).startswith(field if frame is None else f"frames[{frame}].{field}")


def test_too_many_frames_are_refused_before_reading_them(rng) -> None:
    frame = make_batch(rng, n=1).to_json()["frames"][0]
    doc = {"version": 1, "image_size": [640, 480], "frames": [frame] * (MAX_FRAMES + 1)}
    with pytest.raises(LandmarkError, match=f"{MAX_FRAMES + 1} frames, at most {MAX_FRAMES}"):
        parse_batch(doc)


def test_a_batch_must_come_after_the_previous_one(doc) -> None:
    last = doc["frames"][-1]["t"]
    with pytest.raises(LandmarkError, match="previous batch's last time") as info:
        parse_batch(doc, after_t=last)
    assert info.value.frame == 0
    assert parse_batch(doc, after_t=doc["frames"][0]["t"] - 0.001).n_frames == 5


def test_batches_join_in_order_only(rng) -> None:
    a, b = make_batch(rng, n=3, t0=0.0), make_batch(rng, n=3, t0=1.0)
    assert LandmarkBatch.concatenate([a, b]).n_frames == 6
    with pytest.raises(LandmarkError, match="time goes back"):
        LandmarkBatch.concatenate([b, a])
