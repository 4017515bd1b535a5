"""Internal faults of the signal processing, kept apart from bad input.

Bad input (a recording with no frames, an array of the wrong shape) raises ValueError or kinect_agent.errors
.FormatError and is the user's to fix. A ProcessingError is raised when the processing fails on input it has
accepted: a numerical fault of this code (a covariance that lost positive definiteness, a filter that diverged).
The command line reports it as an internal fault (exit 1) and the server as a 500, logged with its context.
"""

from __future__ import annotations


class ProcessingError(Exception):
    """The signal processing failed on input it had accepted (an internal fault, not a problem of the input)."""


class NotPositiveDefinite(ProcessingError):
    """A covariance that must be positive definite is not: its Cholesky factorisation failed.

    what: which matrix (e.g. "innovation covariance S (12, 12)"); info: LAPACK's info when known (the order of the
    leading minor that is not positive).
    """

    def __init__(self, what: str, info: int | None = None) -> None:
        self.what, self.info = what, info
        minor = f" (leading minor {info} is not positive)" if info is not None and info > 0 else ""
        super().__init__(f"{what} is not positive definite{minor}")


class FilterDiverged(ProcessingError):
    """The filter's estimate became non-finite."""


class LapackFailed(ProcessingError):
    """A LAPACK routine reported an illegal argument (info < 0): a bug of the caller."""

    def __init__(self, routine: str, info: int) -> None:
        self.routine, self.info = routine, info
        super().__init__(f"LAPACK {routine} rejected argument {-info} (info={info})")
