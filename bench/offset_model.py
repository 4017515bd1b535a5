"""Kinect v2's systematic per-joint offset against simultaneous Vicon, in the body frame, and the offset model's
validation (issue 13, "The Kinect's systematic offset").

Pairs (both in ../shared/data; one subject each, so no leave-one-subject-out inside a dataset):
    KERAAL   group 3, subject P1: 3 trials (CTK, ELK, RTK), aligned as bench/real_pairs.py (speed cross-correlation,
             then the lowest registration RMS within +-2 frames). Scored joints: the well-estimated SCoRE joints of
             each trial (real_pairs.well_estimated).
    UI-PRMD  subject s01: every movement m01-m10, episodes e01-e10, correct and incorrect (200 Kinect/Vicon
             episode pairs). The two systems were segmented separately (different starts and lengths), so each
             episode is aligned in time: lag by the speed cross-correlation (real_pairs.align, +-MAX_LAG_S), and
             independently by the lowest registration RMS over the same range. A pair is kept when the two lags
             agree within LAG_AGREE_S, the speed correlation is >= MIN_XCORR and the registration RMS is <= MAX_RMS_M;
             the others are dropped (counted in the report). Scored joints: UI_JOINTS. Not the knees and ankles: the
             Kinect legs as formats/ui_prmd.py rebuilds them move with the pelvis (deep squat: Kinect ankles move
             0.56-0.64 m, Vicon's 0.02 m), and not HEAD/HAN/FOO (marker clusters, not joint centres). The Vicon
             joints are Plug-in Gait skin markers (acromion, lateral epicondyle), not joint centres: their offsets
             include marker placement.
Registration: each estimate is registered to Vicon by its own rigid transform (trimmed Kabsch on the scored joints,
    real_pairs.robust_kabsch), so every error here is a shape error: the mean offset common to all scored joints is
    absorbed (not observable without a shared calibration; it changes no angle).
Offset of a trial: component-wise median over frames of (Kinect - Vicon) in the body frame of the Kinect estimate
    (kinect_agent.processing.offset_model: x = subject's left, y = up, z = forward), robust to tracking loss.
Measurement table: per dataset and joint, the mean over trials of the trial offsets and their SD across trials,
    for raw Kinect and for the pipeline's offline output (what the model is applied to); per pose (standing / bent
    knees > 60 deg) where the data has it.
Validation: the model (per joint; per joint and pose) is fitted on the pipeline's offline output of training pairs
    and applied to that of test pairs: KERAAL leave-one-trial-out, UI-PRMD leave-one-movement-out (all episodes of
    the left-out movement held out), cross-dataset both ways, both datasets leave-one-trial/movement-out, and
    in-sample (fit and test on all, an upper bound). Metrics on the pooled test frames, per joint and
    pooled: RMSE before/after, the bias part (RMS over trials of each trial's mean error per joint in the
    body frame: what a constant per recording could remove) and the random part sqrt(RMSE^2 - bias^2).

    .venv/bin/python bench/offset_model.py [--quick] [--json OUT] [--write-constants {none,keraal,uiprmd,both}]
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:
    sys.path.insert(0, str(ROOT_DIR))

from bench import real_pairs as rp  # noqa: E402
from kinect_agent import skeleton  # noqa: E402
from kinect_agent.evaluation.align import interpolate, measured, rms_lag  # noqa: E402
from kinect_agent.evaluation.error_parts import JointErrorSums  # noqa: E402
from kinect_agent.evaluation.pairs import UI_PRMD_JOINTS, joint_mask, well_estimated  # noqa: E402
from kinect_agent.evaluation.register import robust_kabsch  # noqa: E402
from kinect_agent.processing import offset_model as om  # noqa: E402
from kinect_agent.processing.config import PipelineConfig  # noqa: E402
from kinect_agent.processing.pipeline import process  # noqa: E402
from kinect_agent.recording import Recording  # noqa: E402

UI_DIR = rp.DATA_DIR / "ui-prmd"
UI_FOLDERS = (("Segmented Movements", ""), ("Incorrect Segmented Movements", "_inc"))
UI_JOINTS = UI_PRMD_JOINTS
MAX_LAG_S = 1.5  # UI-PRMD episodes last 1.0-4.6 s
LAG_AGREE_S = 2.0 / 30.0
MIN_XCORR = 0.8
MAX_RMS_M = 0.10
DATA_NOTE = {
    "KERAAL": "shared/data/keraal/kinect_vicon_pairs G3 P1T1; Vicon joints by SCoRE (formats.keraal_vicon)",
    "UI-PRMD": "shared/data/ui-prmd s01 Kinect + Vicon episodes; Plug-in Gait markers (formats.ui_prmd_vicon)",
}
CONSTANTS_PATH = ROOT_DIR / "kinect_agent" / "processing" / "offset_constants.py"


@dataclass
class Pair:
    """One Kinect recording with its Vicon joints at the Kinect frames (Vicon frame, NaN outside the overlap)."""

    name: str
    dataset: str
    group: str  # the unit held out: KERAAL trial, UI-PRMD movement
    kinect: Recording
    vicon: np.ndarray  # (T, J, 3) m, Vicon frame, NaN = outside overlap / not scored
    joints: np.ndarray  # (J,) bool, scored
    lag_s: float
    xcorr: float
    lag_rms_s: float
    rms_mm: float
    accepted: bool
    vicon_s: float = 0.0  # duration of the Vicon recording
    filtered: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (T, J, 3) m, pipeline offline


def _raw(rec: Recording) -> np.ndarray:
    return measured(rec)


def lag_by_rms(kinect: Recording, vicon: Recording, joints: np.ndarray) -> float:
    """Returns the lag (s, over +-MAX_LAG_S in Kinect-frame steps) minimising the trimmed registration RMS of the
    joints (J,) bool (kinect_agent.evaluation.align.rms_lag)."""
    return rms_lag(kinect, vicon, joints, MAX_LAG_S)


def make_pair(name: str, dataset: str, group: str, kinect: Recording, vicon: Recording, joints: np.ndarray,
              check: bool) -> Pair:  # fmt: skip
    """Aligns vicon onto kinect's frames; check: also the independent RMS lag and the acceptance rule."""
    al = rp.align(kinect, vicon, joints, max_lag_s=MAX_LAG_S if check else rp.MAX_LAG_S)
    v = interpolate(vicon.t, vicon.positions, kinect.t + al.lag_s)
    v[:, ~joints] = np.nan
    lag_rms = lag_by_rms(kinect, vicon, joints) if check else al.lag_s
    ok = abs(lag_rms - al.lag_s) <= LAG_AGREE_S + 1e-9 and al.xcorr >= MIN_XCORR and al.rms_m <= MAX_RMS_M
    return Pair(name, dataset, group, kinect, v, joints, al.lag_s, al.xcorr, lag_rms, 1e3 * al.rms_m,
                ok or not check, vicon_s=float(vicon.t[-1]))  # fmt: skip


def keraal_pairs() -> list[Pair]:
    out = []
    for path in rp.pair_paths():
        kinect, vicon = rp.read_pair(path)
        joints = well_estimated(vicon.meta.extra.get("fallback_joints", []))
        name = kinect.meta.exercise or path.stem
        out.append(make_pair(name, "KERAAL", name, kinect, vicon, joints, check=False))
    return out


def uiprmd_pairs(episodes: range) -> list[Pair]:
    from kinect_agent.formats import ui_prmd, ui_prmd_vicon

    out = []
    joints = joint_mask(UI_JOINTS)
    for folder, suffix in UI_FOLDERS:
        for m in range(1, 11):
            for e in episodes:
                fname = f"m{m:02d}_s01_e{e:02d}_positions{suffix}.txt.gz"
                k_path, v_path = (UI_DIR / folder / dev / "Positions" / fname for dev in ("Kinect", "Vicon"))
                if not (k_path.is_file() and v_path.is_file()):
                    continue
                kinect, vicon = ui_prmd.read(k_path), ui_prmd_vicon.read(v_path)
                out.append(make_pair(fname.split("_positions")[0] + suffix, "UI-PRMD", f"m{m:02d}", kinect, vicon,
                                     joints, check=True))  # fmt: skip
    return out


# ----------------------------------------------------------------------------------------------- errors


def register(estimate: np.ndarray, vicon: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Returns the Vicon joints (T, J, 3) in the camera frame of estimate by the estimate's own trimmed rigid fit;
    NaN where not scored. estimate, vicon: (T, J, 3) m; joints (J,) bool."""
    R, t, _ = robust_kabsch(vicon[:, joints].reshape(-1, 3), estimate[:, joints].reshape(-1, 3))
    return vicon @ R.T + t


def errors(estimate: np.ndarray, pair: Pair) -> np.ndarray:
    """Returns (T, J, 3) m: estimate - registered Vicon in the estimate's body frame; NaN where not scored."""
    return om.to_body(estimate - register(estimate, pair.vicon, pair.joints), estimate)


def per_joint(sums: JointErrorSums) -> dict[str, dict[str, float]]:
    """Returns {joint: {"rmse_mm", "bias_mm", "random_mm", "n"}} for the joints with errors."""
    rms = sums.rms_mm()
    return {name: {key: (int(v[j]) if key == "n" else float(v[j])) for key, v in rms.items()}
            for j, name in enumerate(skeleton.JOINTS) if sums.n[j] > 0}  # fmt: skip


# ----------------------------------------------------------------------------------------------- measurement


def measure(pairs: list[Pair], use_filtered: bool) -> dict[str, Any]:
    """Returns per pose ("all", "standing", "bent") and joint: mean and SD over trials of the trial offsets (mm, body
    frame) and the number of trials."""
    out: dict[str, Any] = {}
    for per_pose in (False, True):
        trials = []
        for p in pairs:
            est = p.filtered if use_filtered else _raw(p.kinect)
            truth = register(est, p.vicon, p.joints)
            trials.append(om.trial_offsets(est, truth, per_pose))
        for pose in trials[0]:
            stack = np.stack([t[pose] for t in trials])  # (N, J, 3)
            rows = {}
            for j, name in enumerate(skeleton.JOINTS):
                v = stack[:, j][np.all(np.isfinite(stack[:, j]), axis=-1)]
                if len(v):
                    rows[name] = {"mean_mm": (1e3 * v.mean(axis=0)).tolist(), "sd_mm": (1e3 * v.std(axis=0)).tolist(),
                                  "norm_mm": 1e3 * float(np.linalg.norm(v.mean(axis=0))), "trials": len(v)}  # fmt: skip
            out[pose] = rows
    return out


# ----------------------------------------------------------------------------------------------- validation


def evaluate(train: list[Pair], test: list[Pair], per_pose: bool) -> tuple[JointErrorSums, JointErrorSums]:
    """Fits on train (offline outputs) and returns the error sums of test before and after the model."""
    model = om.fit([(p.filtered, register(p.filtered, p.vicon, p.joints)) for p in train], per_pose)
    before, after = JointErrorSums.zeros(skeleton.J), JointErrorSums.zeros(skeleton.J)
    for p in test:
        before.add_body(errors(p.filtered, p))
        after.add_body(errors(model.apply(p.filtered), p))
    return before, after


def cross_validate(pairs: list[Pair], per_pose: bool) -> tuple[JointErrorSums, JointErrorSums]:
    """Leave-one-group-out: each group's pairs tested on a model fitted on the other groups; sums pooled."""
    before, after = JointErrorSums.zeros(skeleton.J), JointErrorSums.zeros(skeleton.J)
    for g in sorted({p.group for p in pairs}):
        b, a = evaluate([p for p in pairs if p.group != g], [p for p in pairs if p.group == g], per_pose)
        before.merge(b)
        after.merge(a)
    return before, after


def _result(before: JointErrorSums, after: JointErrorSums) -> dict[str, Any]:
    return {"before": {"pooled": before.pooled(), "per_joint": per_joint(before)},
            "after": {"pooled": after.pooled(), "per_joint": per_joint(after)}}  # fmt: skip


def validate(keraal: list[Pair], ui: list[Pair]) -> dict[str, Any]:
    out = {}
    for per_pose in (False, True):
        tag = "per_pose" if per_pose else "per_joint"
        out[f"KERAAL in-sample, fit and test on all ({tag})"] = _result(*evaluate(keraal, keraal, per_pose))
        out[f"UI-PRMD in-sample, fit and test on all ({tag})"] = _result(*evaluate(ui, ui, per_pose))
        out[f"KERAAL leave-one-trial-out ({tag})"] = _result(*cross_validate(keraal, per_pose))
        out[f"UI-PRMD leave-one-movement-out ({tag})"] = _result(*cross_validate(ui, per_pose))
        out[f"fit KERAAL, test UI-PRMD ({tag})"] = _result(*evaluate(keraal, ui, per_pose))
        out[f"fit UI-PRMD, test KERAAL ({tag})"] = _result(*evaluate(ui, keraal, per_pose))
        out[f"both datasets, leave-one-trial/movement-out ({tag})"] = _result(*cross_validate(keraal + ui, per_pose))
    return out


# ----------------------------------------------------------------------------------------------- report


def _vec(v: list[float]) -> str:
    return "/".join(f"{x:+.0f}" for x in v)


def _cell(c: dict[str, Any] | None) -> str:
    if not c:
        return "—"
    sd = f" ± {_vec(c['sd_mm']).replace('+', '')}" if c["trials"] > 1 else ""
    return f"{_vec(c['mean_mm'])}{sd} [{c['trials']}]"


def print_report(res: dict[str, Any]) -> None:
    print("\n### UI-PRMD time alignment (speed cross-correlation vs lowest registration RMS)\n")
    a = res["uiprmd_alignment"]
    print(f"{a['accepted']} of {a['pairs']} episode pairs kept (lags agree within {1e3 * LAG_AGREE_S:.0f} ms, "
          f"speed r >= {MIN_XCORR}, registration RMS <= {1e3 * MAX_RMS_M:.0f} mm); dropped: {a['dropped_lag']} lags "
          f"disagree, "
          f"{a['dropped_xcorr']} low r, {a['dropped_rms']} high RMS (a pair may fail several). Kept: registration RMS "
          f"median {a['rms_kept_mm'][1]:.0f} mm (IQR {a['rms_kept_mm'][0]:.0f}-{a['rms_kept_mm'][2]:.0f}), all: "
          f"median {a['rms_all_mm'][1]:.0f} mm. Kept per movement: {a['kept_per_movement']}")  # fmt: skip
    for source in ("raw", "filtered"):
        print(f"\n### Offset per joint, {source}: mean over trials x/y/z mm (left/up/forward) ± SD across trials "
              "[trials]\n")  # fmt: skip
        heads = [f"{d} {pose}" for d in res["measurement"] for pose in ("all", "standing", "bent")]
        print("| joint | " + " | ".join(heads) + " |")
        print("|---" * (1 + 3 * len(res["measurement"])) + "|")
        for jn in skeleton.JOINTS:
            cells = []
            for d in res["measurement"]:
                for pose in ("all", "standing", "bent"):
                    c = res["measurement"][d][source].get(pose, {}).get(jn)
                    cells.append(_cell(c))
            if any(c != "—" for c in cells):
                print(f"| {jn} | " + " | ".join(cells) + " |")
    print("\n### Validation: pipeline offline output before → after the model (test frames pooled), mm\n")
    print("| fold scheme | RMSE | bias part | random part | joint-frames |")
    print("|---|---|---|---|---|")
    for name, r in res["validation"].items():
        b, a = r["before"]["pooled"], r["after"]["pooled"]
        print(f"| {name} | {b['rmse_mm']:.1f} → {a['rmse_mm']:.1f} | {b['bias_mm']:.1f} → {a['bias_mm']:.1f} | "
              f"{b['random_mm']:.1f} → {a['random_mm']:.1f} | {b['n']} |")  # fmt: skip
    for name, r in res["validation"].items():
        if "per_pose" in name:
            continue
        print(f"\n#### {name}: per joint RMSE (bias) before → after, mm\n")
        print("| joint | before | after |")
        print("|---|---|---|")
        for jn, b in r["before"]["per_joint"].items():
            a = r["after"]["per_joint"][jn]
            print(f"| {jn} | {b['rmse_mm']:.1f} ({b['bias_mm']:.1f}) | {a['rmse_mm']:.1f} ({a['bias_mm']:.1f}) |")


def alignment_summary(ui_all: list[Pair]) -> dict[str, Any]:
    kept = [p for p in ui_all if p.accepted]
    per_movement: dict[str, list[int]] = {}
    for p in ui_all:
        per_movement.setdefault(p.group, [0, 0])[0] += int(p.accepted)
        per_movement[p.group][1] += 1
    return {
        "pairs": len(ui_all), "accepted": len(kept),
        "dropped_lag": sum(abs(p.lag_rms_s - p.lag_s) > LAG_AGREE_S + 1e-9 for p in ui_all),
        "dropped_xcorr": sum(p.xcorr < MIN_XCORR for p in ui_all),
        "dropped_rms": sum(p.rms_mm > 1e3 * MAX_RMS_M for p in ui_all),
        "rms_kept_mm": np.percentile([p.rms_mm for p in kept], [25, 50, 75]).tolist() if kept else [np.nan] * 3,
        "rms_all_mm": np.percentile([p.rms_mm for p in ui_all], [25, 50, 75]).tolist(),
        "kept_per_movement": {g: f"{k}/{n}" for g, (k, n) in sorted(per_movement.items())},
        "episodes": [{"name": p.name, "lag_s": p.lag_s, "lag_rms_s": p.lag_rms_s, "xcorr": p.xcorr,
                      "rms_mm": p.rms_mm, "accepted": p.accepted} for p in ui_all],
    }  # fmt: skip


def write_constants(model: om.OffsetModel, path: Path = CONSTANTS_PATH) -> None:
    """Writes the fitted offsets and their provenance as a Python module (kinect_agent.processing.offset_constants)."""
    lines = ['"""Fitted by bench/offset_model.py (generated; do not edit): Kinect minus mocap joint offsets, metres,',
             'body frame (x = subject\'s left, y = up, z = forward). See kinect_agent.processing.offset_model."""', "",
             "# fmt: off", f"PROVENANCE: dict[str, object] = {json.dumps(model.provenance, indent=4)}", "",
             "OFFSETS_M: dict[str, dict[str, tuple[float, float, float]]] = {"]  # fmt: skip
    for pose, off in model.offsets_m.items():
        lines.append(f'    "{pose}": {{')
        for j, name in enumerate(skeleton.JOINTS):
            if np.any(off[j] != 0.0):
                lines.append(f'        "{name}": ({off[j, 0]:.4f}, {off[j, 1]:.4f}, {off[j, 2]:.4f}),')
        lines.append("    },")
    lines += ["}", "# fmt: on"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def run(quick: bool = False, config: PipelineConfig | None = None) -> tuple[dict[str, Any], list[Pair], list[Pair]]:
    config = config or PipelineConfig()
    keraal = keraal_pairs()
    ui_all = uiprmd_pairs(range(1, 4) if quick else range(1, 11))
    ui = [p for p in ui_all if p.accepted]
    for p in (*keraal, *ui):
        p.filtered = process(p.kinect, config=config).filtered.positions
    res = {
        "date": datetime.date.today().isoformat(),
        "uiprmd_alignment": alignment_summary(ui_all),
        "uiprmd_durations_s": {
            "kinect": [min(p.kinect.t[-1] for p in ui_all), max(p.kinect.t[-1] for p in ui_all)],
            "vicon": [min(p.vicon_s for p in ui_all), max(p.vicon_s for p in ui_all)],
        },
        "measurement": {
            d: {s: measure(ps, s == "filtered") for s in ("raw", "filtered")}
            for d, ps in (("KERAAL", keraal), ("UI-PRMD", ui))
        },
        "validation": validate(keraal, ui),
    }
    return res, keraal, ui


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="UI-PRMD episodes e01-e03 only")
    parser.add_argument("--json", help="also write the results to this file")
    parser.add_argument("--write-constants", choices=("none", "keraal", "uiprmd", "both"), default="none",
                        help="fit the shipped model on these pairs and write kinect_agent/processing/"
                             "offset_constants.py")  # fmt: skip
    args = parser.parse_args(argv)
    started = time.perf_counter()
    res, keraal, ui = run(quick=args.quick)
    print_report(res)
    if args.write_constants != "none":
        chosen = {"keraal": keraal, "uiprmd": ui, "both": keraal + ui}[args.write_constants]
        provenance = {"fitted_by": "bench/offset_model.py", "date": res["date"], "on": args.write_constants,
                      "data": sorted({DATA_NOTE[p.dataset] for p in chosen}),
                      "pairs": [f"{p.dataset} {p.name}" for p in chosen][:20] + (["..."] if len(chosen) > 20 else []),
                      "n_pairs": len(chosen), "input": "pipeline offline output (PipelineConfig defaults)",
                      "validation_rmse_mm": {k: [round(v["before"]["pooled"]["rmse_mm"], 1),
                                                 round(v["after"]["pooled"]["rmse_mm"], 1)]
                                             for k, v in res["validation"].items() if "per_pose" not in k}}  # fmt: skip
        write_constants(om.fit([(p.filtered, register(p.filtered, p.vicon, p.joints)) for p in chosen],
                               provenance=provenance))  # fmt: skip
        print(f"\nwrote {CONSTANTS_PATH.relative_to(ROOT_DIR)}")
    print(f"\n({time.perf_counter() - started:.0f} s)")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(res, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
