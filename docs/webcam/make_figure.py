"""Draws docs/webcam/mapping.png: BlazePose's 33 landmarks (grey, numbered) and the 20 joints built from them
(blue, named; SPINE, ROOT, NECK, HEAD and the hands are made of several landmarks, joined by thin lines).

    .venv/bin/python docs/webcam/make_figure.py

The pose is a schematic person standing, facing the viewer (CANONICAL, metres): their left is on the picture's
right, as a camera facing them sees it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from kinect_agent import skeleton  # noqa: E402
from kinect_agent.sources.webcam.landmarks import LANDMARKS  # noqa: E402
from kinect_agent.sources.webcam.mapping import MIX, USES  # noqa: E402

BONES_33 = [(11, 12), (11, 13), (13, 15), (12, 14), (14, 16), (11, 23), (12, 24), (23, 24), (23, 25), (25, 27),
            (24, 26), (26, 28), (27, 29), (29, 31), (27, 31), (28, 30), (30, 32), (28, 32), (15, 17), (15, 19),
            (17, 19), (15, 21), (16, 18), (16, 20), (18, 20), (16, 22), (0, 2), (0, 5), (2, 7), (5, 8),
            (9, 10)]  # fmt: skip


# a schematic standing person facing the viewer, metres (x: the person's left to the right of the picture, y up)
CANONICAL = {
    0: (0.0, 1.62), 1: (0.02, 1.655), 2: (0.035, 1.66), 3: (0.05, 1.655), 4: (-0.02, 1.655), 5: (-0.035, 1.66),
    6: (-0.05, 1.655), 7: (0.075, 1.63), 8: (-0.075, 1.63), 9: (0.025, 1.585), 10: (-0.025, 1.585),
    11: (0.19, 1.42), 12: (-0.19, 1.42), 13: (0.30, 1.17), 14: (-0.30, 1.17), 15: (0.36, 0.93), 16: (-0.36, 0.93),
    17: (0.40, 0.85), 18: (-0.40, 0.85), 19: (0.37, 0.83), 20: (-0.37, 0.83), 21: (0.33, 0.87), 22: (-0.33, 0.87),
    23: (0.10, 0.95), 24: (-0.10, 0.95), 25: (0.12, 0.52), 26: (-0.12, 0.52), 27: (0.13, 0.10), 28: (-0.13, 0.10),
    29: (0.12, 0.04), 30: (-0.12, 0.04), 31: (0.19, 0.01), 32: (-0.19, 0.01),
}  # fmt: skip


def main() -> None:
    xy = np.array([CANONICAL[i] for i in range(33)])
    joints = MIX @ xy
    fig, ax = plt.subplots(figsize=(7.5, 9), dpi=110)
    for a, b in BONES_33:
        ax.plot(*xy[[a, b]].T, color="#c8c8c8", lw=1.5, zorder=1)
    ax.scatter(*xy.T, s=22, color="#8a8a8a", zorder=2)
    for i, (x, y) in enumerate(xy):
        ax.annotate(str(i), (x, y), textcoords="offset points", xytext=(-9, 3), fontsize=7, color="#555555")
    for child in range(1, skeleton.J):
        parent = skeleton.PARENT[child]
        ax.plot(*joints[[parent, child]].T, color="#0b4f9c", lw=2.5, zorder=3)
    for j, name in enumerate(skeleton.JOINTS):
        for k in np.flatnonzero(USES[j]):
            ax.plot(*np.stack([joints[j], xy[k]]).T, color="#0b4f9c", lw=0.6, ls=":", zorder=2)
        ax.scatter(*joints[j], s=60, color="#0b4f9c", zorder=4)
        dx = 8 if name.endswith("_L") else -8
        ha = "left" if name.endswith("_L") else "right"
        dy = -3
        if not name.endswith(("_L", "_R")):
            dx, ha = 10, "left"
        if name == "ROOT":
            dx, dy, ha = 0, -16, "center"
        ax.annotate(name, joints[j], textcoords="offset points", xytext=(dx, dy), fontsize=9, color="#0b3a72",
                    ha=ha, weight="bold")  # fmt: skip
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title("BlazePose 33 landmarks (grey) -> the paper's 20 joints (blue)\n"
                 "SPINE at 0.57 of ROOT->NECK; ROOT, NECK, HEAD, HAN: midpoints (dotted)", fontsize=10)  # fmt: skip
    names = ", ".join(f"{i} {n}" for i, n in enumerate(LANDMARKS))
    fig.text(0.02, 0.01, names, fontsize=5.5, wrap=True, color="#555555")
    out = Path(__file__).with_name("mapping.png")
    fig.savefig(out, bbox_inches="tight")
    print(out)


if __name__ == "__main__":
    main()
