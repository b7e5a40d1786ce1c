#!/usr/bin/python3
"""The highest NEES any covariance can score against a ground truth given an allowance.

    bench/nees_ceiling.py LOG.csv EVALUATION.csv [--allowance T_M,R_RAD]
    bench/nees_ceiling.py --self-test

LOG.csv and EVALUATION.csv are one run's --log and --evaluation files. An evaluation that
allows for the ground truth's own noise adds A = diag(a_t^2, a_t^2, a_t^2, a_r^2, a_r^2, a_r^2)
to each reported covariance P before it whitens the error e: NEES = e^T (P + A)^-1 e. Whatever
P is (any P >= 0), (P + A)^-1 <= A^-1, so no covariance, consistent or over-confident, scores
more than e^T A^-1 e, the NEES of a zero covariance. Where the errors are small against the
allowance, that ceiling lies below the range a consistent covariance is judged by (6 expected),
and only a larger error could reach it.

A consistent covariance (P = S, the error's own) scores tr(S (S + A)^-1) on average: each
whitened direction adds lambda / (1 + lambda), below both 1 and its share of the ceiling. The
report gives it for one S, the errors' mean outer product.

Per pair, and over 1-s windows of consecutive pairs (their errors summed: first order, small
rotations per window). The allowance is the one the evaluation file states, or --allowance.
"""
import math
import sys
import tempfile

import numpy as np

from evaluation_csv import allowance_variances, log_evaluation_and_option, read_evaluation, read_pairs, summed_over, windows, write_synthetic_run


def ceilings(errors, allowance):
    """Mean NEES of a zero covariance (total, translation's and rotation's shares) and of one
    consistent covariance S = mean e e^T, both with the allowance added."""
    a = np.diag(allowance_variances(allowance))
    if not np.all(np.diag(a) > 0):
        sys.exit("nees_ceiling: the allowance must be above 0 in translation and rotation")
    whitened = errors ** 2 / np.diag(a)
    translation, rotation = float(np.mean(whitened[:, :3].sum(axis=1))), float(np.mean(whitened[:, 3:].sum(axis=1)))
    s = errors.T @ errors / len(errors)
    consistent = float(np.trace(np.linalg.solve(s + a, s)))
    return translation + rotation, translation, rotation, consistent


def analyse(log_path, evaluation_path, allowance=None, window_s=1.0):
    """(name, count, reported mean NEES, ceiling, translation share, rotation share, consistent)
    for the pairs and the windows; and the allowance used."""
    evaluation, stated = read_evaluation(evaluation_path)
    allowance = allowance or stated
    t_prev, t_curr, _, _, error = read_pairs(log_path, evaluation_path)
    spans = windows(t_prev, t_curr, window_s)
    summed = summed_over(error, spans)
    rows = []
    for name, errors, column in (("pairs", error, "nees"), (f"{window_s:g}-s windows", summed, "window_nees")):
        reported = evaluation.get(column)
        reported = float(np.nanmean(reported)) if reported is not None and np.any(np.isfinite(reported)) else math.nan
        if len(errors) < 3:
            rows.append((name, len(errors), reported, math.nan, math.nan, math.nan, math.nan))
            continue
        rows.append((name, len(errors), reported) + ceilings(errors, allowance))
    return rows, allowance


def report(log_path, evaluation_path, allowance):
    rows, used = analyse(log_path, evaluation_path, allowance)
    print(f"allowance {used[0] * 1e3:.2f} mm, {used[1] * 1e3:.2f} mrad per axis "
          f"({'given' if allowance else 'as the evaluation file states'})")
    print("               count   reported   ceiling (zero covariance: translation + rotation)   one consistent S")
    for name, count, reported, ceiling, translation, rotation, consistent in rows:
        print(f"{name:>14} {count:6d}   {reported:8.2f}   {ceiling:8.2f} ({translation:.2f} + {rotation:.2f})"
              f"{'':>32}{consistent:8.2f}")


def self_test():
    """Synthetic errors of a known covariance, through the --log and --evaluation formats: the
    ceilings come back as their expectations, and the allowance is read from the file's
    header as the program writes it."""
    rng = np.random.default_rng(5)
    failures = []
    n = 6000
    allowance = (0.0003, 0.0015)
    a = np.diag([0.3e-3 ** 2] * 3 + [1.5e-3 ** 2] * 3)  # written out: the expectations do not use the code under test
    # Errors of a rendered sensor's size: tenths of a millimetre, a tenth of a milliradian,
    # translation and rotation correlated as a fit's are.
    root = np.diag([1.0e-4, 2.0e-4, 0.5e-4, 1.0e-4, 0.7e-4, 0.5e-4])
    root[4, 0] = 0.5e-4
    s = root @ root.T
    errors = rng.multivariate_normal(np.zeros(6), s, n)
    t = 1000 + np.arange(n + 1) / 30
    reported = np.einsum("ij,ij->i", errors, np.linalg.solve(s + a, errors.T).T)  # a consistent P = S
    with tempfile.TemporaryDirectory() as tmp:
        log_path, evaluation_path = write_synthetic_run(tmp, t, np.zeros((n, 6)), [s] * n, errors, reported)
        rows, used = analyse(log_path, evaluation_path)
        spans = windows(t[:-1], t[1:], 1.0)
    if used != allowance:
        failures.append(f"allowance read as {used}, written {allowance}")
    pairs, windowed = rows
    expected_pair = float(np.trace(np.linalg.solve(a, s)))  # 0.59: far below 6
    expected_consistent = float(np.trace(np.linalg.solve(s + a, s)))
    length = float(np.mean([j - i + 1 for i, j in spans]))
    checks = [
        ("pairs: ceiling", pairs[3], expected_pair, 0.05),
        ("pairs: translation share", pairs[4], float(np.trace(np.linalg.solve(a[:3, :3], s[:3, :3]))), 0.05),
        ("pairs: rotation share", pairs[5], float(np.trace(np.linalg.solve(a[3:, 3:], s[3:, 3:]))), 0.05),
        ("pairs: consistent S", pairs[6], expected_consistent, 0.05),
        ("pairs: reported (consistent P)", pairs[2], expected_consistent, 0.05),
        # Independent pairs: a window of L pairs has L S; about 200 independent windows.
        ("windows: ceiling", windowed[3], length * expected_pair, 0.25),
    ]
    for name, got, expected, tolerance in checks:
        if not abs(got - expected) <= tolerance * expected:
            failures.append(f"{name}: {got:.4f}, expected {expected:.4f} within {tolerance:.0%}")
    if not pairs[2] <= pairs[3]:
        failures.append(f"a consistent covariance scored {pairs[2]:.3f}, above the ceiling {pairs[3]:.3f}")
    if failures:
        print("nees_ceiling self-test FAILED:\n  " + "\n  ".join(failures))
        return 1
    print(f"nees_ceiling self-test passed: ceiling {pairs[3]:.3f} (expected {expected_pair:.3f}), "
          f"consistent {pairs[6]:.3f} ({expected_consistent:.3f}), windows {windowed[3]:.2f} "
          f"({length * expected_pair:.2f})")
    return 0


def main():
    args = sys.argv[1:]
    if args == ["--self-test"]:
        return self_test()
    log_path, evaluation_path, text = log_evaluation_and_option(args, "--allowance", __doc__)
    allowance = None
    if text is not None:
        try:
            allowance = tuple(float(x) for x in text.split(","))
        except ValueError:
            allowance = ()
        if len(allowance) != 2:
            sys.exit(f"nees_ceiling: --allowance '{text}' must be two numbers, metres and radians")
    report(log_path, evaluation_path, allowance)
    return 0


if __name__ == "__main__":
    sys.exit(main())
