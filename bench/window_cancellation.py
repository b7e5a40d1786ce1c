#!/usr/bin/python3
"""How much of the pairs' error reaches a 1-s window: where consecutive pairs' errors cancel.

    bench/window_cancellation.py LOG.csv EVALUATION.csv [LOG EVALUATION ...] [--window S] [--scale A[,A...]]
    bench/window_cancellation.py --self-test

A window's covariance, as an evaluator or a consumer builds it from the log, is the sum of its
pairs' covariances: it assumes their errors independent. Per axis and window, the share
    (sum of the pairs' errors)^2 / (sum of their squares)
is 1 on average for independent errors and about 1/N over N pairs for errors that telescope (a
frame's error entering one pair with + and the next with -, as any per-frame error does). With
every pair's covariance consistent (e^2 / var = 1 per axis), a window's e^2 / var comes to
about this share, whatever the covariance: what the windows can score given what the pairs
score. Also the errors' autocorrelation at lags 1-3 per axis.

--scale A[,A...]: what the pairs and the windows would score with every logged covariance
multiplied by A (the allowance the evaluation states added once to a pair and once to a window,
the windows first order as above): the trade between the two that no one factor escapes.
"""
import sys
import tempfile

import numpy as np

from evaluation_csv import (AXES, CHI2_6_95, allowance_variances, main_over_runs, read_evaluation, read_pairs,
                            self_test_verdict, summed_over, windows, write_synthetic_run)

USAGE = ("usage: window_cancellation.py LOG.csv EVALUATION.csv [LOG EVALUATION ...] [--window S] [--scale A[,A...]]"
         " | --self-test")
LAGS = (1, 2, 3)


def shares(runs, window_s):
    """Per axis: the windows' mean share, their count, and the errors' autocorrelation at LAGS."""
    ratios, lagged = [], []
    for log_path, evaluation_path in runs:
        t_prev, t_curr, _, _, error = read_pairs(log_path, evaluation_path)
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


def nees(errors, covariances):
    """e^T C^-1 e for each row of errors and its covariance."""
    return np.einsum("ni,ni->n", errors, np.linalg.solve(covariances, errors[:, :, None])[:, :, 0])


def scaled_scores(runs, scales, window_s):
    """Per scale A: the pairs' mean NEES and share under the gate, then the windows', with every
    logged covariance times A and the stated allowance added once to each."""
    pairs, spans_nees = {a: [] for a in scales}, {a: [] for a in scales}
    for log_path, evaluation_path in runs:
        t_prev, t_curr, _, covariance, error = read_pairs(log_path, evaluation_path)
        allowance = np.diag(allowance_variances(read_evaluation(evaluation_path)[1]))
        spans = windows(t_prev, t_curr, window_s)
        window_error, window_covariance = summed_over(error, spans), summed_over(covariance, spans)
        for a in scales:
            pairs[a].append(nees(error, a * covariance + allowance))
            spans_nees[a].append(nees(window_error, a * window_covariance + allowance))
    out = []
    for a in scales:
        p, w = np.concatenate(pairs[a]), np.concatenate(spans_nees[a])
        out.append((a, p.mean(), np.mean(p <= CHI2_6_95), w.mean(), np.mean(w <= CHI2_6_95)))
    return out


def report(runs, window_s=1.0, scales=()):
    share, count, autocorrelation = shares(runs, window_s)
    print(f"{count} windows of {window_s:g} s over {len(runs)} run(s); (sum e)^2 / sum e^2 per axis, "
          "1 for independent pairs:")
    print("  " + "  ".join(f"{a} {s:.2f}" for a, s in zip(AXES, share)) + f"   mean {share.mean():.2f}")
    for lag, row in zip(LAGS, autocorrelation):
        print(f"  lag {lag} autocorrelation: " + "  ".join(f"{a} {r:+.2f}" for a, r in zip(AXES, row)))
    if scales:
        print(f"every covariance times A: pair NEES mean, share under the gate; {window_s:g}-s windows' the same")
        for a, pair_mean, pair_under, window_mean, window_under in scaled_scores(runs, scales, window_s):
            print(f"  A {a:g}: pairs {pair_mean:.2f}, {100 * pair_under:.1f} %; windows {window_mean:.2f}, "
                  f"{100 * window_under:.1f} %")


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
        # Independent errors of the logged covariance S = 1e-6 I: scaled by A, with the file's
        # allowance a (0.3 mm, 1.5 mrad) once, a pair scores sum S / (A S + a) on average and a
        # window of 30 pairs sum 30 S / (30 A S + a).
        run = write_synthetic_run(d, t, xis, covariances, independent)
        a = allowance_variances((0.0003, 0.0015))
        for scale, pair_mean, _, window_mean, _ in scaled_scores([run], (1.0, 0.5), 1.0):
            expected_pair = float(np.sum(1e-6 / (scale * 1e-6 + a)))
            expected_window = float(np.sum(30e-6 / (scale * 30e-6 + a)))
            print(f"scale {scale:g}: pairs {pair_mean:.2f} (expected {expected_pair:.2f}), "
                  f"windows {window_mean:.2f} (expected {expected_window:.2f})")
            if abs(pair_mean / expected_pair - 1) > 0.05 or abs(window_mean / expected_window - 1) > 0.1:
                failures.append(f"scale {scale:g}: pairs {pair_mean:.2f}, windows {window_mean:.2f}; expected "
                                f"{expected_pair:.2f} and {expected_window:.2f}")
    self_test_verdict(failures)


def take_option(args, flag):
    """args without FLAG VALUE, and VALUE's text (None without the flag)."""
    if flag not in args:
        return args, None
    i = args.index(flag)
    if i + 1 >= len(args):
        sys.exit(USAGE)
    return args[:i] + args[i + 2:], args[i + 1]


def positive_numbers(flag, text):
    """The comma-separated numbers of an option, each above 0, else an error naming it."""
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        sys.exit(f"{flag} {text}: not a number\n{USAGE}")
    if not all(v > 0 for v in values):
        sys.exit(f"{flag} {text}: must be above 0\n{USAGE}")
    return values


def main(args):
    args, window_text = take_option(args, "--window")
    args, scale_text = take_option(args, "--scale")
    window_s = 1.0
    if window_text is not None:
        window_s = positive_numbers("--window", window_text)
        if len(window_s) != 1:
            sys.exit(f"--window {window_text}: one number of seconds\n{USAGE}")
        window_s = window_s[0]
    scales = positive_numbers("--scale", scale_text) if scale_text is not None else ()
    main_over_runs(args, 2, self_test, lambda runs: report(runs, window_s, scales), USAGE)

if __name__ == "__main__":
    main(sys.argv[1:])
