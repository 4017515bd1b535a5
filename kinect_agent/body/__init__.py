"""Body geometry, the lowest layer under formats, sources and processing: rotations, the kinematic model
(forward kinematics and segment lengths) and the clinical joint angles (docs/architecture.md)."""
