"""Typed errors of the analysis: each names what was wrong and where."""

from __future__ import annotations


class AnalysisError(ValueError):
    """Bad input to the analysis (unknown exercise, unreadable or unusable recording)."""


class UnknownExercise(AnalysisError):
    """The exercise slug is not in the library."""


class UnreadableRecording(AnalysisError):
    """The recording file cannot be read or holds no usable frames."""
