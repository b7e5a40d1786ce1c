#!/usr/bin/python3
"""How much of the drift over windows is a delay of the stamps.

    bench/window_delay.py LOG.csv EVALUATION.csv [--window S]
    bench/window_delay.py --self-test

LOG.csv and EVALUATION.csv are one run's --log and --evaluation files. If every frame was
taken d seconds before its stamp, each pair measures the motion over its stamps' interval
moved d earlier, and its error is about -d x (the camera's rate at its newer stamp - the rate
at its older one). Summed over the consecutive pairs of a window, those errors telescope to
-d x (the rate at the window's end - the rate at its start): a delay makes the drift over a
window follow the change of rate across it, and nothing else does so for every window alike.

Per axis, the windows' summed errors (first order: small rotations per pair) are regressed
on the change of the ground truth's rate between the window's end and start stamps. The slope
is minus the delay (a negative slope: the frames were taken before their stamps), R^2 the
share of that axis's drift the delay explains, and "without the delay" the drift left. Where
it is the stamps' delay, a flight controller told it (PX4 EKF2_EV_DELAY, ArduPilot
VISO_DELAY_MS) does not see that share. On the Kinect it is not: the rotation about the optical
axis, which the depth does not enter, reads none; the share is the depth's lag behind the
colour, reaching the other axes through the fit
(bench/MEASUREMENTS.md#drift-over-1-s-the-share-that-follows-the-change-of-rate).

Last, per sideways axis, the share of its windows' error that is the other half of the tilt
rotation's (tx with ry, ty with rx): the slope, the correlation and what is left without it.
"""
import math
import os
import sys
import tempfile

import numpy as np

from evaluation_csv import AXES, LOG_HEADER, log_evaluation_and_option, log_row, read_pairs, summed_over, windows


def analyse(log_path, evaluation_path, window_s=1.0):
    """Per axis: delay (s), R^2, rms of the windows' error and of what the delay leaves; the count."""
    t_prev, t_curr, xi, _, error = read_pairs(log_path, evaluation_path)
    rate = (xi - error) / (t_curr - t_prev)[:, None]  # the ground truth's: the files hold xi - xi_gt
    spans = windows(t_prev, t_curr, window_s)
    if len(spans) < 3:
        sys.exit(f"window_delay: fewer than 3 windows of {window_s} s of consecutive pairs")
    summed = summed_over(error, spans)
    # The rates at the window's two end stamps, from its two outer pairs' mean rates (theirs are
    # half a pair inside), carried out by half a pair at the rate's own change.
    change = np.array([(1.5 * rate[j] - 0.5 * rate[j - 1]) - (1.5 * rate[i] - 0.5 * rate[i + 1]) for i, j in spans])
    result = []
    for a in range(6):
        slope, total, left = through_origin(change[:, a], summed[:, a])
        r2 = 1 - (left / total) ** 2 if total > 0 else 0.0
        result.append((-slope, r2, total, left))
    return result, len(spans), split_shares(summed)


def through_origin(x, y):
    """y = slope x, least squares through the origin: the slope, rms of y, rms of what is left."""
    slope = float(np.dot(x, y) / np.dot(x, x)) if np.dot(x, x) > 0 else 0.0
    left = y - slope * x
    return slope, math.sqrt(float(np.mean(y * y))), math.sqrt(float(np.mean(left * left)))


def split_shares(summed):
    """Per sideways axis, how much of its windows' summed error is the other half of the tilt
    rotation's (tx with ry, ty with rx): the features fix each image motion far better than its
    split between translation and rotation. Slope (m per rad), correlation, rms all / left."""
    shares = []
    for t, r in ((0, 4), (1, 3)):
        y, x = summed[:, t], summed[:, r]
        slope, total, left = through_origin(x, y)
        correlation = float(np.corrcoef(x, y)[0, 1]) if np.std(x) > 0 and np.std(y) > 0 else 0.0
        shares.append((AXES[t], AXES[r], slope, correlation, total, left))
    return shares


def report(log_path, evaluation_path, window_s):
    per_axis, count, shares = analyse(log_path, evaluation_path, window_s)
    print(f"{count} windows of {window_s:g} s: summed error regressed on the change of the ground truth's rate")
    print("axis   delay (ms)   R^2   drift rms   without the delay   (mm or mdeg per window)")
    for a, (delay, r2, total, rest) in zip(AXES, per_axis):
        scale = 1e3 if a.startswith("t") else 1e3 * 180 / math.pi
        print(f"  {a}   {delay * 1e3:+8.1f}   {r2:5.2f}   {total * scale:9.2f}   {rest * scale:9.2f}")
    for name, axes, scale, unit in (("translation", range(3), 1e3, "mm"), ("rotation", range(3, 6), 1e3 * 180 / math.pi,
                                                                              "mdeg")):
        total = math.sqrt(sum(per_axis[a][2] ** 2 for a in axes))
        rest = math.sqrt(sum(per_axis[a][3] ** 2 for a in axes))
        print(f"{name}: {total * scale:.2f} {unit} per window, {rest * scale:.2f} without each axis's delay")
    for t, r, slope, correlation, total, left in shares:
        print(f"{t} against {r}: {slope:+.2f} m x {r}'s summed error (correlation {correlation:+.2f}); "
              f"{t} {total * 1e3:.2f} mm per window, {left * 1e3:.2f} without that share")


def self_test():
    """Synthetic pairs taken a known delay before their stamps, through the same files and code:
    the delay is read back on every axis, and a run with none reads none."""
    rng = np.random.default_rng(11)
    failures = []
    for true_delay in (0.020, 0.0):
        n = 1800
        dt = 1 / 30 + rng.normal(0, 0.001, n)
        t = 1000 + np.concatenate([[0], np.cumsum(dt)])
        # Smooth rates: a few sinusoids per axis (m/s, rad/s), evaluated at the frames' true times.
        freq = rng.uniform(0.2, 1.0, (6, 3))
        amp = np.array([0.2, 0.2, 0.2, 0.3, 0.3, 0.3])[:, None] * rng.uniform(0.3, 1.0, (6, 3))
        phase = rng.uniform(0, 2 * math.pi, (6, 3))

        def position(times):  # integral of the rates
            return np.array([[np.sum(amp[a] / (2 * math.pi * freq[a]) * np.sin(2 * math.pi * freq[a] * s + phase[a]))
                              for a in range(6)] for s in times])
        at_stamps = position(t)
        taken = position(t - true_delay)
        gt = np.diff(at_stamps, axis=0)
        xi = np.diff(taken, axis=0) + rng.normal(0, 2e-4, (n, 6))  # what the pairs measure, with noise
        with tempfile.TemporaryDirectory() as tmp:
            log_path, evaluation_path = os.path.join(tmp, "log.csv"), os.path.join(tmp, "evaluation.csv")
            with open(log_path, "w") as log, open(evaluation_path, "w") as ev:
                log.write(LOG_HEADER + "\n")
                ev.write("# synthetic\nt_s," + ",".join("e_" + a for a in AXES) + "\n")
                for k in range(n):
                    log.write(log_row(t[k], t[k + 1], xi[k], np.eye(6) * 1e-6) + "\n")
                    ev.write(f"{t[k + 1]:.6f}," + ",".join(f"{x:.12g}" for x in xi[k] - gt[k]) + "\n")
                log.write(f"{t[n]:.6f},{t[n] + 1 / 30:.6f},ransac_failed,0," + ",".join(["nan"] * 43) + "\n")
            per_axis, count, _ = analyse(log_path, evaluation_path, 1.0)
        if not 1700 <= count <= 1780:
            failures.append(f"delay {true_delay}: {count} windows of 1 s from {n} pairs of 1/30 s")
        for a, (delay, r2, _, _) in zip(AXES, per_axis):
            # First-order telescoping: the fitted delay is within a millisecond of the true one.
            if abs(delay - true_delay) > 0.001:
                failures.append(f"delay {true_delay * 1e3:.0f} ms, {a}: read {delay * 1e3:.2f} ms")
            if true_delay > 0 and r2 < 0.8:
                failures.append(f"delay {true_delay * 1e3:.0f} ms, {a}: R^2 {r2:.2f}, expected most of the drift")
    # The split share: windows whose tx error is -1.2 m x ry's plus a little of its own, and ty
    # independent of rx, read back as such.
    ry = rng.normal(0, 5e-3, 400)
    summed = np.zeros((400, 6))
    summed[:, 4], summed[:, 0] = ry, -1.2 * ry + rng.normal(0, 1e-3, 400)
    summed[:, 3], summed[:, 1] = rng.normal(0, 5e-3, 400), rng.normal(0, 5e-3, 400)
    (_, _, slope_x, corr_x, total_x, left_x), (_, _, slope_y, corr_y, _, _) = split_shares(summed)
    if abs(slope_x + 1.2) > 0.03 or corr_x > -0.95 or left_x > 0.2 * total_x:
        failures.append(f"split: tx against ry read {slope_x:+.3f} m (correlation {corr_x:+.2f}), expected -1.2")
    if abs(corr_y) > 0.15:
        failures.append(f"split: ty against an independent rx read correlation {corr_y:+.2f}")
    if failures:
        print("window_delay self-test FAILED:\n  " + "\n  ".join(failures))
        return 1
    print("window_delay self-test passed: a 20 ms delay read back on every axis within 1 ms, none where there is none; "
          "a split share read back")
    return 0


def main():
    args = sys.argv[1:]
    if args == ["--self-test"]:
        return self_test()
    log_path, evaluation_path, text = log_evaluation_and_option(args, "--window", __doc__)
    try:
        window_s = float(text) if text is not None else 1.0
    except ValueError:
        window_s = math.nan
    if not window_s > 0:
        sys.exit(f"window_delay: --window '{text}' must be a number of seconds above 0")
    report(log_path, evaluation_path, window_s)
    return 0


if __name__ == "__main__":
    sys.exit(main())
