"""Microsoft Kinect v2 (Kinect for Windows SDK 2.0) as a live source, through the `pykinect2` package.

The SDK only exists on Windows; `pykinect2` is imported inside open(), so this module loads everywhere and
open() raises DeviceUnavailable with what to install when it cannot run. Kinect v2 camera space is already the
project's frame (metres, y up, z away from the sensor); its 25 joints map onto the 20 of the paper.
"""

from __future__ import annotations

import importlib
import sys
import time
from collections.abc import Iterator

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.recording import Metadata
from kinect_agent.sources.base import Frame, SourceBase

# Kinect v2 JointType index of each of our joints (SpineShoulder stands for the Kinect 1 shoulder centre).
JOINT_TYPE: dict[str, int] = {
    "ROOT": 0, "SPINE": 1, "NECK": 20, "HEAD": 3,
    "SHO_L": 4, "ELB_L": 5, "WRI_L": 6, "HAN_L": 7, "SHO_R": 8, "ELB_R": 9, "WRI_R": 10, "HAN_R": 11,
    "HIP_L": 12, "KNE_L": 13, "ANK_L": 14, "FOO_L": 15, "HIP_R": 16, "KNE_R": 17, "ANK_R": 18, "FOO_R": 19,
}  # fmt: skip
FIRST_FRAME_TIMEOUT_S = 5.0
INSTALL_HINT = (
    "Kinect v2 capture needs Windows 10/11 with the Kinect for Windows SDK 2.0 and the Python package "
    "'pykinect2' (pip install pykinect2)"
)


def _import_sdk():
    if sys.platform != "win32":
        raise DeviceUnavailable(f"{INSTALL_HINT}; this machine runs {sys.platform}, where the SDK does not exist")
    try:
        return importlib.import_module("pykinect2.PyKinectV2"), importlib.import_module("pykinect2.PyKinectRuntime")
    except ImportError as exc:
        raise DeviceUnavailable(f"{INSTALL_HINT}; importing it failed: {exc}") from exc


class KinectV2Source(SourceBase):
    """Yields the skeleton of the first tracked body, one frame per SDK body frame (30 Hz)."""

    name = "kinect_v2"
    device = "kinect2"

    def __init__(self) -> None:
        self._runtime = None
        self._v2 = None

    def open(self) -> None:
        """Starts the SDK runtime; raises DeviceUnavailable when the SDK is missing or no sensor is found."""
        v2, runtime_module = _import_sdk()
        try:
            runtime = runtime_module.PyKinectRuntime(v2.FrameSourceTypes_Body)
        except Exception as exc:  # the SDK raises COM errors of its own types
            raise DeviceUnavailable(f"the Kinect v2 runtime did not start ({exc}); is the sensor plugged in?") from exc
        deadline = time.monotonic() + FIRST_FRAME_TIMEOUT_S
        while not runtime.has_new_body_frame():
            if time.monotonic() > deadline:
                runtime.close()
                raise DeviceUnavailable(
                    f"no Kinect v2 sensor found: no body frame within {FIRST_FRAME_TIMEOUT_S:.0f} s "
                    "(check the USB 3 connection and the Kinect Configuration Verifier)"
                )
            time.sleep(0.01)
        self._runtime, self._v2 = runtime, v2

    def frames(self) -> Iterator[Frame]:
        """Yields frames forever; bodyless frames give all joints NaN with state 0."""
        if self._runtime is None:
            raise RuntimeError("KinectV2Source.frames() called before open()")
        while True:
            if not self._runtime.has_new_body_frame():
                time.sleep(0.002)
                continue
            now = time.monotonic()
            bodies = self._runtime.get_last_body_frame()
            yield Frame(now, *self._skeleton(bodies))

    def _skeleton(self, bodies) -> tuple[np.ndarray, np.ndarray]:
        pos = np.full((skeleton.J, 3), np.nan)
        state = np.zeros(skeleton.J, dtype=np.int8)
        body = next((b for b in getattr(bodies, "bodies", []) if b.is_tracked), None)
        if body is None:
            return pos, state
        for j, name in enumerate(skeleton.JOINTS):
            joint = body.joints[JOINT_TYPE[name]]
            state[j] = int(joint.TrackingState)
            if state[j] != skeleton.NOT_TRACKED:
                pos[j] = (joint.Position.x, joint.Position.y, joint.Position.z)
        return pos, state

    def close(self) -> None:
        """Stops the SDK runtime."""
        if self._runtime is not None:
            self._runtime.close()
            self._runtime = None

    def metadata(self) -> Metadata:
        """Returns the capture's metadata."""
        return Metadata(device=self.device, rate_hz=30.0, source="kinect_v2")
