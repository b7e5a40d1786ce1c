"""Reads the program's --evaluation CSV: one home for its format, shared by the bench scripts."""
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
