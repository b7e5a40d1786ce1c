"""Reads the program's --evaluation and --log CSVs (and writes --log rows, for the scripts'
self-tests): one home for their formats, shared by the bench scripts."""
import csv
import math
import re
import sys

import numpy as np

CHI2_6_95 = 12.5916  # upper 95 % bound of chi2(6): the gate a joint 6-D NEES is held to


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
