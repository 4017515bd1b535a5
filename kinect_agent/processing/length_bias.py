"""A device's segment-length bias: the filter's segment lengths scaled to the body's (issue 24 point 3).

The Kinect's joints are not the anatomical joint centres, and its bones come out shorter than the mocap's (the
paper's Kinect 2 table: upper arms 51-66 mm, forearms 25-34 mm short; KERAAL's pairs 8-53 mm). A filter fed such
joints estimates such bones. This step, applied on its own (PipelineConfig.length_bias: the ratios per segment;
None: off), scales the lengths the filter has estimated before they are fixed (offline: after passes 1-2; online:
when online_init_s ends):

    lengths[b] <- ratios[segment of b] * lengths[b]      (19,) m; bones without a ratio unchanged

A ratio is the truth's median segment length over the filter's estimate of it, per segment, fitted on
simultaneous Kinect + mocap recordings by bench/length_bias.py with the filter settings it is meant for (the ratio
of one filter's lengths does not hold for another's). Only segments whose both ends the mocap estimates in both
datasets we have are modelled (upper arm and forearm: KERAAL's SCoRE centres, UI-PRMD's acromion / epicondyle /
wrist markers); see bench/README.md, "A segment-length bias step".
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton

# Fitted by bench/length_bias.py (truth / filter length, per segment, skeleton.SEGMENTS names) for the unbiased
# filter (innovation_at_mean=True, outlier_window_s=0.3; its lengths are the Kinect's, unstretched), 2026-11-28: the
# mean of the two subjects' ratios (KERAAL P1, SCoRE centres: 1.147 / 1.087; UI-PRMD s01, markers: 1.212 / 1.203),
# upper arms only (the forearms disagree: KERAAL 1.149 / 1.017, UI-PRMD 0.994 / 0.985). Not on by default: on
# UI-PRMD's positions it loses (bench/README.md, "A segment-length bias step"). No table for Kinect 1 or the webcam
# (no paired mocap): a device without a table is never scaled.
RATIOS: dict[str, dict[str, float]] = {
    "kinect2": {"ARM_UP_L": 1.179, "ARM_UP_R": 1.145},
}


def bone_ratios(ratios: dict[str, float]) -> np.ndarray:
    """Returns (19,) the factor of each bone (skeleton.BONES order) under `ratios` (segment name -> truth / estimate);
    1 where a bone has none. Raises ValueError for a name that is not in skeleton.SEGMENTS."""
    unknown = set(ratios) - set(skeleton.SEGMENTS)
    if unknown:
        raise ValueError(f"not segments: {sorted(unknown)}")
    out = np.ones(len(skeleton.BONES))
    bone_of = {bone: k for k, bone in enumerate(skeleton.BONES)}
    for segment, ratio in ratios.items():
        a, b = skeleton.SEGMENTS[segment]
        out[bone_of[(skeleton.INDEX[a], skeleton.INDEX[b])]] = ratio
    return out


def apply(lengths: np.ndarray, ratios: dict[str, float] | None) -> np.ndarray:
    """Returns the lengths (19,) m scaled by `ratios` (a new array); None: a copy, unchanged."""
    lengths = np.array(lengths, dtype=np.float64)
    if ratios is None:
        return lengths
    return lengths * bone_ratios(ratios)


__all__ = ["RATIOS", "apply", "bone_ratios"]
