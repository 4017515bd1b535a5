"""The webcam's offline filter (joint_smoother.py, label_swaps.py): the RTS held to a textbook loop, swaps found
where labels flip, and the property of issue 22: the webcam's pipeline makes no clinical angle worse than its input.

Input of the property test: the simulator's exact motion made monocular-like as measured on the Pose2Sim demo
(bench/README.md, "Webcam angles"): jitter 10 mm in the image plane and 25 mm in depth per joint, the fitted hip
distance jittering 30 mm for the whole body, and a stretch where the labels of left and right flicker (the side
view's swaps). Simulated rather than the demo's landmarks: those take the MediaPipe runtime about 35 s for the four
views (and a 51 MB download), not a test's few seconds; bench/webcam_accuracy.py runs them.
"""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body.angles import joint_angles
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.joint_smoother import INFERRED_FACTOR, JointFilter, constant_velocity_rts, smooth_joints
from kinect_agent.processing.label_swaps import MIRROR, body_jumps, labelling_flips, pair_swaps
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate_truth
from tests.webcam_like import ARMS, webcam_like

TOL_DEG = 0.1  # the exact truth has no reference noise: only rounding-level losses are allowed


def _textbook_rts(z: np.ndarray, r: float, q: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One series, one frame at a time, the formulas as printed: returns (Kalman filter, RTS) positions, NaN before
    the first measurement (which starts the filter: x = (z, 0), P = diag(r², 4), then its first update)."""
    H = np.array([[1.0, 0.0]])
    k0 = int(np.flatnonzero(np.isfinite(z))[0])
    x, P = np.array([z[k0], 0.0]), np.diag([r**2, 4.0])
    xs, Ps, xp, Pp, Fs = [], [], [], [], []
    for k in range(k0, len(z)):
        dt = t[k] - t[k - 1] if k > k0 else 0.0
        F = np.array([[1.0, dt], [0.0, 1.0]])
        Q = q**2 * np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]])
        if k > k0:
            x, P = F @ x, F @ P @ F.T + Q
        xp.append(x)
        Pp.append(P)
        Fs.append(F)
        if np.isfinite(z[k]):
            S = H @ P @ H.T + r**2
            K = P @ H.T @ np.linalg.inv(S)
            x = x + (K @ (z[k] - H @ x)).ravel()
            P = (np.eye(2) - K @ H) @ P
        xs.append(x)
        Ps.append(P)
    out = [xs[-1]]
    for i in range(len(xs) - 2, -1, -1):
        G = Ps[i] @ Fs[i + 1].T @ np.linalg.inv(Pp[i + 1])
        out.insert(0, xs[i] + G @ (out[0] - xp[i + 1]))
    pad = np.full(k0, np.nan)
    return np.concatenate([pad, np.array(xs)[:, 0]]), np.concatenate([pad, np.array(out)[:, 0]])


def _frame_times(rng: np.random.Generator, n: int) -> np.ndarray:
    """Returns (n,) s frame times of a browser camera: about 10 a second, irregular, with a gap of 0.8 s."""
    steps = rng.uniform(0.05, 0.15, n)
    steps[n // 2] = 0.8
    return np.cumsum(steps)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_vectorised_rts_equals_the_textbook_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    z = np.cumsum(rng.normal(0, 0.01, (80, 3)), axis=0)
    z[rng.random(z.shape) < 0.1] = np.nan
    z[:5, 2] = np.nan  # a series that starts late
    t = _frame_times(rng, 80)
    got = constant_velocity_rts(z, np.array([0.01, 0.02, 0.05]), 30.0, t)
    for s, r in enumerate((0.01, 0.02, 0.05)):
        np.testing.assert_allclose(got[:, s], _textbook_rts(z[:, s], r, 30.0, t)[1], atol=1e-10, err_msg=f"{s}")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_live_filter_is_the_textbook_kalman_filter_frame_by_frame(seed: int) -> None:
    """The joints filter's causal pass (the webcam's live filter, JointFilter.step) is the smoother's forward pass:
    each coordinate a textbook Kalman filter, between two restarts."""
    rng = np.random.default_rng(seed)
    truth = simulate_truth("squat", 1, seed=seed)
    n = 60
    t = _frame_times(rng, n)
    pos = truth.positions[:n] + rng.normal(0.0, 0.01, (n, skeleton.J, 3))
    state = truth.state[:n].copy()
    state[rng.random(state.shape) < 0.1] = skeleton.NOT_TRACKED
    config = config_for_device("webcam")
    live = JointFilter(config)
    got = np.stack([live.step(float(t[k]), pos[k], state[k]) for k in range(n)])
    assert live.n_restarts == 0
    r = np.where(state == skeleton.INFERRED, INFERRED_FACTOR, 1.0)[..., None] * np.array(
        [config.joint_sigma_image_m, config.joint_sigma_image_m, config.joint_sigma_depth_m]
    )
    z = np.where((state != skeleton.NOT_TRACKED)[..., None], pos, np.nan)
    for j in (skeleton.INDEX["KNE_L"], skeleton.INDEX["WRI_R"]):
        for c in range(3):
            assert np.all(r[:, j, c] == r[0, j, c]), "the test's joints are tracked, one SD"
            want = _textbook_rts(z[:, j, c], float(r[0, j, c]), config.joint_accel_sd_mps2, t)[0]
            np.testing.assert_allclose(got[:, j, c], want, atol=1e-10, err_msg=f"joint {j} axis {c}")


def test_mirror_maps_left_to_right_and_keeps_the_trunk() -> None:
    assert skeleton.JOINTS[MIRROR[skeleton.INDEX["KNE_L"]]] == "KNE_R"
    assert skeleton.JOINTS[MIRROR[skeleton.INDEX["WRI_R"]]] == "WRI_L"
    assert MIRROR[skeleton.INDEX["NECK"]] == skeleton.INDEX["NECK"]
    np.testing.assert_array_equal(MIRROR[MIRROR], np.arange(skeleton.J))


def test_flips_are_found_where_the_labels_swap_and_nowhere_else() -> None:
    truth = simulate_truth("side_step", 2, seed=0)
    pos = truth.positions.copy()
    pos[40:46] = pos[40:46][:, MIRROR]
    assert np.flatnonzero(labelling_flips(pos)).tolist() == [40, 46]
    assert not labelling_flips(truth.positions).any()


def _split_stance(rec: Recording) -> Recording:
    """Returns rec with the left foot 0.3 m back and the right one 0.3 m forward (knee, ankle, foot; along the
    camera's axis): legs that fit the previous frame far worse mirrored than a swap of the arms does, as in the side
    view's frames where the landmarker swapped the arms alone (label_swaps' docstring)."""
    pos = rec.positions.copy()
    for side, dz in (("L", 0.3), ("R", -0.3)):
        pos[:, [skeleton.INDEX[f"{n}_{side}"] for n in ("KNE", "ANK", "FOO")], 2] += dz
    return rec.replace(positions=pos)


def test_arm_swaps_are_found_where_the_arms_alone_swap_and_nowhere_else() -> None:
    truth = _split_stance(simulate_truth("elbow_flexion", 2, seed=0))
    pos = truth.positions.copy()
    pos[40:46, ARMS] = pos[40:46][:, MIRROR[ARMS]]
    assert not labelling_flips(pos).any(), "the whole body's test does not see them: the legs outweigh the arms"
    assert np.flatnonzero(pair_swaps(pos)).tolist() == [40, 46]
    assert not pair_swaps(truth.positions).any()


def test_another_body_is_a_jump_and_walking_is_not() -> None:
    truth = simulate_truth("side_step", 2, seed=0)
    pos = truth.positions.copy()
    assert not body_jumps(pos, truth.t, 2.0, 0.06).any()
    pos[30:] += np.array([0.8, 0.0, 0.5])  # someone else, 0.8 m to the side, taken for the patient
    assert np.flatnonzero(body_jumps(pos, truth.t, 2.0, 0.06)).tolist() == [30]


def _angle_rmse_change(est: np.ndarray, raw: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """Returns {angle: RMSE(est) - RMSE(raw)} in degrees against the truth, over the frames all three define."""
    a_est, a_raw, a_true = joint_angles(est), joint_angles(raw), joint_angles(truth)
    out = {}
    for name, true in a_true.items():
        m = np.isfinite(a_est[name]) & np.isfinite(a_raw[name]) & np.isfinite(true)
        if m.sum() > 10:
            rmse = [float(np.sqrt(np.mean((a[name][m] - true[m]) ** 2))) for a in (a_est, a_raw)]
            out[name] = rmse[0] - rmse[1]
    return out


@pytest.mark.parametrize(("exercise", "seed"), [("squat", 0), ("shoulder_abduction", 1), ("side_step", 2)])
def test_the_webcam_pipeline_makes_no_angle_worse_than_its_input(exercise: str, seed: int) -> None:
    truth = simulate_truth(exercise, 2, seed=seed)
    raw = webcam_like(truth, seed)
    filtered = process(raw, config=config_for_device("webcam")).filtered.positions
    change = _angle_rmse_change(filtered, raw.positions, truth.positions)
    worse = {k: round(v, 2) for k, v in change.items() if v > TOL_DEG}
    assert not worse, f"angles worse after the pipeline (deg): {worse}"
    assert np.mean(list(change.values())) < 0, "the filter should also make the angles better on average"


def test_smoothing_across_the_swaps_would_make_angles_worse() -> None:
    """The property above can fail: without the restarts at label swaps the same filter breaks it."""
    truth = simulate_truth("squat", 2, seed=0)
    raw = webcam_like(truth, 0)
    config = config_for_device("webcam").model_copy(update={"joint_split_at_swaps": False})
    filtered, _ = smooth_joints(raw, config)
    change = _angle_rmse_change(filtered, raw.positions, truth.positions)
    assert max(change.values()) > 1.0, change


@pytest.mark.parametrize(("exercise", "seed"), [("elbow_flexion", 0), ("squat", 1), ("elbow_flexion", 2)])
def test_no_angle_is_made_worse_where_the_arms_alone_swap(exercise: str, seed: int) -> None:
    truth = _split_stance(simulate_truth(exercise, 2, seed=seed))
    raw = webcam_like(truth, seed, arms_only=True)
    filtered = process(raw, config=config_for_device("webcam")).filtered.positions
    change = _angle_rmse_change(filtered, raw.positions, truth.positions)
    worse = {k: round(v, 2) for k, v in change.items() if v > TOL_DEG}
    assert not worse, f"angles worse after the pipeline (deg): {worse}"


def test_smoothing_across_the_arm_swaps_would_make_angles_worse() -> None:
    """Without the restarts at the arms' swaps the same input breaks the property: the smoothed shoulders' line
    shrinks, the trunk's axes turn, and the hip's abduction (measured against them) moves."""
    truth = _split_stance(simulate_truth("elbow_flexion", 2, seed=2))
    raw = webcam_like(truth, 2, arms_only=True)
    config = config_for_device("webcam").model_copy(update={"joint_arm_swaps": False})
    change = _angle_rmse_change(smooth_joints(raw, config)[0], raw.positions, truth.positions)
    assert max(change.values()) > 0.5, change
