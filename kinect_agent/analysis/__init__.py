"""Repetition counting (series conditioning, counting angles, the detector): pure numpy/scipy, shared by the
agent's live count and the server's session analysis."""
