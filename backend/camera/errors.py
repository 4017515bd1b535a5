"""The errors camera sets answer with (rendered as {"error", "detail"} like every AppError)."""

from __future__ import annotations

from backend.exceptions import AppError, Conflict, NotFound


class CameraSetNotFound(NotFound):
    """No set with this id that the caller started (another patient's set is "not found" too)."""


class ConsentMissing(Conflict):
    """The patient has not agreed to the current consent text for camera sets."""


class CameraSetEnded(Conflict):
    """The set ended already: it takes no more batches."""


class BatchOutOfOrder(Conflict):
    """A batch came before the one it follows (the page sends them in order, from its buffer)."""


class BatchConflict(Conflict):
    """A batch number was received before with different frames."""


class CameraRateLimited(AppError):
    """More frames, batches or sets than a camera in real time makes."""

    status_code = 429

    def __init__(self, message: str, retry_after_s: int = 1):
        super().__init__(message, headers={"Retry-After": str(retry_after_s)})


class CameraSetEmpty(Conflict):
    """The set ended with too few frames to analyse; nothing was stored."""
