"""The patient's landmarker, and a look for anyone else in view, at a fraction of the cost of looking on every image.

MediaPipe's pose landmarker in VIDEO mode runs its person detector on an image only while it tracks fewer people than
it looks for (num_poses); otherwise it follows each person from the previous image's landmarks. Looking for two
people when one is in view therefore runs the detector on every image: half the speed (bench/README.md, "Webcam":
lite 16.9 against 8.2 images/s in the Python runtime). So two landmarkers of the same model:

- `one` (num_poses 1) on every image while the patient is alone: it tracks, and detects only when it lost the person;
- `two` (num_poses 2) on the same image once every CHECK_S of the images' time stamps: when it finds two people the
  watch is "in company" and `two` runs on every image (and `one` on none) until it has found at most one person for
  ALONE_S: with two people in view the callers get both poses from a landmarker looking for two on every image, as
  before the watch, and their rules (the patient is the one nearest to where the patient was; "someone else is in
  the picture") work as they did.

A landmarker looking for two on every image had 15 tries a second at finding a second person; the watch has one.
BlazePose's detector scores a second, smaller person near its threshold (0.5): one look finds them in few images
(Pose2Sim's two-person demo as tests/fake_camera.py plays it: 0-5 of 50 images per view), so such a person is noticed
some seconds after they came into view (the patient is kept meanwhile: `one` follows one person, and the callers keep
the one nearest to where the patient was). A lower threshold for `two` (0.3) found them in 6-17 of 50 images with no
more false second people on one person alone, but then kept the watch in company on most images of the camera tests'
clip, where a second person stands on a hut: slower than looking for two on every image (6.0 against 8.5 frames/s):
not kept (TWO_DETECTION_CONFIDENCE; bench/README.md, "One person tracked, a look for a second").

The browser page runs the same logic (frontend/static/camera_pose_core.js) with one difference: in its worker,
`two`'s look runs in a second worker beside `one`'s tracking (it took 2-3 times a tracking image's time, one image a
second held up), so what a look finds takes effect from the first image after its answer, not on the image it looked
at. tests/kinect_agent/sources/webcam/test_company.py holds the two to the same constants.
"""

from __future__ import annotations

from typing import Any, Protocol

CHECK_S = 1.0  # alone: the look for a second person, at most this long apart (s of the images' time stamps)
ALONE_S = 1.0  # in company: back to the single tracker after this long without a second person (s)
TWO_DETECTION_CONFIDENCE = 0.5  # `two`'s min_pose_detection_confidence: MediaPipe's default, as `one`'s


class VideoLandmarker(Protocol):
    """What the watch needs of a MediaPipe PoseLandmarker in VIDEO mode."""

    def detect_for_video(self, image: Any, timestamp_ms: int) -> Any: ...


class CompanyWatch:
    """Runs `one` (looks for 1 person) or `two` (looks for 2) on each image, see the module's docstring.

    detect_for_video(image, ms) returns the MediaPipe result of the landmarker that answered (its pose_landmarks hold
    1 person at most unless a second one is in view); ms must increase strictly from call to call. runs counts the
    images each landmarker analysed."""

    def __init__(self, one: VideoLandmarker, two: VideoLandmarker, *, check_s: float = CHECK_S,
                 alone_s: float = ALONE_S) -> None:  # fmt: skip
        self.one, self.two = one, two
        self.check_ms, self.alone_ms = check_s * 1000.0, alone_s * 1000.0
        self.company = False
        self.runs = {"one": 0, "two": 0}
        self._checked_ms: float | None = None  # when `two` last looked (ms)
        self._two_seen_ms = 0.0  # when `two` last found two people (ms)

    def _two(self, image: Any, ms: int) -> Any:
        result = self.two.detect_for_video(image, ms)
        self.runs["two"] += 1
        self._checked_ms = ms
        if len(result.pose_landmarks) >= 2:
            self.company, self._two_seen_ms = True, ms
        return result

    def detect_for_video(self, image: Any, ms: int) -> Any:
        """Returns the landmarks of the people in the image at time stamp ms (see the class)."""
        if self.company:
            result = self._two(image, ms)
            if len(result.pose_landmarks) < 2 and ms - self._two_seen_ms >= self.alone_ms:
                self.company = False  # the next image goes to `one`; `two` looks again in check_ms
            return result
        result = self.one.detect_for_video(image, ms)
        self.runs["one"] += 1
        if self._checked_ms is None or ms - self._checked_ms >= self.check_ms:
            looked = self._two(image, ms)
            if self.company:  # someone else is in view: both people, as `two` sees them
                return looked
        return result
