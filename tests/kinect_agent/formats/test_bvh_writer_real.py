"""BVH writer on real Kinect recordings (../shared/data) filtered by the pipeline: the file rebuilds the filtered
joints, and its offsets are the filter's segment lengths. Short slices keep each case to a few seconds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import formats, skeleton
from kinect_agent.formats import bvh, bvh_writer
from kinect_agent.processing.pipeline import process

FRAMES = 120
RECORDINGS = {
    "utkinect": ("utkinect/joints_s02_e01.txt", "utkinect"),
    "keraal": ("keraal/kinect_vicon_pairs/G3-Kinect-CTK-P1T1-Unknown-C-0.txt", "keraal"),
    "ui_prmd": ("ui-prmd/Segmented Movements/Kinect/Positions/m01_s01_e01_positions.txt.gz", "ui_prmd"),
}


@pytest.mark.parametrize("name", sorted(RECORDINGS))
def test_filtered_real_recording_round_trips_within_1_mm(data_dir: Path, tmp_path: Path, name: str) -> None:
    relative, fmt = RECORDINGS[name]
    rec = formats.read(data_dir / relative, fmt)
    result = process(rec.slice(0, min(FRAMES, rec.n_frames)))
    filtered = result.filtered
    path = tmp_path / f"{name}.bvh"
    path.write_text(bvh_writer.write_text(filtered.t, filtered.positions), encoding="utf-8")
    back = bvh.read(path)
    err_mm = np.linalg.norm(back.positions - filtered.positions, axis=-1) * 1000
    f, j = np.unravel_index(np.argmax(err_mm), err_mm.shape)
    assert err_mm.max() < 1.0, f"{name}: {err_mm.max():.4f} mm at frame {f} joint {skeleton.JOINTS[j]}"
    written = np.median(skeleton.bone_lengths(back.positions), axis=0)
    np.testing.assert_allclose(written, result.params.segment_lengths, atol=1e-5, err_msg=name)
