"""The 20-joint skeleton is declared once and consistently."""

from __future__ import annotations

import csv

import numpy as np

from kinect_agent import skeleton


def test_twenty_joints_with_parents_before_children() -> None:
    assert skeleton.J == 20
    assert skeleton.PARENT[0] == -1
    assert all(0 <= skeleton.PARENT[j] < j for j in range(1, skeleton.J))


def test_degrees_of_freedom_follow_the_paper() -> None:
    expected = {
        "SPINE": 3,
        "NECK": 3,
        "SHO_L": 3,
        "SHO_R": 3,
        "HIP_L": 3,
        "HIP_R": 3,
        "ELB_L": 1,
        "ELB_R": 1,
        "KNE_L": 1,
        "KNE_R": 1,
        "WRI_L": 2,
        "WRI_R": 2,
        "ANK_L": 2,
        "ANK_R": 2,
    }
    for joint, dof in expected.items():
        assert skeleton.DOF[joint] == dof, joint
    leaves = {j for j in skeleton.JOINTS if j not in skeleton.PARENT_NAME.values()}
    assert leaves == {"HEAD", "HAN_L", "HAN_R", "FOO_L", "FOO_R"}
    assert all(skeleton.DOF[j] == 0 for j in leaves)


def test_segments_match_the_paper_tables(reference_dir) -> None:
    with open(reference_dir / "bone_length_error_standing_mm.csv") as f:
        tabled = [row["segment"] for row in csv.DictReader(f)]
    assert sorted(tabled) == sorted(skeleton.SEGMENT_NAMES)
    with open(reference_dir / "joint_offset_standing_mm.csv") as f:
        assert [row["joint"] for row in csv.DictReader(f)] == list(skeleton.JOINTS)


def test_every_segment_is_a_bone() -> None:
    bones = set(skeleton.BONES)
    for proximal, distal in skeleton.SEGMENT_JOINTS:
        assert (proximal, distal) in bones


def test_segment_lengths_are_nan_where_an_end_is_untracked(rng: np.random.Generator) -> None:
    positions = rng.normal(size=(4, skeleton.J, 3))
    positions[2, skeleton.INDEX["ELB_L"]] = np.nan
    lengths = skeleton.segment_lengths(positions)
    arm_up, arm_lo = skeleton.SEGMENT_NAMES.index("ARM_UP_L"), skeleton.SEGMENT_NAMES.index("ARM_LO_L")
    assert np.isnan(lengths[2, arm_up]) and np.isnan(lengths[2, arm_lo])
    assert np.isfinite(np.delete(lengths, 2, axis=0)).all()


def test_mirror_name() -> None:
    assert skeleton.mirror_name("SHO_L") == "SHO_R"
    assert skeleton.mirror_name("LEG_UP_R") == "LEG_UP_L"
    assert skeleton.mirror_name("ROOT") == "ROOT"
