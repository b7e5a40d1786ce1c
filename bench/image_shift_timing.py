#!/usr/bin/python3
"""At which instant each part of the pairs' motion matches the motion capture.

    bench/image_shift_timing.py LOG.csv GROUNDTRUTH.txt [--depth Z] [--shifts-ms -24:24:4]
    bench/image_shift_timing.py --self-test

A pair's sideways translation and tilt rotation reach the image in two combinations. Their sum,
the image shift of a point ahead at depth Z (tx/Z + ry, ty/Z - rx, as rotations), is what the
features measure most precisely and is the colour's own; their difference, the slide
(tx/Z - ry, ty/Z + rx), only parallax tells apart, and a depth read at another instant enters
it. For each shift s of the log's intervals (the frames taken s before the logged times) the
ground truth's pair motion is read over [t_prev - s, t_curr - s] and the RMS error of each
combination printed (mrad). A sensor whose colour and depth agree has both best at one s; on
TUM fr1's Kinect the image shift is best at the stamps and the slide 14-24 ms later, which is
what the gyro's latency (the tilt rotations') restamps every part of a pair by
(src/pipeline/MEASUREMENTS.md#restamped-pairs-and-their-image-shift).

Last, at s = 0 and at the gyro-like instant the slide prefers, the sideways translation's and
tilt rotation's errors and their correlation.
"""
import os
import sys
import tempfile

import numpy as np

from evaluation_csv import LOG_HEADER, log_row, read_log
from tum_groundtruth import orientation_at, read_groundtruth


def groundtruth_motion(gt, t0, t1):
    """The camera's motion from t0 to t1 in its frame at t0: xi = (t, rotation vector)."""
    p0 = np.array([np.interp(t0, gt[:, 0], gt[:, i]) for i in (1, 2, 3)])
    p1 = np.array([np.interp(t1, gt[:, 0], gt[:, i]) for i in (1, 2, 3)])
    r0, r1 = orientation_at(gt, t0), orientation_at(gt, t1)
    turn = r0.T @ r1
    angle = np.arccos(np.clip((np.trace(turn) - 1) / 2, -1.0, 1.0))
    axis = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]])
    w = axis * (angle / (2 * np.sin(angle)) if angle > 1e-12 else 0.5)
    return np.concatenate([r0.T @ (p1 - p0), w])


def combinations(e, depth):
    """(image shift x, y; slide x, y) of errors e (n x 6), as rotations (rad)."""
    tx, ty, rx, ry = e[:, 0] / depth, e[:, 1] / depth, e[:, 3], e[:, 4]
    return np.stack([tx + ry, ty - rx, tx - ry, ty + rx], axis=1)


def errors_at(pairs, gt, shift_s):
    inside = [p for p in pairs if p[0] - shift_s > gt[0, 0] and p[1] - shift_s < gt[-1, 0]]
    return np.array([p[2] - groundtruth_motion(gt, p[0] - shift_s, p[1] - shift_s) for p in inside])


def analyse(log_path, gt_path, depth, shifts_ms):
    pairs = sorted(read_log(log_path).values(), key=lambda p: p[1])
    gt = read_groundtruth(gt_path)
    table = []
    for s in shifts_ms:
        c = combinations(errors_at(pairs, gt, s * 1e-3), depth)
        table.append((s, np.sqrt(np.mean(c ** 2, axis=0))))
    return table


def best(table, column):
    return min(table, key=lambda row: row[1][column])[0]


def report(log_path, gt_path, depth, shifts_ms):
    table = analyse(log_path, gt_path, depth, shifts_ms)
    print(f"RMS error (mrad) with the frames taken s ms before the logged times, depth {depth} m")
    print("   s | image shift x, y | slide x, y")
    for s, rms in table:
        print(f"{s:5.1f} | {1e3 * rms[0]:6.3f} {1e3 * rms[1]:6.3f} | {1e3 * rms[2]:6.3f} {1e3 * rms[3]:6.3f}")
    print(f"best: image shift at {best(table, 0):g}, {best(table, 1):g} ms; slide at {best(table, 2):g}, {best(table, 3):g} ms")
    pairs = sorted(read_log(log_path).values(), key=lambda p: p[1])
    gt = read_groundtruth(gt_path)
    for s in (0.0, best(table, 2)):
        e = errors_at(pairs, gt, s * 1e-3)
        tx, ry = e[:, 0] / depth, e[:, 4]
        print(f"s = {s:g} ms: tx/Z {1e3 * np.sqrt(np.mean(tx ** 2)):.2f} mrad, ry {1e3 * np.sqrt(np.mean(ry ** 2)):.2f} mrad, "
              f"correlation {np.corrcoef(tx, ry)[0, 1]:.2f}")
    return table


def self_test():
    """A camera swaying sideways while turning; its pairs' image shift taken at their stamps,
    their slide 20 ms earlier: the image shift must read best at 0, the slide at 20 (+-4)."""
    depth, lag = 1.0, 0.020
    t = np.arange(0, 6, 0.01)
    x, yaw = 0.1 * np.sin(2 * np.pi * 0.7 * t), 0.15 * np.sin(2 * np.pi * 0.45 * t + 1)
    q = np.stack([np.zeros_like(t), np.sin(yaw / 2), np.zeros_like(t), np.cos(yaw / 2)], axis=1)  # about y
    gt = np.column_stack([t, x, np.zeros_like(t), np.zeros_like(t), q])
    with tempfile.TemporaryDirectory() as d:
        gt_path, log_path = os.path.join(d, "groundtruth.txt"), os.path.join(d, "log.csv")
        np.savetxt(gt_path, gt, header="timestamp tx ty tz qx qy qz qw")
        rows = [LOG_HEADER]
        for t0 in np.arange(0.5, 5.5, 1 / 30):
            on_time, late = groundtruth_motion(gt, t0, t0 + 1 / 30), groundtruth_motion(gt, t0 - lag, t0 + 1 / 30 - lag)
            shift = on_time[0] / depth + on_time[4]  # keep the image shift, take the slide from `late`
            slide = late[0] / depth - late[4]
            xi = on_time.copy()
            xi[0], xi[4] = depth * (shift + slide) / 2, (shift - slide) / 2
            rows.append(log_row(t0, t0 + 1 / 30, xi, np.eye(6)))
        open(log_path, "w").write("\n".join(rows) + "\n")
        table = report(log_path, gt_path, depth, range(-8, 33, 4))
    ok = abs(best(table, 0)) <= 4 and abs(best(table, 2) - 1e3 * lag) <= 4
    print("self-test passed" if ok else "self-test FAILED")
    return 0 if ok else 1


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) < 3:
        sys.exit(__doc__)
    depth, shifts = 0.8, "-24:24:4"
    rest = argv[3:]
    while rest:
        flag, value, rest = rest[0], rest[1], rest[2:]
        if flag == "--depth":
            depth = float(value)
        elif flag == "--shifts-ms":
            shifts = value
        else:
            sys.exit(f"unknown option {flag}\n{__doc__}")
    lo, hi, step = (float(v) for v in shifts.split(":"))
    report(argv[1], argv[2], depth, np.arange(lo, hi + step / 2, step))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
