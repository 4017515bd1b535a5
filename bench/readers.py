"""Reading time of 10-minute recordings in every text format: CPU seconds per reader (best of --runs).

The files are built in a temp folder from the real samples in ../shared/data, their frames repeated up to
10 minutes: 18 000 frames at 30 Hz for the Kinect formats (Skeleton CSV, Kinect v2 TSV, UTKinect, KERAAL, UI-PRMD),
36 000 at 60 Hz for KERAAL Vicon, 60 000 at 100 Hz for UI-PRMD Vicon, 72 000 at 120 Hz for BVH and AMC (and the same
at 30 Hz, 18 000 frames).

    python bench/readers.py [--runs 3] [--only csv bvh ...]
"""

from __future__ import annotations

import argparse
import gzip
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/readers.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from kinect_agent import formats  # noqa: E402
from kinect_agent.formats import keraal, kinect_v2_tsv, skeleton_csv, utkinect  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

DATA = ROOT_DIR.parent / "shared" / "data"
KINECT_FRAMES = 18_000  # 10 min at 30 Hz
UI_PRMD = DATA / "ui-prmd" / "Segmented Movements"


Row = TypeVar("Row", str, bytes)  # a line of a text or of a binary file


def _lines(source: Path) -> list[bytes]:
    raw = source.read_bytes()
    raw = gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw
    return [line for line in raw.splitlines() if line.strip()]


def _repeat(rows: list[Row], n: int) -> list[Row]:
    return [rows[i % len(rows)] for i in range(n)]


def _utkinect(out: Path) -> Path:
    rows = _repeat(_lines(DATA / "utkinect" / "joints_s01_e01.txt"), KINECT_FRAMES)
    path = out / "joints_s09_e01.txt"
    path.write_bytes(b"\n".join(b"%d %s" % (i + 1, row.split(None, 1)[1]) for i, row in enumerate(rows)) + b"\n")
    return path


def _keraal(out: Path, kind: str = "Kinect", n: int = KINECT_FRAMES) -> Path:
    rows = _repeat(_lines(DATA / "keraal" / "kinect_vicon_pairs" / f"G3-{kind}-CTK-P1T1-Unknown-C-0.txt"), n)
    path = out / f"G3-{kind}-CTK-P9T9-Unknown-C-0.txt"
    path.write_bytes(b"\r\n".join(rows) + b"\r\n")
    return path


def _ui_prmd(out: Path, kind: str = "Kinect", n: int = KINECT_FRAMES) -> Path:
    parts = ("Positions", "Angles") if kind == "Kinect" else ("Positions",)
    for part in parts:
        folder = out / kind / part
        folder.mkdir(parents=True, exist_ok=True)
        rows = _repeat(_lines(UI_PRMD / kind / part / f"m01_s01_e01_{part.lower()}.txt.gz"), n)
        (folder / f"m01_s09_e01_{part.lower()}.txt.gz").write_bytes(gzip.compress(b"\n".join(rows) + b"\n"))
    return out / kind / "Positions" / "m01_s09_e01_positions.txt.gz"


def _bvh(out: Path, n: int, frame_time: str) -> Path:
    head, _, motion = (DATA / "cmu-mocap" / "13_29.bvh").read_text().partition("MOTION\n")
    rows = _repeat(motion.splitlines()[2:], n)
    path = out / f"13_29_{n}.bvh"
    path.write_text(head + f"MOTION\nFrames: {n}\nFrame Time: {frame_time}\n" + "\n".join(rows) + "\n")
    return path


def _amc(out: Path, n: int) -> Path:
    (out / "asf").mkdir(exist_ok=True)
    shutil.copy(DATA / "hdm05" / "asf" / "HDM_bd.asf", out / "asf")
    lines = (DATA / "hdm05" / "squat1Reps" / "HDM_bd_squat1Reps_001_120.amc").read_bytes().splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip() == b"1")
    frames: list[list[bytes]] = []
    for line in lines[start:]:
        if line.strip().isdigit():
            frames.append([])
        else:
            frames[-1].append(line)
    body = [b"%d" % (i + 1) + b"\n" + b"\n".join(frames[i % len(frames)]) for i in range(n)]
    path = out / f"HDM_bd_long{n}_120.amc"
    path.write_bytes(b"\n".join(lines[:start] + body) + b"\n")
    return path


def build(out: Path) -> dict[str, Callable[[], Path]]:
    """Returns the builders of the 10-minute files, by name."""
    return {
        "csv (18000 frames)": lambda: _write(out / "long.csv", skeleton_csv.write),
        "kinect_v2_tsv (18000)": lambda: _write(out / "long.tsv", kinect_v2_tsv.write),
        "utkinect (18000)": lambda: _utkinect(out),
        "keraal (18000)": lambda: _keraal(out),
        "keraal_vicon (36000)": lambda: _keraal(out, "Vicon", 2 * KINECT_FRAMES),
        "ui_prmd (18000)": lambda: _ui_prmd(out),
        "ui_prmd_vicon (60000)": lambda: _ui_prmd(out, "Vicon", 60_000),
        "bvh 30 Hz (18000)": lambda: _bvh(out, KINECT_FRAMES, ".0333333"),
        "bvh 120 Hz (72000)": lambda: _bvh(out, 4 * KINECT_FRAMES, ".0083333"),
        "amc 30 Hz (18000)": lambda: _amc(out, KINECT_FRAMES),
        "amc 120 Hz (72000)": lambda: _amc(out, 4 * KINECT_FRAMES),
    }


def _write(path: Path, writer: Callable[[Recording, Path], None]) -> Path:
    rec = keraal.read(_keraal(path.parent)) if path.suffix == ".tsv" else utkinect.read(_utkinect(path.parent))
    writer(rec, path)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--only", nargs="*", help="names starting with these (csv, bvh, amc ...)")
    args = parser.parse_args()
    if not DATA.is_dir():
        print(f"{DATA} is missing", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        for name, make in build(Path(tmp)).items():
            if args.only and not any(name.startswith(o) for o in args.only):
                continue
            path = make()
            best = float("inf")
            for _ in range(args.runs):
                start = time.process_time()
                rec = formats.read(path)
                best = min(best, time.process_time() - start)
            per_frame = 1e6 * best / rec.n_frames
            print(f"{name:26s} {rec.n_frames:6d} frames  {best:6.2f} s CPU  ({per_frame:5.1f} us/frame)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
