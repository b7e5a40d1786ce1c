"""A TUM RGB-D recording's index files and motion-capture poses, for the bench scripts.

TUM's poses (t tx ty tz qx qy qz qw) are the colour camera's optical centre in the world, so
the rates below are the colour camera's own, in its own frame.
"""
import numpy as np

UNITS_PER_M = 5000.0   # TUM-layout depth PNGs: uint16, 5000 per metre


def read_index(path):
    """rgb.txt / depth.txt: [(stamp, relative path)], comments skipped."""
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith("#")]
    return [(float(r[0]), r[1]) for r in rows]


def read_groundtruth(path):
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith("#")]
    return np.array(rows, dtype=float)


def rotation_matrix(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def orientation_at(gt, t):
    """Orientation interpolated (spherical, between the two samples around t)."""
    i = int(np.clip(np.searchsorted(gt[:, 0], t), 1, len(gt) - 1))
    q0, q1 = gt[i - 1, 4:8] / np.linalg.norm(gt[i - 1, 4:8]), gt[i, 4:8] / np.linalg.norm(gt[i, 4:8])
    if q0 @ q1 < 0:
        q1 = -q1
    s = np.clip((t - gt[i - 1, 0]) / (gt[i, 0] - gt[i - 1, 0]), 0.0, 1.0)
    angle = np.arccos(np.clip(q0 @ q1, -1.0, 1.0))
    if angle < 1e-9:
        return rotation_matrix(q0)
    return rotation_matrix((np.sin((1 - s) * angle) * q0 + np.sin(s * angle) * q1) / np.sin(angle))


def camera_rates(gt, t, half_span_s):
    """The camera's velocity (m/s) and turn rate (rad/s) in its own frame, over t ± half_span_s,
    both interpolated between the samples (ICL-NUIM's come at 30 Hz, not TUM's 100 Hz)."""
    p0 = np.array([np.interp(t - half_span_s, gt[:, 0], gt[:, i]) for i in (1, 2, 3)])
    p1 = np.array([np.interp(t + half_span_s, gt[:, 0], gt[:, i]) for i in (1, 2, 3)])
    r0, r1 = orientation_at(gt, t - half_span_s), orientation_at(gt, t + half_span_s)
    v = r0.T @ (p1 - p0) / (2 * half_span_s)
    turn = r0.T @ r1
    w = 0.5 * np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]])
    return v, w / (2 * half_span_s)
