"""A replay build opens no listening socket: nobody can connect to it and receive a patient's scene."""

from __future__ import annotations

import os
import threading
from pathlib import Path

from backend.replay import scene
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.sources.simulator import simulate
from tests.backend.replay.viser_file import read_viser


def _listening_inodes() -> set[str]:
    """Returns the socket inodes of the machine's TCP sockets in state LISTEN (IPv4 and IPv6)."""
    inodes = set()
    for name in ("/proc/net/tcp", "/proc/net/tcp6"):
        lines = Path(name).read_text().splitlines()[1:] if Path(name).exists() else []
        for line in lines:
            fields = line.split()
            if fields[3] == "0A":  # TCP_LISTEN
                inodes.add(fields[9])
    return inodes


def _own_socket_inodes() -> set[str]:
    """Returns the inodes of the sockets this process holds open."""
    inodes = set()
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    return inodes


def _own_listening() -> set[str]:
    return _listening_inodes() & _own_socket_inodes()


def test_a_replay_build_listens_on_no_port():
    measured, truth, _ = simulate("squat", 3, seed=8)
    payload = SessionPayload(session_id="s8", raw=measured, filtered=truth)
    before = _own_listening()
    threads_before = set(threading.enumerate())
    seen: set[str] = set()
    done = threading.Event()

    def watch() -> None:
        while not done.is_set():
            seen.update(_own_listening() - before)
            done.wait(0.002)

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        replay = scene.build(payload, "sagittal")
    finally:
        done.set()
        watcher.join()
    assert seen == set(), f"{len(seen)} listening socket(s) opened during the build"
    assert replay.n_frames == measured.n_frames and read_viser(replay.data), "the build still records the scene"
    left = [t.name for t in set(threading.enumerate()) - threads_before]
    assert left == [], f"the build left threads running: {left}"
