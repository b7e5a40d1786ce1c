#!/usr/bin/python3
"""How much of the pairs' error reaches a 1-s window: where consecutive pairs' errors cancel.

    bench/window_cancellation.py LOG.csv EVALUATION.csv [LOG EVALUATION ...] [--window S]
    bench/window_cancellation.py --self-test

A window's covariance, as an evaluator or a consumer builds it from the log, is the sum of its
pairs' covariances: it assumes their errors independent. Per axis and window, the share
    (sum of the pairs' errors)^2 / (sum of their squares)
is 1 on average for independent errors and about 1/N over N pairs for errors that telescope (a
frame's error entering one pair with + and the next with -, as any per-frame error does). With
every pair's covariance consistent (e^2 / var = 1 per axis), a window's e^2 / var comes to
about this share, whatever the covariance: what the windows can score given what the pairs
score. Also the errors' autocorrelation at lags 1-3 per axis.
"""
import sys
import tempfile

import numpy as np

from evaluation_csv import AXES, main_over_runs, read_pairs, self_test_verdict, summed_over, windows, write_synthetic_run

USAGE = "usage: window_cancellation.py LOG.csv EVALUATION.csv [LOG EVALUATION ...] [--window S] | --self-test"
LAGS = (1, 2, 3)


def shares(runs, window_s):
    """Per axis: the windows' mean share, their count, and the errors' autocorrelation at LAGS."""
    ratios, lagged = [], []
    for log_path, evaluation_path in runs:
        t_prev, t_curr, _, error = read_pairs(log_path, evaluation_path)
        spans = windows(t_prev, t_curr, window_s)
        summed = summed_over(error, spans)
        ratios.append(summed ** 2 / summed_over(error ** 2, spans))
        centred = error - error.mean(axis=0)
        lagged.append(np.array([(centred[lag:] * centred[:-lag]).sum(axis=0) / (centred ** 2).sum(axis=0)
                                for lag in LAGS]))
    ratios = np.vstack(ratios)
    if len(ratios) == 0:
        sys.exit(f"no {window_s:g}-s window of consecutive solved pairs in the runs given")
    return ratios.mean(axis=0), len(ratios), np.mean(lagged, axis=0)


def report(runs, window_s=1.0):
    share, count, autocorrelation = shares(runs, window_s)
    print(f"{count} windows of {window_s:g} s over {len(runs)} run(s); (sum e)^2 / sum e^2 per axis, "
          "1 for independent pairs:")
    print("  " + "  ".join(f"{a} {s:.2f}" for a, s in zip(AXES, share)) + f"   mean {share.mean():.2f}")
    for lag, row in zip(LAGS, autocorrelation):
        print(f"  lag {lag} autocorrelation: " + "  ".join(f"{a} {r:+.2f}" for a, r in zip(AXES, row)))


def self_test():
    rng = np.random.default_rng(5)
    n = 3000
    t = np.arange(n + 1) / 30.0
    xis, covariances = np.zeros((n, 6)), [np.eye(6) * 1e-6] * n
    independent = rng.normal(size=(n, 6)) * 1e-3
    frame = rng.normal(size=(n + 1, 6)) * 1e-3
    telescoping = frame[1:] - frame[:-1]  # each frame's error: + in one pair, - in the next
    failures = []
    with tempfile.TemporaryDirectory() as d:
        for name, errors, low, high in (("independent", independent, 0.85, 1.15),
                                        ("telescoping", telescoping, 0.02, 0.06),
                                        ("half and half", independent + telescoping / np.sqrt(2), 0.42, 0.62)):
            share, count, autocorrelation = shares([write_synthetic_run(d, t, xis, covariances, errors)], 1.0)
            print(f"{name}: {count} windows, share {share.mean():.3f}, lag 1 {autocorrelation[0].mean():+.2f}")
            if not low <= share.mean() <= high:
                failures.append(f"{name}: share {share.mean():.3f} outside [{low}, {high}]")
        # A telescoping error's lag-1 autocorrelation is -0.5; half of the variance telescoping, -0.25.
        if not -0.35 <= autocorrelation[0].mean() <= -0.15:
            failures.append(f"half and half: lag-1 autocorrelation {autocorrelation[0].mean():+.2f}, expected about -0.25")
    self_test_verdict(failures)


def main(args):
    window_s = 1.0
    if "--window" in args:
        i = args.index("--window")
        if i + 1 >= len(args):
            sys.exit(USAGE)
        try:
            window_s = float(args[i + 1])
        except ValueError:
            sys.exit(f"--window {args[i + 1]}: not a number of seconds\n{USAGE}")
        if not window_s > 0:
            sys.exit(f"--window {args[i + 1]}: must be above 0 s\n{USAGE}")
        args = args[:i] + args[i + 2:]
    main_over_runs(args, 2, self_test, lambda runs: report(runs, window_s), USAGE)


if __name__ == "__main__":
    main(sys.argv[1:])
