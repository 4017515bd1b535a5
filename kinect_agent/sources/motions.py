"""Exercise motions made from the paper's kinematic chain: per-bone local rotations over time, then FK.

Every motion respects the paper's degrees of freedom (kinect_agent.skeleton.DOF): elbows and knees are hinges
about the x axis of the entering bone (Rx), wrists and ankles turn about two axes, shoulders, hips, SPINE and
NECK about three; bones that leave one joint (NECK -> HEAD, SHO_L, SHO_R) share its rotation, and the bones
leaving ROOT are rigid in the ROOT frame. Positions come from kinect_agent.body.kinematics.forward_kinematics.

Body frame (kinematics module): x = the subject's left, y = up, z = forward; identity = neutral standing.
Sign conventions used here, for a bone hanging down (0, -1, 0):
    Rx(-a) swings it forward by a (flexion of shoulder/hip), Rx(+a) backward (knee flexion),
    Rz(+b) swings it towards +x (left abduction), Rz(-b) towards -x (right abduction).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.kinematics import REST_DIRECTIONS, TYPICAL_LENGTHS, forward_kinematics
from kinect_agent.body.rotations import axis_rotation

CAMERA_HEIGHT_M = 0.80  # Kinect above the floor; the floor is at y = -CAMERA_HEIGHT_M in the camera frame
SUBJECT_DISTANCE_M = 2.4  # ankles' distance from the camera along z
ANKLE_HEIGHT_M = 0.08  # ankle joint above the floor


def bone(child: str) -> int:
    """Returns the BONES index of the bone that ends at joint `child`."""
    return skeleton.INDEX[child] - 1


@dataclass(frozen=True)
class Body:
    """A subject's bone lengths: lengths (19,) float, metres, BONES order (constant over a session)."""

    lengths: np.ndarray

    def __post_init__(self) -> None:
        lengths = np.asarray(self.lengths, dtype=np.float64)
        if lengths.shape != (len(skeleton.BONES),):
            raise ValueError(f"Body.lengths must have shape (19,), got {lengths.shape}")
        if not np.all(np.isfinite(lengths) & (lengths > 0)):
            raise ValueError("Body.lengths must be finite and positive (metres)")
        object.__setattr__(self, "lengths", lengths)


def random_body(rng: np.random.Generator) -> Body:
    """Returns a body whose size varies with the generator: overall scale N(1, 0.06), per bone ±3 %, L/R ±1 %."""
    scale = float(np.clip(rng.normal(1.0, 0.06), 0.85, 1.15))
    per_bone = rng.normal(1.0, 0.03, size=len(skeleton.BONES))
    # Mirror pairs share a factor, with a slight left/right asymmetry on top.
    for k, (_, c) in enumerate(skeleton.BONES):
        name = skeleton.JOINTS[c]
        if name.endswith("_R"):
            per_bone[k] = per_bone[bone(skeleton.mirror_name(name))]
    per_bone *= rng.normal(1.0, 0.01, size=len(skeleton.BONES))
    return Body(TYPICAL_LENGTHS * scale * np.clip(per_bone, 0.9, 1.1))


@dataclass(frozen=True)
class ExerciseSpec:
    """How one exercise moves: poses it allows, tempo, amplitude and which angles it drives."""

    slug: str
    poses: tuple[str, ...]  # allowed poses; the first is the natural one
    rep_s: float  # typical duration of one repetition, seconds
    amplitude: float  # peak of the defining movement, degrees
    hold: float  # fraction of a repetition held at the peak
    angles: tuple[str, ...]  # the defining angle(s) of kinect_agent.body.angles (one per moving side)
    drive: Callable[[dict[str, np.ndarray], np.ndarray, np.ndarray, str], None]  # fills angle channels
    planted: str  # "feet" (both ankles fixed), "right"/"left"/"alternate" (stance foot fixed), "root" (seated)
    stance: Callable[[np.ndarray, np.ndarray], Stance] | None = None  # both feet on the floor: legs solved by IK


@dataclass(frozen=True)
class Stance:
    """Where the feet stand and the pelvis goes in an exercise done on both feet (legs then follow by inverse
    kinematics, so both ankles stay exactly where they stand).

    feet: (T, 2, 3) or (2, 3), the left and right ankles' places relative to where they are standing straight;
    pelvis: (T, 2) m, body frame, the ROOT's sideways (x, the subject's left) and forward (z) shift;
    knee: (T, 2) degrees, the least flexion of the left and right knee: the pelvis stands as high as both allow.
    """

    feet: np.ndarray
    pelvis: np.ndarray
    knee: np.ndarray


# Angle channels (degrees, (T,) each) filled by the drivers; all start at a neutral value for the pose.
CHANNELS = (
    "sho_flex_L", "sho_flex_R", "sho_abd_L", "sho_abd_R", "elb_L", "elb_R",
    "hip_flex_L", "hip_flex_R", "hip_abd_L", "hip_abd_R", "knee_L", "knee_R",
    "trunk_lean", "trunk_side", "neck_nod",
    "sho_plane_L", "sho_plane_R", "sho_rot_L", "sho_rot_R",
)  # fmt: skip
# sho_plane: the plane the arm is raised in (sho_abd), turned forward from the frontal plane (scaption: 30-45°);
# sho_rot: the upper arm's rotation about its own axis, external (+) or internal (−), degrees.


def _drive_shoulder_abduction(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["sho_abd_L"] += sL
    ch["sho_abd_R"] += sR
    ch["elb_L"] += 0.05 * sL
    ch["elb_R"] += 0.05 * sR


def _drive_shoulder_flexion(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["sho_flex_L"] += sL
    ch["sho_flex_R"] += sR
    ch["elb_L"] += 0.06 * sL
    ch["elb_R"] += 0.06 * sR
    ch["trunk_lean"] -= 0.03 * 0.5 * (sL + sR)  # slight back arch at the top


def _drive_elbow_flexion(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["elb_L"] += sL
    ch["elb_R"] += sR
    ch["sho_flex_L"] += 0.08 * sL  # elbows drift forward a little
    ch["sho_flex_R"] += 0.08 * sR


def _drive_knee_extension(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["knee_R"] -= sR  # from 90° seated towards straight
    ch["hip_flex_R"] += 0.08 * sR


def _drive_squat(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    s = 0.5 * (sL + sR)
    ch["knee_L"] += sL
    ch["knee_R"] += sR
    ch["hip_flex_L"] += 0.85 * sL
    ch["hip_flex_R"] += 0.85 * sR
    ch["trunk_lean"] += 0.35 * s
    ch["sho_flex_L"] += 0.6 * sL  # arms forward for balance
    ch["sho_flex_R"] += 0.6 * sR


def _drive_sit_to_stand(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # s goes 0 (seated) -> amplitude (standing) -> 0; seated knees and hips are at 90° (set by the pose).
    s = 0.5 * (sL + sR)
    ch["knee_L"] -= sL
    ch["knee_R"] -= sR
    ch["hip_flex_L"] -= sL
    ch["hip_flex_R"] -= sR
    frac = np.clip(s / 90.0, 0.0, 1.0)
    ch["trunk_lean"] += 40.0 * np.sin(np.pi * frac)  # lean forward while rising and sitting down


def _drive_leg_raise(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["hip_flex_R"] += sR
    ch["knee_R"] += 0.06 * sR


def _drive_side_step(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    ch["hip_abd_L"] += sL
    ch["hip_abd_R"] += sR
    ch["trunk_side"] += 0.25 * (sR - sL)  # lean away from the lifted leg


# --- The UI-PRMD movements (Vakanski et al. 2018, m01-m10). Ranges, timing and the moving side follow the recordings
# of s01-s05 (Kinect v2 and Vicon; bench/README.md, "Simulated UI-PRMD movements"): one side moves, the right one.


def _drive_deep_squat(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The legs come from _stance_deep_squat; the trunk leans forward (UI-PRMD m01: 30-45°), arms forward to balance.
    u = 0.5 * (sL + sR) / 120.0
    ch["trunk_lean"] += 65.0 * u  # at the upper spine: the trunk NECK-ROOT leans about half as much
    ch["sho_flex_L"] += 80.0 * u
    ch["sho_flex_R"] += 80.0 * u


def _stance_deep_squat(sL: np.ndarray, sR: np.ndarray) -> Stance:
    # Feet a little wider than the hips; the hips sit back as the knees bend to 120-130° (m01 Vicon: 125°).
    s = 0.5 * (sL + sR)
    u = s / 120.0
    feet = np.array([[0.07, 0.0, 0.0], [-0.07, 0.0, 0.0]])
    pelvis = np.column_stack([np.zeros_like(u), -0.30 * u])
    return Stance(feet, pelvis, np.column_stack([s, s]))


def _drive_trunk_upright(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # Inline lunge: the legs come from its stance; the trunk stays nearly upright (m03 Vicon: 10-16°).
    ch["trunk_lean"] += 0.08 * 0.5 * (sL + sR)


def _stance_inline_lunge(sL: np.ndarray, sR: np.ndarray) -> Stance:
    # Right foot in front (it stays planted), both feet on one line, 0.8-0.9 m apart (m03: 0.85 m); the pelvis goes
    # straight down, both knees bend to about 90° (m03 Vicon: front 103°, back 77°; Kinect 50-170°), the back knee
    # stopping short of the floor.
    s = 0.5 * (sL + sR)
    feet = np.tile([[-0.06, 0.0, -0.48], [0.06, 0.0, 0.48]], (s.shape[0], 1, 1))
    feet[:, 0, 1] = 0.09 * s / 82.0  # the back heel rises as the back knee goes down; the foot stands on its toes
    pelvis = np.zeros((s.shape[0], 2))
    return Stance(feet, pelvis, np.column_stack([8.0 + s, 8.0 + s]))


def _drive_side_lunge(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The legs come from _stance_side_lunge; the trunk leans forward as the hips sit back (m04 Vicon: 46°).
    u = sR / 84.0
    ch["trunk_lean"] += 60.0 * u  # at the upper spine: the trunk NECK-ROOT leans about half as much
    ch["sho_flex_L"] += 45.0 * u
    ch["sho_flex_R"] += 45.0 * u


def _stance_side_lunge(sL: np.ndarray, sR: np.ndarray) -> Stance:
    # Feet wide apart (m04: 0.8-0.9 m between the ankles); the pelvis moves to the right and back while the right knee
    # bends to about 90° (m04 Vicon: 80°) and the left leg stays nearly straight (13-35°).
    u = sR / 84.0
    feet = np.array([[0.30, 0.0, 0.0], [-0.30, 0.0, 0.0]])
    pelvis = np.column_stack([-0.36 * u, -0.12 * u])
    return Stance(feet, pelvis, np.column_stack([np.full_like(sR, 6.0), 6.0 + sR]))


def _drive_hurdle_step(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The right knee comes up and forward (m02 Vicon: hip 113°, knee 103°), a little out to clear the hurdle.
    ch["hip_flex_R"] += sR
    ch["knee_R"] += 0.95 * sR
    ch["hip_abd_R"] += 0.08 * sR
    ch["trunk_lean"] -= 0.04 * sR


def _drive_straight_leg_raise(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The straight right leg swings forward (m06: 70-105°), the knee bending a little at the top (Vicon: 11 -> 31°).
    ch["hip_flex_R"] += sR
    ch["knee_R"] += 0.12 * sR
    ch["trunk_lean"] -= 0.05 * sR


IDLE_ELBOW_DEG = 22.0  # the idle arm's elbow while the other arm exercises (m07-m10 Vicon s01: 22-29°)


def _drive_right_abduction(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The right arm out to the side and up (m07: 150-170°), thumb up: the arm turns outwards as it rises.
    ch["elb_L"][:] = IDLE_ELBOW_DEG
    ch["sho_abd_R"] += sR
    ch["sho_rot_R"] += 0.3 * sR
    ch["elb_R"] += 0.04 * sR
    ch["trunk_side"] += 0.03 * sR  # a slight lean away at the top


def _drive_right_extension(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The straight right arm backwards (m08: shoulder flexion 0 -> -45 to -65°).
    ch["elb_L"][:] = IDLE_ELBOW_DEG
    ch["sho_flex_R"] -= sR
    ch["trunk_lean"] += 0.06 * sR


ROTATION_REST_DEG = -10.0  # m09: the forearm rests just below pointing forward, then turns up (Vicon s01: -8 -> 106°)


def _drive_right_rotation(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The right upper arm held out to the side (m09: 70-95°), the elbow at a right angle (Vicon: 66-74°, Kinect 60-98°);
    # the forearm turns about the upper arm, from forward up to vertical and back.
    ch["sho_abd_R"][:] = 88.0
    ch["elb_R"][:] = 90.0
    ch["elb_L"][:] = IDLE_ELBOW_DEG
    ch["sho_rot_R"] += ROTATION_REST_DEG + sR


def _drive_right_scaption(ch: dict[str, np.ndarray], sL: np.ndarray, sR: np.ndarray, pose: str) -> None:
    # The right arm raised in the scapular plane, 40° forward of the side (m10: flexion and abduction both reach
    # 90-115°), thumb up.
    ch["sho_plane_R"] += 40.0
    ch["elb_L"][:] = IDLE_ELBOW_DEG
    ch["sho_abd_R"] += sR
    ch["sho_rot_R"] += 0.2 * sR
    ch["elb_R"] += 0.04 * sR


SPECS: dict[str, ExerciseSpec] = {
    s.slug: s
    for s in (
        ExerciseSpec("shoulder_abduction", ("standing", "sitting"), 3.6, 150.0, 0.08, ("shoulder_abduction_L",),
                     _drive_shoulder_abduction, "feet"),
        ExerciseSpec("shoulder_flexion", ("standing", "sitting"), 3.6, 155.0, 0.08, ("shoulder_flexion_L",),
                     _drive_shoulder_flexion, "feet"),
        ExerciseSpec("elbow_flexion", ("standing", "sitting"), 2.6, 130.0, 0.05, ("elbow_flexion_L",),
                     _drive_elbow_flexion, "feet"),
        ExerciseSpec("seated_knee_extension", ("sitting",), 3.0, 80.0, 0.12, ("knee_flexion_R",),
                     _drive_knee_extension, "root"),
        ExerciseSpec("squat", ("standing",), 3.4, 95.0, 0.05, ("knee_flexion_L",), _drive_squat, "feet"),
        ExerciseSpec("sit_to_stand", ("sitting", "standing"), 4.0, 90.0, 0.15, ("knee_flexion_L",),
                     _drive_sit_to_stand, "feet"),
        ExerciseSpec("standing_leg_raise", ("standing",), 3.0, 60.0, 0.1, ("hip_flexion_R",), _drive_leg_raise,
                     "left"),
        ExerciseSpec("side_step", ("standing",), 2.6, 28.0, 0.05, ("hip_abduction_L", "hip_abduction_R"),
                     _drive_side_step, "alternate"),
        ExerciseSpec("deep_squat", ("standing",), 2.6, 120.0, 0.05, ("knee_flexion_L", "knee_flexion_R"),
                     _drive_deep_squat, "feet", _stance_deep_squat),
        ExerciseSpec("hurdle_step", ("standing",), 2.4, 100.0, 0.05, ("hip_flexion_R",), _drive_hurdle_step, "left"),
        ExerciseSpec("inline_lunge", ("standing",), 2.5, 82.0, 0.05, ("knee_flexion_L", "knee_flexion_R"),
                     _drive_trunk_upright, "right", _stance_inline_lunge),
        ExerciseSpec("side_lunge", ("standing",), 2.9, 84.0, 0.05, ("knee_flexion_R",), _drive_side_lunge, "feet",
                     _stance_side_lunge),
        ExerciseSpec("standing_active_straight_leg_raise", ("standing",), 2.2, 75.0, 0.05, ("hip_flexion_R",),
                     _drive_straight_leg_raise, "left"),
        ExerciseSpec("standing_shoulder_abduction", ("standing",), 2.6, 155.0, 0.05, ("shoulder_abduction_R",),
                     _drive_right_abduction, "feet"),
        ExerciseSpec("standing_shoulder_extension", ("standing",), 2.2, 55.0, 0.08, ("shoulder_flexion_R",),
                     _drive_right_extension, "feet"),
        ExerciseSpec("standing_shoulder_rotation", ("standing",), 2.6, 100.0, 0.05, ("shoulder_rotation_R",),
                     _drive_right_rotation, "feet"),
        ExerciseSpec("standing_shoulder_scaption", ("standing",), 2.2, 100.0, 0.05, ("shoulder_abduction_R",),
                     _drive_right_scaption, "feet"),
    )
}  # fmt: skip
EXERCISES: tuple[str, ...] = tuple(SPECS)


@dataclass(frozen=True)
class Schedule:
    """Per-frame activation of one session: t (T,) s; sL, sR (T,) degrees; rep_bounds (N, 2) s; lead (N,) 0=L, 1=R."""

    t: np.ndarray
    sL: np.ndarray
    sR: np.ndarray
    rep_bounds: np.ndarray
    lead: np.ndarray


def _profile(u: np.ndarray, hold: float) -> np.ndarray:
    """Returns the 0 -> 1 -> 0 shape of one repetition for u in [0, 1]: cosine rise, hold, slightly slower lowering."""
    rise = 0.45 * (1.0 - hold)
    down0 = rise + hold
    out = np.zeros_like(u)
    up = u < rise
    out[up] = 0.5 - 0.5 * np.cos(np.pi * u[up] / rise)
    out[(u >= rise) & (u < down0)] = 1.0
    dn = u >= down0
    out[dn] = 0.5 + 0.5 * np.cos(np.pi * (u[dn] - down0) / (1.0 - down0))
    return out


def schedule(spec: ExerciseSpec, reps: int, rng: np.random.Generator, rate_hz: float) -> Schedule:
    """Returns the timing and amplitude of `reps` repetitions with human variability.

    Tempo varies per session (×0.85-1.2) and per repetition (5 %); fatigue lowers the amplitude (5-15 % by the last
    repetition) and slows the movement (5-20 %); pauses between repetitions last 0.3-1.5 s; the right side moves
    with a slightly different amplitude (±4 %) and a lag of up to 60 ms.
    """
    tempo = rng.uniform(0.85, 1.2)
    fat_amp, fat_speed = rng.uniform(0.05, 0.15), rng.uniform(0.05, 0.2)
    asym, lag = rng.normal(1.0, 0.04), rng.uniform(0.0, 0.06)
    amp0 = spec.amplitude * rng.normal(1.0, 0.05)
    starts, ends, amps = [], [], []
    clock = rng.uniform(0.8, 1.5)
    for i in range(reps):
        f = i / (reps - 1) if reps > 1 else 0.0
        dur = spec.rep_s * tempo * (1.0 + fat_speed * f) * rng.normal(1.0, 0.05)
        starts.append(clock)
        ends.append(clock + dur)
        amps.append(amp0 * (1.0 - fat_amp * f) * rng.normal(1.0, 0.04))
        clock += dur + rng.uniform(0.3, 1.5)
    total = ends[-1] + lag + rng.uniform(0.8, 1.5)
    t = np.arange(int(np.ceil(total * rate_hz)) + 1) / rate_hz
    lead = np.arange(reps) % 2 if spec.planted == "alternate" else np.zeros(reps, dtype=int)
    sL, sR = np.zeros_like(t), np.zeros_like(t)
    for i, (a, b, amp) in enumerate(zip(starts, ends, amps, strict=True)):
        for side, arr, shift, gain in ((0, sL, 0.0, 1.0), (1, sR, lag, asym)):
            if spec.planted == "alternate" and lead[i] != side:
                continue
            m = (t >= a + shift) & (t <= b + shift)
            arr[m] += amp * gain * _profile((t[m] - a - shift) / (b - a), spec.hold)
    return Schedule(t, sL, sR, np.column_stack([starts, ends]), lead)


def _neutral(pose: str, T: int) -> dict[str, np.ndarray]:
    ch = {name: np.zeros(T) for name in CHANNELS}
    ch["sho_abd_L"] += 6.0  # arms hang just clear of the body
    ch["sho_abd_R"] += 6.0
    ch["elb_L"] += 8.0
    ch["elb_R"] += 8.0
    if pose == "sitting":
        for side in "LR":
            ch[f"hip_flex_{side}"] += 90.0
            ch[f"knee_{side}"] += 90.0
    return ch


def _sway(rng: np.random.Generator, t: np.ndarray, amplitude: float, n: int = 3) -> np.ndarray:
    """Returns a smooth postural sway (T,), a sum of slow sines (0.1-0.6 Hz) with random phases."""
    freqs = rng.uniform(0.1, 0.6, size=n)
    phases = rng.uniform(0, 2 * np.pi, size=n)
    weights = rng.uniform(0.5, 1.0, size=n)
    wave = np.sum(weights[:, None] * np.sin(2 * np.pi * freqs[:, None] * t[None, :] + phases[:, None]), axis=0)
    return amplitude * wave / np.sum(weights)


DORSIFLEXION_MAX_DEG = 35.0  # the shank's forward tilt over a flat foot (ankle dorsiflexion), at most


def local_rotations(ch: dict[str, np.ndarray], rng: np.random.Generator, t: np.ndarray) -> np.ndarray:
    """Returns R_local (T, 19, 3, 3) from the angle channels (degrees), with small natural wrist/ankle/neck motion."""
    T = t.shape[0]
    R = np.tile(np.eye(3), (T, len(skeleton.BONES), 1, 1))
    rad = {k: np.radians(v) for k, v in ch.items()}

    def Rx(a: float | np.ndarray) -> np.ndarray:
        return axis_rotation(0, a)

    def Ry(a: float | np.ndarray) -> np.ndarray:
        return axis_rotation(1, a)

    def Rz(a: float | np.ndarray) -> np.ndarray:
        return axis_rotation(2, a)

    # SPINE joint (3 DoF): trunk lean forward (+) and sideways, a little twist.
    twist = np.radians(_sway(rng, t, 2.0))
    R[:, bone("NECK")] = Ry(twist) @ Rz(rad["trunk_side"]) @ Rx(rad["trunk_lean"])
    # NECK joint (3 DoF), shared by the three bones that leave it.
    neck = Rx(rad["neck_nod"] + np.radians(_sway(rng, t, 3.0))) @ Ry(np.radians(_sway(rng, t, 4.0)))
    for child in ("HEAD", "SHO_L", "SHO_R"):
        R[:, bone(child)] = neck
    # Shoulders and hips (3 DoF each), elbows and knees (hinges), wrists and ankles (2 DoF).
    # Shoulder: raised by sho_abd in a plane turned forward by sho_plane (Ry(∓plane)·Rz(±abd)·Ry(±plane) keeps the
    # arm's own axis when the plane turns), flexed forward, then turned about its own axis by sho_rot.
    pL, pR = rad["sho_plane_L"], rad["sho_plane_R"]
    R[:, bone("ELB_L")] = Ry(-pL) @ Rz(rad["sho_abd_L"]) @ Ry(pL) @ Rx(-rad["sho_flex_L"]) @ Ry(rad["sho_rot_L"])
    R[:, bone("ELB_R")] = Ry(pR) @ Rz(-rad["sho_abd_R"]) @ Ry(-pR) @ Rx(-rad["sho_flex_R"]) @ Ry(-rad["sho_rot_R"])
    R[:, bone("WRI_L")] = Rx(-rad["elb_L"])
    R[:, bone("WRI_R")] = Rx(-rad["elb_R"])
    for side in "LR":
        a, b = np.radians(_sway(rng, t, 8.0)), np.radians(_sway(rng, t, 6.0))
        R[:, bone(f"HAN_{side}")] = Rx(a) @ Rz(b)
    R[:, bone("KNE_L")] = Rz(rad["hip_abd_L"]) @ Rx(-rad["hip_flex_L"])
    R[:, bone("KNE_R")] = Rz(-rad["hip_abd_R"]) @ Rx(-rad["hip_flex_R"])
    for side, sign in (("L", 1.0), ("R", -1.0)):
        knee = rad[f"knee_{side}"]
        R[:, bone(f"ANK_{side}")] = Rx(knee)
        # Ankle (2 DoF): keep the foot flat while the shank tilts forward up to the ankle's reach (then the heel rises:
        # the back foot of a lunge); the foot stays level when the leg lifts.
        shank = np.minimum(knee - rad[f"hip_flex_{side}"], np.radians(DORSIFLEXION_MAX_DEG))
        R[:, bone(f"FOO_{side}")] = Rx(-shank) @ Ry(sign * np.radians(5.0) + 0.0 * shank)
    return R


def _facing(view_deg: float) -> np.ndarray:
    """Returns R_world_root (3, 3): the subject faces the camera, turned by view_deg about the vertical."""
    return axis_rotation(1, np.radians(180.0 + view_deg))


def truth_positions(
    spec: ExerciseSpec, sched: Schedule, body: Body, pose: str, view_deg: float, rng: np.random.Generator
) -> np.ndarray:
    """Returns exact joint positions (T, J, 3), metres, camera frame, by FK of the session's parameters.

    The ROOT translation keeps the planted foot (or both, or the pelvis when seated) fixed in the room.
    """
    T = sched.t.shape[0]
    ch = _neutral(pose, T)
    spec.drive(ch, sched.sL, sched.sR, pose)
    if spec.stance is not None:
        _stand_legs(ch, spec.stance(sched.sL, sched.sR), body)
    ch["trunk_lean"] += _sway(rng, sched.t, 1.5)
    R_local = local_rotations(ch, rng, sched.t)
    R_root = np.broadcast_to(_facing(view_deg), (T, 3, 3))
    pos = forward_kinematics(np.zeros((T, 3)), R_root, np.broadcast_to(body.lengths, (T, 19)), R_local)
    ankles = pos[:, [skeleton.INDEX["ANK_L"], skeleton.INDEX["ANK_R"]], :]  # (T, 2, 3)
    # Each ankle's place in the room: where it is in the first frame, relative to a fixed anchor point.
    anchor_world = np.array([0.0, -CAMERA_HEIGHT_M + ANKLE_HEIGHT_M, SUBJECT_DISTANCE_M])
    targets = anchor_world + ankles[0] - ankles[0].mean(axis=0)  # (2, 3)
    w = _stance_weights(spec, sched)
    if spec.planted == "root":
        w[:] = w[0]
        ankles = np.broadcast_to(ankles[0], ankles.shape)  # the pelvis stays on the chair
    root = np.einsum("ts,tsk->tk", w, targets[None] - ankles)
    sway = np.stack([_sway(rng, sched.t, 0.01), np.zeros(T), _sway(rng, sched.t, 0.01)], axis=1)
    root = root + sway
    return forward_kinematics(root, R_root, np.broadcast_to(body.lengths, (T, 19)), R_local)


def leg_ik(v: np.ndarray, thigh: float, shank: float, side: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (hip flexion, hip abduction, knee flexion) (T,) degrees, in the channels' conventions, that put the
    ankle at v: (T, 3) m, hip -> ankle in the body frame; thigh, shank: m. A target beyond reach gives a straight leg
    towards it."""
    D = np.minimum(np.linalg.norm(v, axis=-1), thigh + shank)
    cos_k = (D**2 - thigh**2 - shank**2) / (2.0 * thigh * shank)
    knee = np.arccos(np.clip(cos_k, -1.0, 1.0))
    b = np.arctan2(v[:, 0], -v[:, 1])  # the leg's plane tilted sideways: Rz(b)
    y_rot = -np.hypot(v[:, 0], v[:, 1])
    along_y, along_z = -(thigh + shank * np.cos(knee)), -shank * np.sin(knee)  # the leg in its own plane
    flex = np.arctan2(along_z, along_y) - np.arctan2(v[:, 2], y_rot)
    flex = (flex + np.pi) % (2.0 * np.pi) - np.pi
    abd = b if side == "L" else -b
    return np.degrees(flex), np.degrees(abd), np.degrees(knee)


def _stand_legs(ch: dict[str, np.ndarray], stance: Stance, body: Body) -> None:
    """Sets the hip and knee channels so that both ankles stand where `stance` puts them (units of leg length)."""
    T = stance.knee.shape[0]
    hips, straight, lengths = {}, {}, {}
    for side in "LR":
        k_hip = bone(f"HIP_{side}")
        hips[side] = body.lengths[k_hip] * REST_DIRECTIONS[k_hip]  # (3,) ROOT -> hip, body frame
        lengths[side] = (float(body.lengths[bone(f"KNE_{side}")]), float(body.lengths[bone(f"ANK_{side}")]))
        straight[side] = hips[side] + np.array([0.0, -sum(lengths[side]), 0.0])
    leg = 0.5 * (sum(lengths["L"]) + sum(lengths["R"]))
    feet = np.broadcast_to(stance.feet, (T, 2, 3))
    ankles = {side: straight[side] + leg * feet[:, "LR".index(side)] for side in "LR"}  # (T, 3) each
    # The pelvis height: the highest at which each knee bends at least its stance.knee.
    pelvis = np.zeros((T, 3))
    pelvis[:, 0], pelvis[:, 2] = leg * stance.pelvis[:, 0], leg * stance.pelvis[:, 1]
    heights = []
    for i, side in enumerate("LR"):
        thigh, shank = lengths[side]
        k = np.radians(stance.knee[:, i])
        reach = np.sqrt(thigh**2 + shank**2 + 2.0 * thigh * shank * np.cos(k))  # hip-ankle distance at that knee
        flat = ankles[side][:, [0, 2]] - hips[side][[0, 2]] - pelvis[:, [0, 2]]  # (T, 2) horizontal hip -> ankle
        drop = np.sqrt(np.maximum(reach**2 - np.sum(flat**2, axis=1), 0.0))
        heights.append(ankles[side][:, 1] - hips[side][1] + drop)
    pelvis[:, 1] = np.min(heights, axis=0)
    for side in "LR":
        flex, abd, knee = leg_ik(ankles[side] - hips[side] - pelvis, *lengths[side], side)
        ch[f"hip_flex_{side}"], ch[f"hip_abd_{side}"], ch[f"knee_{side}"] = flex, abd, knee


def _stance_weights(spec: ExerciseSpec, sched: Schedule) -> np.ndarray:
    """Returns (T, 2) weights of the left and right ankle in the planted anchor."""
    T = sched.t.shape[0]
    w = np.full((T, 2), 0.5)
    if spec.planted == "left":
        w[:] = (1.0, 0.0)
    elif spec.planted == "right":
        w[:] = (0.0, 1.0)
    elif spec.planted == "alternate":
        # The foot that does not lift carries the weight; switch smoothly by the activation of each side.
        share_L = 0.5 + 0.5 * np.tanh((sched.sR - sched.sL) / 2.0)
        w = np.column_stack([share_L, 1.0 - share_L])
    return w
