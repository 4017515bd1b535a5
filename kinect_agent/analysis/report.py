"""The analysis document of one session, the one home of the session analysis: the server stores it with each
upload, `coach-server analyze FILE --exercise NAME` prints it (backend.session_texts.summary).

analyze_recording measures a recording that has already been through the agent's pipeline (or is clean, like
simulated truth); analyze_file reads any format kinect_agent.formats knows, takes the filtered recording of a
.khs session file when it has one and otherwise runs kinect_agent.processing.pipeline.process on the raw input,
then measures. Every key of the document is present, None when it does not apply.
The document's shape is kinect_agent.analysis.document.AnalysisReport (versioned, with every field described).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from kinect_agent.analysis import activity, quality
from kinect_agent.analysis.anatomy import own_angles, repetition_beyond_anatomy, repetition_frames, rom_beyond_anatomy
from kinect_agent.analysis.angles import counting_angles, measured_angles
from kinect_agent.analysis.balance import missing_reason, sway
from kinect_agent.analysis.document import AnalysisReport, json_ready
from kinect_agent.analysis.errors import AnalysisError, UnreadableRecording
from kinect_agent.analysis.exercise import ExerciseSpec, get_exercise
from kinect_agent.analysis.intervals import (
    KINDS,
    beyond_anatomy,
    beyond_raw,
    beyond_raw_reason,
    count_interval,
    rom_intervals,
)
from kinect_agent.analysis.live import amplitude_floor, counting_params, counting_positions, done_repetitions
from kinect_agent.analysis.most_moving import most_moving_joints
from kinect_agent.analysis.range_of_motion import range_of_motion
from kinect_agent.analysis.reachable import reachable_range
from kinect_agent.analysis.reasons import Reason
from kinect_agent.analysis.repetitions import Repetition, RepetitionParams, count_repetitions
from kinect_agent.analysis.sit_to_stand import sit_to_stand
from kinect_agent.body.angles import body_frame, joint_angles
from kinect_agent.errors import FormatError
from kinect_agent.processing.params import KinematicParams
from kinect_agent.recording import Recording


def _measured_positions(
    recording: Recording, params: KinematicParams | None, filtered: Recording | None
) -> tuple[np.ndarray, str]:
    """Returns the positions (T, J, 3) m the metrics use and where they come from."""
    if filtered is not None:
        if filtered.n_frames != recording.n_frames:
            raise AnalysisError(f"filtered has {filtered.n_frames} frames, the recording {recording.n_frames}")
        return filtered.positions, "filtered"
    if params is not None:
        if params.n_frames != recording.n_frames:
            raise AnalysisError(f"params have {params.n_frames} frames, the recording {recording.n_frames}")
        return params.positions(), "params"
    return recording.positions, "raw"


def _angle_sd(angle_sd: dict[str, np.ndarray] | None, n_frames: int) -> dict[str, np.ndarray] | None:
    """Returns the per-frame angle SDs when they describe n_frames frames, else None."""
    if not angle_sd:
        return None
    if any(np.shape(v) != (n_frames,) for v in angle_sd.values()):
        raise AnalysisError(f"angle_sd must hold ({n_frames},) per angle, like the recording")
    return angle_sd


def _median(values: list[float]) -> float | None:
    return round(float(np.median(values)), 1) if values else None


def measured_peak(t: np.ndarray, angles: dict[str, np.ndarray], names: tuple[str, ...], rep: Repetition) -> float:
    """Returns the repetition's peak angle, degrees (0.1): the measured angles (angles: {name: (T,) degrees}) of
    its side among `names` at its peak frame (t: (T,) s), averaged over both sides for "both" or "center". Where
    they are undefined at that frame, at the repetition's nearest frame where one is defined, so the peak stays a
    value of the curves (UI-PRMD m06 s01: hip flexion undefined at two peaks, whose thigh elevation was 8° above
    the curve's maximum); the counter's own peak only when none is defined in the repetition. The counter reads hip
    flexion as the thigh's elevation: its peak is reported on the measured angle, like the range of motion and the
    curves."""
    k = int(np.clip(np.searchsorted(t - t[0], rep.peak_s - 1e-9), 0, t.shape[0] - 1))
    own = own_angles(names, rep.side)
    series = np.stack([angles[n] for n in own if n in angles]) if any(n in angles for n in own) else None
    if series is None:
        return round(rep.peak_deg, 1)
    frames = repetition_frames(t, rep)  # the repetition's frames, its peak among them
    defined = frames[np.isfinite(series[:, frames]).any(axis=0)]
    if defined.size == 0:
        return round(rep.peak_deg, 1)
    nearest = int(defined[np.argmin(np.abs(defined - k))])
    return round(float(np.nanmean(series[:, nearest])), 1)


def _repetition_list(
    t: np.ndarray, angles: dict[str, np.ndarray], names: tuple[str, ...], reps: list[Repetition]
) -> list[dict[str, Any]]:
    """Returns the document's repetition_list: each repetition's keys with its peak on the measured angles
    (angles: {name: (T,) degrees}; measured_peak) and "withheld" None; a repetition measured on a curve past what the
    joint bends (anatomy.repetition_beyond_anatomy) has its peak_deg and amplitude_deg None and that reason."""
    out = []
    for rep in reps:
        why = repetition_beyond_anatomy(t, angles, names, rep)
        if why is None:
            out.append(rep.to_dict() | {"peak_deg": measured_peak(t, angles, names, rep), "withheld": None})
        else:
            out.append(rep.to_dict() | {"peak_deg": None, "amplitude_deg": None, "withheld": why})
    return out


def _beyond_raw(
    recording: Recording, rom: dict[str, dict[str, float | None]]
) -> tuple[dict[str, float], dict[str, Reason]]:
    """Returns {angle: degrees its measured range leaves the raw angle's envelope (intervals.beyond_raw)} and the
    reasons of the ranges withheld for it: {angle: beyond_raw} of those beyond by more than 0. The filter and the
    smoothing must not take an angle where the camera never put it (issue 24.1; where they do, bench/raw_envelope.py
    says why, and bench/README.md "Where the filtered range leaves the raw data")."""
    raw = joint_angles(recording.positions)
    beyond = {name: beyond_raw(rom[name], raw[name]) for name in rom if name in raw}
    return beyond, {name: beyond_raw_reason(off) for name, off in beyond.items() if off > 0.0}


def peak_end(rom: dict[str, float | None] | None, repetitions: list[dict[str, Any]]) -> str:
    """Returns "max" or "min": the end of the defining angle's range that its repetitions reach (the median
    repetition peak is nearer to it), so that the session's "peak angle" and the repetitions' peaks are one
    quantity (a seated knee extension rests bent and peaks near 0°: its peak is the range's minimum). "max"
    without repetitions or a range."""
    peaks = [r["peak_deg"] for r in repetitions if r.get("peak_deg") is not None]
    lo, hi = (rom or {}).get("min_deg"), (rom or {}).get("max_deg")
    if lo is None or hi is None or not peaks:
        return "max"
    mid = 0.5 * (lo + hi)
    return "min" if float(np.median(peaks)) < mid else "max"


def analyze_recording(
    recording: Recording,
    exercise: ExerciseSpec,
    *,
    params: KinematicParams | None = None,
    filtered: Recording | None = None,
    repetition_params: RepetitionParams | None = None,
    angle_sd: dict[str, np.ndarray] | None = None,
) -> AnalysisReport:
    """Returns the analysis document of one session (kinect_agent.analysis.document.AnalysisReport).

    recording: the raw recording (its tracking states feed the quality check). filtered: the pipeline's output
    for the same frames, measured when given; else the positions rebuilt from params; else the recording itself.
    angle_sd: {angle: (T,) degrees}, the per-frame SD of the filtered angles (the session file's angle SDs); with
    it and `filtered`, "range_of_motion_95" ({angle: {"min_deg", "max_deg", "range_deg": [lo, hi]} or None}) and
    "repetitions_95" ({"low", "high", "ambiguous"}) hold 95 % intervals (intervals.py); else both are None.
    Measured on filtered positions (or params), an angle whose range leaves the raw angle's envelope
    (intervals.beyond_raw), or whose flexion passes what the joint bends (intervals.beyond_anatomy), has its range
    None and why in "range_of_motion_withheld" ({} when none; None on raw). A repetition measured on a knee,
    elbow or hip flexion past what the joint bends (anatomy) has its peak and amplitude None and why in its "withheld";
    then the median amplitude "rom_deg" (and the fatigue's amplitude trend) is None too, why in "rom_deg_withheld".
    """
    if recording.n_frames < 2:
        raise AnalysisError(f"the recording has {recording.n_frames} frame(s); at least 2 are needed")
    positions, source = _measured_positions(recording, params, filtered)
    t = recording.t
    names = tuple(exercise.defining_angles)
    measured = measured_angles(t, positions)
    smoothed, clinical = measured.positions, measured.angles
    frame = body_frame(smoothed)
    causal = counting_positions(recording)
    if causal is None:
        counted = counting_angles(smoothed, names, clinical, measured.up)
    else:  # the webcam: counted as its live count counts, on the same causal pass (live.counting_positions)
        live = measured_angles(t, causal)
        counted = counting_angles(live.positions, names, live.angles, live.up)
        floor = amplitude_floor(recording.meta.device, t, causal, names)  # as live measures it, on the same frames
        device_params = counting_params(recording.meta.device, floor)
        repetition_params = device_params if repetition_params is None else dataclasses.replace(
            repetition_params, rest="start", min_amplitude_deg=device_params.min_amplitude_deg)  # fmt: skip
    reps = count_repetitions(t, counted, names, repetition_params)
    if causal is not None:  # and, as live, only the repetitions back at rest before the set's last frame
        reps = dataclasses.replace(reps, repetitions=done_repetitions(reps, t))
    rep_list = _repetition_list(t, clinical, names, reps.repetitions)
    sd = _angle_sd(angle_sd, recording.n_frames) if source == "filtered" else None
    rom = range_of_motion(t, clinical, presmoothed=True)
    tracked = {name: quality.tracked_fraction(recording, (name,)) for name in clinical}
    beyond, rom_withheld = _beyond_raw(recording, rom) if source != "raw" else ({}, None)
    # a flexion past what the joint bends is the camera losing the limb, whatever the raw data say (issue 24.1)
    anatomy = {name: why for name, r in rom.items() if (why := beyond_anatomy(name, r)) is not None}
    if rom_withheld is not None:
        rom_withheld = {**rom_withheld, **anatomy}
    rom = {name: dict.fromkeys(KINDS) if rom_withheld and name in rom_withheld else r for name, r in rom.items()}
    ivs = None
    if sd is not None:
        ivs = rom_intervals(t, clinical, sd, smoothed, recording.meta.device, tracked, names, beyond, anatomy)
    rom_why = rom_beyond_anatomy([r["withheld"] for r in rep_list])
    moving_s, rest_s = activity.moving_time(t, smoothed)
    balance = sway(t, smoothed, clinical)
    doc = {
        "exercise": exercise.slug,
        "duration_s": round(recording.duration, 3),
        "n_frames": recording.n_frames,
        "rate_hz": round(recording.rate_hz, 3),
        "measured_on": source,
        "repetitions": len(rep_list),
        "repetition_list": rep_list,
        "defining_angle": reps.defining_angle,
        "peak_end": peak_end(rom.get(reps.defining_angle or ""), rep_list),
        "range_of_motion": rom,
        "range_of_motion_withheld": rom_withheld,
        "range_of_motion_95": None if ivs is None else ivs.intervals,
        "range_of_motion_95_withheld": None if ivs is None else ivs.withheld,
        "repetitions_95": None
        if sd is None
        else count_interval(t, counted, sd, names, repetition_params, count=len(rep_list)).to_dict(),
        "rom_deg": None if rom_why is not None else _median([r.amplitude_deg for r in reps.repetitions]),
        "rom_deg_withheld": rom_why,
        "most_moving_joints": most_moving_joints(smoothed),
        "reachable_range": reachable_range(smoothed, frame),
        "moving_time_s": moving_s,
        "rest_time_s": rest_s,
        "tempo_s_per_rep": activity.tempo(reps.repetitions),
        "fatigue": activity.fatigue(reps.repetitions) | ({"amplitude_slope_pct_per_rep": None} if rom_why else {}),
        "balance": balance,
        "balance_missing": None if balance is not None else missing_reason(t, smoothed, clinical),
        "sit_to_stand": sit_to_stand(t, positions) if exercise.slug == "sit_to_stand" else None,
        "quality": quality.assess(recording, None if source == "raw" else positions, names),
    }
    return AnalysisReport.model_validate(json_ready(doc))


def load(path: str | Path) -> tuple[Recording, Recording, dict[str, np.ndarray] | None]:
    """Returns (raw, filtered, angle SDs {angle: (T,) degrees} or None) of a recording file of any supported format.

    A .khs session file's own filtered recording (and its angle SDs) is used when present; otherwise the agent's
    pipeline runs on the raw input. Raises UnreadableRecording naming the file and the reason.
    """
    from kinect_agent import formats
    from kinect_agent.formats import session_file
    from kinect_agent.processing.config import config_for_device
    from kinect_agent.processing.pipeline import process

    path = Path(path)
    try:
        module = formats.detect(path)
        if module is session_file:
            payload = session_file.read_payload(path)
            raw, filtered, angle_sd = payload.raw, payload.filtered, payload.angle_sd
        else:
            raw, filtered, angle_sd = formats.read(path), None, None
    except FormatError as exc:
        raise UnreadableRecording(str(exc)) from None
    except OSError as exc:
        raise UnreadableRecording(f"{path}: {exc.strerror or exc}") from None
    if raw.n_frames < 2:
        raise UnreadableRecording(f"{path}: {raw.n_frames} frame(s); at least 2 are needed")
    if filtered is None:
        try:
            result = process(raw, config=config_for_device(raw.meta.device))
        except ValueError as exc:
            raise UnreadableRecording(f"{path}: the pipeline cannot filter this recording: {exc}") from None
        filtered, angle_sd = result.filtered, result.angle_sd
    return raw, filtered, angle_sd


def analyze_file(path: str | Path, exercise_slug: str) -> AnalysisReport:
    """Returns the analysis document of the recording file at `path` as exercise `exercise_slug`."""
    exercise = get_exercise(exercise_slug)
    raw, filtered, angle_sd = load(path)
    return analyze_recording(raw, exercise, filtered=filtered, angle_sd=angle_sd)
