"""Application errors: AppError(message, status_code) and its subclasses, rendered as {"error", "detail"}."""

from __future__ import annotations

from typing import Any


class AppError(Exception):
    """Base of every error the API answers on purpose; the class name becomes the JSON "error" field."""

    status_code = 400

    def __init__(
        self,
        message: str,
        status_code: int | None = None,
        headers: dict[str, str] | None = None,
        *,
        keep_changes: bool = False,
    ):
        super().__init__(message)
        self.message = message
        self.keep_changes = keep_changes  # commit the request's changes anyway (e.g. a failed-login record)
        if status_code is not None:
            self.status_code = status_code
        self.headers = headers or {}


class NotAuthenticated(AppError):
    status_code = 401


class Forbidden(AppError):
    status_code = 403


class CsrfFailed(Forbidden):
    pass


class InsufficientScope(Forbidden):
    pass


class TooManyLoginAttempts(AppError):
    status_code = 429


class PasswordCheckBusy(AppError):
    """Every password-hashing slot of this server process stayed taken while the request waited."""

    status_code = 503


class NotFound(AppError):
    status_code = 404


class UserNotFound(NotFound):
    pass


class PatientNotFound(NotFound):
    pass


class TherapistNotFound(NotFound):
    pass


class DeviceNotFound(NotFound):
    pass


class TokenNotFound(NotFound):
    pass


class ExerciseNotFound(NotFound):
    pass


class PlanNotFound(NotFound):
    pass


class UnsubscribeLinkUnknown(NotFound):
    """An unsubscribe link whose token belongs to no reminder e-mail (mistyped, or of a deleted account)."""


class SuggestionNotFound(NotFound):
    pass


class ReplyNotFound(NotFound):
    pass


class SessionNotFound(NotFound):
    pass


class Conflict(AppError):
    status_code = 409


class SessionConflict(Conflict):
    pass


class InvalidSessionFile(AppError):
    status_code = 400


class SessionFileRemoved(AppError):
    """The session's file was removed by the clinic's retention period; its metrics are kept."""

    status_code = 410


class ArchiveReplaced(AppError):
    """The patient's archive asked for by its sha256 was replaced by a newer one (or erased): ask again."""

    status_code = 410


class ArchiveNotMade(AppError):
    """The build of a patient's archive failed for good (its job's tries are spent); the message says why."""

    status_code = 500


class MetricsUnreadable(AppError):
    """A session's stored metrics document that no schema version reads (e.g. a reason id no message has): the
    server's data fault, named rather than hidden."""

    status_code = 500


class SessionTooLarge(AppError):
    status_code = 413


class UploadCutOff(AppError):
    """The client went away before the whole upload arrived."""

    status_code = 400


class ExportUnavailable(Conflict):
    """The session cannot be exported in the asked format yet (e.g. fhir before its metrics exist)."""


class EmailAlreadyRegistered(Conflict):
    pass


class SuggestionNotPending(Conflict):
    pass


class AgentOffline(Conflict):
    """The patient's home agent is not connected, so it cannot be asked to record."""


class LiveSetUnknown(Conflict):
    """A device posts live progress for a set the server did not start on that device."""


class PatientIdRequired(AppError):
    """A therapist or admin uploads a session without naming its patient (staff have no sessions of their own)."""

    status_code = 403


class SessionOwnerMismatch(AppError):
    """The session file names (recorded_by) another patient than the one it is stored for, or another device than
    the one sending it."""

    status_code = 403


class PairingCodeInvalid(AppError):
    """A well-formed pairing code that pairs nothing (unknown, used or expired): a refused credential."""

    status_code = 403


class InvalidInput(AppError):
    status_code = 422


class DatabaseBusy(AppError):
    """The database refused a write because another request held its lock (SQLite) or a serialisation failure."""

    status_code = 503

    def __init__(self, message: str):
        super().__init__(message, headers={"Retry-After": "1"})


class ServerBusy(AppError):
    """No database slot of this server process came free within COACH_DB_SLOT_WAIT_S (backend/db_slots.py)."""

    status_code = 503

    def __init__(self, message: str):
        super().__init__(message, headers={"Retry-After": "5"})


class DatabaseNotMigrated(RuntimeError):
    """Raised at start-up when the database revision is not Alembic head."""


# What any authenticated route can answer: no or bad credentials, no access, bad CSRF token, token scope too small.
AUTH_ERRORS = (NotAuthenticated, Forbidden, CsrfFailed, InsufficientScope)


def error_responses(*errors: type[AppError]) -> dict[int | str, dict[str, Any]]:
    """Returns a FastAPI `responses=` mapping documenting the given errors with examples."""
    by_status: dict[int, list[type[AppError]]] = {}
    for err in errors:
        by_status.setdefault(err.status_code, []).append(err)
    out: dict[int | str, dict[str, Any]] = {}
    for status, errs in by_status.items():
        examples = {
            e.__name__: {"value": {"error": e.__name__, "detail": _EXAMPLE_DETAIL.get(e.__name__, e.__name__)}}
            for e in errs
        }
        out[status] = {
            "description": ", ".join(e.__name__ for e in errs),
            "content": {
                "application/json": {"schema": {"$ref": "#/components/schemas/ErrorOut"}, "examples": examples}
            },
        }
    return out


_EXAMPLE_DETAIL = {
    "MetricsUnreadable": "the stored metrics document of session 7 cannot be read: quality.reasons.0: unknown reason "
    "id 'too_blurry'",
    "PatientIdRequired": "a therapist or admin uploads for a patient: name them with ?patient_id=",
    "NotAuthenticated": "missing or invalid credentials",
    "Forbidden": "you may not access patient 12",
    "CsrfFailed": "missing or wrong X-CSRF-Token header",
    "InsufficientScope": "this API token lacks the 'write' scope",
    "TooManyLoginAttempts": "too many failed logins; retry in 900 s",
    "PatientNotFound": "patient 12 does not exist",
    "UserNotFound": "user 12 does not exist",
    "PlanNotFound": "plan 3 does not exist",
    "SuggestionNotFound": "suggestion 7 does not exist",
    "SuggestionNotPending": "suggestion 7 is approved; only pending system suggestions can be approved or dismissed",
    "ExerciseNotFound": "exercise 'squat' does not exist",
    "PairingCodeInvalid": "pairing code is unknown, used or expired",
    "EmailAlreadyRegistered": "a user with email ana@example.org exists",
    "SessionNotFound": "session 31 does not exist",
    "SessionConflict": "session 8c1e... of patient 12 was already uploaded with different content",
    "ExportUnavailable": "session 12 has no metrics; the fhir export needs them",
    "InvalidSessionFile": "checksum_mismatch: SHA-256 trailer does not match the content",
    "SessionTooLarge": "the upload exceeds 16777216 bytes",
    "SessionFileRemoved": "This session was removed on 2026-11-27 under the clinic's retention policy: its recording "
    "(curves, replay, exports) is gone; its metrics are kept (session 31)",
}
