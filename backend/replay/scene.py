"""The 3D replay of one session as a viser scene recording (a `.viser` file), built once and played in the browser.

The recording holds, frame by frame, the raw skeleton as the camera measured it (orange, outlier-flagged joints
marked by larger red points) and the filtered skeleton (blue), both switchable in the viewer's scene tree
(`/raw`, `/filtered`), a floor grid, and a default camera that shows the exercise: from the side for movements in
the sagittal plane (squats, leg raises), from the front for the others (abduction). viser's own client plays it
(play/pause, scrubbing, speed) from the app's origin, so no viewer process and no extra port serve patients' data.

Positions in the scene: metres, the body's ground frame: the Kinect camera frame (x side, y up, z away from the
camera) shifted so that the session's median ROOT sits above the origin and the feet stand on y = 0.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from backend.replay import socketless
from backend.session_texts import data_quality, work_budget
from kinect_agent import skeleton
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording

if TYPE_CHECKING:
    from viser import LineSegmentsHandle, PointCloudHandle, SceneApi

VERSION = "replay-1"  # stored with each recording; a new version rebuilds the stored ones on first use
RAW_COLOR = (214, 110, 20)  # orange
FILTERED_COLOR = (11, 79, 156)  # the pages' accent blue
OUTLIER_COLOR = (200, 0, 0)
MAX_RATE_HZ = 30.0  # frames played per second at most (a faster recording is thinned)
_BONES = np.asarray(skeleton.BONES)  # (19, 2) parent, child
# one build at a time per process (each holds a whole recording in memory)
_BUILD_LOCK = threading.Lock()


@dataclass(frozen=True)
class Replay:
    """One built recording: the `.viser` bytes and what it shows."""

    data: bytes
    n_frames: int
    duration_s: float
    view: str  # "side" | "front"


def bone_points(positions: np.ndarray) -> np.ndarray:
    """Returns the bones of one frame as line segments (19, 2, 3) float32, metres; untracked joints give NaN.

    positions: (20, 3) float, metres, NaN = untracked.
    """
    if positions.shape != (skeleton.J, 3):
        raise ValueError(f"positions must have shape ({skeleton.J}, 3), got {positions.shape}")
    return positions[_BONES].astype(np.float32)


def ground_frame(reference: np.ndarray) -> np.ndarray:
    """Returns the shift (3,) float, metres, that puts the median ROOT above the origin and the feet on y = 0.

    reference: (T, 20, 3) float, metres, camera frame, NaN = untracked.
    """
    root = np.nanmedian(reference[:, skeleton.INDEX["ROOT"], :], axis=0) if np.isfinite(reference).any() else None
    root = np.zeros(3) if root is None or not np.isfinite(root).all() else root
    feet = reference[:, [skeleton.INDEX["FOO_L"], skeleton.INDEX["FOO_R"]], 1]
    floor = float(np.nanpercentile(feet, 2)) if np.isfinite(feet).any() else float(np.nanmin(reference[..., 1]))
    return np.array([root[0], floor, root[2]])


Point3 = tuple[float, float, float]


def camera_pose(reference: np.ndarray, plane: str) -> tuple[Point3, Point3, str]:
    """Returns (camera position (3,), look-at point (3,), "side" | "front"), metres, ground frame.

    The body's sides come from the median shoulder axis, so a patient standing at an angle to the Kinect is still
    seen from their side or their front. reference: (T, 20, 3) float, metres, ground frame.
    plane: the exercise's plane ("sagittal" → side view, else front view).
    """
    axis = np.nanmedian(reference[:, skeleton.INDEX["SHO_R"]] - reference[:, skeleton.INDEX["SHO_L"]], axis=0)
    side = np.array([axis[0], 0.0, axis[2]]) if np.isfinite(axis).all() else np.array([1.0, 0.0, 0.0])
    side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-6 else np.array([1.0, 0.0, 0.0])
    toward_kinect = np.cross(side, [0.0, 1.0, 0.0])  # the way the patient faces (towards the camera)
    if toward_kinect[2] > 0:  # the Kinect is at negative z of the patient; keep the front camera on its side
        toward_kinect = -toward_kinect
    view = "side" if plane == "sagittal" else "front"
    direction = side if view == "side" else toward_kinect
    centre = np.nanmedian(reference[:, skeleton.INDEX["SPINE"], 1]) if np.isfinite(reference).any() else np.nan
    look_at = np.array([0.0, float(centre) if np.isfinite(centre) else 0.9, 0.0])  # the middle of the body
    position = look_at + 2.4 * direction + np.array([0.0, 0.3, 0.0])
    return _point(position), _point(look_at), view


def _point(v: np.ndarray) -> Point3:
    return float(v[0]), float(v[1]), float(v[2])


def outlier_flags(raw: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, 20) bool: the raw samples the agent's outlier step removes (mixture model + excursions), as the
    session page's tracking-error strip computes them (data_quality.outlier_probabilities)."""
    config = config or PipelineConfig()
    prob = data_quality.outlier_probabilities(raw, config)
    return (prob > config.outlier_threshold) & np.isfinite(raw.positions).all(axis=2)


def frame_indices(t: np.ndarray, max_rate_hz: float = MAX_RATE_HZ) -> np.ndarray:
    """Returns the indices (K,) of the frames to play: every frame, thinned to at most max_rate_hz.

    t: (T,) float, seconds, increasing.
    """
    if len(t) < 2:
        return np.arange(len(t))
    period = float(np.median(np.diff(t)))
    step = max(1, int(round((1.0 / max_rate_hz) / period))) if period > 0 else 1
    return np.arange(0, len(t), step)


LAYERS = ("raw", "filtered")  # the skeletons a recording can hold


def build(payload: SessionPayload, plane: str, layers: tuple[str, ...] = LAYERS) -> Replay:
    """Returns the replay recording of a decoded session file.

    plane: the exercise's plane of movement ("sagittal", "frontal", "transverse"); picks the default camera.
    The outlier marks come from the server's own settings on the frames work_budget.thinned keeps (the file's
    params["config"] is not obeyed), so the build's work is bounded by the recording's duration.
    layers: the skeletons to show, of LAYERS (the replay page's two checkboxes); the camera is the same either way.
    """
    duration_s = payload.raw.duration if payload.raw.n_frames else 0.0
    payload = work_budget.thinned(payload)
    raw = payload.raw
    filtered = payload.filtered
    if filtered is not None and filtered.n_frames != raw.n_frames:
        filtered = None  # a file whose recordings disagree shows its raw skeleton only
    flags = np.zeros((raw.n_frames, skeleton.J), dtype=bool)
    if raw.n_frames >= 3:
        flags = outlier_flags(raw, work_budget.SERVER_PIPELINE)
    reference = filtered.positions if filtered is not None else raw.positions
    shift = ground_frame(reference)
    raw_pos = raw.positions - shift
    filt_pos = filtered.positions - shift if filtered is not None else None
    camera, look_at, view = camera_pose(filt_pos if filt_pos is not None else raw_pos, plane)
    t = raw.t - raw.t[0]
    keep = frame_indices(t)
    with _BUILD_LOCK:
        data = _record(t, keep, raw_pos if "raw" in layers else None,
                       filt_pos if "filtered" in layers else None, flags, camera, look_at)  # fmt: skip
    return Replay(data=data, n_frames=len(keep), duration_s=float(duration_s), view=view)


def _record(
    t: np.ndarray,
    keep: np.ndarray,
    raw: np.ndarray | None,
    filtered: np.ndarray | None,
    flags: np.ndarray,
    camera: Point3,
    look_at: Point3,
) -> bytes:
    """Plays the frames `keep` into a viser scene recording and returns its bytes.

    t: (T,) s from the start. raw, filtered: (T, 20, 3) metres, ground frame, NaN = untracked; None: not shown.
    flags: (T, 20) bool.
    """
    # viser 1.1.1 has no scene API without a server: this one listens on no socket (socketless.py)
    with socketless.recording_server() as server:
        serializer = server.get_scene_serializer()
        scene = server.scene
        scene.set_up_direction("+y")
        server.initial_camera.position = camera
        server.initial_camera.look_at = look_at
        scene.add_grid("/floor", width=4.0, height=4.0, plane="xz", cell_size=0.25, cell_color=(200, 200, 200))
        skeletons = [_Skeleton(scene, "/raw", RAW_COLOR, raw, flags)] if raw is not None else []
        if filtered is not None:
            skeletons.append(_Skeleton(scene, "/filtered", FILTERED_COLOR, filtered, None))
        for n, i in enumerate(keep):
            for sk in skeletons:
                sk.show(i)
            if n + 1 < len(keep):
                serializer.insert_sleep(float(t[keep[n + 1]] - t[i]))
        return serializer.serialize()


class _Skeleton:
    """One skeleton of the scene (bones as line segments, joints as points), updated frame by frame.

    The nodes are made once and their points replaced for each frame (viser sends only the changed property).
    """

    def __init__(
        self, scene: SceneApi, name: str, color: tuple[int, int, int], positions: np.ndarray, flags: np.ndarray | None
    ) -> None:
        self.positions = positions  # (T, 20, 3) metres, ground frame, NaN = untracked
        self.flags = flags  # (T, 20) bool or None
        self.bones = scene.add_line_segments(f"{name}/bones", _NOWHERE_BONE, color, thickness=0.025, visible=False)
        self.joints = scene.add_point_cloud(f"{name}/joints", _NOWHERE, color, point_size=0.045,
                                            point_shape="circle", visible=False)  # fmt: skip
        self.outliers = None
        if flags is not None:
            self.outliers = scene.add_point_cloud(f"{name}/outliers", _NOWHERE, OUTLIER_COLOR, point_size=0.09,
                                                  point_shape="circle", visible=False)  # fmt: skip

    def show(self, i: int) -> None:
        """Sends frame i: bones and joints (hidden when nothing is tracked), outlier marks when any is flagged."""
        pts = self.positions[i]
        ok = np.isfinite(pts).all(axis=1)
        bones = bone_points(pts)
        bones = bones[np.isfinite(bones).all(axis=(1, 2))]
        _update(self.bones, bones)
        _update(self.joints, pts[ok])
        if self.outliers is not None and self.flags is not None:
            _update(self.outliers, pts[self.flags[i] & ok])


def _update(node: PointCloudHandle | LineSegmentsHandle, points: np.ndarray) -> None:
    """Replaces the points of a scene node; hides it while there are none."""
    if len(points):
        node.points = points.astype(np.float32)
    if node.visible != bool(len(points)):
        node.visible = bool(len(points))


_NOWHERE = np.zeros((1, 3), dtype=np.float32)
_NOWHERE_BONE = np.zeros((1, 2, 3), dtype=np.float32)
