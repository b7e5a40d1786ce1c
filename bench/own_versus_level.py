#!/usr/bin/python3
"""Does a pair's own covariance, where it is wider than the reported level, carry its error?

    bench/own_versus_level.py OWN.csv REPORTED.csv EVALUATION.csv [OWN REPORTED EVALUATION ...]
    bench/own_versus_level.py --self-test

What goes out is the level of the last second's pairs (pipeline/reported_covariance.hpp), which a
pair's own covariance enters only where it is wider by covariance.smoothing_pass_ratio's margin.
OWN.csv is the --log of a run with `--set covariance.smoothing_s=0` (each pair's own goes out),
REPORTED.csv and EVALUATION.csv the --log and --evaluation of the same run as shipped: the motions
are the same (the reported covariance feeds nothing back), which is checked.

Each pair is binned by rho, the largest eigenvalue of its own covariance in the reported one's
whitened coordinates (both plus the evaluation's allowance): how much wider than what went out
the pair's own is, in its widest direction. Per bin, the NEES against each. Where the pairs'
own excess is error, the NEES against their own stays flat across the bins and the reported
one climbs; where it is noise of the estimate, the reverse.
"""
import sys
import tempfile

import numpy as np

from evaluation_csv import (AXES, CHI2_6_95, allowance_variances, main_over_runs, quantile_bins, read_evaluation,
                            read_log, self_test_verdict, stamp_key, write_synthetic_run)

USAGE = "usage: own_versus_level.py OWN.csv REPORTED.csv EVALUATION.csv [...] | --self-test"
BIN_QUANTILES = [0, 0.25, 0.5, 0.75, 0.9, 1]


def pairs(runs):
    """rho, NEES against the own covariance and against the reported one, for every pair."""
    rows = []
    for own_path, reported_path, evaluation_path in runs:
        own, reported = read_log(own_path), read_log(reported_path)
        evaluation, allowance = read_evaluation(evaluation_path)
        a = np.diag(allowance_variances(allowance))
        for n, t in enumerate(evaluation["t_s"]):
            k = stamp_key(t)
            error = np.array([evaluation["e_" + x][n] for x in AXES])
            if k not in own or k not in reported or not np.all(np.isfinite(error)):
                continue
            xi_own, p_own = own[k][2], own[k][3] + a
            xi_reported, p_reported = reported[k][2], reported[k][3] + a
            if not np.allclose(xi_own, xi_reported, rtol=0, atol=1e-9):
                sys.exit(f"own_versus_level: the runs' motions differ at {t:.6f}: not the same run")
            root_inv = np.linalg.inv(np.linalg.cholesky(p_reported))
            rho = np.linalg.eigvalsh(root_inv @ p_own @ root_inv.T).max()
            rows.append((rho, error @ np.linalg.solve(p_own, error), error @ np.linalg.solve(p_reported, error)))
    if len(rows) < 20:
        sys.exit("own_versus_level: fewer than 20 pairs in all three files")
    return np.array(rows)


def by_rho(rows):
    """(rho from, to, pairs, own NEES, own share under the gate, reported NEES, its share) per bin."""
    out = []
    for lo, hi, m in quantile_bins(rows[:, 0], BIN_QUANTILES):
        own, reported = rows[m, 1], rows[m, 2]
        out.append((lo, hi, int(m.sum()), own.mean(), np.mean(own <= CHI2_6_95), reported.mean(),
                    np.mean(reported <= CHI2_6_95)))
    return out


def report(runs):
    rows = pairs(runs)
    print(f"{len(rows)} pairs, binned by how much wider their own covariance is than the reported one "
          "(rho); NEES mean (share under the chi2(6) 95 % gate)")
    for lo, hi, n, own, own_in, rep, rep_in in by_rho(rows):
        print(f"  rho {lo:5.2f}-{hi:5.2f} ({n:4d}): against its own {own:5.2f} ({100 * own_in:3.0f} %), "
              f"against the reported {rep:5.2f} ({100 * rep_in:3.0f} %)")


def self_test():
    """Synthetic pairs whose own covariance varies 1-4x in scale about a reported level: errors
    drawn from their own give a flat NEES against it and a climbing one against the level; errors
    drawn from the level, the reverse."""
    rng = np.random.default_rng(5)
    failures = []
    n = 3000
    q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    level = q @ np.diag(np.array([0.5, 1.0, 2.0, 3.0, 5.0, 8.0]) ** 2 * 1e-6) @ q.T
    a = np.diag([0.3e-3 ** 2] * 3 + [1.5e-3 ** 2] * 3)  # written out, not from the code under test
    scale = rng.uniform(1.0, 4.0, n)
    own = [s * level for s in scale]
    t = 1000 + np.arange(n + 1) / 30
    xis = np.zeros((n, 6))
    for truth in ("own", "level"):
        errors = np.array([rng.multivariate_normal(np.zeros(6), (o if truth == "own" else level) + a) for o in own])
        with tempfile.TemporaryDirectory() as tmp:
            own_log, evaluation = write_synthetic_run(tmp, t, xis, own, errors)
            reported_log, _ = write_synthetic_run(tempfile.mkdtemp(dir=tmp), t, xis, [level] * n, errors)
            bins = by_rho(pairs([(own_log, reported_log, evaluation)]))
        own_nees = np.array([b[3] for b in bins])
        reported_nees = np.array([b[5] for b in bins])
        flat, climbing = (own_nees, reported_nees) if truth == "own" else (reported_nees, own_nees)
        if not np.all(np.abs(flat - 6) < 0.8):
            failures.append(f"errors from the {truth}: NEES against it by bin {flat}, expected 6 each")
        rising = climbing[-1] / climbing[0]
        if truth == "own" and not rising > 2.0:
            failures.append(f"errors from their own: the level's NEES rises {rising:.2f}x across the bins, "
                            "expected > 2")
        if truth == "level" and not rising < 0.6:
            failures.append(f"errors from the level: their own's NEES falls to {rising:.2f}x, expected < 0.6")
    self_test_verdict(failures)


def main(args):
    main_over_runs(args, 3, self_test, report, USAGE)


if __name__ == "__main__":
    main(sys.argv[1:])
