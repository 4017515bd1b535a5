"""3D replay of a stored session: one viser server per session, started on demand, reused, closed when idle.

A viewer shows the session's filtered skeleton (the raw one when the file has no filtered recording): the 20
joints as points and the 19 bones of kinect_agent.skeleton as line segments, with Play/Pause, a frame slider and
the time. Positions: (T, 20, 3) float, metres, Kinect camera frame (x side, y up, z away from the camera).
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from kinect_agent import skeleton
from kinect_agent.formats.session_file import decode
from kinect_agent.recording import Recording

log = logging.getLogger(__name__)
BONE_COLOR = (11, 79, 156)  # the pages' accent blue
JOINT_COLOR = (161, 22, 27)


def free_port(host: str = "127.0.0.1") -> int:
    """Returns a TCP port that was free on host a moment ago."""
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def bone_points(positions: np.ndarray) -> np.ndarray:
    """Returns the bones of one frame as line segments (19, 2, 3) float32, metres; untracked joints give NaN.

    positions: (20, 3) float, metres, camera frame, NaN = untracked.
    """
    if positions.shape != (skeleton.J, 3):
        raise ValueError(f"positions must have shape ({skeleton.J}, 3), got {positions.shape}")
    bones = np.asarray(skeleton.BONES)  # (19, 2) parent, child
    return positions[bones].astype(np.float32)


@dataclass
class Viewer:
    """One running viser server showing one session."""

    session_id: int
    port: int
    server: object
    n_frames: int
    last_used: float = field(default_factory=time.monotonic)
    stop_event: threading.Event = field(default_factory=threading.Event)


class ReplayManager:
    """Starts a viser server per session on a free port on first use, reuses it, and stops it after idle_s seconds
    without a connected browser and without a new request."""

    def __init__(self, *, host: str = "127.0.0.1", idle_s: float = 600.0, check_every_s: float = 30.0) -> None:
        self.host = host
        self.idle_s = idle_s
        self.check_every_s = check_every_s
        self._viewers: dict[int, Viewer] = {}
        self._lock = threading.Lock()
        self._reaper: threading.Thread | None = None
        self._closed = threading.Event()

    def open(self, session_id: int, load: Callable[[], bytes]) -> Viewer:
        """Returns the viewer of a session, starting it with the file that load() returns when none runs."""
        with self._lock:
            viewer = self._viewers.get(session_id)
            if viewer is None:
                viewer = self._start(session_id, load())
                self._viewers[session_id] = viewer
            viewer.last_used = time.monotonic()
            if self._reaper is None or not self._reaper.is_alive():
                self._closed.clear()
                self._reaper = threading.Thread(target=self._reap_loop, name="replay-reaper", daemon=True)
                self._reaper.start()
            return viewer

    def close(self, session_id: int) -> None:
        """Stops the viewer of a session if one runs."""
        with self._lock:
            viewer = self._viewers.pop(session_id, None)
        if viewer is not None:
            self._stop(viewer)

    def close_all(self) -> None:
        """Stops every viewer and the idle check."""
        self._closed.set()
        with self._lock:
            viewers, self._viewers = list(self._viewers.values()), {}
        for viewer in viewers:
            self._stop(viewer)

    def running(self) -> list[int]:
        """Returns the ids of the sessions whose viewer runs."""
        with self._lock:
            return sorted(self._viewers)

    def close_idle(self, now: float | None = None) -> list[int]:
        """Stops the viewers unused for idle_s seconds (a connected browser counts as use); returns their ids."""
        now = time.monotonic() if now is None else now
        idle = []
        with self._lock:
            for sid, viewer in list(self._viewers.items()):
                if viewer.server.get_clients():  # type: ignore[attr-defined]
                    viewer.last_used = now
                elif now - viewer.last_used >= self.idle_s:
                    idle.append(self._viewers.pop(sid))
        for viewer in idle:
            self._stop(viewer)
        return [v.session_id for v in idle]

    def _reap_loop(self) -> None:
        while not self._closed.wait(self.check_every_s):
            try:
                self.close_idle()
            except Exception:  # noqa: BLE001 - the idle check must keep running
                log.exception("replay idle check failed")

    @staticmethod
    def _stop(viewer: Viewer) -> None:
        viewer.stop_event.set()
        try:
            viewer.server.stop()  # type: ignore[attr-defined]
        except Exception:  # noqa: BLE001 - already stopped
            log.debug("viser server of session %s stopped with an error", viewer.session_id, exc_info=True)

    def _start(self, session_id: int, data: bytes) -> Viewer:
        import viser

        payload = decode(data)
        rec = payload.filtered if payload.filtered is not None else payload.raw
        port = free_port(self.host)
        server = viser.ViserServer(host=self.host, port=port, label=f"Session {session_id}", verbose=False)
        viewer = Viewer(session_id=session_id, port=port, server=server, n_frames=len(rec.t))
        try:
            _build_scene(server, rec, "filtered" if payload.filtered is not None else "raw", viewer.stop_event)
        except Exception:
            server.stop()
            raise
        log.info("replay of session %s on port %s (%s frames)", session_id, port, len(rec.t))
        return viewer


def _build_scene(server, rec: Recording, which: str, stop: threading.Event) -> None:
    """Adds the skeleton, the floor grid and the playback controls to a viser server and starts playback."""
    positions = rec.positions  # (T, 20, 3) metres, camera frame
    t = rec.t - rec.t[0]  # (T,) s
    n = len(t)
    centre = np.nanmedian(positions[:, 0, :], axis=0)  # ROOT over the session
    centre = np.where(np.isfinite(centre), centre, 0.0)
    floor_y = float(np.nanmin(positions[..., 1])) if np.isfinite(positions[..., 1]).any() else 0.0
    shifted = positions - np.array([centre[0], floor_y, centre[2]])  # feet on y = 0, body above the origin

    server.scene.set_up_direction("+y")
    server.scene.add_grid("/floor", width=3.0, height=3.0, plane="xz", cell_size=0.25)
    server.initial_camera.position = (0.0, 1.3, -2.6)  # where the Kinect was: in front of the patient
    server.initial_camera.look_at = (0.0, 0.9, 0.0)
    period = float(np.median(np.diff(t))) if n > 1 else 1 / 30

    gui = server.gui
    gui.add_markdown(f"**{n} frames, {t[-1]:.1f} s** · {which} skeleton")
    playing = gui.add_checkbox("Play", initial_value=True, hint="untick to pause, then drag the frame slider")
    slider = gui.add_slider("Frame", min=0, max=max(n - 1, 1), step=1, initial_value=0)
    clock = gui.add_text("Time", initial_value="0.0 s", disabled=True)
    speed = gui.add_slider("Speed", min=0.25, max=2.0, step=0.25, initial_value=1.0)
    state = {"shown": -1}

    def show(frame: int) -> None:
        frame = int(np.clip(frame, 0, n - 1))
        if frame == state["shown"]:
            return
        state["shown"] = frame
        pts = shifted[frame]
        ok = np.isfinite(pts).all(axis=1)
        bones = bone_points(pts)
        good = np.isfinite(bones).all(axis=(1, 2))
        with server.atomic():
            server.scene.add_line_segments("/skeleton/bones", bones[good], BONE_COLOR, thickness=0.025)
            server.scene.add_point_cloud("/skeleton/joints", pts[ok].astype(np.float32), JOINT_COLOR,
                                         point_size=0.045, point_shape="circle")  # fmt: skip
        clock.value = f"{t[frame]:.1f} s"

    @slider.on_update
    def _(_event) -> None:
        show(int(slider.value))

    def loop() -> None:
        frame, step_s = 0, max(period, 1 / 30)
        while not stop.wait(step_s / max(float(speed.value), 0.1)):
            if not playing.value:
                continue
            frame = (int(slider.value) + max(1, round(step_s / period))) % n
            slider.value = frame
            show(frame)

    show(0)
    threading.Thread(target=loop, name="replay-player", daemon=True).start()


replays = ReplayManager()
