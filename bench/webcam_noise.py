"""The webcam's noise model, measured: jitter of the 20 mapped joints per axis on real clips (issue 22).

    .venv/bin/python bench/webcam_noise.py [--model lite|full] [--json out.json]

Jitter = the sample minus a local quadratic fit over WINDOW_S around it (Savitzky-Golay), tracked samples only,
as an SD per axis (Kinect camera frame: x to the camera's left, y up, z away) per joint; the fit removes the
movement, not the error that persists over a window (bias, depth scale), which bench/webcam_accuracy.py measures
against a multi-view reference. These SDs set config_for_device("webcam") (kinect_agent/processing/config.py).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.signal import savgol_filter

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.webcam_clips import CLIPS, RATES, landmarks  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.sources.webcam.landmarks import check_arrays  # noqa: E402
from kinect_agent.sources.webcam.mapping import to_skeletons  # noqa: E402

WINDOW_S = 0.3
MAX_HIP_STEP = 0.03  # image widths per frame: a larger jump of the hips is a switch of person or a lost track
SPORTS2D_FRAMES = 150  # Sports2D's demo: after ~5 s the subject jumps off the hut and a second person is followed


@dataclass(frozen=True)
class ClipJitter:
    """One clip's jitter SDs (J, 3) m of its tracked and its inferred joints, and its number of frames."""

    tracked: np.ndarray
    inferred: np.ndarray
    frames: int


def jitter(positions: np.ndarray, state: np.ndarray, t: np.ndarray, rate: float, want_state: int,
           hips_image: np.ndarray) -> np.ndarray:  # fmt: skip
    """Returns (J, 3) the SD of the residual from a local quadratic, per joint and axis, over runs of consecutive
    frames (no time gap, no hip jump in the image: hips_image (N, 2)) with the joint in state `want_state`; NaN
    where fewer than 20 samples."""
    window = int(round(WINDOW_S * rate)) | 1
    step = np.diff(t)
    jump = np.linalg.norm(np.diff(hips_image, axis=0), axis=1) > MAX_HIP_STEP
    cuts = np.flatnonzero((step > 1.5 / rate) | jump) + 1
    out = np.full((skeleton.J, 3), np.nan)
    for j in range(skeleton.J):
        residuals = []
        for run_idx in np.split(np.arange(len(t)), cuts):
            ok = state[run_idx, j] == want_state
            for seg in np.split(run_idx[ok], np.flatnonzero(np.diff(run_idx[ok]) > 1) + 1):
                if len(seg) >= window + 2:
                    p = positions[seg, j]
                    residuals.append(p - savgol_filter(p, window, 2, axis=0))
        if residuals:
            r = np.concatenate(residuals)
            if len(r) >= 20:
                # a quadratic over `window` samples absorbs part of white noise: scale back to the sample's SD
                out[j] = r.std(axis=0) / np.sqrt(1 - _hat_diag(window))
    return out


def _hat_diag(window: int) -> float:
    """Returns the centre weight of a quadratic Savitzky-Golay smoother of `window` samples (its own share)."""
    e = np.zeros(window)
    e[window // 2] = 1.0
    return float(savgol_filter(e, window, 2)[window // 2])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="lite", choices=("lite", "full"))
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows: dict[str, ClipJitter] = {}
    for clip in CLIPS:
        batch, _ = landmarks(clip, args.model)
        if clip == "sports2d":
            batch = check_arrays(batch.t[:SPORTS2D_FRAMES], batch.world[:SPORTS2D_FRAMES],
                                 batch.image[:SPORTS2D_FRAMES], batch.visibility[:SPORTS2D_FRAMES],
                                 batch.image_size)  # fmt: skip
        mapped = to_skeletons(batch)
        hips = batch.image[:, [23, 24], :2].mean(axis=1)
        tracked = jitter(mapped.positions, mapped.state, batch.t, RATES[clip], skeleton.TRACKED, hips)
        inferred = jitter(mapped.positions, mapped.state, batch.t, RATES[clip], skeleton.INFERRED, hips)
        rows[clip] = ClipJitter(tracked, inferred, batch.n_frames)
    print(f"jitter SD (mm), {args.model} model, local quadratic over {WINDOW_S} s; median over joints")
    print(f"{'clip':16s} {'x':>6s} {'y':>6s} {'z':>6s}  {'3D/axis':>7s}  {'inferred 3D/axis':>16s}  frames")
    summary = {}
    for clip, r in rows.items():
        tr, inf = r.tracked, r.inferred
        per_axis = np.nanmedian(tr, axis=0) * 1000
        rms = float(np.sqrt(np.nanmean(np.nanmedian(tr, axis=0) ** 2)) * 1000)
        with np.errstate(all="ignore"):
            rms_inf = (
                float(np.sqrt(np.nanmean(np.nanmedian(inf, axis=0) ** 2)) * 1000) if np.isfinite(inf).any() else np.nan
            )
        summary[clip] = {"x_mm": per_axis[0], "y_mm": per_axis[1], "z_mm": per_axis[2], "rms_axis_mm": rms,
                         "inferred_rms_axis_mm": rms_inf, "frames": r.frames}  # fmt: skip
        print(f"{clip:16s} {per_axis[0]:6.1f} {per_axis[1]:6.1f} {per_axis[2]:6.1f}  {rms:7.1f}  {rms_inf:16.1f}  "
              f"{r.frames}")  # fmt: skip
    all_tracked = np.stack([r.tracked for r in rows.values()])  # (clips, J, 3)
    per_joint = np.nanmedian(all_tracked, axis=0) * 1000  # (J, 3)
    med = np.nanmedian(np.nanmedian(all_tracked, axis=1), axis=0) * 1000  # median joint, median clip, per axis
    print(
        f"\nall clips: median joint per axis x {med[0]:.1f}, y {med[1]:.1f}, z {med[2]:.1f} mm; "
        f"RMS over axes {np.sqrt(np.mean(med**2)):.1f} mm"
    )
    print("\nper joint, median over clips (mm): x y z")
    for j, name in enumerate(skeleton.JOINTS):
        print(f"  {name:6s} {per_joint[j, 0]:6.1f} {per_joint[j, 1]:6.1f} {per_joint[j, 2]:6.1f}")
    if args.json:
        args.json.write_text(json.dumps({"model": args.model, "window_s": WINDOW_S, "clips": summary,
                                         "per_joint_mm": per_joint.tolist()}, indent=1, default=float))  # fmt: skip


if __name__ == "__main__":
    main()
