"""Quaternion and rotation helpers, vectorised over leading axes. Quaternions are scalar-first `wxyz`."""

from __future__ import annotations

import numpy as np

COMPILED_MIN_MATRICES = 4096  # matrix_to_quat of at least this many matrices runs compiled (numba's import is lazy)


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """Returns unit quaternions. q: (..., 4) wxyz."""
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Returns the Hamilton product a·b. a, b: (..., 4) wxyz, broadcastable."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        (
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ),
        axis=-1,
    )


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    """Returns the conjugate (inverse of a unit quaternion). q: (..., 4) wxyz."""
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Returns rotation matrices (..., 3, 3) for quaternions q (..., 4) wxyz (normalised here)."""
    w, x, y, z = np.moveaxis(quat_normalize(q), -1, 0)
    return np.stack(
        (
            np.stack((1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)), axis=-1),
            np.stack((2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)), axis=-1),
            np.stack((2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)), axis=-1),
        ),
        axis=-2,
    )


def matrix_to_quat(R: np.ndarray, compiled: bool = True) -> np.ndarray:
    """Returns unit quaternions (..., 4) wxyz with w >= 0 for rotation matrices R (..., 3, 3).

    compiled: for COMPILED_MIN_MATRICES matrices or more, by _rotations_numba's kernel when numba is installed (the
    same numbers bit for bit; imported here, so that reading a file does not load numba); False: numpy.
    """
    R = np.asarray(R, dtype=np.float64)
    if compiled and R.ndim >= 2 and R.shape[-2:] == (3, 3) and R.size >= 9 * COMPILED_MIN_MATRICES:
        from kinect_agent.body import _rotations_numba

        if not _rotations_numba.AVAILABLE:
            return matrix_to_quat(R, compiled=False)
        flat = np.ascontiguousarray(R.reshape(-1, 3, 3))
        out = np.empty((flat.shape[0], 4))
        _rotations_numba.matrix_to_quat(flat, out)
        return out.reshape(R.shape[:-2] + (4,))
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    # Four candidate formulas; pick the numerically largest denominator per element.
    cand = np.stack(
        (
            np.stack((1 + m00 + m11 + m22, R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                      R[..., 1, 0] - R[..., 0, 1]), axis=-1),
            np.stack((R[..., 2, 1] - R[..., 1, 2], 1 + m00 - m11 - m22, R[..., 0, 1] + R[..., 1, 0],
                      R[..., 0, 2] + R[..., 2, 0]), axis=-1),
            np.stack((R[..., 0, 2] - R[..., 2, 0], R[..., 0, 1] + R[..., 1, 0], 1 - m00 + m11 - m22,
                      R[..., 1, 2] + R[..., 2, 1]), axis=-1),
            np.stack((R[..., 1, 0] - R[..., 0, 1], R[..., 0, 2] + R[..., 2, 0], R[..., 1, 2] + R[..., 2, 1],
                      1 - m00 - m11 + m22), axis=-1),
        ),
        axis=-2,
    )  # fmt: skip
    diag = np.stack((1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22), axis=-1)
    best = np.argmax(diag, axis=-1)
    q = np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]
    q = quat_normalize(q)
    return q * np.where(q[..., :1] < 0, -1.0, 1.0)


def quat_from_rotvec(v: np.ndarray) -> np.ndarray:
    """Returns unit quaternions (..., 4) wxyz for rotation vectors v (..., 3) in radians (axis * angle)."""
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(a/2)/a, with its limit 1/2 near zero.
    scale = np.where(angle > 1e-12, np.sin(half) / np.where(angle > 1e-12, angle, 1.0), 0.5 - angle**2 / 48.0)
    return np.concatenate((np.cos(half), v * scale), axis=-1)


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """Returns rotation vectors (..., 3), radians, for quaternions (..., 4) wxyz (shortest rotation)."""
    q = quat_normalize(q)
    q = q * np.where(q[..., :1] < 0, -1.0, 1.0)
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    scale = np.where(s > 1e-12, angle / np.where(s > 1e-12, s, 1.0), 2.0)
    return q[..., 1:] * scale


def rotvec_to_matrix(v: np.ndarray) -> np.ndarray:
    """Returns rotation matrices (..., 3, 3) for rotation vectors v (..., 3), radians (Rodrigues)."""
    angle = np.linalg.norm(v, axis=-1)[..., None, None]
    safe = np.where(angle > 1e-12, angle, 1.0)
    k = v / safe[..., 0]
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    small = angle <= 1e-12
    sin = np.where(small, 0.0, np.sin(angle))
    cos1 = np.where(small, 0.0, 1.0 - np.cos(angle))
    return np.eye(3) + sin * K + cos1 * (K @ K)


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Returns the smallest rotation matrices (..., 3, 3) turning unit vectors a onto unit vectors b (..., 3)."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1, keepdims=True)
    c = np.sum(a * b, axis=-1, keepdims=True)
    angle = np.arctan2(s, c)
    # Opposite vectors: rotate by pi about any axis orthogonal to a.
    ortho = np.cross(a, np.where(np.abs(a[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]))
    axis = np.where(s > 1e-9, axis, ortho)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    return rotvec_to_matrix(axis * angle)


def axis_rotation(axis: int, angle: float | np.ndarray) -> np.ndarray:
    """Returns rotation matrices (..., 3, 3) about the body axis `axis` (0 = x, 1 = y, 2 = z) by `angle` (...) rad."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(np.shape(angle) + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def euler(angles_rad: np.ndarray, order: str) -> np.ndarray:
    """Returns (..., 3, 3): rotations about fixed axes applied in `order` (first letter first).

    angles_rad: (..., len(order)) radians, one per letter of order (e.g. "XYZ" -> Rz @ Ry @ Rx).
    """
    angles_rad = np.asarray(angles_rad, dtype=np.float64)
    R = np.broadcast_to(np.eye(3), angles_rad.shape[:-1] + (3, 3)).copy()
    for k, letter in enumerate(order):
        R = axis_rotation("XYZ".index(letter.upper()), angles_rad[..., k]) @ R
    return R


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Returns rotation vectors (..., 3), radians, for rotation matrices R (..., 3, 3)."""
    return quat_to_rotvec(matrix_to_quat(R))


def quat_mean(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Returns the normalised sign-aligned mean of unit quaternions q (..., 4) wxyz along `axis` (chordal mean)."""
    q = np.moveaxis(np.asarray(q, dtype=np.float64), axis, 0)
    ref = q[0]
    aligned = q * np.where(np.sum(q * ref, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    mean = np.nansum(aligned, axis=0)
    norm = np.linalg.norm(mean, axis=-1, keepdims=True)
    return np.where(norm > 1e-12, mean / np.where(norm > 1e-12, norm, 1.0), np.array([1.0, 0.0, 0.0, 0.0]))


def frame_from_axes(y: np.ndarray, x_hint: np.ndarray) -> np.ndarray:
    """Returns rotation matrices (..., 3, 3) whose columns are (x, y, z): y = unit(y), x = x_hint made orthogonal to y.

    y, x_hint: (..., 3) any length; z = x × y. Where x_hint is parallel to y the result is NaN.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        yu = y / np.linalg.norm(y, axis=-1, keepdims=True)
        x = x_hint - np.sum(x_hint * yu, axis=-1, keepdims=True) * yu
        x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    z = np.cross(x, yu)
    return np.stack((x, yu, z), axis=-1)
