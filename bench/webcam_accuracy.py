"""Webcam accuracy against an independent multi-view reference, per joint angle and view (issue 22).

    .venv/bin/python bench/webcam_accuracy.py [--clip single|multi] [--model lite|full] [--leave-out] [--stages]
        [--set NAME=VALUE ...] [--json out.json]

Data: Pose2Sim's single-person demo (PyPI `pose2sim` 0.10.49, BSD-3-Clause): four synchronised, calibrated views
(Qualisys calibration Calib.qca.txt) of one person walking, 1080x1920 at 60 fps, 100 frames (1.7 s); --clip multi:
the same wheel's multi-person demo (two people, the same cameras and calibration; the landmarker keeps one person per
view, and the reference keeps only points that the views agree on).
Reference: the BlazePose image landmarks of all four views (--leave-out: the other three views) triangulated (linear
DLT, views with visibility >= 0.5, the worst view dropped while its reprojection error exceeds 20 px and 3 views
remain), mapped onto the 20 joints by the same rules as the webcam (kinect_agent.sources.webcam.mapping.MIX) and
expressed in each camera's frame.
Monocular: each view alone through the webcam mapping (the hips placed with the assumed 65 deg field of view), its
angles raw and after the pipeline (process() with config_for_device("webcam")).
Error: RMS over the frames where the raw, filtered and reference angles are all defined, degrees, per angle and view;
a cell is worse when the filtered RMSE exceeds the raw one by more than the tolerance, twice the SD of that change
over a moving-block bootstrap of the frames (rmse_change). --stages switches the pipeline's stages one at a time.

Limits: the reference shares the 2D landmark model with the monocular estimate (its 2D errors are not seen here;
only the depth from four views is independent); 1.7 s of walking; lens distortion is ignored (the calibration's
coefficients are ~1e-3 after Pose2Sim's scaling).
"""

from __future__ import annotations

import argparse
import json
import sys
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.webcam_clips import landmarks  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.processing.combined_outliers import remove_outliers_combined  # noqa: E402
from kinect_agent.processing.config import PipelineConfig, config_for_device  # noqa: E402
from kinect_agent.processing.ik import fill_gaps, inverse_kinematics  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Metadata, Recording  # noqa: E402
from kinect_agent.skeleton import NOT_TRACKED  # noqa: E402
from kinect_agent.sources.webcam.landmarks import LandmarkBatch  # noqa: E402
from kinect_agent.sources.webcam.mapping import MIX, to_recording  # noqa: E402
from tests.media import pose2sim_calibration  # noqa: E402

VIEWS = (1, 2, 3, 4)
RATE_HZ = 60.0
MIN_VIS = 0.5
MAX_REPROJ_PX = 20.0
ANGLES = ("knee_flexion_L", "knee_flexion_R", "hip_flexion_L", "hip_flexion_R", "elbow_flexion_L", "elbow_flexion_R",
          "shoulder_flexion_L", "shoulder_flexion_R", "shoulder_abduction_L", "shoulder_abduction_R",
          "hip_abduction_L", "hip_abduction_R", "trunk_flexion", "trunk_lateral_flexion")  # fmt: skip
CV_TO_KINECT = np.array([-1.0, -1.0, 1.0])  # OpenCV camera (x right, y down, z forward) -> Kinect (x left, y up)


def _child(element: ET.Element, tag: str) -> ET.Element:
    """Returns the first child `tag` of a .qca element."""
    child = element.find(tag)
    if child is None:
        raise ValueError(f"a .qca camera without <{tag}>")
    return child


def read_qca(path: Path) -> list[dict[str, Any]]:
    """Returns per camera {K (3,3) px, R (3,3), t (3,) m}: world -> OpenCV camera, as Pose2Sim converts a .qca."""
    root = ET.parse(path).getroot()
    out = []
    for cam in root.findall("cameras/camera"):
        fov, intr, tr = (_child(cam, tag).attrib for tag in ("fov_video", "intrinsic", "transform"))
        K = np.array([[float(intr["focalLengthU"]) / 64, 0, float(intr["centerPointU"]) / 64 - float(fov["left"])],
                      [0, float(intr["focalLengthV"]) / 64, float(intr["centerPointV"]) / 64 - float(fov["top"])],
                      [0, 0, 1]])  # fmt: skip
        M = np.array([[float(tr[f"r{i}{j}"]) for j in (1, 2, 3)] for i in (1, 2, 3)])
        T = np.array([float(tr[k]) for k in "xyz"]) / 1000.0
        flip = np.diag([1.0, -1.0, -1.0])  # Pose2Sim's rotate_cam(ang_x=pi)
        R = flip @ M
        out.append({"name": cam.attrib["serial"], "K": K, "R": R, "t": -(flip @ M @ T)})
    return out


def triangulate(cams: list[dict[str, Any]], pixels: np.ndarray, vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns ((N, 33, 3) world points, m, NaN where fewer than 2 views; (N, 33) views used).

    pixels: (V, N, 33, 2) px; vis: (V, N, 33)."""
    P = np.stack([c["K"] @ np.column_stack([c["R"], c["t"]]) for c in cams])  # (V, 3, 4)
    V, N, L, _ = pixels.shape
    out = np.full((N, L, 3), np.nan)
    used = np.zeros((N, L), int)
    for n in range(N):
        for k in range(L):
            views = [v for v in range(V) if vis[v, n, k] >= MIN_VIS]
            while len(views) >= 2:
                A = np.concatenate([pixels[v, n, k, :, None] * P[v, 2][None] - P[v, :2] for v in views])
                X = np.linalg.svd(A)[2][-1]
                X = X[:3] / X[3]
                h = P[views] @ np.append(X, 1.0)
                err = np.linalg.norm(h[:, :2] / h[:, 2:] - pixels[views, n, k], axis=1)
                if err.max() <= MAX_REPROJ_PX or len(views) == 2:
                    break
                views.pop(int(np.argmax(err)))  # a view that disagrees (a swapped or misplaced point) is left out
            if len(views) >= 2:
                out[n, k], used[n, k] = X, len(views)
    return out, used


BLOCK_S = 0.25  # block length of the bootstrap, s (the angle errors are correlated over a few frames)
BOOTSTRAP = 500
MIN_BLOCKS = 2  # a cell needs frames for this many bootstrap blocks (0.5 s) where all three angles are defined


def angle_errors(
    est: dict[str, Any], raw: dict[str, Any], ref: dict[str, Any], name: str
) -> tuple[np.ndarray, np.ndarray]:
    """Returns ((n,) est - ref, (n,) raw - ref) in degrees over the frames where all three angles are defined (the
    same frames for both, so that a filter that defines an angle where the raw data do not is not judged on other
    frames)."""
    m = np.isfinite(est[name]) & np.isfinite(raw[name]) & np.isfinite(ref[name])
    return est[name][m] - ref[name][m], raw[name][m] - ref[name][m]


def rmse_change(e_est: np.ndarray, e_raw: np.ndarray, rng: np.random.Generator, block: int) -> tuple[float, float,
                                                                                                    float]:  # fmt: skip
    """Returns (RMSE raw, RMSE est, tolerance) in degrees: the tolerance is twice the SD of RMSE est - RMSE raw over
    a moving-block bootstrap of the frames (blocks of `block` frames): how much the change could move had the
    clip been filmed again, the resolution of this measurement. All NaN (unresolved) with fewer than MIN_BLOCKS
    blocks of frames."""
    n = len(e_est)
    if n < MIN_BLOCKS * block:  # too few frames to resolve anything: the cell is reported as unresolved
        return float("nan"), float("nan"), float("nan")
    r_raw, r_est = float(np.sqrt(np.mean(e_raw**2))), float(np.sqrt(np.mean(e_est**2)))
    block = max(1, min(block, n))
    starts = rng.integers(0, n - block + 1, size=(BOOTSTRAP, -(-n // block)))
    idx = (starts[..., None] + np.arange(block)).reshape(BOOTSTRAP, -1)[:, :n]
    d = np.sqrt(np.mean(e_est[idx] ** 2, axis=1)) - np.sqrt(np.mean(e_raw[idx] ** 2, axis=1))
    return r_raw, r_est, float(2.0 * np.std(d))


def views_reference(
    cams: list[dict[str, Any]], pixels: np.ndarray, vis: np.ndarray, v: int, leave_out: bool, min_views: int = 2
) -> np.ndarray:
    """Returns (N, 20, 3) m, the reference joints in view v's Kinect camera frame, triangulated from all views or
    (leave_out) from the other views only; NaN where a landmark of the joint was triangulated from fewer than
    min_views views that agree (within MAX_REPROJ_PX)."""
    others = [k for k in range(len(cams)) if k != v] if leave_out else list(range(len(cams)))
    ref_world, used = triangulate([cams[k] for k in others], pixels[others], vis[others])
    ref_world[used < min_views] = np.nan
    joints_world = np.einsum("jl,nlc->njc", MIX, np.nan_to_num(ref_world))  # (N, 20, 3)
    missing = np.einsum("jl,nl->nj", (MIX > 0).astype(float), np.isnan(ref_world[..., 0]).astype(float)) > 0
    joints_world[missing] = np.nan
    return (joints_world @ cams[v]["R"].T + cams[v]["t"]) * CV_TO_KINECT


def stage_variants(config: PipelineConfig) -> dict[str, Callable[[Recording], np.ndarray]]:
    """Returns the pipeline's stages switched one at a time: name -> recording -> (T, J, 3) positions."""
    chain = config.model_copy(update={"offline_filter": "chain", "remove_outliers": True})

    def run(c: PipelineConfig) -> Callable[[Recording], np.ndarray]:
        return lambda rec: process(rec, config=c).filtered.positions

    def outliers_only(rec: Recording) -> np.ndarray:
        return fill_gaps(remove_outliers_combined(rec, chain)[0].positions)

    def ik_only(rec: Recording) -> np.ndarray:
        ik = inverse_kinematics(fill_gaps(rec.positions))
        return ik.model.positions(ik.root, np.broadcast_to(ik.lengths, (rec.n_frames, len(ik.lengths))), ik.theta)

    return {
        "chain (before)": run(chain),
        "chain, no outlier removal": run(chain.model_copy(update={"remove_outliers": False})),
        "chain, sigma 0.01 m": run(chain.model_copy(update={"sigma_tracked_m": 0.01, "sigma_inferred_m": 0.02})),
        "outlier removal only": outliers_only,
        "chain fit per frame only (IK)": ik_only,
        "joints, no swap restarts": run(config.model_copy(update={"joint_split_at_swaps": False})),
        "joints, whole-body swaps only": run(config.model_copy(update={"joint_arm_swaps": False})),
        "joints, with outlier removal": run(config.model_copy(update={"remove_outliers": True})),
        "joints (shipped)": run(config),
    }


def evaluate(
    raw: list[dict[str, Any]], refs: list[dict[str, Any]], ests: list[dict[str, Any]], rate_hz: float, seed: int = 0
) -> np.ndarray:
    """Returns (A, V, 3) per angle and view: RMSE raw, RMSE est, tolerance (rmse_change), degrees."""
    rng = np.random.default_rng(seed)
    block = int(round(BLOCK_S * rate_hz))
    out = np.full((len(ANGLES), len(raw), 3), np.nan)
    for v in range(len(raw)):
        for a, name in enumerate(ANGLES):
            out[a, v] = rmse_change(*angle_errors(ests[v], raw[v], refs[v], name), rng, block)
    return out


def worse_cells(table: np.ndarray) -> np.ndarray:
    """Returns (A, V) bool: the estimate's RMSE exceeds the raw one's by more than the tolerance."""
    return table[..., 1] - table[..., 0] > table[..., 2]


def synchronised(batches: list[LandmarkBatch], rate_hz: float) -> list[LandmarkBatch]:
    """Returns the batches cut to the frames every view has (frame times equal within a quarter frame): a view
    where the landmarker found nobody in an image has no frame there."""
    frames = [np.round(b.t * rate_hz).astype(np.int64) for b in batches]
    common = frames[0]
    for f in frames[1:]:
        common = np.intersect1d(common, f)
    out = []
    for b, f in zip(batches, frames, strict=True):
        k = np.flatnonzero(np.isin(f, common))
        out.append(LandmarkBatch(b.t[k], b.world[k], b.image[k], b.visibility[k], b.image_size))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="lite", choices=("lite", "full"))
    parser.add_argument("--landmarker", default="watch", choices=("watch", "two"),
                        help="the agent's company watch (shipped), or one landmarker looking for two people on every "
                             "image (before 2026-11-28)")  # fmt: skip
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="pipeline setting")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--true-fov", action="store_true", help="place the hips with each camera's calibrated FOV")
    parser.add_argument("--leave-out", action=argparse.BooleanOptionalAction, default=False,
                        help="triangulate each view's reference from the other views only")  # fmt: skip
    parser.add_argument("--stages", action="store_true", help="also switch the pipeline's stages one at a time")
    parser.add_argument("--min-views", type=int, default=2,
                        help="reference points triangulated from fewer agreeing views are left out")  # fmt: skip
    parser.add_argument("--clip", default="single", choices=("single", "multi"),
                        help="Pose2Sim's single-person demo, or its multi-person demo (the same cameras)")  # fmt: skip
    args = parser.parse_args()
    config = config_for_device("webcam")
    if args.set:
        config = config.model_copy(update={k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)})
        config = type(config)(**config.model_dump())  # validated
    cams = read_qca(pose2sim_calibration())
    prefix = "pose2sim_cam" if args.clip == "single" else "pose2sim_multi_cam"
    batches = [landmarks(f"{prefix}{v}", args.model, args.landmarker)[0] for v in VIEWS]
    batches = synchronised(batches, RATE_HZ)
    n = batches[0].n_frames
    pixels = np.stack([b.image[:n, :, :2] * np.array(b.image_size) for b in batches])
    vis = np.stack([b.visibility[:n] for b in batches])
    world, used = triangulate(cams, pixels, vis)
    monos, refs, raws, extra = [], [], [], {}
    for v, (cam, batch) in enumerate(zip(cams, batches, strict=True)):
        # --leave-out: the reference of view v leaves view v out, so that the view's own 2D errors are not in its
        # reference (they would favour the unfiltered estimate)
        ref_cam = views_reference(cams, pixels, vis, v, args.leave_out, args.min_views)
        refs.append(joint_angles(ref_cam))
        fov = float(np.degrees(2 * np.arctan(batch.image_size[0] / 2 / cam["K"][0, 0]))) if args.true_fov else 65.0
        mono = to_recording(batch, Metadata(device="webcam", rate_hz=RATE_HZ), fov_deg=fov)
        monos.append(mono)
        raws.append(joint_angles(mono.positions))
        depth_err = float(np.nanmedian(np.abs(mono.positions[:, 0, 2] - ref_cam[:, 0, 2])))
        extra[cam["name"]] = {"hip_depth_error_m": depth_err, "fov_deg": fov,
                              "untracked": float((mono.state == NOT_TRACKED).mean())}  # fmt: skip
    results = [process(m, config=config) for m in monos]
    table = evaluate(raws, refs, [joint_angles(r.filtered.positions) for r in results], RATE_HZ)
    left_out = ", each view left out of its own" if args.leave_out else ""
    restarts = ", ".join(f"{c['name']} {r.quality['joint_restarts']}" for c, r in zip(cams, results, strict=True))
    print(
        f"clip {args.clip} ({n} frames in every view), model {args.model}, landmarker {args.landmarker}; reference: "
        f"{np.isfinite(world[..., 0]).mean():.0%} of landmarks triangulated, median {np.median(used[used > 0]):.0f} "
        f"views (at least {args.min_views}){left_out}; pipeline {args.set or 'config_for_device(webcam)'}; "
        f"restarts at label swaps and body jumps: {restarts}"
    )
    print("RMSE in degrees over the frames where raw, filtered and reference are all defined: raw > filtered "
          "(+- tolerance: 2 SD of the change over a block bootstrap of the frames)")  # fmt: skip
    print(f"{'angle':22s}" + "".join(f"{c['name']:>20s}" for c in cams) + f"{'mean':>14s}")
    bad = worse_cells(table)
    for a, name in enumerate(ANGLES):
        cells = [f"{r:5.1f}>{e:5.1f} ±{tol:4.1f}{'*' if w else ' '}"
                 for (r, e, tol), w in zip(table[a], bad[a], strict=True)]  # fmt: skip
        mean = np.nanmean(table[a], axis=0)
        print(f"{name:22s}" + "".join(f"{c:>20s}" for c in cells) + f"{mean[0]:7.1f}>{mean[1]:5.1f}")
    for key, label in (("hip_depth_error_m", "hip depth error (m)"), ("fov_deg", "FOV used (deg)")):
        print(f"{label:22s}" + "".join(f"{extra[c['name']][key]:20.2f}" for c in cams))
    change = table[..., 1] - table[..., 0]
    print(f"filtered worse than raw beyond the tolerance (*): {int(bad.sum())} of {bad.size}; by more than 0.05 deg: "
          f"{int((change > 0.05).sum())}; largest change {np.nanmax(change):+.2f} deg, mean {np.nanmean(change):+.2f}, "
          f"median tolerance {np.nanmedian(table[..., 2]):.2f}; unresolved (under {MIN_BLOCKS * BLOCK_S:g} s of "
          f"frames): {int(np.isnan(change).sum())}")  # fmt: skip
    if args.stages:
        print("\nstages one at a time (cells worse beyond the tolerance / by > 0.05 deg; largest, mean change, deg):")
        for label, fn in stage_variants(config).items():
            t = evaluate(raws, refs, [joint_angles(fn(m)) for m in monos], RATE_HZ)
            ch = t[..., 1] - t[..., 0]
            per_view = " ".join(f"{c['name']} {int(w)}" for c, w in zip(cams, worse_cells(t).sum(axis=0), strict=True))
            print(
                f"  {label:32s} {int(worse_cells(t).sum()):2d} / {int((ch > 0.05).sum()):2d} of {ch.size}; "
                f"max {np.nanmax(ch):+6.2f} mean {np.nanmean(ch):+5.2f}; worse per view: {per_view}"
            )
    if args.json:
        keys = ("raw", "filtered", "tolerance")
        out = {c["name"]: {"angles": {name: dict(zip(keys, table[a, v].tolist(), strict=True))
                                      for a, name in enumerate(ANGLES)}, **extra[c["name"]]}
               for v, c in enumerate(cams)}  # fmt: skip
        args.json.write_text(json.dumps({"model": args.model, "set": args.set, "results": out}, indent=1))


if __name__ == "__main__":
    main()
