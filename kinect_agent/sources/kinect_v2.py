"""Microsoft Kinect v2 (Kinect for Windows SDK 2.0) as a live source, through `pykinect2024` (or `pykinect2`).

The SDK only exists on Windows; the wrapper is imported inside open(), so this module loads everywhere and open()
raises DeviceUnavailable with what to install when it cannot run. The published `pykinect2` 0.1.0 (2015) does not
import on 64-bit Python 3.8+: it asserts the 32-bit size of a COM structure (sizeof(tagSTATSTG) == 72; it is 80) and
calls time.clock, removed in Python 3.8. `pykinect2024` (PyPI, the same wrapper with the size computed for the
platform and time.clock gone) imports; it and pykinect2 still build their body arrays with `numpy.object`, removed in
NumPy 1.24, so the alias is restored before they are imported. Kinect v2 camera space is already the project's
frame (metres, y up, z away from the sensor); its 25 joints map onto the 20 of the paper. The patient is chosen among
up to six tracked bodies (body_choice.PatientChooser); frame times are the SDK's RelativeTime (100 ns ticks).
"""

from __future__ import annotations

import importlib
import sys
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

# Kinect v2 JointType index of each of our joints (SpineShoulder stands for the Kinect 1 shoulder centre).
JOINT_TYPE: dict[str, int] = {
    "ROOT": 0, "SPINE": 1, "NECK": 20, "HEAD": 3,
    "SHO_L": 4, "ELB_L": 5, "WRI_L": 6, "HAN_L": 7, "SHO_R": 8, "ELB_R": 9, "WRI_R": 10, "HAN_R": 11,
    "HIP_L": 12, "KNE_L": 13, "ANK_L": 14, "FOO_L": 15, "HIP_R": 16, "KNE_R": 17, "ANK_R": 18, "FOO_R": 19,
}  # fmt: skip
FIRST_FRAME_TIMEOUT_S = 5.0
TICKS_PER_S = 10_000_000  # RelativeTime unit: 100 ns
INSTALL_HINT = (
    "Kinect v2 capture needs Windows 10/11 with the Kinect for Windows SDK 2.0 and the Python package "
    "'pykinect2024' (pip install pykinect2024; the older 'pykinect2' 0.1.0 does not import on 64-bit Python 3.8+)"
)
# (wrapper module, runtime module) in the order they are tried
WRAPPERS = (
    ("pykinect2024.PyKinect2024", "pykinect2024.PyKinectRuntime"),
    ("pykinect2.PyKinectV2", "pykinect2.PyKinectRuntime"),
)


def _import_sdk() -> tuple[ModuleType, ModuleType]:
    """Returns (wrapper module, runtime module) of the first wrapper that imports; raises DeviceUnavailable."""
    if sys.platform != "win32":
        raise DeviceUnavailable(f"{INSTALL_HINT}; this machine runs {sys.platform}, where the SDK does not exist")
    if "object" not in np.__dict__:
        np.object = object  # the wrappers' numpy.ndarray(..., dtype=numpy.object)
    failures = []
    for wrapper, runtime in WRAPPERS:
        try:
            return importlib.import_module(wrapper), importlib.import_module(runtime)
        except ModuleNotFoundError as exc:
            failures.append(f"{wrapper.split('.')[0]} is not installed ({exc.name})")
        except (ImportError, AssertionError, AttributeError, OSError) as exc:
            failures.append(f"{wrapper.split('.')[0]} did not import ({type(exc).__name__}: {exc})")
    raise DeviceUnavailable(f"{INSTALL_HINT}; {'; '.join(failures)}")


class KinectV2Source(SourceBase):
    """Yields the patient's skeleton (body_choice), one frame per SDK body frame (30 Hz), timed by the sensor."""

    name = "kinect_v2"
    device = "kinect2"

    def __init__(self) -> None:
        self._runtime: Any = None  # the SDK's runtime object (untyped)
        self._v2: ModuleType | None = None
        self._chooser = PatientChooser()

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
        """Yields frames forever, timed by the SDK's RelativeTime (s); frames without the patient give all joints
        NaN with state 0."""
        if self._runtime is None:
            raise RuntimeError("KinectV2Source.frames() called before open()")
        while True:
            if not self._runtime.has_new_body_frame():
                time.sleep(0.002)
                continue
            frame = self._runtime.get_last_body_frame()
            ticks = getattr(frame, "relative_time", None)
            t = ticks / TICKS_PER_S if ticks is not None else time.monotonic()
            sdk_bodies = getattr(frame, "bodies", None)
            sdk_bodies = [] if sdk_bodies is None else sdk_bodies
            body = self._chooser.choose([_body(b) for b in sdk_bodies if b.is_tracked])
            if body is None:
                yield Frame(t, np.full((skeleton.J, 3), np.nan), np.zeros(skeleton.J, dtype=np.int8))
            else:
                yield Frame(t, body.positions, body.state)

    def close(self) -> None:
        """Stops the SDK runtime."""
        self._chooser = PatientChooser()
        if self._runtime is not None:
            self._runtime.close()
            self._runtime = None

    def metadata(self) -> Metadata:
        """Returns the capture's metadata."""
        return Metadata(device=self.device, rate_hz=30.0, source="kinect_v2")


def _body(sdk_body: Any) -> Body:
    """Returns one tracked SDK body as a Body: the 20 joints, metres in camera space, TrackingState as state."""
    pos = np.full((skeleton.J, 3), np.nan)
    state = np.zeros(skeleton.J, dtype=np.int8)
    for j, name in enumerate(skeleton.JOINTS):
        joint = sdk_body.joints[JOINT_TYPE[name]]
        state[j] = min(max(int(joint.TrackingState), 0), 2)
        if state[j] != skeleton.NOT_TRACKED:
            pos[j] = (joint.Position.x, joint.Position.y, joint.Position.z)
    return Body(int(sdk_body.tracking_id), pos, state)
