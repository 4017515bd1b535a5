"""The signal pipeline of the home agent: outlier removal, then the four-pass kinematic UKF (Wang et al., §3.2, §4).

    rec ──combined_outliers: temporal mixture (outliers.py) + sustained excursions (excursions.py)──> clean
        (tracking-loss samples -> missing)
        ──ik.inverse_kinematics────> personalised chain + start values
        ──pass 1 forward UKF, pass 2 backward UKF (state: root, 19 lengths, 33 joint angles; x(t) = x(t±1) + δ)
        ──lengths fixed (removed from the state: covariance and process noise zero)
        ──pass 3 forward UKF, then either (config.smoother; why: bench/README.md, "Tuning history of the pipeline
          defaults", `smoother`)
              "urts" (default): the unscented RTS smoother (Särkkä 2008) run backwards over pass 3's estimates
                           (exact for the random-walk transition);
              "four_pass": the paper's pass 4, a backward UKF started from pass 3's end. Output (four_pass_combine):
                           "last" = pass 4 itself (default), or "information" = per frame the information-weighted
                           mean of passes 3 and 4 (P = (P3⁻¹ + P4⁻¹)⁻¹, x = P (P3⁻¹ x3 + P4⁻¹ x4)).
        ──forward kinematics──> filtered Recording (every joint of every frame) + KinematicParams + quality.

State per frame (ChainModel of kinematics.py): root position (3, m), segment lengths (19, m; passes 1-2 only) and
33 joint angles (rad): rotation vectors relative to per-sequence reference rotations for the 3-DoF joints, hinge
angles for elbows/knees, two angles for wrists/ankles. Observation: the 20 joint positions (60 values, m, camera
frame); per frame only observed joints enter (rows of z and R selected), tracked joints with SD sigma_tracked_m per
axis, inferred joints with sigma_inferred_m. Process noise is a random walk scaled with the frame interval:
Q = q² · dt · rate_ref (offline: offline_q_rot_rad / offline_q_root_m in place of q_rot_rad / q_root_m), with a
variance ceiling (the initial variance) so that directions no joint observes cannot spread the sigma points over
several radians. Joints whose innovation is improbable (d² > gate_chi2 for one joint) are skipped in that step; a
joint skipped for reacquire_s without a break has lost track: the angles that place it restart from inverse
kinematics of that frame with the initial variance, and the gate admits it again (why: bench/README.md, "Tuning
history of the pipeline defaults", `reacquire_s`).
Passes 1-2 use the first length_pass_max_frames frames of longer recordings (they only estimate the lengths).
An exact input (segment lengths rigid to below rigid_input_sd_m: mocap, a filtered recording fed again) is filtered
with noise_level.rigid_settings: the chain's misfit as measurement SD and the innovation at the mean state's joints,
so that what goes in comes out (why: bench/README.md, "Fed the truth, return the truth").

config.offline_filter = "joints" (the webcam's setting) replaces the four passes offline by joint_smoother.py: each
joint coordinate smoothed on its own (constant-velocity RTS), restarted at left/right label swaps and body jumps
(quality["joint_restarts"]); the kinematic parameters are then the chain fitted to its output frame by frame, and
angle_sd is None (why: bench/README.md, "Webcam angles: why the pipeline made them worse").

Where the parts live: the settings in config.py (PipelineConfig), the chain's UKF (state layout, observation
function, variance ceiling, gated update, re-acquisition) in chain_filter.py (ChainFilter), the forward pass frame
by frame for live feedback and process(online=True) in online.py (OnlineFilter, run_online); here the passes,
the smoother and process().
"""

from __future__ import annotations

import mmap
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np

from kinect_agent import skeleton
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.body.angles import joint_angles
from kinect_agent.body.kinematics import ChainModel
from kinect_agent.body.rotations import matrix_to_quat
from kinect_agent.processing import length_bias, noise_level, offset_model, uncertainty
from kinect_agent.processing.chain_filter import N_LEN, N_ROOT, ChainFilter, FrameData
from kinect_agent.processing.combined_outliers import remove_outliers_combined
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.errors import FilterDiverged
from kinect_agent.processing.ik import IKResult, inverse_kinematics
from kinect_agent.processing.joint_smoother import smooth_joints
from kinect_agent.processing.online import run_online
from kinect_agent.processing.params import KinematicParams
from kinect_agent.processing.ukf import combine_information, unscented_rts
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED, TRACKED

# The pipeline's version: written to every session file's params["pipeline"] (provenance.pipeline_params) and to each
# filtered recording's history. Raise it when process() gives other output for the same input and settings; a change
# of a default setting needs no raise (the file's params["config"] is compared too). `coach-server reanalyze
# --pipeline` filters again every stored session made by another version or other settings (provenance.stale_reason).
VERSION = "ukf-4pass v1"
MAX_COORDINATE_M = 100.0  # farther from the camera than this on any axis: not metres (a Kinect sees up to ~8 m)
Progress = Callable[[int, int], None]


@dataclass
class PipelineResult:
    """filtered: same frames and times as the input, every joint filled (state 2 observed, 1 filled by the model).

    params: kinematic parameters. quality: outlier_fraction {joint: fraction of present samples removed},
    segment_sd_before_mm / segment_sd_after_mm {segment: SD of its length}, frames_without_observation,
    n_frames, n_outliers, n_gated, smoother, online, seconds, angle_sd_seconds, stage_cpu_seconds {outliers,
    passes, smoother, angle_sd: CPU s of each step (steadier than wall time on a shared machine), for benchmarks}.
    segment_noise_mm: the measurement SD the input's segment lengths show (noise_level.segment_noise_m; None: too
    few segments), rigid_input: whether it was below config.rigid_input_sd_m, so filtered as exact (offline only).
    offline_filter: config.offline_filter (None online); joint_restarts: the frames the joints filter restarted at
    (label swaps, body jumps; None unless that filter ran).
    angle_sd: {angle of angles.ANGLE_NAMES: (T,) degrees}, the calibrated SD of each clinical angle per frame
    (uncertainty.angle_sd of the smoother's covariance); None online (the forward pass keeps no covariances).
    """

    filtered: Recording
    params: KinematicParams
    quality: dict[str, Any]
    angle_sd: dict[str, np.ndarray] | None = None


# ----------------------------------------------------------------------------------------------------- filtering


def observations(rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns z (T, 60) m, observed (T, 60) bool, R_diag (T, 60) m² from a recording (missing rows NaN/False).

    R_diag: sigma_inferred_m² for inferred joints, sigma_tracked_m² (the offline SD) for tracked ones.
    """
    T = rec.n_frames
    z = rec.positions.reshape(T, -1)
    obs = np.repeat(rec.state != NOT_TRACKED, 3, axis=1) & np.isfinite(z)
    sd = np.where(rec.state == INFERRED, config.sigma_inferred_m, config.sigma_tracked_m)
    return z, obs, np.repeat(sd**2, 3, axis=1)


def small_pages(shape: tuple[int, ...]) -> np.ndarray:
    """Returns an uninitialised float64 array of `shape`, as np.empty, on its own anonymous memory map.

    numpy asks the kernel for transparent huge pages (madvise) on every large array, and where the system's THP
    defrag setting is "madvise" (as on the machines of bench/README.md) the kernel then compacts memory to fault
    them in. Pass 3's covariances, (T, 36, 36) = 190 MB for 10 minutes at 30 Hz, written frame by frame, cost
    0.24-0.33 s of system time that way and 0.11 s in 4-KiB pages (bench/README.md, "Speed on hard recordings").
    The map is released with the last array that uses it.
    """
    count = int(np.prod(shape))
    if count == 0:
        return np.empty(shape)
    return np.frombuffer(mmap.mmap(-1, 8 * count), dtype=np.float64).reshape(shape)


Observations = tuple[np.ndarray, np.ndarray, np.ndarray]  # z (T, 60) m, observed (T, 60) bool, R_diag (T, 60) m²


@overload
def _run_pass(
    kf: ChainFilter, order: np.ndarray, obs: Observations, q_steps: np.ndarray, config: PipelineConfig,
    store: Literal[True], tick: Callable[[int], None], restart: tuple[np.ndarray, int] | None = None,
) -> tuple[np.ndarray, np.ndarray, int]: ...  # fmt: skip


@overload
def _run_pass(
    kf: ChainFilter, order: np.ndarray, obs: Observations, q_steps: np.ndarray, config: PipelineConfig,
    store: Literal[False], tick: Callable[[int], None], restart: tuple[np.ndarray, int] | None = None,
) -> tuple[None, None, int]: ...  # fmt: skip


def _run_pass(
    kf: ChainFilter,
    order: np.ndarray,
    obs: Observations,
    q_steps: np.ndarray,
    config: PipelineConfig,
    store: bool,
    tick: Callable[[int], None],
    restart: tuple[np.ndarray, int] | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None, int]:
    """Runs one filter pass over frames in `order`; returns (xs (T, n), Ps (T, n, n)) in frame order if stored.

    q_steps: (T,) scale of Q (dt · rate_ref) for the step into each frame of `order` (first frame: no predict).
    restart: (start (T, 36) root m + theta rad per frame, e.g. from IK; n_frames): a joint the gate dropped in
    n_frames consecutive observed frames has lost track, and the entries that place it restart from `start` at the
    next frame it is observed (ChainFilter.reacquire). Returns also the number of joint samples dropped by the
    innovation gate.
    """
    z, observed, R_diag = obs
    n = kf.dim_x
    T = len(order)
    xs = np.empty((T, n)) if store else None
    Ps = small_pages((T, n, n)) if store else None
    gated = 0
    run = np.zeros(skeleton.J, dtype=np.int64)  # consecutive observed frames each joint was gated
    if kf.compiled:
        return _run_pass_compiled(kf, order, FrameData.of(z, observed, R_diag), q_steps, config, xs, Ps, tick, restart)
    any_observed: np.ndarray = np.any(observed, axis=1)  # (T,) per frame, computed once rather than per step
    present_joints: np.ndarray = np.all(observed.reshape(len(observed), skeleton.J, 3), axis=2)  # (T, J)
    n_present = present_joints.sum(axis=1)  # (T,)
    for i, k in enumerate(order):
        if i:
            kf.predict_random_walk(q_steps[i])
        if any_observed[k]:
            present = present_joints[k]
            if restart is not None:
                lost = present & (run >= restart[1])
                if lost.any():
                    kf.reacquire(np.flatnonzero(lost), restart[0][k])
                    run[lost] = 0
            used = kf.update_joints(z[k], observed[k], R_diag[k], config.gate_chi2)
            gated += int(n_present[k]) - int(np.count_nonzero(used))
            run += present & ~used
            run[used] = 0
        if xs is not None and Ps is not None:
            xs[k] = kf.x
            Ps[k] = kf.P
        if i % 64 == 63:
            tick(64)
    tick(T % 64)
    return xs, Ps, gated


def _run_pass_compiled(
    kf: ChainFilter,
    order: np.ndarray,
    frames: FrameData,
    q_steps: np.ndarray,
    config: PipelineConfig,
    xs: np.ndarray | None,
    Ps: np.ndarray | None,
    tick: Callable[[int], None],
    restart: tuple[np.ndarray, int] | None,
) -> tuple[np.ndarray | None, np.ndarray | None, int]:
    """_run_pass in compiled stretches of 64 frames (ChainFilter.run_frames), the same steps and results; a frame
    whose update the kernel declines is updated here by update_joints (its numpy fallback), as _run_pass does."""
    T = len(order)
    order = np.ascontiguousarray(order, dtype=np.int64)
    q_steps = np.ascontiguousarray(q_steps, dtype=np.float64)
    run = np.zeros(skeleton.J, dtype=np.int64)
    store = None if xs is None or Ps is None else (xs, Ps)
    restart_c = None if restart is None else (np.ascontiguousarray(restart[0], dtype=np.float64), restart[1])
    gated = 0
    for begin in range(0, T, 64):
        i, end = begin, min(begin + 64, T)
        while i < end:
            i, g = kf.run_frames(frames, order, q_steps, (i, end), config.gate_chi2, restart_c, run, store)
            gated += g
            if i < end:  # the kernel declined this frame's update: numpy's
                k = order[i]
                present = frames.present[k]
                used = kf.update_joints(frames.z[k], frames.observed[k], frames.R_diag[k], config.gate_chi2)
                gated += int(frames.n_present[k]) - int(np.count_nonzero(used))
                run += present & ~used
                run[used] = 0
                if store is not None:
                    store[0][k] = kf.x
                    store[1][k] = kf.P
                i += 1  # the next frame's predict is the kernel's
        if end - begin == 64:
            tick(64)
    tick(T % 64)
    return xs, Ps, gated


def _step_scales(t: np.ndarray, config: PipelineConfig) -> np.ndarray:
    """Returns (T,) the Q scale for stepping into frame k from frame k−1: dt · rate_ref (entry 0 unused)."""
    dt = np.diff(t, prepend=t[0] - 1.0 / config.rate_ref_hz)
    return np.maximum(dt, 1e-6) * config.rate_ref_hz


def _fixed_length_config(config: PipelineConfig) -> PipelineConfig:
    """Returns the settings of passes 3-4: innovation_at_mean replaced by fixed_innovation_at_mean when that is set.

    With the lengths fixed, the unscented offset of Σ Wm·h(σ) against h(x̄) can only be absorbed by the joint angles
    (bench/README.md, "Per-motion accuracy (issue 13)").
    """
    if config.fixed_innovation_at_mean is None:
        return config
    return config.model_copy(update={"innovation_at_mean": config.fixed_innovation_at_mean})


def smooth(
    clean: Recording,
    ik: IKResult,
    config: PipelineConfig,
    progress: Progress | None = None,
    covariances: bool = False,
    forward: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Runs the four passes on an outlier-free recording; returns (root (T, 3), lengths (19,), theta (T, 33), info).

    info: length_sd_m (19,) m, gated_per_pass [4 ints], length_pass_frames, stage_cpu_seconds {passes, smoother}
    (CPU s: passes 1-3; the unscented RTS or pass 4); with covariances=True also
    "covariance": (T, 36, 36) the smoothed covariance of each frame's state (root (3) m, theta (33) rad; m², rad²,
    m·rad), in the order of the returned root and theta; with forward=True also "forward": (root (T, 3) m,
    theta (T, 33) rad), pass 3's filtered estimates, the causal pass the smoother starts from (same lengths).
    """
    config = config.model_copy(
        update={
            "q_rot_rad": config.q_rot_rad if config.offline_q_rot_rad is None else config.offline_q_rot_rad,
            "q_root_m": config.q_root_m if config.offline_q_root_m is None else config.offline_q_root_m,
        }
    )
    cpu_started = time.process_time()
    T = clean.n_frames
    total = 4 * T
    done = [0]

    def tick(k: int) -> None:
        done[0] += k
        if progress is not None and k:
            progress(min(done[0], total), total)

    obs = observations(clean, config)
    scale = _step_scales(clean.t, config)
    fwd, bwd = np.arange(T), np.arange(T - 1, -1, -1)
    scale_bwd = np.concatenate(([0.0], scale[1:][::-1]))  # stepping from k+1 back to k uses dt of k+1
    # Passes 1 and 2: lengths in the state, over the first length_pass_max_frames frames (the lengths are constants
    # of the body; a contiguous stretch keeps the frame rate the angles were tuned for, which subsampling did not).
    n_len = T if not config.length_pass_max_frames else min(T, config.length_pass_max_frames)
    sub = np.arange(n_len)
    obs_sub = (obs[0][sub], obs[1][sub], obs[2][sub])
    scale_sub = scale[sub]
    scale_sub_bwd = np.concatenate(([0.0], scale_sub[1:][::-1]))
    n_sub = len(sub)
    restart = None
    if config.reacquire_s is not None and config.gate_chi2 is not None:
        dt = np.median(np.diff(clean.t)) if T > 1 else 1.0 / config.rate_ref_hz
        restart = (np.concatenate((ik.root, ik.theta), axis=1), max(1, int(round(config.reacquire_s / dt))))
    total = 2 * n_sub + 2 * T
    kf = ChainFilter(ik.model, None, config, np.concatenate((ik.root[0], ik.lengths, ik.theta[0])))
    _, _, g1 = _run_pass(kf, np.arange(n_sub), obs_sub, scale_sub, config, False, tick, restart)
    _, _, g2 = _run_pass(kf, np.arange(n_sub - 1, -1, -1), obs_sub, scale_sub_bwd, config, False, tick, restart)
    lengths = kf.x[N_ROOT : N_ROOT + N_LEN].copy()
    # A bone seen too rarely can wander (even below zero); keep the measured median length there.
    implausible = ~((lengths > 0.5 * ik.lengths) & (lengths < 2.0 * ik.lengths))
    lengths[implausible] = ik.lengths[implausible]
    lengths = length_bias.apply(lengths, config.length_bias)  # the device's bias, its own step (None: unchanged)
    length_sd = np.sqrt(np.diag(kf.P)[N_ROOT : N_ROOT + N_LEN])
    # Passes 3 and 4: lengths fixed (removed from the state: zero covariance and process noise).
    fixed = _fixed_length_config(config)
    kf3 = kf.with_lengths_fixed(lengths, fixed)
    xs3, Ps3, g3 = _run_pass(kf3, fwd, obs, scale, fixed, True, tick, restart)
    passes_done = time.process_time()
    if config.smoother == "urts":
        xs, Ps = unscented_rts(  # Ps3 smoothed in place (190 MB for 10 minutes), or not at all; xs3 for `forward`
            xs3.copy(), Ps3, kf3.Q, None, kf3.points, q_scale=np.append(scale[1:], 0.0), overwrite=True,
            covariances=covariances,
        )  # fmt: skip
        tick(T)
        g4 = 0
    else:
        kf4 = kf3.copy(fixed)
        xs4, Ps4, g4 = _run_pass(kf4, bwd, obs, scale_bwd, fixed, True, tick, restart)
        xs, Ps = (xs4, Ps4) if config.four_pass_combine == "last" else combine_information(xs3, Ps3, xs4, Ps4)
    stage_seconds = {"passes": passes_done - cpu_started, "smoother": time.process_time() - passes_done}
    info = {
        "length_sd_m": length_sd,
        "gated_per_pass": [g1, g2, g3, g4],
        "length_pass_frames": n_len,
        "stage_cpu_seconds": {k: round(v, 3) for k, v in stage_seconds.items()},
    }
    if covariances:
        info["covariance"] = Ps
    if forward:
        info["forward"] = (xs3[:, :N_ROOT], xs3[:, N_ROOT:])
    return xs[:, :N_ROOT], lengths, xs[:, N_ROOT:], info


# ----------------------------------------------------------------------------------------------------- process


def _segment_sd_mm(positions: np.ndarray) -> dict[str, float | None]:
    seg = skeleton.segment_lengths(positions)
    with np.errstate(all="ignore"):
        ok = np.isfinite(seg).sum(axis=0) >= 2
        sd = np.where(ok, np.nanstd(np.where(ok, seg, 0.0), axis=0), np.nan) * 1000.0
    return {name: (float(v) if np.isfinite(v) else None) for name, v in zip(skeleton.SEGMENT_NAMES, sd, strict=True)}


def _check_input(rec: Recording) -> None:
    if not isinstance(rec, Recording):
        raise TypeError(f"process needs a Recording, got {type(rec).__name__}")
    if rec.n_frames < 1:
        raise ValueError("the recording has no frames")
    if not np.any(rec.state != NOT_TRACKED):
        raise ValueError("no joint is tracked in any frame of the recording: nothing to filter")
    tracked = rec.positions[rec.state != NOT_TRACKED]
    with np.errstate(invalid="ignore"):
        farthest = float(np.nanmax(np.abs(tracked))) if np.isfinite(tracked).any() else 0.0
    if not farthest <= MAX_COORDINATE_M:
        raise ValueError(
            f"a tracked joint is {farthest:.3g} m from the camera on one axis (at most {MAX_COORDINATE_M:g} m "
            "expected): the positions must be in metres"
        )


def process(
    rec: Recording,
    *,
    online: bool = False,
    config: PipelineConfig | None = None,
    progress: Progress | None = None,
) -> PipelineResult:
    """Filters a recording: outlier removal then the four-pass UKF (or, online=True, the forward pass only).

    rec: positions (T, J, 3) m, NaN = untracked; state (T, J). progress(done, total) is called now and then.
    Returns the filtered recording (same t), the kinematic parameters and a quality summary. Runs with one BLAS
    thread (kinect_agent.blas_threads), whatever the caller's environment says.
    """
    started = time.perf_counter()
    with one_blas_thread():
        filtered, quality, chain = _filter(rec, online=online, config=config, progress=progress, angle_sds=True)
        params = _kinematic_params(rec.t, chain)
    quality["seconds"] = round(time.perf_counter() - started, 3)
    return PipelineResult(filtered, params, quality, chain.angle_sd)


@dataclass
class FilterResult:
    """filter_recording's output: filtered and quality as PipelineResult's (without the angle SDs' timings)."""

    filtered: Recording
    quality: dict[str, Any]


def filter_recording(
    rec: Recording,
    *,
    online: bool = False,
    config: PipelineConfig | None = None,
    progress: Progress | None = None,
) -> FilterResult:
    """process() for a caller that keeps only the filtered recording (`kinect-agent filter` without --params).

    The filtered recording and the quality summary are process()'s, bit for bit; what nobody would read is not
    built: the angle SDs, the smoothed covariances behind them (the RTS smooths the means only), the quaternions
    and the joint angles of KinematicParams (≈ 0.6 s CPU of a 10-minute 30 Hz recording).
    """
    started = time.perf_counter()
    with one_blas_thread():
        filtered, quality, _ = _filter(rec, online=online, config=config, progress=progress, angle_sds=False)
    quality["seconds"] = round(time.perf_counter() - started, 3)
    return FilterResult(filtered, quality)


@dataclass
class _Chain:
    """The estimates behind a filtered recording: model (the personalised chain), root (T, 3) m, lengths (19,) m,
    theta (T, 33) rad, positions (T, J, 3) m (the filtered joints), outlier_prob (T, J), angle_sd as
    PipelineResult's (None when not computed)."""

    model: ChainModel
    root: np.ndarray
    lengths: np.ndarray
    theta: np.ndarray
    positions: np.ndarray
    outlier_prob: np.ndarray
    angle_sd: dict[str, np.ndarray] | None


def _kinematic_params(t: np.ndarray, chain: _Chain) -> KinematicParams:
    """Returns the kinematic parameters of the chain's estimates at times t (T,) s: rotations as quaternions, the
    joint angles of its positions, the outlier probabilities."""
    R_world_root, R_local = chain.model.standard_rotations(chain.theta)
    return KinematicParams(
        t=t.copy(),
        segment_lengths=chain.lengths,
        root=chain.root,
        q_root=matrix_to_quat(R_world_root),
        q_local=matrix_to_quat(R_local),
        joint_angles=joint_angles(chain.positions),
        outlier_prob=chain.outlier_prob,
    )


def _filter(
    rec: Recording, *, online: bool, config: PipelineConfig | None, progress: Progress | None, angle_sds: bool
) -> tuple[Recording, dict[str, Any], _Chain]:
    """Returns (filtered recording, quality, the chain's estimates) of process(); angle_sds False: no angle SDs
    (nor the smoothed covariances they come from)."""
    started, cpu_started = time.perf_counter(), time.process_time()
    config = config or PipelineConfig()
    _check_input(rec)
    T = rec.n_frames
    stages: dict[str, float] = {}
    noise = noise_level.segment_noise_m(rec)
    rigid = not online and noise_level.is_rigid(noise, config)
    if rigid:
        config = noise_level.rigid_settings(config)
    if config.remove_outliers and not online:
        clean, prob = remove_outliers_combined(rec, config)
        stages["outliers"] = round(time.process_time() - cpu_started, 3)
        outlier = (prob > config.outlier_threshold) & (rec.state != NOT_TRACKED)
    else:
        clean, prob, outlier = rec, np.where(rec.state == NOT_TRACKED, 1.0, 0.0), np.zeros((T, skeleton.J), bool)
    sd = None
    smoothed = None
    if online:
        root, lengths, theta, model, info = run_online(clean, config, progress)
    elif config.offline_filter == "joints":
        smoothed, restarts = smooth_joints(clean, config)
        ik = inverse_kinematics(smoothed)
        root, lengths, theta, model = ik.root, ik.lengths, ik.theta, ik.model
        info = {"joint_restarts": int(restarts.sum())}
        stages["joints"] = round(time.process_time() - cpu_started - stages.get("outliers", 0.0), 3)
        if progress is not None:
            progress(T, T)
    else:
        ik = inverse_kinematics(clean.positions)
        root, lengths, theta, info = smooth(clean, ik, config, progress, covariances=angle_sds)
        model = ik.model
        stages.update(info.pop("stage_cpu_seconds"))
        if angle_sds:
            sd_started, sd_cpu = time.perf_counter(), time.process_time()
            sd = uncertainty.angle_sd(model, lengths, theta, info.pop("covariance"))
            info["angle_sd_seconds"] = round(time.perf_counter() - sd_started, 3)
            stages["angle_sd"] = round(time.process_time() - sd_cpu, 3)
    positions = model.positions(root, np.broadcast_to(lengths, (T, N_LEN)), theta) if smoothed is None else smoothed
    if not np.all(np.isfinite(positions)):
        bad = np.flatnonzero(~np.isfinite(positions).all(axis=(1, 2)))
        raise FilterDiverged(f"the filter's estimate is not finite in {len(bad)} of {T} frames (first: frame {bad[0]})")
    if config.offset_model:
        positions = offset_model.correct(positions)
    observed = clean.state != NOT_TRACKED
    state = np.where(observed, TRACKED, INFERRED).astype(np.int8)
    mode = "online forward pass" if online else config.smoother if config.offline_filter == "chain" else "joints"
    step = f"{VERSION} ({mode}; {int(outlier.sum())} outliers removed)"
    filtered = rec.replace(step=step, positions=positions, state=state)
    present = rec.state != NOT_TRACKED
    with np.errstate(all="ignore"):
        frac = np.where(present.sum(0) > 0, outlier.sum(0) / np.maximum(present.sum(0), 1), 0.0)
    quality = {
        "n_frames": T,
        "online": online,
        "smoother": None if online else config.smoother,
        "offline_filter": None if online else config.offline_filter,
        "joint_restarts": info.get("joint_restarts"),
        "n_outliers": int(outlier.sum()),
        "outlier_fraction": {j: float(f) for j, f in zip(skeleton.JOINTS, frac, strict=True)},
        "frames_without_observation": int(np.sum(~observed.any(axis=1))),
        "segment_sd_before_mm": _segment_sd_mm(rec.positions),
        "segment_sd_after_mm": _segment_sd_mm(positions),
        "segment_lengths_m": {
            f"{skeleton.JOINTS[p]}-{skeleton.JOINTS[c]}": float(v)
            for (p, c), v in zip(skeleton.BONES, lengths, strict=True)
        },
        "segment_noise_mm": None if noise is None else round(1e3 * noise, 3),
        "rigid_input": rigid,
        "n_gated": int(sum(info.get("gated_per_pass", [info.get("n_gated", 0)]))),
        "length_pass_frames": info.get("length_pass_frames"),
        "angle_sd_seconds": info.get("angle_sd_seconds"),
        "seconds": round(time.perf_counter() - started, 3),
        "stage_cpu_seconds": stages,
    }
    return filtered, quality, _Chain(model, root, lengths, theta, positions, prob, sd)


__all__ = ["VERSION", "FilterResult", "PipelineResult", "filter_recording", "observations", "process", "smooth"]
