"""The analysis' reasons: why a session's quality check failed (backend.analysis.quality.assess), why an angle's
95 % interval is withheld (backend.analysis.intervals.withheld_reason) and why balance was not measured
(backend.analysis.balance.missing_reason).

The analysis document (schema 3, kinect_agent.analysis.document) stores a reason as a `Reason`: the id of one of
MESSAGES and its numbers; the server writes it in the reader's language from them (backend.analysis.reasons). Each
message is a catalogue msgid of the `messages` domain (backend.i18n.catalogues extracts the N_ marks of this file:
this layer cannot import the server's). A reason an older analysis stored as a text no message matches is kept as
that text (id None).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Kind = Literal["int", "percent", "decimal0", "decimal1", "general"]


def N_(message: str) -> str:  # noqa: N802 (the gettext convention)
    """Marks a message for extraction (backend.i18n.catalogues) without translating it."""
    return message


class UnknownReason(ValueError):
    """A reason whose id no message of MESSAGES has, or whose numbers are not its message's."""


@dataclass(frozen=True)
class Message:
    """One reason's message (%(name)s placeholders, English) and the kind of number each placeholder holds:
    int, percent (a fraction 0..1, written as a whole percent), decimal0 / decimal1 (0 or 1 decimal), general (as
    few decimals as the number needs)."""

    id: str
    message: str
    kinds: tuple[tuple[str, Kind], ...] = ()

    def reason(self, **values: float) -> Reason:
        """Returns this reason with its numbers (one per placeholder; pydantic.ValidationError when one is missing or
        extra)."""
        return Reason(id=self.id, params=values)

    def checked(self, params: dict[str, float]) -> dict[str, float]:
        """Returns params as this message stores them (ints for int placeholders, other numbers to 4 decimals);
        raises UnknownReason when they are not one number per placeholder."""
        kinds = dict(self.kinds)
        if set(params) != set(kinds) or any(isinstance(v, bool) for v in params.values()):
            raise UnknownReason(f"reason {self.id!r} needs the numbers {sorted(kinds)}, got {sorted(params)}")
        return {k: int(v) if kinds[k] == "int" else round(float(v), 4) for k, v in params.items()}


class Reason(BaseModel):
    """One reason of the analysis: a message's id and its numbers, or (id None) a text no message matches that an
    older analysis stored."""

    model_config = ConfigDict(extra="forbid")

    id: str | None = Field(description="the message's id (kinect_agent.analysis.reasons.MESSAGES); None: a text")
    params: dict[str, int | float] = Field(
        default_factory=dict, description="the message's numbers by placeholder (fractions 0..1, seconds, degrees)"
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
        message = BY_ID.get(self.id)
        if message is None:
            raise UnknownReason(f"unknown reason id {self.id!r} (known: {', '.join(sorted(BY_ID))})")
        self.params = message.checked(self.params)
        return self


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
            JOINTS_UNTRACKED, UNKNOWN_ANGLE, TOO_UNCERTAIN, RECORDING_TOO_SHORT, NOT_STANDING, NEVER_STILL)  # fmt: skip
BY_ID = {m.id: m for m in MESSAGES}
