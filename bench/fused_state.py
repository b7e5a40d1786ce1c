#!/usr/bin/python3
"""How a flight controller's filter fuses the odometry: fused velocity and position hold.

usage: fused_state.py TUM_DIR ODOMETRY.csv [--seeds 10] [--window 5] [--up 0,0,1]
       fused_state.py --self-test

A Kalman filter of the kind PX4's EKF2 runs, reduced to what velocity fusion exercises: position,
velocity and accelerometer bias in the world frame, the attitude known (the autopilot's own is
good to a degree or two; the ground truth's here). It is driven by an IMU made from TUM_DIR's
ground truth (200 Hz, PX4's default accelerometer noise and bias), held vertically by a
barometer (0.1 m, 10 Hz) and aided by the log's pairs as external-vision velocity: translation /
dt, turned into the world frame, at the pair's middle instant. As EKF2 does with such a
measurement, it keeps the diagonal of the covariance (world frame), floors each sigma at
0.05 m/s and rejects a sample whose horizontal innovation exceeds 3 sigma (the two horizontal
axes tested together).

Cases, each over the same IMU seeds: the log with its own covariance; a constant sigma of
0.1 m/s (EKF2_EVV_NOISE's default); the log's median sigma; its true RMS error (an oracle no
real system has). Printed per case, medians over the seeds: the fused horizontal velocity's RMS
error (m/s), the growth of the horizontal position error over windows of --window seconds (m,
RMS over windows starting every 0.5 s: what a drone holding position drifts) and the samples
the gate rejected. --self-test: a synthetic recording whose odometry errors have the variance
its covariance states, pair by pair; there the covariance must beat every constant.
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evaluation_csv  # noqa: E402
import tum_groundtruth  # noqa: E402

IMU_HZ = 200.0
ACC_NOISE = 0.35        # m/s^2 a sample: EKF2_ACC_NOISE
ACC_BIAS_SIGMA = 0.05   # m/s^2, turn-on bias per axis
ACC_BIAS_WALK = 3e-3    # m/s^3: EKF2_ACC_B_NOISE
BARO_SIGMA = 0.1        # m, every 0.1 s
EV_SIGMA_FLOOR = 0.05   # m/s
GATE = 3.0              # sigmas
PX4_DEFAULT_SIGMA = 0.1


class Truth:
    """The ground truth resampled at the IMU rate: position, velocity, acceleration (smoothed
    over smooth_s, a Gaussian's sigma) and the camera's orientation at any instant."""

    def __init__(self, gt, smooth_s):
        self.gt = gt
        self.t = np.arange(gt[0, 0], gt[-1, 0], 1.0 / IMU_HZ)
        p = np.stack([np.interp(self.t, gt[:, 0], gt[:, i]) for i in (1, 2, 3)], axis=1)
        half = int(math.ceil(3 * smooth_s * IMU_HZ))
        kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / (smooth_s * IMU_HZ)) ** 2)
        kernel /= kernel.sum()
        padded = np.pad(p, ((half, half), (0, 0)), mode="edge")
        self.p = np.stack([np.convolve(padded[:, i], kernel, mode="valid") for i in range(3)], axis=1)
        self.v = np.gradient(self.p, 1.0 / IMU_HZ, axis=0)
        self.a = np.gradient(self.v, 1.0 / IMU_HZ, axis=0)

    def velocity_at(self, t):
        return np.array([np.interp(t, self.t, self.v[:, i]) for i in range(3)])


def ev_samples(truth, log_rows, fixed_sigma=None):
    """The log's solved pairs as world-frame velocity samples: (t_mid, v, variances, true error)."""
    out = []
    for t_prev, t_curr, xi, cov in log_rows:
        dt = t_curr - t_prev
        if dt <= 0 or t_prev < truth.t[0] or t_curr > truth.t[-1]:
            continue
        r = tum_groundtruth.orientation_at(truth.gt, t_prev)
        v = r @ xi[:3] / dt
        if fixed_sigma is not None:
            var = np.full(3, fixed_sigma ** 2)
        else:
            var = np.diag(r @ cov[:3, :3] @ r.T) / dt ** 2
        t_mid = 0.5 * (t_prev + t_curr)
        out.append((t_mid, v, var, v - truth.velocity_at(t_mid)))
    return out


def fuse(truth, samples, up, seed):
    """One run of the filter; returns (fused horizontal velocity RMS, position errors at the
    IMU instants within the samples' span, samples rejected)."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / IMU_HZ
    up = up / np.linalg.norm(up)
    horizontal = np.eye(3) - np.outer(up, up)
    bias = rng.normal(0, ACC_BIAS_SIGMA, 3)
    # State: position, velocity, accelerometer bias (world frame).
    x = np.concatenate([truth.p[0], truth.v[0], np.zeros(3)])
    P = np.diag([1e-4] * 3 + [1e-4] * 3 + [ACC_BIAS_SIGMA ** 2] * 3)
    F = np.eye(9)
    F[0:3, 3:6] = dt * np.eye(3)
    F[0:3, 6:9] = -0.5 * dt * dt * np.eye(3)
    F[3:6, 6:9] = -dt * np.eye(3)
    Q = np.zeros((9, 9))
    Q[0:3, 0:3] = (0.5 * dt * dt * ACC_NOISE) ** 2 * np.eye(3)
    Q[3:6, 3:6] = (dt * ACC_NOISE) ** 2 * np.eye(3)
    Q[6:9, 6:9] = ACC_BIAS_WALK ** 2 * dt * np.eye(3)
    baro_every = int(IMU_HZ / 10)
    samples = sorted(samples, key=lambda s: s[0])
    first, last = samples[0][0], samples[-1][0]
    k_sample, rejected = 0, 0
    velocity_errors, position_errors = [], []
    for k in range(1, len(truth.t)):
        bias += rng.normal(0, ACC_BIAS_WALK * math.sqrt(dt), 3)
        accel = truth.a[k - 1] + bias + rng.normal(0, ACC_NOISE, 3)
        x[0:3] += dt * x[3:6] + 0.5 * dt * dt * (accel - x[6:9])
        x[3:6] += dt * (accel - x[6:9])
        P = F @ P @ F.T + Q
        t = truth.t[k]
        if k % baro_every == 0:
            z = up @ truth.p[k] + rng.normal(0, BARO_SIGMA)
            h = np.concatenate([up, np.zeros(6)])
            x, P = update(x, P, h[None, :], np.array([z - up @ x[0:3]]), np.array([[BARO_SIGMA ** 2]]))
        while k_sample < len(samples) and samples[k_sample][0] <= t:
            _, v, var, _ = samples[k_sample]
            k_sample += 1
            R = np.diag(np.maximum(var, EV_SIGMA_FLOOR ** 2))
            H = np.zeros((3, 9))
            H[:, 3:6] = np.eye(3)
            innovation = v - x[3:6]
            S = H @ P @ H.T + R
            ratio = innovation ** 2 / (GATE ** 2 * np.diag(S))
            horizontal_axes = np.abs(up) < 0.9  # the axes the filter tests together as horizontal
            if np.max(ratio[horizontal_axes]) > 1:
                rejected += 1
                continue
            x, P = update(x, P, H, innovation, R)
        if first <= t <= last:
            velocity_errors.append(horizontal @ (x[3:6] - truth.v[k]))
            position_errors.append((t, horizontal @ (x[0:3] - truth.p[k])))
    v_rms = math.sqrt(np.mean(np.sum(np.square(velocity_errors), axis=1)))
    return v_rms, position_errors, rejected


def update(x, P, H, innovation, R):
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    x = x + K @ innovation
    I_KH = np.eye(len(x)) - K @ H
    return x, I_KH @ P @ I_KH.T + K @ R @ K.T


def position_growth(position_errors, window_s):
    """RMS over windows (starting every 0.5 s) of how far the horizontal position error moved
    within the window; NaN when the run is shorter than a window."""
    t = np.array([e[0] for e in position_errors])
    p = np.array([e[1] for e in position_errors])
    moves = []
    for start in np.arange(t[0], t[-1] - window_s, 0.5):
        i, j = np.searchsorted(t, start), np.searchsorted(t, start + window_s)
        moves.append(np.linalg.norm(p[min(j, len(t) - 1)] - p[i]))
    return math.sqrt(np.mean(np.square(moves))) if moves else float("nan")


def run_cases(truth, log_rows, up, seeds, window_s, out=sys.stdout):
    ours = ev_samples(truth, log_rows)
    sigmas = np.sqrt(np.concatenate([s[2] for s in ours]))
    errors = np.concatenate([s[3] for s in ours])
    median_sigma, true_rms = float(np.median(sigmas)), float(np.sqrt(np.mean(errors ** 2)))
    cases = [("its covariance", None), (f"sigma {PX4_DEFAULT_SIGMA} (PX4 default)", PX4_DEFAULT_SIGMA),
             (f"its median sigma {median_sigma:.3f}", median_sigma),
             (f"its true RMS error {true_rms:.3f} (oracle)", true_rms)]
    print(f"| {len(ours)} velocity samples, {seeds} seeds | fused velocity h (m/s) | {window_s:g}-s position growth h (m) "
          "| rejected |", file=out)
    print("|---|---|---|---|", file=out)
    results = {}
    for name, fixed in cases:
        samples = ours if fixed is None else ev_samples(truth, log_rows, fixed)
        runs = [fuse(truth, samples, up, seed) for seed in range(1, seeds + 1)]
        v = float(np.median([r[0] for r in runs]))
        g = float(np.median([position_growth(r[1], window_s) for r in runs]))
        rej = float(np.median([r[2] for r in runs]))
        results[name.split(" ")[0] + ("" if fixed is None else f"_{fixed:.4f}")] = (v, g, rej)
        print(f"| {name} | {v:.4f} | {g:.3f} | {rej:g} |", file=out)
    return results


def self_test():
    """A synthetic recording (a camera swaying 0.3 m at 0.4 Hz, z up) and its odometry: pair
    errors drawn with the variance the covariance states, which varies 10x from pair to pair.
    There the filter must gain from the covariance: velocity and position both better than with
    every constant sigma."""
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 30.0, 0.01)
    gt = np.zeros((len(t), 8))
    gt[:, 0] = t
    gt[:, 1] = 0.3 * np.sin(2 * math.pi * 0.4 * t)
    gt[:, 2] = 0.2 * np.cos(2 * math.pi * 0.25 * t)
    gt[:, 3] = 1.0
    gt[:, 7] = 1.0  # identity orientation: the camera frame is the world's
    truth = Truth(gt, 0.01)
    rows = []
    frame_t = np.arange(0.05, 29.9, 1 / 30.0)
    for a, b in zip(frame_t[:-1], frame_t[1:]):
        sigma = 0.0005 * 10 ** rng.uniform(0, 1)  # 0.5-5 mm a pair
        move = np.array([np.interp(b, t, gt[:, i]) - np.interp(a, t, gt[:, i]) for i in (1, 2, 3)])
        xi = np.concatenate([move + rng.normal(0, sigma, 3), np.zeros(3)])
        rows.append((a, b, xi, np.diag([sigma ** 2] * 3 + [1e-6] * 3)))
    results = run_cases(truth, rows, np.array([0.0, 0.0, 1.0]), seeds=3, window_s=5.0)
    ours = results["its"]
    constants = [v for k, v in results.items() if k != "its"]
    if not all(ours[0] < c[0] and ours[1] < c[1] for c in constants):
        sys.exit("self-test failed: the stated covariance did not beat every constant sigma")
    print("self-test passed: the stated covariance beats every constant sigma")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("tum_dir", nargs="?")
    ap.add_argument("odometry", nargs="?")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--window", type=float, default=5.0, help="position-growth window (s)")
    ap.add_argument("--up", default="0,0,1", help="the world's up in the ground truth's frame (ICL-NUIM: 0,-1,0)")
    ap.add_argument("--smooth", type=float, default=0.04, help="ground-truth smoothing sigma (s; exact poses: 0.005)")
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    if a.self_test:
        return self_test()
    if not a.tum_dir or not a.odometry:
        ap.error("TUM_DIR and ODOMETRY.csv are needed")
    truth = Truth(tum_groundtruth.read_groundtruth(os.path.join(a.tum_dir, "groundtruth.txt")), a.smooth)
    log_rows = sorted(evaluation_csv.read_log(a.odometry).values(), key=lambda r: r[1])
    run_cases(truth, log_rows, np.array([float(x) for x in a.up.split(",")]), a.seeds, a.window)


if __name__ == "__main__":
    main()
