"""Mocap as truth (bench/accuracy.py, simulate --from): placed in the camera frame and resampled to 30 Hz."""

import numpy as np

from kinect_agent import skeleton
from kinect_agent.recording import Recording
from kinect_agent.sources.mocap_truth import place_in_camera, resample


def _standing() -> np.ndarray:
    p = np.zeros((2, skeleton.J, 3))
    p[:, :, 1] = 1.0
    for name in ("ANK_L", "ANK_R", "FOO_L", "FOO_R"):
        p[:, skeleton.INDEX[name], 1] = 0.0
    p[:, skeleton.INDEX["SHO_L"], 0] = 0.2  # subject's left at +x, facing +z (CMU frame 0)
    p[:, skeleton.INDEX["SHO_R"], 0] = -0.2
    p[:, skeleton.INDEX["FOO_L"], 2] = 0.15  # toes point forward
    return p


def test_subject_faces_the_camera_on_the_floor() -> None:
    out = place_in_camera(_standing(), 0.0, 0.0)
    sho_l, sho_r, foo = (out[0, skeleton.INDEX[n]] for n in ("SHO_L", "SHO_R", "FOO_L"))
    assert foo[2] < out[0, 0, 2], "toes point towards the camera (−z)"
    assert sho_l[0] < sho_r[0], "facing the camera, the subject's left is on the camera's −x side"
    np.testing.assert_allclose(out[0, skeleton.INDEX["ANK_L"], 1], -0.8, atol=1e-9, err_msg="floor 0.8 m below")
    np.testing.assert_allclose(out[0, 0, [0, 2]], [0.0, 2.4], atol=1e-9, err_msg="pelvis 2.4 m in front")


def test_view_turns_about_the_vertical() -> None:
    a, b = place_in_camera(_standing(), 0.0, 0.0), place_in_camera(_standing(), 60.0, 0.0)
    across_a = a[0, skeleton.INDEX["SHO_L"]] - a[0, skeleton.INDEX["SHO_R"]]
    across_b = b[0, skeleton.INDEX["SHO_L"]] - b[0, skeleton.INDEX["SHO_R"]]
    cos = across_a @ across_b / np.linalg.norm(across_a) / np.linalg.norm(across_b)
    np.testing.assert_allclose(np.degrees(np.arccos(cos)), 60.0, atol=1e-6)


def test_resample_120_to_30_hz_keeps_every_fourth_frame() -> None:
    t = np.arange(13) / 120.0
    p = np.random.default_rng(0).standard_normal((13, skeleton.J, 3))
    t30, p30 = resample(Recording.from_positions(t, p), 30.0)
    np.testing.assert_allclose(t30, np.arange(4) / 30.0, atol=1e-12)
    np.testing.assert_allclose(p30, p[::4], atol=1e-9)
