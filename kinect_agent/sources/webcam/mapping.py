"""BlazePose's 33 landmarks -> the paper's 20 joints in the Kinect camera frame (docs/webcam.md has the figure).

Joints (BlazePose landmark numbers in brackets, "mid" = midpoint):
    ROOT   mid of the hips [23, 24]                  (Kinect v2 SpineBase)
    SPINE  ROOT + SPINE_FRACTION * (NECK - ROOT)     (SpineMid; the fraction measured on Kinect v2 recordings)
    NECK   mid of the shoulders [11, 12]             (SpineShoulder, the Kinect 1 shoulder centre)
    HEAD   mid of the ears [7, 8]                    (the Kinect's head joint is the centre of the head)
    SHO/ELB/WRI  shoulder, elbow, wrist [11/12, 13/14, 15/16]
    HAN    mid of the index and little-finger knuckles [19, 17] / [20, 18]  (Kinect HandLeft/Right: the palm)
    HIP/KNE/ANK  hip, knee, ankle [23/24, 25/26, 27/28]
    FOO    the toe point [31 / 32]                   (Kinect FootLeft/Right: the forefoot)
"_L" is the person's left in both models.

Frames: MediaPipe's world landmarks are metres around the hips in a camera-aligned frame (x image-right, y
image-down, z away from the camera); the Kinect camera frame of this project is x to the camera's left, y up, z away
(kinect_agent.skeleton): x and y change sign. The world landmarks carry no distance to the camera, so the hips are
placed where the image landmarks say, by a pinhole model: for each frame the translation T (m) that makes the
projections of world + T fit the image landmarks in the least-squares sense, weighted by visibility,

    f (X_i + Tx) = u_i (Z_i + Tz),   f (Y_i + Ty) = v_i (Z_i + Tz),   u_i, v_i pixels from the image centre,

with the focal length f = (width / 2) / tan(fov / 2) from an assumed horizontal field of view (DEFAULT_FOV_DEG,
typical of laptop and USB webcams; the true value is seldom known). The distance is only as good as that assumption
and the model's body-size prior: in-plane angles do not depend on it, distances in metres along z do
(kinect_agent.analysis.validity).

Tracking state from visibility (the model's estimate that a point is in view and not occluded): a joint takes the
smallest visibility of its landmarks; >= TRACKED_VISIBILITY -> tracked (2), >= INFERRED_VISIBILITY -> inferred (1),
below -> not tracked (0, NaN). A joint whose image point lies outside the image is inferred at best.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources.webcam.landmarks import LANDMARK, LandmarkBatch

DEFAULT_FOV_DEG = 65.0  # horizontal field of view assumed for an unknown webcam (typical: 60-78 deg)
SPINE_FRACTION = 0.57  # Kinect v2 SpineMid on SpineBase->SpineShoulder: median 0.570-0.573 on 9 KERAAL/UI-PRMD files
TRACKED_VISIBILITY = 0.6
INFERRED_VISIBILITY = 0.15
IMAGE_MARGIN = 0.02  # a point this far outside the image (fraction of its size) is not seen
MIN_DEPTH_M, MAX_DEPTH_M = 0.3, 15.0  # a fitted hip distance outside this range is not a person in front of a webcam
MIN_FIT_POINTS = 6  # landmarks with weight needed to place a frame

_L = LANDMARK
JOINT_LANDMARKS: dict[str, tuple[int, ...]] = {
    "ROOT": (_L["left_hip"], _L["right_hip"]),
    "NECK": (_L["left_shoulder"], _L["right_shoulder"]),
    "HEAD": (_L["left_ear"], _L["right_ear"]),
    "SHO_L": (_L["left_shoulder"],), "ELB_L": (_L["left_elbow"],), "WRI_L": (_L["left_wrist"],),
    "HAN_L": (_L["left_index"], _L["left_pinky"]),
    "SHO_R": (_L["right_shoulder"],), "ELB_R": (_L["right_elbow"],), "WRI_R": (_L["right_wrist"],),
    "HAN_R": (_L["right_index"], _L["right_pinky"]),
    "HIP_L": (_L["left_hip"],), "KNE_L": (_L["left_knee"],), "ANK_L": (_L["left_ankle"],),
    "FOO_L": (_L["left_foot_index"],),
    "HIP_R": (_L["right_hip"],), "KNE_R": (_L["right_knee"],), "ANK_R": (_L["right_ankle"],),
    "FOO_R": (_L["right_foot_index"],),
}  # fmt: skip
SYNTHESISED = ("SPINE",)  # from ROOT and NECK
# (20, 33) averaging matrix: joint j = mean of its landmarks (SPINE row filled from ROOT and NECK's rows)
_ROOT_ROW = np.zeros(33)
_ROOT_ROW[list(JOINT_LANDMARKS["ROOT"])] = 0.5
_NECK_ROW = np.zeros(33)
_NECK_ROW[list(JOINT_LANDMARKS["NECK"])] = 0.5
MIX = np.zeros((skeleton.J, 33))
for _name, _ids in JOINT_LANDMARKS.items():
    MIX[skeleton.INDEX[_name], list(_ids)] = 1.0 / len(_ids)
MIX[skeleton.INDEX["SPINE"]] = (1 - SPINE_FRACTION) * _ROOT_ROW + SPINE_FRACTION * _NECK_ROW
USES = MIX > 0  # (20, 33): which landmarks each joint is made of
MEDIAPIPE_TO_KINECT = np.array([-1.0, -1.0, 1.0])  # x image-right -> camera's left, y down -> up, z unchanged


@dataclass(frozen=True)
class Skeletons:
    """Mapped frames. positions: (N, 20, 3) m, Kinect camera frame, NaN = not tracked; state: (N, 20) int8;
    hips: (N, 3) m, the fitted hip midpoint in the Kinect camera frame (NaN where a frame could not be placed)."""

    t: np.ndarray
    positions: np.ndarray
    state: np.ndarray
    hips: np.ndarray


def focal_px(width: int, fov_deg: float = DEFAULT_FOV_DEG) -> float:
    """Returns the focal length in pixels of an image `width` px wide with a horizontal field of view fov_deg."""
    if not 10.0 <= fov_deg <= 170.0:
        raise ValueError(f"fov_deg must be within 10..170 degrees, got {fov_deg}")
    return (width / 2.0) / float(np.tan(np.radians(fov_deg) / 2.0))


def hip_translation(batch: LandmarkBatch, fov_deg: float = DEFAULT_FOV_DEG) -> np.ndarray:
    """Returns (N, 3) m, the position of the hip midpoint in MediaPipe's camera-aligned frame (x right, y down,
    z away from the camera) that best explains the image landmarks (module docstring); NaN rows for frames with
    fewer than MIN_FIT_POINTS weighted landmarks or a distance outside MIN_DEPTH_M..MAX_DEPTH_M."""
    width, height = batch.image_size
    f = focal_px(width, fov_deg)
    u = (batch.image[..., 0] - 0.5) * width  # (N, 33) pixels from the centre
    v = (batch.image[..., 1] - 0.5) * height
    X, Y, Z = batch.world[..., 0], batch.world[..., 1], batch.world[..., 2]
    w = np.where(_inside(batch.image), batch.visibility, 0.0)
    w = np.where(w >= INFERRED_VISIBILITY, w, 0.0)
    # rows [f, 0, -u] . T = u Z - f X and [0, f, -v] . T = v Z - f Y, stacked per frame: A (N, 66, 3), b (N, 66)
    n = batch.n_frames
    A = np.zeros((n, 66, 3))
    A[:, :33, 0] = f
    A[:, :33, 2] = -u
    A[:, 33:, 1] = f
    A[:, 33:, 2] = -v
    b = np.concatenate([u * Z - f * X, v * Z - f * Y], axis=1)
    W = np.concatenate([w, w], axis=1)
    AtA = np.einsum("nki,nk,nkj->nij", A, W, A)
    Atb = np.einsum("nki,nk,nk->ni", A, W, b)
    ok = (w > 0).sum(axis=1) >= MIN_FIT_POINTS
    T = np.full((n, 3), np.nan)
    if ok.any():
        T[ok] = np.linalg.solve(AtA[ok], Atb[ok][..., None])[..., 0]
    bad = ~((T[:, 2] >= MIN_DEPTH_M) & (T[:, 2] <= MAX_DEPTH_M))
    T[bad] = np.nan
    return T


def joint_visibility(batch: LandmarkBatch) -> np.ndarray:
    """Returns (N, 20) the visibility of each joint: the smallest of its landmarks', kept just below
    TRACKED_VISIBILITY (inferred at best) where one of them lies outside the image by more than IMAGE_MARGIN."""
    vis = batch.visibility[:, None, :]  # (N, 1, 33)
    joint = np.min(np.where(USES[None], vis, np.inf), axis=-1)  # (N, 20)
    outside = ~_inside(batch.image)  # (N, 33)
    any_out = np.any(USES[None] & outside[:, None, :], axis=-1)
    return np.where(any_out, np.minimum(joint, np.nextafter(TRACKED_VISIBILITY, 0)), joint)


def to_skeletons(batch: LandmarkBatch, fov_deg: float = DEFAULT_FOV_DEG) -> Skeletons:
    """Maps a batch onto the 20 joints in the Kinect camera frame (module docstring)."""
    T = hip_translation(batch, fov_deg)  # (N, 3)
    local = np.einsum("jl,nlc->njc", MIX, batch.world)  # (N, 20, 3) around the hips, MediaPipe axes
    positions = (local + T[:, None, :]) * MEDIAPIPE_TO_KINECT
    vis = joint_visibility(batch)
    levels = [vis >= TRACKED_VISIBILITY, vis >= INFERRED_VISIBILITY]
    state = np.select(levels, [skeleton.TRACKED, skeleton.INFERRED], skeleton.NOT_TRACKED).astype(np.int8)
    state[~np.isfinite(T[:, 2])] = skeleton.NOT_TRACKED
    positions[state == skeleton.NOT_TRACKED] = np.nan
    return Skeletons(batch.t.copy(), positions, state, T * MEDIAPIPE_TO_KINECT)


def to_recording(batch: LandmarkBatch, meta: Metadata | None = None, fov_deg: float = DEFAULT_FOV_DEG) -> Recording:
    """Returns the batch as a Recording of the webcam device (times relative to the first frame)."""
    mapped = to_skeletons(batch, fov_deg)
    meta = meta or Metadata(device="webcam")
    meta.extra.setdefault("webcam", {})["fov_deg"] = fov_deg
    return Recording(mapped.t - mapped.t[0], mapped.positions, mapped.state, meta)


def _inside(image: np.ndarray) -> np.ndarray:
    """Returns (N, 33) whether each image landmark lies within the image (with IMAGE_MARGIN)."""
    xy = image[..., :2]
    return np.all((xy >= -IMAGE_MARGIN) & (xy <= 1 + IMAGE_MARGIN), axis=-1)
