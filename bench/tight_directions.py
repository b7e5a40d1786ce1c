#!/usr/bin/python3
"""Where a run's errors lie against its covariance's own directions.

    bench/tight_directions.py LOG.csv EVALUATION.csv [LOG.csv EVALUATION.csv ...]
    bench/tight_directions.py --self-test

Each pair's reported covariance plus the evaluation's allowance, P + A, is split into its
eigen-directions, smallest first, and the error's square along each is divided by that
direction's variance: 1 on average where the covariance is consistent there. On TUM's Kinect
the two smallest are the image-shift combinations of sideways translation and tilt rotation,
the largest the slides between them. Along the two smallest, the excess, the square root of
the mean over pairs of sum(e^2 - lambda), is printed by quartiles of the pair's rotation rate:
an error that follows the motion grows across them, one that follows something else does not.
Several runs are pooled (a thinned copy's phases, say); the directions mix metres and radians,
and the excess is printed in thousandths of them (mm or mrad).
"""
import sys
import tempfile

import numpy as np

from evaluation_csv import (AXES, CHI2_6_95, allowance_variances, main_over_runs, quantile_bins, read_evaluation,
                            read_log, self_test_verdict, stamp_key, write_synthetic_run)

USAGE = "usage: tight_directions.py LOG.csv EVALUATION.csv [LOG.csv EVALUATION.csv ...] | --self-test"


def along_directions(runs):
    """For every pair of every (log, evaluation) run: e^2 / lambda per eigen-rank (smallest
    first), the two smallest directions' e^2 and lambda summed, and the pair's rotation rate."""
    ratios, tight_e2, tight_lambda, rates = [], [], [], []
    for log_path, evaluation_path in runs:
        log = read_log(log_path)
        evaluation, allowance = read_evaluation(evaluation_path)
        a = np.diag(allowance_variances(allowance))
        for n, t in enumerate(evaluation["t_s"]):
            k = stamp_key(t)
            error = np.array([evaluation["e_" + x][n] for x in AXES])
            if k not in log or not np.all(np.isfinite(error)):
                continue
            t_prev, t_curr, xi, p = log[k]
            lam, v = np.linalg.eigh(p + a)
            along = (v.T @ error) ** 2
            ratios.append(along / lam)
            tight_e2.append(along[:2].sum())
            tight_lambda.append(lam[:2].sum())
            rates.append(np.linalg.norm(xi[3:]) / (t_curr - t_prev))
    if len(ratios) < 8:
        sys.exit("tight_directions: fewer than 8 pairs in both files")
    return np.array(ratios), np.array(tight_e2), np.array(tight_lambda), np.array(rates)


def excess(e2, lam):
    """sqrt(mean(e^2 - lambda)), 0 where the errors are inside."""
    return float(np.sqrt(max(0.0, np.mean(e2) - np.mean(lam))))


def by_rate(tight_e2, tight_lambda, rates):
    """(rate from, rate to, excess, mean e^2 / mean lambda, which pairs) per quartile of the
    rotation rate."""
    return [(lo, hi, excess(tight_e2[m], tight_lambda[m]), float(np.mean(tight_e2[m]) / np.mean(tight_lambda[m])), m)
            for lo, hi, m in quantile_bins(rates, [0, 0.25, 0.5, 0.75, 1])]


def report(runs):
    ratios, tight_e2, tight_lambda, rates = along_directions(runs)
    print(f"{len(ratios)} pairs; e^2 / lambda by eigen-direction of P + A, smallest first (1: consistent there)")
    print("  mean   " + "  ".join(f"{x:5.2f}" for x in ratios.mean(axis=0)))
    print("  median " + "  ".join(f"{x:5.2f}" for x in np.median(ratios, axis=0)))
    print(f"the two smallest: excess {1e3 * excess(tight_e2, tight_lambda):.2f} (mm or mrad), "
          f"mean e^2 / mean lambda {np.mean(tight_e2) / np.mean(tight_lambda):.2f}")
    nees = ratios.sum(axis=1)
    for lo, hi, ex, ratio, m in by_rate(tight_e2, tight_lambda, rates):
        print(f"  rotation {lo:.3f}-{hi:.3f} rad/s: excess {1e3 * ex:.2f}, ratio {ratio:.2f}; "
              f"pair NEES {nees[m].mean():.2f}, {100 * np.mean(nees[m] <= CHI2_6_95):.1f} % "
              "under the chi2(6) 95 % gate")


def self_test():
    """Synthetic pairs whose errors are drawn from their reported covariance: every direction
    scores 1 and there is no excess; then an error along the smallest direction added to the
    fastest quarter alone: found there, of its size, and nowhere else."""
    rng = np.random.default_rng(3)
    failures = []
    n = 4000
    q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    p = q @ np.diag(np.array([0.2, 0.5, 1.0, 2.0, 4.0, 8.0]) ** 2 * 1e-6) @ q.T  # (mm or mrad)^2 scales
    a = np.diag([0.3e-3 ** 2] * 3 + [1.5e-3 ** 2] * 3)  # written out, not from the code under test
    lam, v = np.linalg.eigh(p + a)
    rates = rng.uniform(0.05, 1.0, n)
    t = 1000 + np.arange(n + 1) / 30
    extra = 2e-3  # along the smallest direction, the fastest quarter only
    for added in (0.0, extra):
        errors = rng.multivariate_normal(np.zeros(6), p + a, n)
        fast = rates > np.quantile(rates, 0.75)
        errors[fast] += np.outer(rng.normal(0, added, fast.sum()), v[:, 0])
        with tempfile.TemporaryDirectory() as tmp:
            xis = np.zeros((n, 6))
            xis[:, 3] = rates / 30  # a turn about x at the pair's rate
            log_path, evaluation_path = write_synthetic_run(tmp, t, xis, [p] * n, errors)
            ratios, tight_e2, tight_lambda, r = along_directions([(log_path, evaluation_path)])
        quartiles = by_rate(tight_e2, tight_lambda, r)
        if added == 0:
            if not np.all(np.abs(ratios.mean(axis=0) - 1) < 0.08):
                failures.append(f"consistent errors: e^2/lambda {ratios.mean(axis=0)}, expected 1 each")
            if not np.all([0.85 < ratio < 1.15 for _, _, _, ratio, _ in quartiles]):
                failures.append(f"consistent errors: quartile ratios {[x[3] for x in quartiles]}, expected 1")
        else:
            lo, hi, found, _, _ = quartiles[3]
            if not abs(found - extra) < 0.15 * extra:
                failures.append(f"fastest quarter's excess {found:.2e}, added {extra:.2e}")
            if not abs(lo - np.quantile(rates, 0.75)) < 1e-3:
                failures.append(f"fastest quarter from {lo:.3f} rad/s, expected {np.quantile(rates, 0.75):.3f}")
            for _, _, other, _, _ in quartiles[:3]:
                if not other < 0.35 * extra:
                    failures.append(f"a slower quarter's excess {other:.2e}, nothing added there")
    self_test_verdict(failures)


def main(args):
    main_over_runs(args, 2, self_test, report, USAGE)


if __name__ == "__main__":
    main(sys.argv[1:])
