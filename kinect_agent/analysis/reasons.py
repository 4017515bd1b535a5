"""The analysis' reasons: why a session's quality check failed (kinect_agent.analysis.quality.assess), why an angle's
95 % interval is withheld (kinect_agent.analysis.intervals.withheld_reason) and why balance was not measured
(kinect_agent.analysis.balance.missing_reason); and the indicators' bases: how each indicator was scored
(kinect_agent.analysis.indicators, BASES, stored as a `Basis` from schema 4 on).

The analysis document (schema 3, kinect_agent.analysis.document) stores a reason as a `Reason`: the id of one of
MESSAGES and its numbers; the server writes it in the reader's language from them (backend.session_texts.reasons). Each
message is a catalogue msgid of the `messages` domain (backend.i18n.catalogues extracts the N_ marks of this file:
this layer cannot import the server's). A reason an older analysis stored as a text no message matches is kept as
that text (id None).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Kind = Literal["int", "percent", "decimal0", "decimal1", "general", "angle"]
_ANGLE_ID = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")


def N_(message: str) -> str:  # noqa: N802 (the gettext convention)
    """Marks a message for extraction (backend.i18n.catalogues) without translating it."""
    return message


class UnknownReason(ValueError):
    """A reason whose id no message of MESSAGES has, or whose numbers are not its message's."""


@dataclass(frozen=True)
class Message:
    """One reason's message (%(name)s placeholders, English) and the kind of number each placeholder holds:
    int, percent (a fraction 0..1, written as a whole percent), decimal0 / decimal1 (0 or 1 decimal), general (as
    few decimals as the number needs), angle (not a number: an angle's name, kinect_agent.body.angles, written in the
    reader's words)."""

    id: str
    message: str
    kinds: tuple[tuple[str, Kind], ...] = ()

    def reason(self, **values: float) -> Reason:
        """Returns this reason with its numbers (one per placeholder; pydantic.ValidationError when one is missing or
        extra)."""
        return Reason(id=self.id, params=values)

    def basis(self, **values: float | str) -> Basis:
        """Returns this indicator basis with its numbers and angle (one per placeholder; pydantic.ValidationError
        when one is missing or extra)."""
        return Basis(id=self.id, params=values)

    def checked(self, params: dict[str, float | str]) -> dict[str, float | str]:
        """Returns params as this message stores them (ints for int placeholders, an angle's name as it is, other
        numbers to 4 decimals); raises UnknownReason when they are not one value of its kind per placeholder."""
        kinds = dict(self.kinds)
        if set(params) != set(kinds) or any(not _fits(v, kinds[k]) for k, v in params.items()):
            raise UnknownReason(f"reason {self.id!r} needs the numbers {sorted(kinds)}, got {params!r}")
        return {k: _stored(v, kinds[k]) for k, v in params.items()}


def _fits(value: object, kind: Kind) -> bool:
    """Returns whether a value can fill a placeholder of this kind (a number, or for an angle its name)."""
    if kind == "angle":
        return isinstance(value, str) and _ANGLE_ID.fullmatch(value) is not None
    return isinstance(value, int | float) and not isinstance(value, bool)


def _stored(value: float | str, kind: Kind) -> float | str:
    if isinstance(value, str):
        return value
    return int(value) if kind == "int" else round(float(value), 4)


class Reason(BaseModel):
    """One reason of the analysis: a message's id and its numbers, or (id None) a text no message matches that an
    older analysis stored."""

    model_config = ConfigDict(extra="forbid")

    id: str | None = Field(description="the message's id (kinect_agent.analysis.reasons.MESSAGES); None: a text")
    params: dict[str, int | float | str] = Field(
        default_factory=dict,
        description="the message's numbers by placeholder (fractions 0..1, seconds, degrees; an angle by its name)",
    )
    text: str | None = Field(
        default=None,
        description="the reason in words: in an API answer, in the reader's language; stored, only when id is None",
    )

    @model_validator(mode="after")
    def _known(self) -> Reason:
        if self.id is None:
            if not self.text or self.params:
                raise UnknownReason("a reason without an id is a text, with no numbers")
            return self
        known = self._known_messages()
        message = known.get(self.id)
        if message is None:
            raise UnknownReason(f"unknown {self.word} id {self.id!r} (known: {', '.join(sorted(known))})")
        self.params = message.checked(self.params)
        return self

    word: ClassVar[str] = "reason"  # what an unknown id is said to be

    @classmethod
    def _known_messages(cls) -> dict[str, Message]:
        return BY_ID


class Basis(Reason):
    """How one indicator was scored (schema 4 on): a message of BASES and its numbers (and angle), or (id None) a
    text no message matches that an older analysis stored."""

    word: ClassVar[str] = "basis"

    @classmethod
    def _known_messages(cls) -> dict[str, Message]:
        return BASES_BY_ID


# quality.assess: why a session is not ok
TOO_FEW_FRAMES = Message("too_few_frames", N_("only %(frames)s frames (at least %(needed)s needed)"),
                         (("frames", "int"), ("needed", "int")))  # fmt: skip
TOO_SHORT = Message("too_short", N_("only %(seconds)s s recorded (at least %(needed)s s needed)"),
                    (("seconds", "decimal1"), ("needed", "decimal0")))  # fmt: skip
TOO_LITTLE_TRACKED = Message(
    "too_little_tracked", N_("the body was tracked in %(tracked)s of the samples (at least %(needed)s needed)"),
    (("tracked", "percent"), ("needed", "percent")))  # fmt: skip
TOO_MANY_ERRORS = Message(
    "too_many_errors", N_("%(errors)s of the samples were tracking errors (at most %(allowed)s allowed)"),
    (("errors", "percent"), ("allowed", "percent")))  # fmt: skip
GAPS = Message("gaps", N_("the measured positions have gaps"))
# intervals.withheld_reason: why an angle's 95 % interval is not shown
ROTATION_UNDEFINED = Message(
    "rotation_undefined", N_("shoulder rotation is undefined while the elbow is straight, so it has no interval")
)
OUT_OF_PLANE = Message(
    "out_of_plane", N_("the angle is defined in only %(defined)s of the frames (the limb was out of its plane)"),
    (("defined", "percent"),))  # fmt: skip
JOINTS_UNTRACKED = Message(
    "joints_untracked", N_("the joints of this angle were tracked in only %(tracked)s of the frames"),
    (("tracked", "percent"),))  # fmt: skip
UNKNOWN_ANGLE = Message(
    "unknown_angle", N_("the angle or its uncertainty is unknown in every frame, or it spun through a full turn")
)
TOO_UNCERTAIN = Message(
    "too_uncertain",
    N_("the tracking is too uncertain: a 95 %% interval would span %(width)s° (at most %(most)s° is shown)"),
    (("width", "decimal0"), ("most", "decimal0")),
)
BEYOND_RAW = Message(
    "beyond_raw", N_("the filtered curve reaches %(by)s° beyond what the camera measured"), (("by", "general"),)
)
BEYOND_ANATOMY = Message(
    "beyond_anatomy",
    N_("the curve reaches %(reached)s°, more than the joint can bend (%(limit)s°): the camera lost the limb"),
    (("reached", "decimal0"), ("limit", "decimal0")),
)
# anatomy.rom_beyond_anatomy: why the session's range of motion (median repetition amplitude) is withheld
REPETITIONS_BEYOND_ANATOMY = Message(
    "repetitions_beyond_anatomy",
    N_("in %(withheld)s of %(count)s repetitions the curve reaches up to %(reached)s°, more than the joint can bend "
       "(%(limit)s°): the camera lost the limb"),
    (("withheld", "int"), ("count", "int"), ("reached", "decimal0"), ("limit", "decimal0")),
)  # fmt: skip
# balance.missing_reason: why balance was not measured
RECORDING_TOO_SHORT = Message("recording_too_short", N_("the recording is too short"))
NOT_STANDING = Message("not_standing", N_("the patient was seated or crouching: balance is measured while standing"))
NEVER_STILL = Message(
    "never_still",
    N_(
        "the patient never stood still with both feet down for %(seconds)s s in total (steps, a raised leg or a bent "
        "trunk do not count)"
    ),
    (("seconds", "general"),),
)
MESSAGES = (TOO_FEW_FRAMES, TOO_SHORT, TOO_LITTLE_TRACKED, TOO_MANY_ERRORS, GAPS, ROTATION_UNDEFINED, OUT_OF_PLANE,
            JOINTS_UNTRACKED, UNKNOWN_ANGLE, TOO_UNCERTAIN, BEYOND_RAW, BEYOND_ANATOMY, REPETITIONS_BEYOND_ANATOMY,
            RECORDING_TOO_SHORT, NOT_STANDING, NEVER_STILL)  # fmt: skip
BY_ID = {m.id: m for m in MESSAGES}

# kinect_agent.analysis.indicators: how each indicator was scored (the indicator's "basis")
BASIS_FLEXIBILITY = Message(
    "flexibility_normal_range",
    N_("median amplitude of the %(angle)s over the repetitions, against its normal range of %(low)s to %(high)s°"),
    (("angle", "angle"), ("low", "general"), ("high", "general")),
)
BASIS_FLEXIBILITY_NO_ANGLE = Message(
    "flexibility_no_angle",
    N_("median amplitude over the repetitions against the normal range of %(low)s to %(high)s°; no angle moved enough "
       "to count repetitions"),
    (("low", "general"), ("high", "general")),
)  # fmt: skip
BASIS_ENDURANCE_TARGET = Message(
    "endurance_target", N_("repetitions against the target of %(target)s"), (("target", "int"),)
)
BASIS_ENDURANCE_USUAL = Message(
    "endurance_usual", N_("repetitions against the usual %(usual)s of earlier sessions"), (("usual", "general"),)
)
BASIS_ENDURANCE_NONE = Message(
    "endurance_no_reference", N_("repetitions; no target and no earlier session to compare with")
)
BASIS_STRENGTH_RISE = Message(
    "strength_rise_time",
    N_("sit-to-stand rise time (from 20 to 80 %% of the rise): %(fast)s s scores 100, %(slow)s s scores 0"),
    (("fast", "general"), ("slow", "general")),
)
BASIS_STRENGTH_SPEED = Message("strength_speed_best", N_("movement speed (°/s) against the best earlier session"))
BASIS_STRENGTH_SPEED_NONE = Message(
    "strength_speed_no_reference", N_("movement speed (°/s); no earlier session to compare with")
)
BASIS_BALANCE_SWAY = Message(
    "balance_sway",
    N_("sway of the trunk and hips while standing: %(good)s cm/s scores 100, %(poor)s cm/s scores 0"),
    (("good", "general"), ("poor", "general")),
)
BASES = (BASIS_FLEXIBILITY, BASIS_FLEXIBILITY_NO_ANGLE, BASIS_ENDURANCE_TARGET, BASIS_ENDURANCE_USUAL,
         BASIS_ENDURANCE_NONE, BASIS_STRENGTH_RISE, BASIS_STRENGTH_SPEED, BASIS_STRENGTH_SPEED_NONE,
         BASIS_BALANCE_SWAY)  # fmt: skip
BASES_BY_ID = {m.id: m for m in BASES}


def message_of(id_: str) -> Message | None:
    """Returns the message of a reason's or a basis' id (None: no message has it)."""
    return BY_ID.get(id_) or BASES_BY_ID.get(id_)
