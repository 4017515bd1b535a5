"""Shared inputs of the analysis tests: simulated sessions and UI-PRMD movements."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from kinect_agent.formats import ui_prmd
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate

UI_PRMD_KINECT = Path("ui-prmd") / "Segmented Movements" / "Kinect"


@lru_cache(maxsize=8)
def noisy(exercise: str, reps: int, seed: int) -> tuple[Recording, Recording]:
    """Returns (measured, truth) of a simulated Kinect 2 session at 0°."""
    measured, truth, _ = simulate(exercise, reps, seed=seed)
    return measured, truth


def uiprmd(data_dir: Path, movement: str, subject: str) -> Recording:
    """Returns the 10 episodes of one UI-PRMD movement and subject, joined."""
    return ui_prmd.read_episodes(data_dir / UI_PRMD_KINECT, movement=movement, subject=subject)
