#!/usr/bin/python3
"""Which part of the error against ground truth is ours: a three-cornered hat with a peer.

    bench/peer_check.py LOG.csv EVALUATION.csv PEER.csv
    bench/peer_check.py --self-test

LOG.csv and EVALUATION.csv are one run's --log and --evaluation files; PEER.csv is
bench/peer_odometry's estimate of the same pairs (OpenCV's dense RgbdICPOdometry). Three
estimates of each motion -- ours, the peer's and the motion capture's -- differ pairwise by
e_ours - e_gt, e_peer - e_gt and e_ours - e_peer. If the three errors are independent, each
one's mean square follows from the three differences (the "three-cornered hat" of clock
comparison):

    common = (|ours-gt|^2 + |peer-gt|^2 - |ours-peer|^2) / 2   the ground truth's own error,
                                                               plus whatever the sensor gives
                                                               both estimators alike (timing)
    ours   = (|ours-gt|^2 + |ours-peer|^2 - |peer-gt|^2) / 2   our own error
    peer   = (|peer-gt|^2 + |ours-peer|^2 - |ours-gt|^2) / 2

(estimates: one may come out below 0 when it is small against the others). Reported per axis
and along the eigen-directions of each pair's reported covariance, whitened by it, smallest
first: there a covariance that covers our own error has `ours` <= 1, and `common` is what a
check against this ground truth charges to us besides it.

First, on the same pairs, each estimator's pair error and its drift over 1-s windows of
consecutive pairs (their errors summed: first order).
"""
import math
import os
import sys
import tempfile

import numpy as np

from evaluation_csv import AXES, LOG_HEADER, allowance_variances, log_row, read_evaluation, read_log, read_rows, stamp_key, summed_over, windows


# Below this many pairs joined, or half the log's, the hat's sampling error would be the verdict
# (a restamped log joined on its times alone once left 2 pairs of 235, and a verdict on them).
MIN_PAIRS = 30
# How far a capture clock may have moved a frame's time from its stamp (latency.min_s, max_s).
LATENCY_RANGE_S = (-0.1, 0.25)


def read_inputs(log_path, evaluation_path, peer_path):
    """Pairs present, solved, in all three files, in time order: their stamps (t_prev, t_curr),
    ours, peer (xi), e_ours, reported covariance; and the evaluation's ground-truth allowance."""
    log = read_log(log_path)
    ours = {k: (xi, cov) for k, (_, _, xi, cov) in log.items()}
    evaluation, allowance = read_evaluation(evaluation_path)
    errors = {stamp_key(t): np.array([evaluation["e_" + a][n] for a in AXES]) for n, t in enumerate(evaluation["t_s"])}
    peer_rows = read_rows(peer_path)
    frame_at = frame_join(sorted({t for v in log.values() for t in v[:2]}),
                          sorted({float(r[end]) for r in peer_rows for end in ("t_prev", "t_curr")}))
    log_prev = {k: stamp_key(v[0]) for k, v in log.items()}
    peer = {}
    for r in peer_rows:  # a peer pair joins the log's pair of the same two frames
        prev, curr = (frame_at.get(stamp_key(r[end])) for end in ("t_prev", "t_curr"))
        if r["ok"] == "1" and curr is not None and log_prev.get(curr) == prev:
            peer[curr] = np.array([float(r[a]) for a in AXES])
    keys = sorted(k for k in ours if k in errors and k in peer and np.all(np.isfinite(errors[k])))
    if len(keys) < max(MIN_PAIRS, len(ours) // 2):
        sys.exit(f"peer_check: {len(keys)} of the log's {len(ours)} solved pairs are in all of {log_path}, "
                 f"{evaluation_path} and {peer_path}: too few for a verdict (at least {MIN_PAIRS} and half of them)")
    xi = np.array([ours[k][0] for k in keys])
    stamps = np.array([log[k][:2] for k in keys])
    return (stamps, xi, np.array([peer[k] for k in keys]), np.array([errors[k] for k in keys]),
            np.array([ours[k][1] for k in keys]), allowance)


def frame_join(log_times, peer_stamps):
    """stamp_key(peer stamp) -> stamp_key(log time) of the same frame (both lists sorted). Where a
    gyro restamped the log (src/pipeline/capture_latency.hpp) its times are the stamps less a
    latency that moves slowly from frame to frame (at most latency.max_slew): each log time goes
    with the peer stamp, within the latencies' range, whose latency is nearest the last frame
    joined (0 at the start: nothing applied yet), if nearer than half the stamps' spacing there;
    a frame that moved further is left out rather than joined to its neighbour. Unrestamped logs
    join on equal stamps."""
    stamps = np.array(peer_stamps)
    joined, latency = {}, 0.0
    for t in log_times:
        lo, hi = np.searchsorted(stamps, [t + LATENCY_RANGE_S[0], t + LATENCY_RANGE_S[1]])
        if lo == hi:
            continue
        best = lo + int(np.argmin(np.abs(stamps[lo:hi] - t - latency)))
        spacing = np.min(np.diff(stamps[max(best - 1, 0):best + 2])) if len(stamps) > 1 else np.inf
        if abs(stamps[best] - t - latency) < spacing / 2:
            latency = stamps[best] - t
            joined[stamp_key(stamps[best])] = stamp_key(t)
    return joined


def three_cornered_hat(ours_gt, peer_gt):
    """Mean squares (per column) of the common, our own and the peer's own error."""
    ours_peer = ours_gt - peer_gt
    a, b, c = (np.mean(x * x, axis=0) for x in (ours_gt, peer_gt, ours_peer))
    return (a + b - c) / 2, (a + c - b) / 2, (b + c - a) / 2


def whitened(vectors, covariances):
    """Each vector in its covariance's eigen-basis, divided by the sd there, smallest first."""
    out = np.empty_like(vectors)
    for n, (v, cov) in enumerate(zip(vectors, covariances)):
        lam, u = np.linalg.eigh(cov)  # ascending
        out[n] = (u.T @ v) / np.sqrt(lam)
    return out


def allowance_along(covariances, allowance):
    """Mean square of the allowance's sd along each whitened eigen-direction, smallest first."""
    variance = allowance_variances(allowance)
    out = np.zeros(6)
    for cov in covariances:
        lam, u = np.linalg.eigh(cov)
        out += (u * u).T @ variance / lam
    return out / len(covariances)


def window_sums(stamps, errors, window_s=1.0):
    """Each window's summed errors, over windows of consecutive pairs spanning window_s."""
    return summed_over(errors, windows(stamps[:, 0], stamps[:, 1], window_s))


def parts(mean_squares):
    """Per-axis mean squares -> (translation, rotation): the rms of the sums over their axes."""
    return tuple(math.sqrt(max(float(np.sum(mean_squares[axes])), 0.0)) for axes in (slice(0, 3), slice(3, 6)))


def own_part_sd(ours_gt, peer_gt, resamples=400):
    """Our own part's sampling error (its sd over resamplings of the pairs, a fixed seed): on a
    few dozen pairs, where the ground truth's own error dwarfs ours along a direction, its
    estimate moves by more than itself from one draw of the pairs to the next."""
    rng = np.random.default_rng(1)
    n = len(ours_gt)
    return np.std([three_cornered_hat(ours_gt[idx], peer_gt[idx])[1]
                   for idx in (rng.integers(0, n, n) for _ in range(resamples))], axis=0)


def exceeding(ours, sd):
    """Directions where our own part exceeds the covariance (1) by more than twice its sampling error."""
    return [i for i in range(len(ours)) if ours[i] - 2 * sd[i] > 1]


def analyse(log_path, evaluation_path, peer_path):
    stamps, xi, peer, e_ours, cov, allowance = read_inputs(log_path, evaluation_path, peer_path)
    e_peer = e_ours - (xi - peer)  # the program wrote e_ours = xi - xi_gt
    per_axis = three_cornered_hat(e_ours, e_peer)
    white_ours, white_peer = whitened(e_ours, cov), whitened(e_peer, cov)
    along = three_cornered_hat(white_ours, white_peer) + (own_part_sd(white_ours, white_peer),)
    summed_ours, summed_peer = window_sums(stamps, e_ours), window_sums(stamps, e_peer)
    windowed = three_cornered_hat(summed_ours, summed_peer) if len(summed_ours) else None
    drifts = tuple(parts(np.mean(x * x, axis=0)) + (len(x),) if len(x) else (math.nan, math.nan, 0)
                   for x in (summed_ours, summed_peer))
    return len(xi), (e_ours, e_peer), per_axis, along, allowance_along(cov, allowance), drifts, windowed


def rms_text(mean_square, unit_scale):
    return f"{unit_scale * math.sqrt(mean_square):6.2f}" if mean_square >= 0 else "   < 0"


def report(log_path, evaluation_path, peer_path):
    n, (e_ours, e_peer), per_axis, along, allowance, drifts, windowed = analyse(log_path, evaluation_path, peer_path)
    print(f"{n} pairs solved by both, with ground truth")
    print("on these pairs              pair rms: translation  rotation | over 1-s windows (first order): translation  rotation")
    for name, e, (t_rms, r_rms, count) in (("ours", e_ours, drifts[0]), ("peer", e_peer, drifts[1])):
        pair_t, pair_r = parts(np.mean(e * e, axis=0))
        print(f"  {name}                         {1e3 * pair_t:6.2f} mm  {math.degrees(pair_r):7.3f} deg |"
              f"   {1e3 * t_rms:6.2f} mm  {math.degrees(r_rms):6.3f} deg  ({count} windows)")
    if windowed is not None:
        shares = [parts(m) for m in windowed]
        print("the windows' drift, three-cornered hat (common / ours alone / peer alone; a part below 0 shows as 0): translation "
              + " / ".join(f"{1e3 * t:.2f}" for t, _ in shares) + " mm, rotation "
              + " / ".join(f"{math.degrees(r):.3f}" for _, r in shares) + " deg")
    print("rms per axis (mm, mrad):  ours-gt  peer-gt  ours-peer | common     ours     peer")
    for i, a in enumerate(AXES):
        d = [np.mean(x[:, i] ** 2) for x in (e_ours, e_peer, e_ours - e_peer)]
        cols = "  ".join(rms_text(v, 1e3) for v in d)
        hat = "   ".join(rms_text(p[i], 1e3) for p in per_axis)
        print(f"  {a}                      {cols} | {hat}")
    print("mean square along the reported covariance's eigen-directions, whitened (1 = covered; ours +- its sampling error):")
    print("  direction (smallest first)    common        ours     peer | the evaluation's ground-truth allowance")
    for i in range(6):
        print(f"  {i}                          {along[0][i]:8.2f} {along[1][i]:6.2f} +-{along[3][i]:5.2f} {along[2][i]:8.2f} |"
              f" {allowance[i]:8.2f}")
    over = exceeding(along[1], along[3])
    if over:
        print("verdict: our own error exceeds the reported covariance, by more than twice its sampling error, along "
              "direction(s) " + ", ".join(map(str, over)))
    else:
        print("verdict: our own error is within the reported covariance along every direction (to twice its sampling "
              "error)")


def restamped_copy(paths, tmp):
    """The self-test's log and evaluation with every frame's time its stamp less a latency that
    grows by 0.5 ms a frame to 25 ms (past half a frame, where the nearest stamp is the next
    frame's), analysed against the same peer: (pairs joined, whitened parts)."""
    log, evaluation_path, peer = paths
    rows = [line for line in open(log) if not line.startswith("#")]
    shift = {}  # stamp key -> restamped time

    def moved(t):
        k = stamp_key(t)
        if k not in shift:
            shift[k] = float(t) - min(0.025, 0.0005 * len(shift))
        return shift[k]

    out = [os.path.join(tmp, name) for name in ("restamped_log.csv", "restamped_evaluation.csv")]
    with open(out[0], "w") as f:
        f.write(rows[0])
        for r in rows[1:]:
            t_prev, t_curr, rest = r.split(",", 2)
            f.write(f"{moved(t_prev):.6f},{moved(t_curr):.6f},{rest}")
    with open(evaluation_path) as src, open(out[1], "w") as f:
        for line in src:
            if line.startswith("#") or line.startswith("t_s"):
                f.write(line)
            else:
                t, rest = line.split(",", 1)
                f.write(f"{moved(t):.6f},{rest}")
    count, _, _, along, _, _, _ = analyse(out[0], out[1], peer)
    return count, along


def self_test():
    """Synthetic pairs with known common and own errors, through the same files and code."""
    rng = np.random.default_rng(7)
    n = 4000
    true_common = np.array([0.8, 0.4, 0.3, 0.2, 0.1, 0.05])  # mean squares, whitened
    true_ours = np.full(6, 1.0)
    true_peer = np.array([3.0, 2.0, 1.0, 1.0, 0.5, 0.5])
    generated = []  # each pair's common, our own and the peer's own error
    with tempfile.TemporaryDirectory() as tmp:
        paths = [os.path.join(tmp, name) for name in ("log.csv", "evaluation.csv", "peer.csv")]
        with open(paths[0], "w") as log, open(paths[1], "w") as ev, open(paths[2], "w") as peer:
            log.write(LOG_HEADER + "\n")
            ev.write("# synthetic\nt_s," + ",".join("e_" + a for a in AXES) + "\n")
            peer.write("t_prev,t_curr,ok," + ",".join(AXES) + "\n")
            for k in range(n):
                q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
                sd = np.sort(np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), 6)))  # eigh order: ascending
                cov = q @ np.diag(sd * sd) @ q.T
                in_basis = q * sd  # maps whitened draws into this pair's coordinates
                truth = np.concatenate([rng.normal(0, 0.02, 3), rng.normal(0, 0.02, 3)])
                common = in_basis @ rng.normal(0, np.sqrt(true_common))
                own = [in_basis @ rng.normal(0, np.sqrt(true_ours)), in_basis @ rng.normal(0, np.sqrt(true_peer))]
                generated.append((common, own[0], own[1]))
                ours = truth + common + own[0]
                other = truth + common + own[1]
                t = 1000 + k / 30
                log.write(log_row(t - 1 / 30, t, ours, cov) + "\n")
                ev.write(f"{t:.6f}," + ",".join(f"{x:.12g}" for x in ours - truth) + "\n")
                peer.write(f"{t - 1 / 30:.6f},{t:.6f},1," + ",".join(f"{x:.12g}" for x in other) + "\n")
            peer.write(f"{t:.6f},{t + 1 / 30:.6f},0,nan,nan,nan,nan,nan,nan\n")  # a failed peer pair is skipped
        count, (e_ours, e_peer), _, along, allowance, drifts, windowed = analyse(*paths)
        restamped_count, restamped_along = restamped_copy(paths, tmp)
    failures = []
    # The same pairs restamped as a gyro's capture clock does (each frame its stamp less a
    # latency that grows from 0 to 25 ms): every pair joined to the peer's, the same figures.
    if restamped_count != n or not np.allclose(restamped_along[1], along[1]):
        failures.append(f"restamped log: {restamped_count} pairs joined of {n}, our own part {restamped_along[1]} "
                        f"against {along[1]}")
    # The hat over the windows: each part's window sums, as generated, within a quarter of the
    # largest part (their cross terms over ~130 independent windows).
    t = 1000 + np.arange(n) / 30
    stamps = np.column_stack([t - 1 / 30, t])
    for axes, part in ((slice(0, 3), "translation"), (slice(3, 6), "rotation")):
        truth_parts = [np.mean(np.sum(window_sums(stamps, np.array([g[i] for g in generated]))[:, axes] ** 2, axis=1))
                       for i in range(3)]
        for name, got, want in zip(("common", "ours", "peer"), windowed, truth_parts):
            got = float(np.sum(got[axes]))
            if not abs(got - want) <= 0.25 * max(truth_parts):
                failures.append(f"windows, {name} in {part}: mean square {got:.4g}, generated {want:.4g}")
    # Independent pairs: a window of L pairs sums to L times a pair's mean square; 30 pairs a
    # window of 1 s at 30 Hz (about 130 independent windows: within 20 %).
    for name, e, (t_rms, r_rms, windows_read) in (("ours", e_ours, drifts[0]), ("peer", e_peer, drifts[1])):
        if not n - 35 <= windows_read <= n - 25:
            failures.append(f"{name}: {windows_read} windows of 1 s from {n} consecutive pairs of 1/30 s")
        for part, got, axes in (("translation", t_rms, slice(0, 3)), ("rotation", r_rms, slice(3, 6))):
            expected = math.sqrt(30 * np.mean(np.sum(e[:, axes] ** 2, axis=1)))
            if not abs(got - expected) <= 0.2 * expected:
                failures.append(f"{name}: 1-s drift in {part} {got:.4g}, expected {expected:.4g} within 20 %")
    if count != n:
        failures.append(f"{count} pairs read, {n} written")
    if np.any(allowance != 0):
        failures.append(f"allowance {allowance} from a file that states none")
    # Sampling error of a mean square over n pairs: ~sqrt(2/n) of the largest term involved.
    for name, got, want in zip(("common", "ours", "peer"), along, (true_common, true_ours, true_peer)):
        tolerance = 0.1 * max(want.max(), 1.0) + 0.05
        for i in range(6):
            if abs(got[i] - want[i]) > tolerance:
                failures.append(f"{name} direction {i}: {got[i]:.3f}, expected {want[i]:.3f} +- {tolerance:.3f}")
    # The sampling error of our own part: about sqrt(2 / n) of the mean squares involved (a few
    # hundredths here); a part flagged only once it stands clear of it.
    for i in range(6):
        if not 0.005 < along[3][i] < 0.1:
            failures.append(f"ours direction {i}: sampling error {along[3][i]:.4f}, expected a few hundredths")
    if exceeding(np.array([3.0, 1.3, 0.5]), np.array([0.5, 0.3, 0.1])) != [0]:
        failures.append("a part 4 sampling errors above 1 must be flagged, one 1 sampling error above it not")
    if failures:
        print("peer_check self-test FAILED:\n  " + "\n  ".join(failures))
        return 1
    print(f"peer_check self-test passed: {n} synthetic pairs, the common, own and peer mean squares, per pair and "
          "over 1-s windows, and both drifts recovered; the same pairs restamped joined alike")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    report(*sys.argv[1:])
    return 0


if __name__ == "__main__":
    sys.exit(main())
