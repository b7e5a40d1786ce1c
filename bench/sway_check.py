#!/usr/bin/python3
"""A drone swaying over one view: does the reported pose come back where it started?

    bench/sway_check.py SOURCE_DIR --exe build/release/rgbd-odometry [--config CFG] \
        [--first A] [--last B] [--cycles 10] [--depth-noise 1.425e-3] [--colour-noise 2] \
        [--still N] [--seed 1] [--keep DIR] [--expect-within MM,DEG] [-- PROGRAM OPTIONS...]

Writes a copy of SOURCE_DIR's images A..B played forth and back CYCLES times (A..B, B-1..A: each
cycle ends on image A, where the true path is back at its start), every visit of an image with
fresh noise of a Kinect's kind (depth: N(0, (c Z^2)^2) rounded to the file's units; colour:
N(0, sigma) per channel), stamped at 30 Hz with the ground truth retimed. With --still N, image
A alone is played N times instead (a camera at rest, fresh noise each frame). Then runs the
program on it with --trajectory and prints, for each cycle's end, how far the reported pose is
from the start (translation, rotation): the drift a hovering drone would see. A frame-to-frame
odometry whose pairs there and back do not cancel walks away by the same amount every cycle.
With --expect-within, it exits 1 when the last cycle's end is further than MM millimetres or DEG
degrees from the start (or has no pose): a test's bound.

Noise-free visits (--depth-noise 0 --colour-noise 0) replay the recorded images themselves: a
synchronous sensor's recording (ICL-NUIM) is the same played backwards; a Kinect recording is not
(its colour/depth lag would reverse), so use one with fresh noise per visit instead.
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

from tum_groundtruth import UNITS_PER_M, read_groundtruth, read_index, rotation_matrix

FRAME_PERIOD_S = 1.0 / 30.0


def visit_order(first, last, cycles):
    """Image indices of the sway: first..last, last-1..first, CYCLES times (forth and back)."""
    forth = list(range(first, last + 1))
    order = [first]
    for _ in range(cycles):
        order += forth[1:] + forth[-2::-1]
    return order


def cycle_ends(first, last, cycles):
    """Positions in visit_order of each cycle's end (back on image `first`)."""
    period = 2 * (last - first)
    return [c * period for c in range(1, cycles + 1)]


def pose_distance(a, b):
    """Translation (m) and rotation (deg) between two TUM poses (tx ty tz qx qy qz qw)."""
    dt = np.linalg.norm(a[:3] - b[:3])
    r = rotation_matrix(a[3:7]).T @ rotation_matrix(b[3:7])
    angle = np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))
    return dt, angle


def noisy_depth(raw, coeff, rng):
    if coeff <= 0:
        return raw
    z = raw.astype(np.float64) / UNITS_PER_M
    noisy = z + coeff * z * z * rng.standard_normal(z.shape)
    return np.where(raw > 0, np.clip(np.round(noisy * UNITS_PER_M), 1, 65535), 0).astype(np.uint16)


def noisy_colour(rgb, sigma, rng):
    if sigma <= 0:
        return rgb
    return np.clip(np.round(rgb + sigma * rng.standard_normal(rgb.shape)), 0, 255).astype(np.uint8)


def write_sway(source, out, order, depth_noise, colour_noise, seed):
    """The swayed copy of `source` in `out`: images, index files, retimed ground truth."""
    colour, depth = read_index(os.path.join(source, "rgb.txt")), read_index(os.path.join(source, "depth.txt"))
    gt = read_groundtruth(os.path.join(source, "groundtruth.txt"))
    rng = np.random.default_rng(seed)
    noise_free = depth_noise <= 0 and colour_noise <= 0
    for sub in ("rgb", "depth"):
        os.makedirs(os.path.join(out, sub), exist_ok=True)
    with open(os.path.join(out, "rgb.txt"), "w") as rgb_txt, open(os.path.join(out, "depth.txt"), "w") as depth_txt, \
         open(os.path.join(out, "groundtruth.txt"), "w") as gt_txt:
        header = f"# {source} images {order[0]}.. swayed by bench/sway_check.py\n"
        for f in (rgb_txt, depth_txt, gt_txt):
            f.write(header)
        for k, i in enumerate(order):
            t = k * FRAME_PERIOD_S
            for (stamp, path), sub, txt in ((colour[i], "rgb", rgb_txt), (depth[i], "depth", depth_txt)):
                name = f"{sub}/{k:05d}.png"
                src, dst = os.path.join(source, path), os.path.join(out, name)
                if noise_free:
                    os.symlink(os.path.abspath(src), dst)
                elif sub == "rgb":
                    Image.fromarray(noisy_colour(np.asarray(Image.open(src).convert("RGB")), colour_noise, rng)).save(dst)
                else:
                    Image.fromarray(noisy_depth(np.asarray(Image.open(src)), depth_noise, rng)).save(dst)
                txt.write(f"{t:.6f} {name}\n")
            # The pose of the colour image's instant (its nearest ground-truth sample).
            row = gt[int(np.argmin(np.abs(gt[:, 0] - colour[i][0])))]
            gt_txt.write(f"{t:.6f} " + " ".join(f"{v:.9g}" for v in row[1:8]) + "\n")
    camera = os.path.join(source, "camera.txt")
    if os.path.exists(camera):
        with open(camera) as src, open(os.path.join(out, "camera.txt"), "w") as dst:
            dst.write(src.read())


def read_trajectory(path):
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith("#")]
    return np.array(rows, dtype=float)


def report(trajectory, ends):
    """Each cycle's end against the start, by the frames' times: [(cycle, mm, deg)]; a cycle
    whose last frame has no pose (a failed pair there) is left out."""
    start = trajectory[0, 1:8]
    out = []
    for c, at in enumerate(ends, 1):
        row = int(np.argmin(np.abs(trajectory[:, 0] - at * FRAME_PERIOD_S)))
        if abs(trajectory[row, 0] - at * FRAME_PERIOD_S) < FRAME_PERIOD_S / 2:
            mm, deg = pose_distance(start, trajectory[row, 1:8])
            out.append((c, mm * 1e3, deg))
    return out


def self_test():
    order = visit_order(3, 5, 2)
    assert order == [3, 4, 5, 4, 3, 4, 5, 4, 3], order
    assert [order[e] for e in cycle_ends(3, 5, 2)] == [3, 3]
    # A trajectory that walks 1 mm and 0.1 deg (about z) further every cycle.
    ends = cycle_ends(0, 2, 3)
    traj = np.zeros((ends[-1] + 1, 8))
    traj[:, 0] = np.arange(len(traj)) * FRAME_PERIOD_S
    traj[:, 7] = 1.0
    for c, at in enumerate(ends, 1):
        half = np.radians(0.1 * c) / 2
        traj[at, 1:8] = [1e-3 * c, 0, 0, 0, 0, np.sin(half), np.cos(half)]
    got = report(traj, ends)
    assert all(abs(mm - c) < 1e-9 and abs(deg - 0.1 * c) < 1e-6 for c, mm, deg in got), got
    rng = np.random.default_rng(1)
    depth = noisy_depth(np.full((200, 200), 10000, dtype=np.uint16), 1.425e-3, rng)  # 2 m
    spread = np.std(depth / UNITS_PER_M)
    assert abs(spread - 1.425e-3 * 4) < 3e-4, spread  # 5.7 mm at 2 m
    assert noisy_depth(np.zeros((4, 4), dtype=np.uint16), 1e-3, rng).max() == 0  # holes stay holes
    print("sway_check self-test passed")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", nargs="?")
    parser.add_argument("--exe")
    parser.add_argument("--config")
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--last", type=int, default=29)
    parser.add_argument("--cycles", type=int, default=10)
    parser.add_argument("--still", type=int, default=0, help="image FIRST alone, this many times")
    parser.add_argument("--depth-noise", type=float, default=1.425e-3)
    parser.add_argument("--colour-noise", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--keep", help="write the swayed copy here (default: a temporary directory)")
    parser.add_argument("--expect-within", metavar="MM,DEG", help="exit 1 if the last cycle's end is further")
    parser.add_argument("--self-test", action="store_true")
    parser.add_argument("program_options", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    if args.self_test:
        self_test()
        return
    if not args.source or not args.exe:
        parser.error("SOURCE_DIR and --exe are required")
    bound = None
    if args.expect_within:
        try:
            bound = tuple(float(x) for x in args.expect_within.split(","))
        except ValueError:
            bound = ()
        if len(bound) != 2:
            parser.error(f"--expect-within takes MM,DEG, not '{args.expect_within}'")
    if args.still > 0:
        order, ends = [args.first] * args.still, [args.still - 1]
    else:
        order, ends = visit_order(args.first, args.last, args.cycles), cycle_ends(args.first, args.last, args.cycles)
    with tempfile.TemporaryDirectory() as scratch:
        out = args.keep or os.path.join(scratch, "sway")
        os.makedirs(out, exist_ok=True)
        write_sway(args.source, out, order, args.depth_noise, args.colour_noise, args.seed)
        trajectory = os.path.join(out, "trajectory.txt")
        command = [args.exe, "--source", f"tum:{out}", "-q", "--trajectory", trajectory]
        if args.config:
            command += ["--config", args.config]
        command += [o for o in args.program_options if o != "--"]
        run = subprocess.run(command, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"sway_check: the program failed ({run.returncode}):\n{run.stdout}\n{run.stderr}")
        rows = report(read_trajectory(trajectory), ends)
    what = f"still on image {args.first}" if args.still > 0 else \
        f"images {args.first}-{args.last} forth and back {args.cycles} times"
    print(f"sway: {what}, {len(order)} frames; noise: depth {args.depth_noise:g} Z^2, colour {args.colour_noise:g}")
    for c, mm, deg in rows:
        print(f"  end of cycle {c:3d}: {mm:7.2f} mm {deg:6.3f} deg from the start")
    if rows:
        c, mm, deg = rows[-1]
        print(f"after {c} cycles: {mm:.2f} mm, {deg:.3f} deg from the start")
    if bound is not None:
        if not rows or rows[-1][0] != len(ends):
            sys.exit("sway_check: the last cycle's end has no pose (a failed pair there)")
        if not (rows[-1][1] <= bound[0] and rows[-1][2] <= bound[1]):
            sys.exit(f"sway_check: {rows[-1][1]:.2f} mm, {rows[-1][2]:.3f} deg from the start, "
                     f"beyond {bound[0]:g} mm, {bound[1]:g} deg")
        print(f"within {bound[0]:g} mm and {bound[1]:g} deg")


if __name__ == "__main__":
    main()
