"""The paper's figures from measured pairs, as PNG (matplotlib, Agg backend; imported only when drawing):
figure 3  per scored joint: the histogram of the raw offset distance with the Gaussian + uniform mixture fitted
          to it (kinect_agent.processing.outliers.fit_mixture, 1-D, the pipeline's floors) drawn over it
figure 4  joint angles over time of one pair: Kinect raw, Kinect filtered (the pipeline) and mocap, for the two
          angles with the largest mocap range
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.angles import joint_angles
from kinect_agent.errors import AgentError
from kinect_agent.evaluation.measure import PairErrors
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.outliers import fit_mixture

ANGLES = ("elbow_flexion_L", "elbow_flexion_R", "shoulder_abduction_L", "shoulder_abduction_R", "shoulder_flexion_L",
          "shoulder_flexion_R", "knee_flexion_L", "knee_flexion_R", "hip_flexion_L", "hip_flexion_R")  # fmt: skip


class PlottingUnavailable(AgentError):
    """matplotlib is not installed (it is in the `evaluate` extra)."""


def pyplot() -> ModuleType:
    """Returns matplotlib.pyplot on the Agg backend; raises PlottingUnavailable when matplotlib is missing."""
    try:
        import matplotlib
    except ModuleNotFoundError:
        raise PlottingUnavailable(
            "the evaluate figures need matplotlib: pip install 'kinect-home-coach[evaluate]' (or pass --no-figures)"
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def mixture_figure(errors: list[PairErrors], path: Path, config: PipelineConfig | None = None) -> None:
    """Draws figure 3: per joint with raw offsets, histogram (mm) and the fitted mixture density, to path (PNG)."""
    config = config or PipelineConfig()
    plt = pyplot()
    d = np.concatenate([e.distance("raw") for e in errors], axis=0)  # (N, J) m
    joints = [j for j in range(skeleton.J) if np.isfinite(d[:, j]).sum() >= 10]
    if not joints:
        return
    mix = fit_mixture(d[:, joints], min_sigma=config.outlier_min_sigma_m, min_width=config.outlier_min_range_m,
                      min_rho=0.5)  # fmt: skip
    cols = 4
    rows = (len(joints) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.4 * rows), squeeze=False)
    for k, j in enumerate(joints):
        ax = axes[k // cols][k % cols]
        v = 1e3 * d[np.isfinite(d[:, j]), j]
        ax.hist(v, bins=40, density=True, color="#9ecae1", edgecolor="none")
        x = np.linspace(0.0, max(v.max(), 1.0), 300)
        mu, sigma, rho = 1e3 * mix.mu[k, 0], 1e3 * mix.sigma[k, 0], mix.rho[0, k]
        width = 1e3 * (mix.x2[k, 0] - mix.x1[k, 0])
        gauss = rho * np.exp(-0.5 * ((x - mu) / sigma) ** 2) / (sigma * np.sqrt(2 * np.pi))
        ax.plot(x, gauss + (1.0 - rho) / width, color="#d62728", lw=1.2)
        ax.set_title(f"{skeleton.JOINTS[j]}  ρ={rho:.2f}", fontsize=9)
        ax.tick_params(labelsize=7)
    for k in range(len(joints), rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.supxlabel("offset to mocap, mm (raw Kinect)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def angle_figure(e: PairErrors, path: Path) -> list[str]:
    """Draws figure 4 for one pair to path (PNG); returns the angles drawn (none: nothing written)."""
    series = {s: joint_angles(x) for s, x in
              (("raw", e.estimates["raw"]), ("filtered", e.estimates["pipeline"]), ("mocap", e.truth))}  # fmt: skip
    ranges = {}
    for name in ANGLES:
        m = series["mocap"][name]
        if np.isfinite(m).mean() > 0.5:
            ranges[name] = float(np.nanmax(m) - np.nanmin(m))
    chosen = sorted(ranges, key=lambda name: ranges[name], reverse=True)[:2]
    if not chosen:
        return []
    plt = pyplot()
    fig, axes = plt.subplots(len(chosen), 1, figsize=(8, 2.6 * len(chosen)), squeeze=False)
    t = e.t - e.t[0]
    for ax, name in zip(axes[:, 0], chosen, strict=True):
        ax.plot(t, series["raw"][name], color="#bbbbbb", lw=1, label="Kinect raw")
        ax.plot(t, series["filtered"][name], color="#1f77b4", lw=1.4, label="Kinect filtered")
        ax.plot(t, series["mocap"][name], color="#d62728", lw=1.2, ls="--", label="mocap")
        ax.set_ylabel(f"{name}, °", fontsize=8)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time, s")
    fig.suptitle(e.pair.spec.name, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return chosen
