"""The calibrated Kinect simulator: exact exercise motion from the kinematic chain, plus Kinect errors.

simulate_truth gives the exact recording (FK of the true parameters); simulate adds the measurement errors of
kinect_noise (calibrated on the paper's tables) and returns the measured recording, the truth and the mask of
joint-frames replaced by tracking-loss outliers.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np

from kinect_agent import skeleton
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources import motions
from kinect_agent.sources.base import Frame, Pacer, SourceBase
from kinect_agent.sources.kinect_noise import SimulationError, add_kinect_noise, check_setting
from kinect_agent.sources.motions import Body

EXERCISES: tuple[str, ...] = motions.EXERCISES
MAX_REPS = 500
__all__ = ["EXERCISES", "Body", "SimulationError", "SimulatorSource", "simulate", "simulate_truth"]


def _check(exercise: str, reps: int, pose: str | None, rate_hz: float) -> tuple[motions.ExerciseSpec, str]:
    if exercise not in motions.SPECS:
        raise SimulationError(f"unknown exercise {exercise!r}; known exercises: {', '.join(EXERCISES)}")
    if isinstance(reps, bool) or not isinstance(reps, (int, np.integer)) or not 1 <= reps <= MAX_REPS:
        raise SimulationError(f"reps must be a whole number from 1 to {MAX_REPS}, got {reps!r}")
    if not (isinstance(rate_hz, (int, float)) and np.isfinite(rate_hz) and 5.0 <= rate_hz <= 240.0):
        raise SimulationError(f"rate must be between 5 and 240 Hz, got {rate_hz!r}")
    spec = motions.SPECS[exercise]
    pose = pose or spec.poses[0]
    if pose not in ("sitting", "standing"):
        raise SimulationError(f"unknown pose {pose!r}; use sitting or standing")
    if pose not in spec.poses:
        raise SimulationError(f"{exercise} cannot be done {pose}; it is done {' or '.join(spec.poses)}")
    return spec, pose


def _truth(
    exercise: str,
    reps: int,
    pose: str | None,
    seed: int,
    rate_hz: float,
    body: Body | None,
    view_deg: float,
    amplitude_deg: float | None = None,
) -> Recording:
    spec, pose = _check(exercise, reps, pose, rate_hz)
    if amplitude_deg is not None:
        if not (np.isfinite(amplitude_deg) and 0.0 <= amplitude_deg <= 180.0):
            raise SimulationError(f"amplitude must be between 0 and 180 degrees, got {amplitude_deg!r}")
        spec = dataclasses.replace(spec, amplitude=float(amplitude_deg))
    rng_motion = np.random.default_rng([seed, 0])
    body = body or motions.random_body(np.random.default_rng([seed, 1]))
    sched = motions.schedule(spec, int(reps), rng_motion, float(rate_hz))
    positions = motions.truth_positions(spec, sched, body, pose, view_deg, rng_motion)
    meta = Metadata(
        device="simulator",
        rate_hz=float(rate_hz),
        subject=f"simulated-{seed}",
        exercise=exercise,
        view_deg=float(view_deg),
        pose=pose,
        source="simulator",
        history=[
            f"simulate_truth(exercise={exercise}, reps={reps}, pose={pose}, seed={seed}, rate={rate_hz}"
            + ("" if amplitude_deg is None else f", amplitude={amplitude_deg}")
            + ")"
        ],
        extra={
            "rep_bounds_s": [[float(a), float(b)] for a, b in sched.rep_bounds],
            "bone_lengths_m": [float(x) for x in body.lengths],
            "seed": int(seed),
        },
    )
    state = np.full(positions.shape[:2], skeleton.TRACKED, dtype=np.int8)
    return Recording(sched.t, positions, state, meta)


def simulate_truth(
    exercise: str,
    reps: int,
    *,
    pose: str | None = None,
    seed: int = 0,
    rate_hz: float = 30.0,
    body: Body | None = None,
    amplitude_deg: float | None = None,
) -> Recording:
    """Returns the exact recording of `reps` repetitions (device "simulator", subject facing the camera).

    amplitude_deg: the peak of the defining movement in degrees instead of the exercise's own (motions.SPECS), e.g. a
    shallow set (0: the subject stands or sits still, swaying); the same seed gives the same timing and body.

    positions: (T, J, 3) metres, camera frame (y up, camera 0.8 m above the floor), FK of the true parameters;
    segment lengths are constant. meta.extra["rep_bounds_s"]: [[start, end], ...] seconds, one per repetition.
    """
    return _truth(exercise, reps, pose, seed, rate_hz, body, 0.0, amplitude_deg)


def simulate(
    exercise: str,
    reps: int,
    *,
    device: str = "kinect2",
    view_deg: int = 0,
    pose: str | None = None,
    seed: int = 0,
    rate_hz: float = 30.0,
) -> tuple[Recording, Recording, np.ndarray]:
    """Returns (measured, truth, outlier_mask (T, J) bool) for a Kinect `device` viewing at `view_deg` degrees.

    The subject is turned by view_deg about the vertical; errors follow the paper's tables for (device, view, pose).
    """
    spec, pose = _check(exercise, reps, pose, rate_hz)
    check_setting(device, view_deg, pose)
    truth = _truth(exercise, reps, pose, seed, rate_hz, None, float(view_deg))
    measured, mask = add_kinect_noise(
        truth, device=device, view_deg=view_deg, pose=pose, rng=np.random.default_rng([seed, 2])
    )
    return measured, truth, mask


class SimulatorSource(SourceBase):
    """The simulator as a live source: measured frames of an exercise, block after block, forever.

    Each block is `simulate(exercise, reps_per_block, ..., seed=seed + block)`; the clock continues across blocks.
    realtime=True paces frames at the frame rate; False yields them as fast as possible.
    """

    name = "simulator"

    def __init__(
        self,
        exercise: str = "shoulder_abduction",
        *,
        device: str = "kinect2",
        view_deg: int = 0,
        pose: str | None = None,
        seed: int = 0,
        rate_hz: float = 30.0,
        reps_per_block: int = 3,
        realtime: bool = True,
    ) -> None:
        spec, self.pose = _check(exercise, reps_per_block, pose, rate_hz)
        check_setting(device, view_deg, self.pose)
        self.exercise, self.device, self.view_deg = exercise, device, view_deg
        self.seed, self.rate_hz, self.reps_per_block, self.realtime = seed, rate_hz, reps_per_block, realtime
        self._open = False

    def open(self) -> None:
        """Nothing to acquire; marks the source open."""
        self._open = True

    def close(self) -> None:
        """Marks the source closed."""
        self._open = False

    def frames(self) -> Iterator[Frame]:
        """Yields measured frames without end."""
        if not self._open:
            raise RuntimeError("SimulatorSource.frames() called before open()")
        pacer = Pacer(self.realtime)
        offset, block = 0.0, 0
        while True:
            measured, _, _ = simulate(
                self.exercise, self.reps_per_block, device=self.device, view_deg=self.view_deg, pose=self.pose,
                seed=self.seed + block, rate_hz=self.rate_hz,
            )  # fmt: skip
            for i in range(measured.n_frames):
                t = offset + float(measured.t[i])
                pacer.wait(t)
                yield Frame(t, measured.positions[i].copy(), measured.state[i].copy())
            offset += float(measured.t[-1]) + 1.0 / self.rate_hz
            block += 1

    def metadata(self) -> Metadata:
        """Returns the metadata of the simulated capture."""
        return Metadata(
            device=self.device, rate_hz=float(self.rate_hz), exercise=self.exercise, view_deg=float(self.view_deg),
            pose=self.pose, source="simulator", subject=f"simulated-{self.seed}",
            extra={"seed": int(self.seed), "reps_per_block": int(self.reps_per_block)},
        )  # fmt: skip
