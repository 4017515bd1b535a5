"""Azure Kinect and Orbbec Femto (through Orbbec's K4A wrapper) as a live source.

Device access is checked with `pyk4a`; skeletons come from the Azure Kinect Body Tracking SDK through
`pykinect_azure`. Both are imported inside open(), so this module loads everywhere and open() raises
DeviceUnavailable with what to install when it cannot run. Azure camera space (mm, x right, y down, z forward)
is turned into the project's frame (m, x left, y up, z forward, like Kinect v2) by negating x and y. Joint positions
come as the SDK's k4a_float3_t union (position.xyz.x ...). The patient is chosen among the tracked bodies by
body_choice.PatientChooser (by k4abt body id); frame times are the body frame's device timestamp (microseconds).

Orbbec Femto Bolt and Mega, the Azure Kinect's successors, run through this same path: Orbbec's K4A wrapper
(OrbbecSDK-K4A-Wrapper) stands in for the Azure Kinect Sensor SDK, and Microsoft's Body Tracking SDK does the
skeletons. Orbbec's own Python SDK (pyorbbecsdk) gives depth and colour images but no body tracking, so it cannot
feed this agent by itself.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Iterator
from types import ModuleType
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.recording import Metadata
from kinect_agent.sources.base import Frame, SourceBase
from kinect_agent.sources.body_choice import Body, PatientChooser

# k4abt joint index of each of our joints (NECK stands for the Kinect 1 shoulder centre).
K4ABT_JOINT: dict[str, int] = {
    "ROOT": 0, "SPINE": 1, "NECK": 3, "HEAD": 26,
    "SHO_L": 5, "ELB_L": 6, "WRI_L": 7, "HAN_L": 8, "SHO_R": 12, "ELB_R": 13, "WRI_R": 14, "HAN_R": 15,
    "HIP_L": 18, "KNE_L": 19, "ANK_L": 20, "FOO_L": 21, "HIP_R": 22, "KNE_R": 23, "ANK_R": 24, "FOO_R": 25,
}  # fmt: skip
# k4abt confidence (0 none, 1 low, 2 medium, 3 high) -> our state.
CONFIDENCE_STATE = np.array([skeleton.NOT_TRACKED, skeleton.INFERRED, skeleton.TRACKED, skeleton.TRACKED], np.int8)
INSTALL_HINT = (
    "Azure Kinect / Orbbec Femto capture needs the Azure Kinect Sensor SDK (for Femto: Orbbec's K4A wrapper) and "
    "the Body Tracking SDK on Windows or Ubuntu, plus the Python packages 'pyk4a' and 'pykinect_azure' "
    "(pip install pyk4a pykinect_azure)"
)


def _import(name: str) -> ModuleType:
    try:
        return importlib.import_module(name)
    except ImportError as exc:  # also OSError-free: a missing native library surfaces as ImportError in both
        raise DeviceUnavailable(f"{INSTALL_HINT}; importing {name} failed: {exc}") from exc
    except OSError as exc:
        raise DeviceUnavailable(f"{INSTALL_HINT}; the native library for {name} did not load: {exc}") from exc


class AzureKinectSource(SourceBase):
    """Yields the patient's skeleton (body_choice) from the Body Tracking SDK, one frame per capture (30 Hz), timed by
    the device."""

    name = "azure_kinect"

    def __init__(self, *, device: str = "azure_kinect", device_index: int = 0) -> None:
        if device not in ("azure_kinect", "femto"):
            raise ValueError(f"device must be azure_kinect or femto, got {device!r}")
        self.device, self.device_index = device, device_index
        self._camera = None
        self._tracker = None
        self._chooser = PatientChooser()

    def open(self) -> None:
        """Starts the camera and the body tracker; raises DeviceUnavailable when a part is missing."""
        pyk4a = _import("pyk4a")
        count = int(pyk4a.connected_device_count())
        if count <= self.device_index:
            raise DeviceUnavailable(
                f"no Azure Kinect / Femto device found (pyk4a sees {count} device(s), wanted index {self.device_index})"
            )
        pykinect = _import("pykinect_azure")
        try:
            pykinect.initialize_libraries(track_body=True)
            config = pykinect.default_configuration
            config.depth_mode = pykinect.K4A_DEPTH_MODE_NFOV_UNBINNED
            self._camera = pykinect.start_device(device_index=self.device_index, config=config)
            self._tracker = pykinect.start_body_tracker()
        except Exception as exc:  # the SDK wrappers raise plain Exceptions
            self.close()
            raise DeviceUnavailable(f"the Azure Kinect body tracker did not start: {exc}") from exc

    def frames(self) -> Iterator[Frame]:
        """Yields frames forever; frames without the patient give all joints NaN with state 0."""
        if self._tracker is None:
            raise RuntimeError("AzureKinectSource.frames() called before open()")
        while True:
            self._camera.update()
            body_frame = self._tracker.update()
            stamp = getattr(body_frame, "get_device_timestamp_usec", None)
            t = stamp() / 1e6 if stamp is not None else time.monotonic()
            bodies = [_body(body_frame, i) for i in range(int(body_frame.get_num_bodies()))]
            body = self._chooser.choose(bodies)
            if body is None:
                yield Frame(t, np.full((skeleton.J, 3), np.nan), np.zeros(skeleton.J, dtype=np.int8))
            else:
                yield Frame(t, body.positions, body.state)

    def close(self) -> None:
        """Stops the tracker and the camera."""
        self._chooser = PatientChooser()
        for part, stop in ((self._tracker, "destroy"), (self._camera, "close")):
            if part is not None and hasattr(part, stop):
                getattr(part, stop)()
        self._tracker = self._camera = None

    def metadata(self) -> Metadata:
        """Returns the capture's metadata."""
        return Metadata(device=self.device, rate_hz=30.0, source=self.name)


def _body(body_frame: Any, index: int) -> Body:
    """Returns body `index` of a k4abt body frame as a Body: the 20 joints in metres, project frame, confidence as
    state."""
    joints = body_frame.get_body_skeleton(index).joints
    pos = np.full((skeleton.J, 3), np.nan)
    state = np.zeros(skeleton.J, dtype=np.int8)
    for j, name in enumerate(skeleton.JOINTS):
        joint = joints[K4ABT_JOINT[name]]
        state[j] = CONFIDENCE_STATE[min(max(int(joint.confidence_level), 0), 3)]
        if state[j] != skeleton.NOT_TRACKED:
            p = joint.position.xyz
            pos[j] = (-p.x / 1000.0, -p.y / 1000.0, p.z / 1000.0)
    return Body(int(body_frame.get_body_id(index)), pos, state)
