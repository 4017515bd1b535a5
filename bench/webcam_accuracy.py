"""Webcam accuracy against an independent multi-view reference, per joint angle and view (issue 22).

    .venv/bin/python bench/webcam_accuracy.py [--model lite|full] [--set NAME=VALUE ...] [--json out.json]

Data: Pose2Sim's single-person demo (PyPI `pose2sim` 0.10.49, BSD-3-Clause): four synchronised, calibrated views
(Qualisys calibration Calib.qca.txt) of one person walking, 1080x1920 at 60 fps, 100 frames (1.7 s).
Reference: the BlazePose image landmarks of all four views triangulated (linear DLT, views with visibility >= 0.5,
the worst view dropped while its reprojection error exceeds 20 px and 3 views remain), mapped onto the 20 joints by the
same rules as the webcam (kinect_agent.sources.webcam.mapping.MIX) and expressed in each camera's frame.
Monocular: each view alone through the webcam mapping (the hips placed with the assumed 65 deg field of view), its
angles raw and after the pipeline (process() with config_for_device("webcam")).
Error: RMS over frames of (monocular angle - reference angle), degrees, per angle and view.

Limits: the reference shares the 2D landmark model with the monocular estimate (its 2D errors are not seen here;
only the depth from four views is independent); 1.7 s of walking; lens distortion is ignored (the calibration's
coefficients are ~1e-3 after Pose2Sim's scaling).
"""

from __future__ import annotations

import argparse
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.webcam_clips import landmarks  # noqa: E402
from kinect_agent.body.angles import joint_angles  # noqa: E402
from kinect_agent.processing.config import config_for_device  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Metadata  # noqa: E402
from kinect_agent.skeleton import NOT_TRACKED  # noqa: E402
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


def read_qca(path: Path) -> list[dict]:
    """Returns per camera {K (3,3) px, R (3,3), t (3,) m}: world -> OpenCV camera, as Pose2Sim converts a .qca."""
    root = ET.parse(path).getroot()
    out = []
    for cam in root.findall("cameras/camera"):
        fov = cam.find("fov_video").attrib
        intr = cam.find("intrinsic").attrib
        tr = cam.find("transform").attrib
        K = np.array([[float(intr["focalLengthU"]) / 64, 0, float(intr["centerPointU"]) / 64 - float(fov["left"])],
                      [0, float(intr["focalLengthV"]) / 64, float(intr["centerPointV"]) / 64 - float(fov["top"])],
                      [0, 0, 1]])  # fmt: skip
        M = np.array([[float(tr[f"r{i}{j}"]) for j in (1, 2, 3)] for i in (1, 2, 3)])
        T = np.array([float(tr[k]) for k in "xyz"]) / 1000.0
        flip = np.diag([1.0, -1.0, -1.0])  # Pose2Sim's rotate_cam(ang_x=pi)
        R = flip @ M
        out.append({"name": cam.attrib["serial"], "K": K, "R": R, "t": -(flip @ M @ T)})
    return out


def triangulate(cams: list[dict], pixels: np.ndarray, vis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def angle_rmse(est: dict, ref: dict) -> dict[str, float]:
    """Returns the RMS of est - ref over frames where both exist, per angle, degrees."""
    out = {}
    for name in ANGLES:
        d = est[name] - ref[name]
        out[name] = float(np.sqrt(np.nanmean(d**2))) if np.isfinite(d).any() else float("nan")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="lite", choices=("lite", "full"))
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="pipeline setting")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--true-fov", action="store_true", help="place the hips with each camera's calibrated FOV")
    parser.add_argument("--leave-out", action=argparse.BooleanOptionalAction, default=False,
                        help="triangulate each view's reference from the other views only")  # fmt: skip
    args = parser.parse_args()
    config = config_for_device("webcam")
    if args.set:
        config = config.model_copy(update={k: json.loads(v) for k, v in (s.split("=", 1) for s in args.set)})
        config = type(config)(**config.model_dump())  # validated
    cams = read_qca(pose2sim_calibration())
    batches = [landmarks(f"pose2sim_cam{v}", args.model)[0] for v in VIEWS]
    n = min(b.n_frames for b in batches)
    assert all(np.allclose(b.t[:n], batches[0].t[:n]) for b in batches), "views must be frame-synchronised"
    pixels = np.stack([b.image[:n, :, :2] * np.array(b.image_size) for b in batches])
    vis = np.stack([b.visibility[:n] for b in batches])
    world, used = triangulate(cams, pixels, vis)
    results = {}
    for v, (cam, batch) in enumerate(zip(cams, batches, strict=True)):
        # the reference of view v leaves view v out: the other three views' landmarks only, so that the view's own
        # 2D errors are not in its reference (they would favour the unfiltered estimate)
        others = [k for k in range(len(cams)) if k != v] if args.leave_out else list(range(len(cams)))
        ref_world, _ = triangulate([cams[k] for k in others], pixels[others], vis[others])
        joints_world = np.einsum("jl,nlc->njc", MIX, ref_world)  # (N, 20, 3)
        ref_cam = (joints_world @ cam["R"].T + cam["t"]) * CV_TO_KINECT
        ref = joint_angles(ref_cam)
        fov = float(np.degrees(2 * np.arctan(batch.image_size[0] / 2 / cam["K"][0, 0]))) if args.true_fov else 65.0
        mono = to_recording(batch, Metadata(device="webcam", rate_hz=RATE_HZ), fov_deg=fov).slice(0, n)
        raw = joint_angles(mono.positions)
        filtered = joint_angles(process(mono, config=config).filtered.positions)
        depth_err = np.nanmedian(np.abs(mono.positions[:, 0, 2] - ref_cam[:, 0, 2]))
        results[cam["name"]] = {"raw": angle_rmse(raw, ref), "filtered": angle_rmse(filtered, ref),
                                "hip_depth_error_m": float(depth_err), "fov_deg": fov,
                                "untracked": float((mono.state == NOT_TRACKED).mean())}  # fmt: skip
    print(
        f"model {args.model}; reference: {np.isfinite(world[..., 0]).mean():.0%} of landmarks triangulated, "
        f"median {np.median(used[used > 0]):.0f} views; pipeline {args.set or 'config_for_device(webcam)'}"
    )
    print(f"{'angle (RMSE deg)':22s}" + "".join(f"{c['name']:>14s}" for c in cams) + f"{'mean':>14s}")
    worse = []
    for name in ANGLES:
        cells, raws, filts = [], [], []
        for cam in cams:
            r = results[cam["name"]]
            raws.append(r["raw"][name])
            filts.append(r["filtered"][name])
            cells.append(f"{r['raw'][name]:6.1f}>{r['filtered'][name]:5.1f}")
            if r["filtered"][name] > r["raw"][name] + 0.05:
                worse.append((name, cam["name"], r["raw"][name], r["filtered"][name]))
        print(f"{name:22s}" + "".join(f"{c:>14s}" for c in cells) + f"{np.nanmean(raws):7.1f}>{np.nanmean(filts):5.1f}")
    print("hip depth error (m):  " + "".join(f"{results[c['name']]['hip_depth_error_m']:14.2f}" for c in cams))
    print("FOV used (deg):       " + "".join(f"{results[c['name']]['fov_deg']:14.1f}" for c in cams))
    print(f"filtered worse than raw (> 0.05 deg): {len(worse)} of {len(ANGLES) * len(cams)}")
    for w in worse:
        print(f"  {w[0]} {w[1]}: {w[2]:.2f} -> {w[3]:.2f}")
    if args.json:
        args.json.write_text(json.dumps({"model": args.model, "set": args.set, "results": results}, indent=1))


if __name__ == "__main__":
    main()
