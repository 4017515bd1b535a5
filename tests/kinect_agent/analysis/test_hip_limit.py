"""A hip flexion past what a hip reaches is the Kinect losing the thigh, withheld with its reason; a real deep one is
shown (kinect_agent.analysis.anatomy: HIP_LIMIT_DEG, 190°; bench/flexion_limit.py and bench/README.md, "Hip
flexion's anatomical limit").

Hip flexion is the thigh in the trunk's sagittal plane (kinect_agent.body.angles): 90 seated, 180 along the trunk
towards the neck. On mocap no frame passes 181.1° (UI-PRMD Vicon s01's incorrect deep squat, the trunk folded onto the
thighs); the UI-PRMD Kinect reads its thighs at 200-260° in sit-to-stands and where it flips a thigh over the top at a
hurdle step's knee lift, where its Vicon reads 114-145°."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import formats
from kinect_agent.analysis.anatomy import HIP_LIMIT_DEG
from kinect_agent.analysis.document import AnalysisReport
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.formats import ui_prmd, ui_prmd_vicon
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording

HIPS = ("hip_flexion_L", "hip_flexion_R")
FOLDERS = {"correct": "Segmented Movements", "incorrect": "Incorrect Segmented Movements"}


def analysed(raw: Recording, slug: str) -> AnalysisReport:
    """Returns the session's document as the server makes it: the agent's filter, then the analysis."""
    result = process(raw)
    return analyze_recording(raw, EXERCISES[slug], filtered=result.filtered, angle_sd=result.angle_sd)


def test_a_kinect_thigh_flipped_over_the_top_at_a_hurdle_step_is_withheld(data_dir: Path) -> None:
    """UI-PRMD s04's hurdle step (Kinect): at the top of each knee lift the right thigh flips to 250-260° (knee
    behind and above the hip) for 2-3 frames; its Vicon (s01) lifts to 114°. The right hip's range and the
    repetitions whose peak is measured on that curve say why instead of showing it, naming the hip's limit."""
    folder = data_dir / "ui-prmd" / FOLDERS["correct"] / "Kinect"
    doc = analysed(ui_prmd.read_episodes(folder, movement="m02", subject="s04"), "hurdle_step")
    why = (doc.range_of_motion_withheld or {}).get("hip_flexion_R")
    assert why is not None and why.id == "beyond_anatomy", doc.range_of_motion_withheld
    assert why.params["limit"] == round(HIP_LIMIT_DEG) and float(why.params["reached"]) > 240.0, why
    assert doc.range_of_motion["hip_flexion_R"].max_deg is None
    withheld = [r for r in doc.repetition_list if r.withheld is not None]
    assert withheld, [r.peak_deg for r in doc.repetition_list]
    assert all(r.withheld is not None and r.withheld.params["limit"] == round(HIP_LIMIT_DEG) for r in withheld)
    assert all(r.peak_deg is not None and r.peak_deg <= HIP_LIMIT_DEG for r in doc.repetition_list if not r.withheld)
    assert doc.rom_deg is None and doc.rom_deg_withheld is not None
    assert doc.rom_deg_withheld.id == "repetitions_beyond_anatomy"
    assert doc.range_of_motion["hip_flexion_L"].max_deg is not None  # the standing leg: a hip's range, shown


def test_a_kinect_sit_to_stand_s_seated_thighs_are_withheld(data_dir: Path) -> None:
    """UI-PRMD s01's sit to stand: the Kinect reads the seated thighs at 200-222° where its Vicon reads 128-131°;
    both hips' ranges are withheld (the exercise counts on the knees: its repetitions are the knees' to withhold)."""
    folder = data_dir / "ui-prmd" / FOLDERS["correct"] / "Kinect"
    doc = analysed(ui_prmd.read_episodes(folder, movement="m05", subject="s01"), "sit_to_stand")
    for name in HIPS:
        why = (doc.range_of_motion_withheld or {}).get(name)
        assert why is not None and why.id == "beyond_anatomy" and why.params["limit"] == round(HIP_LIMIT_DEG), why


@pytest.mark.parametrize(
    ("kind", "movement", "slug", "deepest"),
    [("incorrect", "m01", "deep_squat", 170.0), ("incorrect", "m02", "hurdle_step", 120.0)],
)
def test_a_mocap_deep_hip_is_shown(data_dir: Path, kind: str, movement: str, slug: str, deepest: float) -> None:
    """UI-PRMD Vicon s01: the incorrect deep squat folds the trunk onto the thighs (the deepest hip on mocap,
    about 180°), the incorrect hurdle step lifts the knee to about 130°; nothing of them is withheld as beyond
    anatomy, and the deep squat's range reads past 170°."""
    paths = sorted((data_dir / "ui-prmd" / FOLDERS[kind] / "Vicon" / "Positions").glob(f"{movement}_s01_e*"))
    episodes = [ui_prmd_vicon.read(p) for p in paths]
    positions = np.concatenate([r.positions for r in episodes])[::3]  # 100 Hz thinned to 33 Hz
    raw = Recording.from_positions(np.arange(len(positions)) / (episodes[0].rate_hz / 3), positions, episodes[0].meta)
    doc = analysed(raw, slug)
    withheld = doc.range_of_motion_withheld or {}
    assert not any(why.id == "beyond_anatomy" for why in withheld.values()), withheld
    assert all(r.withheld is None for r in doc.repetition_list) and doc.rom_deg_withheld is None
    top = max(doc.range_of_motion[name].max_deg or 0.0 for name in HIPS)
    assert deepest < top <= HIP_LIMIT_DEG, top


def test_hdm05_elbow_to_knee_lifts_are_shown(data_dir: Path) -> None:
    """HDM05 (mocap) bd's elbow-to-knee clips: the hips flex to about 120° with the trunk bent onto the knee;
    counted as hip exercises, none of their repetitions is withheld."""
    clips = sorted((data_dir / "hdm05" / "elbowToKnee1RepsLelbowStart").glob("*_bd_*.amc"))[:3]
    recs = [formats.read(p) for p in clips]
    positions = np.concatenate([r.positions[::4] for r in recs])  # 120 Hz thinned to 30 Hz
    raw = Recording.from_positions(np.arange(len(positions)) / 30.0, positions, recs[0].meta)
    doc = analysed(raw, "hurdle_step")
    assert doc.repetitions >= 1 and all(r.withheld is None for r in doc.repetition_list), doc.repetition_list
    assert not any(why.id == "beyond_anatomy" for why in (doc.range_of_motion_withheld or {}).values())
