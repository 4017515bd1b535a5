"""The Kinect v2 and Azure Kinect / Femto adapters, proved without hardware: fake SDK modules with the real wrappers'
names and shapes (pykinect2024's runtime and body objects; pykinect_azure's k4abt ctypes structures, position as the
k4a_float3_t union) replay a real KERAAL Kinect v2 recording, with a bystander and a passer-by in the room.

Checked: the joint mapping and units against the KERAAL reader, tracking states and confidences, device timestamps,
and which body is taken for the patient; also what a user is told when only the broken pykinect2 0.1.0 is there.
"""

from __future__ import annotations

import ctypes
import itertools
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.errors import DeviceUnavailable
from kinect_agent.formats import keraal
from kinect_agent.recording import Recording
from kinect_agent.sources import azure_kinect, kinect_v2
from kinect_agent.sources.body_choice import STABLE_FRAMES

pytestmark = pytest.mark.shared_data

PATIENT_ID, BYSTANDER_ID, PASSER_ID = 72057594037928100, 72057594037928200, 72057594037928300
BYSTANDER_OFFSET = np.array([1.3, 0.0, 1.1])  # m: on the sofa to the side, behind
TICKS_PER_FRAME = 333_333  # 100 ns ticks at 30 Hz


def _recording(data_dir: Path) -> tuple[np.ndarray, np.ndarray, Recording]:
    """Returns the first KERAAL Kinect pair file as (25-joint xyz (T, 25, 3) m, states (T, 25), its reading)."""
    path = sorted((data_dir / "keraal" / "kinect_vicon_pairs").glob("*Kinect*.txt"))[0]
    values = np.loadtxt(path).reshape(-1, 25, 7)[:, :, :3]
    lost = np.all(values == 0.0, axis=-1)
    state = np.where(lost, 0, 2).astype(np.int8)
    state[::7, 7] = np.where(lost[::7, 7], 0, 1)  # now and then an inferred left hand
    return values, state, keraal.read(path)


def _passer(frame: int) -> bool:
    """A person walking past, centred and nearer than the patient, in frames 40-49."""
    return 40 <= frame < 50


# ---------------------------------------------------------------------------------------------- Kinect v2 fakes


class _V2Joint:
    def __init__(self, xyz, tracking_state: int) -> None:
        self.Position = types.SimpleNamespace(x=float(xyz[0]), y=float(xyz[1]), z=float(xyz[2]))
        self.TrackingState = tracking_state


class _V2Body:
    def __init__(self, tracking_id: int, xyz: np.ndarray | None, state: np.ndarray | None) -> None:
        self.is_tracked = xyz is not None
        self.tracking_id = tracking_id if self.is_tracked else -1
        if xyz is not None and state is not None:
            self.joints = [_V2Joint(xyz[k], int(state[k])) for k in range(25)]


def _v2_modules(values: np.ndarray, state: np.ndarray) -> dict[str, types.ModuleType]:
    """pykinect2024's two modules: the wrapper's constants and a runtime whose body frames replay the recording
    (six body slots as the SDK gives them; the bystander in the first slot, the patient in the fourth)."""
    body_source = 32  # FrameSourceTypes_Body
    wrapper = _module("pykinect2024.PyKinect2024", FrameSourceTypes_Body=body_source, JointType_Count=25)
    frames = []
    for i in range(len(values)):
        slots = [_V2Body(0, None, None) for _ in range(6)]
        slots[0] = _V2Body(BYSTANDER_ID, values[i] + BYSTANDER_OFFSET, np.full(25, 2))
        slots[3] = _V2Body(PATIENT_ID, values[i], state[i])
        if _passer(i):
            slots[5] = _V2Body(PASSER_ID, values[i] - values[i, 0] + [0.02, 0.0, 1.2], np.full(25, 2))
        stamp = 9_000_000 + i * TICKS_PER_FRAME
        frames.append(types.SimpleNamespace(bodies=np.array(slots, dtype=object), relative_time=stamp))

    class PyKinectRuntime:
        def __init__(self, frame_source_types: int) -> None:
            assert frame_source_types == body_source
            self.queue = list(frames)

        def has_new_body_frame(self) -> bool:
            return bool(self.queue)

        def get_last_body_frame(self):
            return self.queue.pop(0)

        def close(self) -> None:
            self.queue = []

    runtime = _module("pykinect2024.PyKinectRuntime", PyKinectRuntime=PyKinectRuntime)
    return {"pykinect2024": types.ModuleType("pykinect2024"), "pykinect2024.PyKinect2024": wrapper,
            "pykinect2024.PyKinectRuntime": runtime}  # fmt: skip


def _module(name: str, **attributes: object) -> types.ModuleType:
    """Returns a module named `name` holding `attributes` (a fake of one of an SDK's modules)."""
    module = types.ModuleType(name)
    module.__dict__.update(attributes)
    return module


def _install(monkeypatch, modules: dict[str, types.ModuleType]) -> None:
    for name, module in modules.items():
        monkeypatch.setitem(sys.modules, name, module)


def _take(source, n: int):
    source.open()
    try:
        return list(itertools.islice(source.frames(), n))
    finally:
        source.close()


def _expected(reading, i: int) -> tuple[np.ndarray, np.ndarray]:
    return reading.positions[i], reading.state[i]


def test_kinect_v2_maps_joints_states_and_sensor_time_and_follows_the_patient(data_dir, monkeypatch) -> None:
    values, state, reading = _recording(data_dir)
    _install(monkeypatch, _v2_modules(values, state))
    monkeypatch.setattr(sys, "platform", "win32")  # kinect_v2 reads sys.platform
    n = 120
    frames = _take(kinect_v2.KinectV2Source(), n)
    assert len(frames) == n
    np.testing.assert_allclose([f.t for f in frames], (9_000_000 + np.arange(n) * TICKS_PER_FRAME) / 1e7)
    for i, frame in enumerate(frames):  # the patient in every frame: not the bystander, not the passer-by
        positions, expected_state = _expected(reading, i)
        tracked = expected_state != skeleton.NOT_TRACKED
        np.testing.assert_allclose(frame.positions[tracked], positions[tracked], atol=1e-9, err_msg=f"frame {i}")
        assert np.all(np.isnan(frame.positions[~tracked]))
        assert np.array_equal(frame.state != 0, tracked), i
    han_l = skeleton.INDEX["HAN_L"]
    assert {int(f.state[han_l]) for f in frames[::7]} <= {0, 1} and any(f.state[han_l] == 1 for f in frames[::7])


def test_only_the_broken_pykinect2_says_which_package_works(monkeypatch, tmp_path) -> None:
    """pykinect2 0.1.0 asserts the 32-bit size of tagSTATSTG on import; the user is told to install pykinect2024."""
    package = tmp_path / "pykinect2"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "PyKinectV2.py").write_text("assert 80 == 72, 80  # sizeof(tagSTATSTG) on 64-bit Python\n")
    (package / "PyKinectRuntime.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in [m for m in sys.modules if m.startswith(("pykinect2", "pykinect2024"))]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "pykinect2024", None)  # not installed
    monkeypatch.setattr(sys, "platform", "win32")  # kinect_v2 reads sys.platform
    with pytest.raises(DeviceUnavailable) as refused:
        kinect_v2.KinectV2Source().open()
    message = str(refused.value)
    assert "pip install pykinect2024" in message and "pykinect2 did not import (AssertionError: 80)" in message


# ---------------------------------------------------------------------------------------------- Azure fakes
# ctypes layouts as pykinect_azure 0.0.4 declares them (k4a/_k4atypes.py, k4abt/_k4abtTypes.py)


class _Xyz(ctypes.Structure):
    _fields_ = [("x", ctypes.c_float), ("y", ctypes.c_float), ("z", ctypes.c_float)]


class _Float3(ctypes.Union):
    _fields_ = [("xyz", _Xyz), ("v", ctypes.c_float * 3)]


class _Quaternion(ctypes.Structure):
    _fields_ = [("w", ctypes.c_float), ("x", ctypes.c_float), ("y", ctypes.c_float), ("z", ctypes.c_float)]


class _K4abtJoint(ctypes.Structure):
    _fields_ = [("position", _Float3), ("orientation", _Quaternion), ("confidence_level", ctypes.c_int)]


class _K4abtSkeleton(ctypes.Structure):
    _fields_ = [("joints", _K4abtJoint * 32)]


def _k4abt_skeleton(xyz_m: np.ndarray, confidence: np.ndarray) -> _K4abtSkeleton:
    """Our 20 joints (project frame, m) as a k4abt skeleton (Azure frame, mm); other k4abt joints stay zero."""
    sk = _K4abtSkeleton()
    for j, name in enumerate(skeleton.JOINTS):
        k = azure_kinect.K4ABT_JOINT[name]
        if np.all(np.isfinite(xyz_m[j])):
            x, y, z = xyz_m[j]
            sk.joints[k].position.xyz = _Xyz(-x * 1000.0, -y * 1000.0, z * 1000.0)
        sk.joints[k].confidence_level = int(confidence[j])
    return sk


def _azure_modules(reading, count: int = 1) -> dict[str, types.ModuleType]:
    confidence = np.where(reading.state == 0, 0, 2)  # medium where tracked
    confidence[::5, skeleton.INDEX["WRI_R"]] = np.where(reading.state[::5, skeleton.INDEX["WRI_R"]] == 0, 0, 1)
    confidence[::3, skeleton.INDEX["HEAD"]] = 3
    frames = []
    for i in range(reading.n_frames):
        bodies = [(BYSTANDER_ID % 1000, _k4abt_skeleton(reading.positions[i] + BYSTANDER_OFFSET, np.full(20, 2)))]
        if _passer(i):
            passer = reading.positions[i] - reading.positions[i, 0] + [0.02, 0.0, 1.2]
            bodies.append((PASSER_ID % 1000, _k4abt_skeleton(passer, np.full(20, 2))))
        bodies.insert(1, (PATIENT_ID % 1000, _k4abt_skeleton(reading.positions[i], confidence[i])))
        frames.append((1_500_000 + i * 33_333, bodies))

    class BodyFrame:
        def __init__(self, stamp_us: int, bodies) -> None:
            self.stamp_us, self.bodies = stamp_us, bodies

        def get_num_bodies(self) -> int:
            return len(self.bodies)

        def get_body_skeleton(self, index: int = 0) -> _K4abtSkeleton:
            return self.bodies[index][1]

        def get_body_id(self, index: int = 0) -> int:
            return self.bodies[index][0]

        def get_device_timestamp_usec(self) -> int:
            return self.stamp_us

    queue = list(frames)
    device = types.SimpleNamespace(update=lambda: None, close=lambda: None)
    tracker = types.SimpleNamespace(update=lambda: BodyFrame(*queue.pop(0)), destroy=lambda: None)
    pykinect = _module(
        "pykinect_azure",
        K4A_DEPTH_MODE_NFOV_UNBINNED=2,
        default_configuration=types.SimpleNamespace(depth_mode=0),
        initialize_libraries=lambda track_body=False: None,
        start_device=lambda device_index=0, config=None: device,
        start_body_tracker=lambda: tracker,
    )
    pyk4a = _module("pyk4a", connected_device_count=lambda: count)
    return {"pykinect_azure": pykinect, "pyk4a": pyk4a}


@pytest.mark.parametrize("device", ["azure_kinect", "femto"])
def test_azure_kinect_and_femto_map_millimetres_confidence_and_device_time(data_dir, monkeypatch, device) -> None:
    _, _, reading = _recording(data_dir)
    _install(monkeypatch, _azure_modules(reading))
    n = 120
    frames = _take(azure_kinect.AzureKinectSource(device=device), n)
    np.testing.assert_allclose([f.t for f in frames], (1_500_000 + np.arange(n) * 33_333) / 1e6)
    wri_r, head = skeleton.INDEX["WRI_R"], skeleton.INDEX["HEAD"]
    for i, frame in enumerate(frames):
        tracked = reading.state[i] != skeleton.NOT_TRACKED
        np.testing.assert_allclose(frame.positions[tracked], reading.positions[i][tracked], atol=1e-4,
                                   err_msg=f"frame {i}: mm -> m, x and y negated")  # fmt: skip
        assert np.all(np.isnan(frame.positions[~tracked])) and np.array_equal(frame.state != 0, tracked)
        if tracked[wri_r]:
            assert frame.state[wri_r] == (skeleton.INFERRED if i % 5 == 0 else skeleton.TRACKED)
        if tracked[head]:
            assert frame.state[head] == skeleton.TRACKED  # high confidence is tracked too


def test_no_azure_device_is_said_plainly(monkeypatch, data_dir) -> None:
    _, _, reading = _recording(data_dir)
    _install(monkeypatch, _azure_modules(reading, count=0))
    with pytest.raises(DeviceUnavailable, match="no Azure Kinect / Femto device found"):
        azure_kinect.AzureKinectSource().open()


def test_a_stable_patient_is_not_taken_over_by_someone_more_centred(data_dir) -> None:
    """The chooser on its own: the passer-by is centred and nearer, but comes after the patient was followed for
    STABLE_FRAMES frames; the bystander is tracked all along but sits to the side and behind."""
    from kinect_agent.sources.body_choice import Body, PatientChooser

    _, _, reading = _recording(data_dir)
    chooser = PatientChooser()
    for i in range(60):
        p = reading.positions[i]
        bodies = [Body(2, p + BYSTANDER_OFFSET, np.full(20, 2)), Body(1, p, reading.state[i])]
        if i >= STABLE_FRAMES + 5:
            bodies.append(Body(3, p - p[0] + [0.0, 0.0, 1.0], np.full(20, 2)))
        chosen = chooser.choose(bodies)
        assert chosen is not None and chosen.tracking_id == 1, i
    chosen = chooser.choose([Body(2, p + BYSTANDER_OFFSET, np.full(20, 2))])
    assert chosen is not None and chosen.tracking_id == 2  # the patient left
