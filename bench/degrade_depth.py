#!/usr/bin/python3
"""Copies a TUM-layout sequence with its depth degraded by a known law: do the sensor constants
the program learns from the data come out right, and does the covariance still hold?

    bench/degrade_depth.py SOURCE_DIR OUT_DIR [--noise C] [--depth-lag S] [--seed N]

--noise C      each depth Z (metres) gets a draw of N(0, (C Z^2)^2), rounded back to the file's
               units (5000 per metre): the law the program's depth noise coefficient estimates.
--depth-lag S  the depth index's stamps moved S seconds later than the images were taken, so
               the depth lags its stamps (and the colour) by S: the lag the program learns.

Colour images, ground truth and camera.txt are linked or copied unchanged.
"""
import argparse
import os

import numpy as np
from PIL import Image

from tum_groundtruth import UNITS_PER_M


def link_or_copy(src, dst):
    if os.path.exists(src) and not os.path.exists(dst):
        os.symlink(os.path.abspath(src), dst)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source")
    parser.add_argument("out")
    parser.add_argument("--noise", type=float, default=0.0)
    parser.add_argument("--depth-lag", type=float, default=0.0)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    os.makedirs(os.path.join(args.out, "depth"), exist_ok=True)
    for name in ("rgb", "rgb.txt", "groundtruth.txt", "camera.txt"):
        link_or_copy(os.path.join(args.source, name), os.path.join(args.out, name))
    rng = np.random.default_rng(args.seed)
    with open(os.path.join(args.source, "depth.txt")) as index, \
         open(os.path.join(args.out, "depth.txt"), "w") as out_index:
        for line in index:
            fields = line.split()
            if not fields or line.startswith("#"):
                out_index.write(line)
                continue
            stamp, path = float(fields[0]), fields[1]
            out_index.write(f"{stamp + args.depth_lag:.6f} {path}\n")
            raw = np.asarray(Image.open(os.path.join(args.source, path)), dtype=np.float64)
            if args.noise > 0:
                z = raw / UNITS_PER_M
                noisy = z + args.noise * z * z * rng.standard_normal(z.shape)
                raw = np.where(raw > 0, np.clip(np.round(noisy * UNITS_PER_M), 1, 65535), 0)
            Image.fromarray(raw.astype(np.uint16)).save(os.path.join(args.out, path))
    print(f"{args.out}: depth noise {args.noise} Z^2, depth {args.depth_lag * 1e3:.1f} ms behind its stamps")


if __name__ == "__main__":
    main()
