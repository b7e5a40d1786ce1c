"""Reads the program's --evaluation and --log CSVs (and writes --log rows, for the scripts'
self-tests): one home for their formats, shared by the bench scripts."""
import csv
import math
import os
import re
import sys

import numpy as np

CHI2_6_95 = 12.5916  # upper 95 % bound of chi2(6): the gate a joint 6-D NEES is held to
AXES = ["tx", "ty", "tz", "rx", "ry", "rz"]  # the order of xi and of the evaluation's e_ columns


def read_evaluation(path):
    """Columns by header name (NaN for an empty field) and the stated ground-truth allowance
    (m, rad; (0, 0) when the file states none)."""
    allowance = (0.0, 0.0)
    header = None
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                m = re.search(r"allowance: ([0-9.eE+-]+) m, ([0-9.eE+-]+) rad", line)
                if m:
                    allowance = (float(m.group(1)), float(m.group(2)))
                continue
            if header is None:
                header = line.strip().split(",")
                continue
            rows.append([float(x) if x else np.nan for x in line.strip().split(",")])
    if header is None or not rows:
        sys.exit(f"{path} holds no evaluated pairs")
    data = np.array(rows)
    return {name: data[:, i] for i, name in enumerate(header)}, allowance


def allowance_variances(allowance):
    """The per-axis variances (tx ty tz rx ry rz) of a ground-truth allowance (metres, radians)."""
    return np.array([allowance[0] ** 2] * 3 + [allowance[1] ** 2] * 3)


def stamp_key(t):
    """A pair's stamp as a join key: the files write their stamps to the microsecond."""
    return round(float(t) * 1e6)


def rotation_vector(qw, qx, qy, qz):
    if qw < 0:
        qw, qx, qy, qz = -qw, -qx, -qy, -qz
    s = math.sqrt(qx * qx + qy * qy + qz * qz)
    if s < 1e-15:
        return [0.0, 0.0, 0.0]
    angle = 2 * math.atan2(s, qw)
    return [angle * qx / s, angle * qy / s, angle * qz / s]


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def read_log(path):
    """The --log file's solved pairs by stamp_key(t_curr): (t_prev, t_curr, xi, covariance), xi =
    (t [m], rotation vector [rad]) as the evaluation's errors are."""
    pairs = {}
    for r in read_rows(path):
        if r["status"] != "ok":
            continue
        xi = [float(r[a]) for a in ("tx", "ty", "tz")]
        xi += rotation_vector(float(r["qw"]), float(r["qx"]), float(r["qy"]), float(r["qz"]))
        cov = np.array([[float(r[f"c{i}{j}"]) for j in range(6)] for i in range(6)])
        pairs[stamp_key(r["t_curr"])] = (float(r["t_prev"]), float(r["t_curr"]), np.array(xi), cov)
    return pairs


LOG_HEADER = "t_prev,t_curr,status,inliers,tx,ty,tz,qx,qy,qz,qw," + ",".join(
    f"c{i}{j}" for i in range(6) for j in range(6))


def log_row(t_prev, t_curr, xi, covariance):
    """A solved pair as the program's --log writes it (100 inliers), from xi = (t, rotation vector)."""
    angle = float(np.linalg.norm(xi[3:]))
    axis = xi[3:] / angle if angle > 0 else np.zeros(3)
    q = list(axis * math.sin(angle / 2)) + [math.cos(angle / 2)]  # qx, qy, qz, qw
    return (f"{t_prev:.6f},{t_curr:.6f},ok,100," + ",".join(f"{x:.12g}" for x in list(xi[:3]) + q) + "," +
            ",".join(f"{x:.12g}" for x in np.ravel(covariance)))


def write_synthetic_run(directory, t, xis, covariances, errors, reported_nees=None):
    """A synthetic run's --log and --evaluation files in directory, for the scripts' self-tests:
    pair k spans t[k] .. t[k + 1] with motion xis[k], covariance covariances[k] and error
    errors[k]; the evaluation states the usual allowance (0.3 mm, 1.5 mrad) and, given
    reported_nees, a nees column (window_nees left empty). Returns the two paths."""
    log_path, evaluation_path = os.path.join(directory, "log.csv"), os.path.join(directory, "evaluation.csv")
    with open(log_path, "w") as log, open(evaluation_path, "w") as ev:
        log.write(LOG_HEADER + "\n")
        ev.write("# synthetic\n# ground-truth allowance: 0.0003 m, 0.0015 rad (given)\n")
        ev.write("t_s," + ",".join("e_" + x for x in AXES) + (",nees,window_nees" if reported_nees is not None else "") + "\n")
        for k in range(len(errors)):
            log.write(log_row(t[k], t[k + 1], xis[k], covariances[k]) + "\n")
            nees = f",{reported_nees[k]:.12g}," if reported_nees is not None else ""
            ev.write(f"{t[k + 1]:.6f}," + ",".join(f"{x:.12g}" for x in errors[k]) + nees + "\n")
    return log_path, evaluation_path


def read_pairs(log_path, evaluation_path):
    """Pairs in both files with a finite error, in time order: t_prev, t_curr, xi, covariance
    (n x 6 x 6, as logged, no allowance), error."""
    log = read_log(log_path)
    evaluation, _ = read_evaluation(evaluation_path)
    rows = []
    for n, t in enumerate(evaluation["t_s"]):
        k = stamp_key(t)
        error = np.array([evaluation["e_" + a][n] for a in AXES])
        if k in log and np.all(np.isfinite(error)):
            t_prev, t_curr, xi, covariance = log[k]
            rows.append((t_prev, t_curr, xi, covariance, error))
    if len(rows) < 3:
        sys.exit(f"fewer than 3 pairs in both {log_path} and {evaluation_path}")
    rows.sort(key=lambda r: r[1])
    return tuple(np.array([r[i] for r in rows]) for i in range(5))


def windows(t_prev, t_curr, window_s):
    """(first, last) pair of each window: consecutive pairs (each starting where the one before
    ended) spanning window_s, to within half a pair."""
    out = []
    n = len(t_curr)
    for i in range(n):
        j = i
        while j + 1 < n and abs(t_prev[j + 1] - t_curr[j]) < 1e-6 and t_curr[j + 1] - t_prev[i] <= window_s + 0.5 * (
                t_curr[j + 1] - t_prev[j + 1]):
            j += 1
        if t_curr[j] - t_prev[i] >= window_s - 0.5 * (t_curr[j] - t_prev[j]) and j > i:
            out.append((i, j))
    return out


def summed_over(errors, spans):
    """Each window's errors summed (first order: small rotations per window), from windows()."""
    return np.array([errors[i:j + 1].sum(axis=0) for i, j in spans]) if spans else np.zeros((0, errors.shape[1]))


def log_evaluation_and_option(args, flag, usage):
    """A bench script's command line, LOG.csv EVALUATION.csv [FLAG VALUE]: the two paths and
    VALUE's text (None without the flag); anything else exits with the usage."""
    option = None
    if len(args) == 4 and args[2] == flag:
        option = args[3]
        args = args[:2]
    if len(args) != 2:
        sys.exit(usage)
    return args[0], args[1], option


def quantile_bins(values, quantiles):
    """(from, to, which) per bin between consecutive quantiles of values, the last bin closed."""
    edges = np.quantile(values, quantiles)
    for i in range(len(edges) - 1):
        upper = (values <= edges[i + 1]) if i == len(edges) - 2 else (values < edges[i + 1])
        yield edges[i], edges[i + 1], (values >= edges[i]) & upper


def self_test_verdict(failures):
    """A self-test's end: its failures printed and exit 1, or the line its ctest looks for."""
    if failures:
        print("\n".join(failures))
        sys.exit(1)
    print("self-test passed")


def main_over_runs(args, files_per_run, self_test, report, usage):
    """A bench script's command line: --self-test, or runs of files_per_run paths each, pooled
    into report([(path, ...), ...]); anything else exits with the usage."""
    if args == ["--self-test"]:
        self_test()
        return
    if len(args) < files_per_run or len(args) % files_per_run:
        sys.exit(usage)
    report([tuple(args[i:i + files_per_run]) for i in range(0, len(args), files_per_run)])

