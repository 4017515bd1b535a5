"""Joint-position error split into bias and random parts: moved to kinect_agent.evaluation.error_parts (the
`kinect-agent evaluate` command uses it); re-exported for the bench scripts."""

from kinect_agent.evaluation.error_parts import ErrorSums, body_rotations, error_sums

__all__ = ["ErrorSums", "body_rotations", "error_sums"]
