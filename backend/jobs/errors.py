"""Errors a job raises on purpose."""

from __future__ import annotations


class PermanentJobError(Exception):
    """The job cannot succeed on a retry (the stored data itself is the cause): the worker marks it failed at once,
    with this message, instead of trying it again (backend.jobs.queue.fail, final=True)."""
