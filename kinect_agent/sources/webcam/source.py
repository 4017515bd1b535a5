"""An ordinary camera (or a video file) as a capture source: MediaPipe's Python runtime runs the pinned BlazePose
landmarker (kinect_agent.vendor, the same `.task` the browser page loads) on each image, and
kinect_agent.sources.webcam.mapping turns its landmarks into the 20 joints in the Kinect camera frame.

`mediapipe` and OpenCV (the `webcam` extra) are imported inside open(), so this module loads everywhere and open()
raises DeviceUnavailable with one line saying what is missing: the packages, the model files, the camera, the video.
When the model sees more than one person, the patient is the one whose hips are nearest to where the patient's were
(image coordinates), the largest one at the start, so a person walking past is not recorded instead. The landmarker is
a company watch (kinect_agent.sources.webcam.company): it tracks one person on every image and looks for a second one
once a second, or on every image while one is in view.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent.errors import DeviceUnavailable
from kinect_agent.recording import Metadata
from kinect_agent.sources.base import Frame, Pacer, SourceBase
from kinect_agent.sources.webcam.company import TWO_DETECTION_CONFIDENCE, CompanyWatch, VideoLandmarker
from kinect_agent.sources.webcam.header import webcam_header
from kinect_agent.sources.webcam.landmarks import N_LANDMARKS, LandmarkBatch, check_arrays
from kinect_agent.sources.webcam.mapping import DEFAULT_FOV_DEG, to_skeletons
from kinect_agent.vendor import VendorError, model_info, task_path

INSTALL_HINT = "webcam capture needs the 'webcam' extra: pip install '.[agent,webcam]' (MediaPipe and OpenCV)"
MAX_PEOPLE = 2  # the watch's second landmarker looks for this many, so the patient can be told from a second person
FIRST_FRAME_TIMEOUT_S = 5.0


def import_runtime() -> tuple[Any, Any, Any]:
    """Returns (cv2, mediapipe, mediapipe.tasks.python.vision); raises DeviceUnavailable."""
    os.environ.setdefault("GLOG_minloglevel", "2")  # MediaPipe's per-frame native warnings: errors only
    try:
        import cv2
        import mediapipe
        from mediapipe.tasks.python import vision
    except ImportError as exc:
        raise DeviceUnavailable(f"{INSTALL_HINT}; importing {exc.name or 'it'} failed") from exc
    return cv2, mediapipe, vision


def landmarker_options(mp: Any, vision: Any, model_path: Path, *, image_mode: bool = False,
                       people: int = MAX_PEOPLE, detection: float = 0.5) -> Any:  # fmt: skip
    """Returns the PoseLandmarkerOptions of the agent's landmarkers (the page's worker, camera_pose_core.js, sets the
    same): VIDEO mode (tracking from image to image, smoothed) unless image_mode, looking for `people` people (the
    watch's `one` 1, its `two` MAX_PEOPLE), person detection threshold `detection` (MediaPipe's default 0.5; the
    watch's `two` TWO_DETECTION_CONFIDENCE), MediaPipe's default presence and tracking thresholds (0.5)."""
    return vision.PoseLandmarkerOptions(
        base_options=mp.tasks.BaseOptions(model_asset_path=str(model_path)),
        running_mode=vision.RunningMode.IMAGE if image_mode else vision.RunningMode.VIDEO,
        num_poses=people,
        min_pose_detection_confidence=detection,
    )


@contextlib.contextmanager
def _native_stderr_silenced() -> Iterator[None]:
    """Sends file descriptor 2 to /dev/null for a moment: TFLite prints ~50 lines when it loads the models (one per
    sparse tensor, and its accelerator set-up), which would bury the agent's own lines. Python errors still carry
    their message."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no real stderr (a test's capture, a service without one)
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


class LandmarkFrame:
    """One analysed image: t s; world, image (33, 3); visibility (33,) (kinect_agent.sources.webcam.landmarks)."""

    __slots__ = ("t", "world", "image", "visibility")

    def __init__(self, t: float, world: np.ndarray, image: np.ndarray, visibility: np.ndarray) -> None:
        self.t, self.world, self.image, self.visibility = t, world, image, visibility


def choose_person(people: list[np.ndarray], previous_hips: np.ndarray | None) -> int:
    """Returns the index of the patient among the people of one image.

    people: list of (33, 3) image landmarks (normalised). previous_hips: (2,) the patient's hip midpoint in the
    previous image, or None: then the person with the largest bounding box is taken.
    """
    if previous_hips is None:
        areas = [float(np.ptp(p[:, 0]) * np.ptp(p[:, 1])) for p in people]
        return int(np.argmax(areas))
    hips = [p[[23, 24], :2].mean(axis=0) for p in people]
    return int(np.argmin([np.linalg.norm(h - previous_hips) for h in hips]))


class WebcamSource(SourceBase):
    """Yields the patient's skeleton for every image the landmarker finds them in (images without them yield no
    frame). camera: device index; video: a file played instead of a camera (timed by its frame rate, paced in real
    time when realtime); model: "lite" or "full"; fov_deg: the camera's assumed horizontal field of view; watch: the
    company watch (True), or one landmarker looking for MAX_PEOPLE on every image (False: the source before
    2026-11-28, kept for benchmarks that compare the two)."""

    name = "webcam"
    device = "webcam"

    def __init__(
        self,
        *,
        camera: int = 0,
        video: str | Path | None = None,
        model: str = "lite",
        fov_deg: float = DEFAULT_FOV_DEG,
        realtime: bool = True,
        watch: bool = True,
    ) -> None:
        self.camera = camera
        self.video = Path(video) if video is not None else None
        self.model = model
        self.fov_deg = fov_deg
        self.realtime = realtime
        self.watch = watch
        self.info = model_info(model)
        self.landmark_frames: list[LandmarkFrame] = []  # what the model gave for the frames yielded, in order
        self._cv2: Any = None
        self._mp: Any = None
        self._capture: Any = None
        self._landmarkers: list[Any] = []  # MediaPipe's: looking for 1 person, for MAX_PEOPLE
        self._landmarker: VideoLandmarker | None = None  # the watch, or (watch=False) one landmarker
        self._image_size: tuple[int, int] | None = None
        self._video_fps: float | None = None
        self._wall_s = 0.0  # seconds spent reading and analysing images
        self._images = 0  # images analysed
        self._hips: np.ndarray | None = None

    def open(self) -> None:
        """Opens the camera or video and the landmarker; raises DeviceUnavailable naming what is missing."""
        cv2, mp, vision = import_runtime()
        try:
            model_path = task_path(self.model)
        except VendorError as exc:
            raise DeviceUnavailable(str(exc)) from exc
        if self.video is not None:
            if not self.video.is_file():
                raise DeviceUnavailable(f"video file {self.video} does not exist")
            capture = cv2.VideoCapture(str(self.video))
            what = f"video file {self.video}"
        else:
            capture = cv2.VideoCapture(self.camera)
            what = f"camera {self.camera}"
        if not capture.isOpened():
            capture.release()
            raise DeviceUnavailable(f"{what} cannot be opened (is it connected, and not used by another program?)")
        if self.video is None:
            capture.set(cv2.CAP_PROP_BUFFERSIZE, 1)  # the newest image, not a queue of old ones
        fps = capture.get(cv2.CAP_PROP_FPS)
        self._video_fps = float(fps) if self.video is not None and fps and 1.0 <= fps <= 1000.0 else None
        if self.video is not None and self._video_fps is None:
            capture.release()
            raise DeviceUnavailable(f"{what} has no usable frame rate ({fps})")
        made: list[Any] = []
        try:
            with _native_stderr_silenced():
                kinds = ((1, 0.5), (MAX_PEOPLE, TWO_DETECTION_CONFIDENCE)) if self.watch else ((MAX_PEOPLE, 0.5),)
                for people, detection in kinds:
                    options = landmarker_options(mp, vision, model_path, people=people, detection=detection)
                    made.append(vision.PoseLandmarker.create_from_options(options))
        except (RuntimeError, ValueError) as exc:
            for landmarker in made:
                landmarker.close()
            capture.release()
            raise DeviceUnavailable(f"the pose model {model_path.name} did not load: {exc}") from exc
        self._landmarkers = made
        self._landmarker = CompanyWatch(*made) if self.watch else made[0]
        self._cv2, self._mp, self._capture = cv2, mp, capture

    def frames(self) -> Iterator[Frame]:
        """Yields one Frame per image in which the patient was found, until the video ends (or forever)."""
        if self._capture is None:
            raise RuntimeError("open() the source first")
        cv2, mp = self._cv2, self._mp
        pacer = Pacer(self.realtime and self.video is not None)
        index, start, last_ms = 0, time.monotonic(), -1
        while True:
            began = time.monotonic()
            ok, bgr = self._capture.read()
            if not ok:
                if self.video is not None:
                    return
                if self._images == 0 and time.monotonic() - start < FIRST_FRAME_TIMEOUT_S:
                    time.sleep(0.05)
                    continue
                raise DeviceUnavailable(f"camera {self.camera} stopped giving images (unplugged?)")
            t = index / self._video_fps if self._video_fps else time.monotonic()
            index += 1
            pacer.wait(t)
            ms = max(last_ms + 1, int(round(t * 1000)))  # the landmarker needs strictly increasing ms
            last_ms = ms
            height, width = bgr.shape[:2]
            self._image_size = (int(width), int(height))
            image = mp.Image(image_format=mp.ImageFormat.SRGB, data=cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
            assert self._landmarker is not None
            result = self._landmarker.detect_for_video(image, ms)
            self._images += 1
            self._wall_s += time.monotonic() - began
            frame = self._frame(t, result)
            if frame is not None:
                yield frame

    def _frame(self, t: float, result: Any) -> Frame | None:
        """Returns the patient's Frame of one landmarker result, or None when nobody was found."""
        if not result.pose_landmarks:
            return None
        people = [np.array([[p.x, p.y, p.z] for p in person]) for person in result.pose_landmarks]
        k = choose_person(people, self._hips)
        world = np.array([[p.x, p.y, p.z] for p in result.pose_world_landmarks[k]])
        visibility = np.clip([p.visibility if p.visibility is not None else 0.0 for p in result.pose_landmarks[k]],
                             0.0, 1.0)  # fmt: skip
        image = people[k]
        if world.shape != (N_LANDMARKS, 3) or not (np.isfinite(world).all() and np.isfinite(image).all()):
            return None
        self._hips = image[[23, 24], :2].mean(axis=0)
        assert self._image_size is not None
        batch = check_arrays(np.array([t]), world[None], image[None], visibility[None], self._image_size)
        mapped = to_skeletons(batch, self.fov_deg)
        self.landmark_frames.append(LandmarkFrame(t, world, image, visibility))
        return Frame(t, mapped.positions[0], mapped.state[0])

    def landmark_batch(self) -> LandmarkBatch:
        """Returns the landmarks of every frame yielded so far as one batch (the wire form the browser sends)."""
        if not self.landmark_frames or self._image_size is None:
            raise ValueError("no landmark frame yet")
        fr = self.landmark_frames
        return check_arrays(np.array([f.t for f in fr]), np.stack([f.world for f in fr]),
                            np.stack([f.image for f in fr]), np.stack([f.visibility for f in fr]),
                            self._image_size)  # fmt: skip

    @property
    def company_watch(self) -> CompanyWatch | None:
        """The company watch while open (None before open(), after close(), or with watch=False)."""
        return self._landmarker if isinstance(self._landmarker, CompanyWatch) else None

    @property
    def images(self) -> int:
        """Images read and analysed so far."""
        return self._images

    @property
    def fps_achieved(self) -> float | None:
        """Images read and analysed per second of wall time (None before the first)."""
        return self._images / self._wall_s if self._images and self._wall_s > 0 else None

    def close(self) -> None:
        """Releases the camera and the landmarker; safe to call twice."""
        for landmarker in self._landmarkers:
            landmarker.close()
        self._landmarkers, self._landmarker = [], None
        if self._capture is not None:
            self._capture.release()
            self._capture = None

    def metadata(self) -> Metadata:
        """Returns the device `webcam` with the model's name, version and SHA-256, and the frame rates."""
        webcam = webcam_header(model=self.model, runtime=f"mediapipe {getattr(self._mp, '__version__', '?')} (Python)",
                               fps_achieved=self.fps_achieved, image_size=self._image_size, fov_deg=self.fov_deg,
                               images=self._images)  # fmt: skip
        rate = self._video_fps
        if rate is None and len(self.landmark_frames) > 1:
            rate = (len(self.landmark_frames) - 1) / (self.landmark_frames[-1].t - self.landmark_frames[0].t)
        source = str(self.video) if self.video is not None else f"camera {self.camera}"
        return Metadata(device="webcam", rate_hz=rate, source=source, extra={"webcam": webcam})
