#!/usr/bin/python3
"""How old each depth image is at the instant of the colour image it is paired with, read from
the images themselves.

    bench/depth_lag_edges.py TUM_DIR [--camera FX,FY,CX,CY[,K1,K2,P1,P2,K3]] [--every N]
    bench/depth_lag_edges.py --self-test TUM_DIR [--camera ...]

Where the depth steps (an occlusion edge) the colour image has an edge too. On a moving camera
the two lie apart by the image motion between the instants the two images were taken. Each
frame's depth edges (the nearer side of every step of over 8 %) are slid over the colour
image's gradient to the shift where they land on the strongest gradient. Across frames the
shifts are regressed on the image velocity the ground truth gives at those edges (the camera's
velocity and turn rate at the colour stamp, each edge pixel's own depth, through the lens
model). The slope is the depth image's age at the colour's instant: the offset of the two
stamps plus whatever lag the stamps do not show. The intercepts are a static misregistration
of the depth against the colour, in pixels. The colour is paired with the depth as the program
pairs it: the depth frame of the nearest stamp.

The camera defaults to TUM fr1's colour calibration (deploy/config/tum-fr1.yaml), or to
TUM_DIR/camera.txt (fx fy cx cy, as ICL-NUIM ships it) where there is one.

--self-test takes a recording whose depth is taken with its colour (ICL-NUIM's rendering) and
a copy of it whose depth stamps are one depth period later, so that every colour frame pairs
with the depth frame before. As recorded the age must read within 2 ms of none; in the copy it
must grow by 90-110 % of the interval between the two paired depth frames. The edges' shifts
are regressed on image velocities that differ along an edge, which pulls the slope in: on
ICL-NUIM's bundled frames the copy reads 30.3 of 33.3 ms, on its 100 frames with the depth made
30 ms late (bench/degrade_depth.py) 32.1 of 33.3.
"""
import argparse
import os
import sys
import tempfile

import numpy as np
from PIL import Image
from scipy import ndimage

from tum_groundtruth import UNITS_PER_M, camera_rates, read_groundtruth, read_index

TUM_FR1 = (517.306408, 516.469215, 318.643040, 255.313989, 0.262383, -0.953104, -0.005358, 0.002628, 1.163314)
EDGE_RELATIVE_STEP = 0.08   # a step between neighbours of over 8 % of the nearer depth
SEARCH_PX = 16              # the depth edges are searched for within ±16 px of the colour's
MIN_EDGE_PIXELS = 200
RATE_HALF_SPAN_S = 0.02     # the ground truth's rates over ±20 ms (two 100 Hz samples each side)
GRADIENT_SMOOTHING_PX = 0.7
HUBER_K = 1.5               # residuals beyond 1.5 sigma weigh less (Huber's usual constant)
HUBER_ITERATIONS = 30


class Lens:
    """OpenCV's pinhole + radial/tangential model (k1, k2, p1, p2, k3)."""

    def __init__(self, camera):
        self.fx, self.fy, self.cx, self.cy = camera[:4]
        self.k1, self.k2, self.p1, self.p2, self.k3 = (list(camera[4:]) + [0.0] * 5)[:5]

    def distort(self, x, y):
        r2 = x * x + y * y
        radial = 1 + self.k1 * r2 + self.k2 * r2 ** 2 + self.k3 * r2 ** 3
        xd = x * radial + 2 * self.p1 * x * y + self.p2 * (r2 + 2 * x * x)
        yd = y * radial + self.p1 * (r2 + 2 * y * y) + 2 * self.p2 * x * y
        return xd * self.fx + self.cx, yd * self.fy + self.cy

    def undistort(self, u, v):
        xd, yd = (u - self.cx) / self.fx, (v - self.cy) / self.fy
        x, y = xd.copy(), yd.copy()
        for _ in range(10):   # fixed-point, as cv::undistortPoints
            r2 = x * x + y * y
            radial = 1 + self.k1 * r2 + self.k2 * r2 ** 2 + self.k3 * r2 ** 3
            x = (xd - 2 * self.p1 * x * y - self.p2 * (r2 + 2 * x * x)) / radial
            y = (yd - self.p1 * (r2 + 2 * y * y) - 2 * self.p2 * x * y) / radial
        return x, y


def occlusion_edges(z):
    """Pixels on the nearer side of a step of over EDGE_RELATIVE_STEP to a 4-neighbour."""
    edge = np.zeros(z.shape, bool)
    for axis in (0, 1):
        a = [slice(None)] * 2
        b = [slice(None)] * 2
        a[axis], b[axis] = slice(1, None), slice(None, -1)
        za, zb = z[tuple(a)], z[tuple(b)]
        step = (za > 0) & (zb > 0) & (np.abs(za - zb) > EDGE_RELATIVE_STEP * np.minimum(za, zb))
        edge[tuple(a)] |= step & (za < zb)
        edge[tuple(b)] |= step & (zb < za)
    return edge


def best_shift(gradient, rows, cols):
    """The shift (du, dv) moving the depth edges onto the strongest colour gradient: every 2 px
    over the search window, then every 0.5 px and every 0.1 px around the best so far."""
    def score(du, dv):
        return ndimage.map_coordinates(gradient, [rows + dv, cols + du], order=1, mode="nearest").mean()

    best = (0.0, 0.0)
    for step, reach in ((2.0, SEARCH_PX), (0.5, 2.0), (0.1, 0.5)):
        offsets = np.arange(-reach, reach + step / 2, step)
        best = max(((best[0] + a, best[1] + b) for a in offsets for b in offsets), key=lambda s: score(*s))
    return best


def image_velocity(lens, v, w, u_px, v_px, z):
    """Pixel velocity of static points seen at (u_px, v_px) at depth z, for a camera moving at
    v (m/s) and turning at w (rad/s) in its own frame."""
    x, y = lens.undistort(u_px, v_px)
    xdot = (-v[0] + x * v[2]) / z + x * y * w[0] - (1 + x * x) * w[1] + y * w[2]
    ydot = (-v[1] + y * v[2]) / z + (1 + y * y) * w[0] - x * y * w[1] - x * w[2]
    eps = 1e-3
    u0, v0 = lens.distort(x, y)
    u1, v1 = lens.distort(x + eps * xdot, y + eps * ydot)
    return (u1 - u0) / eps, (v1 - v0) / eps


def measure(directory, camera, every):
    """Per frame used: the shift of the depth edges onto the colour's, the mean image velocity
    at them, and the stamps' offset (colour - depth), in px, px/s and s."""
    lens = Lens(camera)
    colour = read_index(os.path.join(directory, "rgb.txt"))
    depth = read_index(os.path.join(directory, "depth.txt"))
    depth_stamps = np.array([s for s, _ in depth])
    gt = read_groundtruth(os.path.join(directory, "groundtruth.txt"))
    shifts, velocities, offsets = [], [], []
    for stamp, name in colour[::every]:
        if not gt[0, 0] + RATE_HALF_SPAN_S <= stamp <= gt[-1, 0] - RATE_HALF_SPAN_S:
            continue
        j = int(np.argmin(np.abs(depth_stamps - stamp)))
        grey = np.asarray(Image.open(os.path.join(directory, name)).convert("L"), float)
        grey = ndimage.gaussian_filter(grey, GRADIENT_SMOOTHING_PX)
        gradient = np.hypot(ndimage.sobel(grey, 1), ndimage.sobel(grey, 0))
        z = np.asarray(Image.open(os.path.join(directory, depth[j][1])), float) / UNITS_PER_M
        rows, cols = np.nonzero(occlusion_edges(z))
        if len(rows) < MIN_EDGE_PIXELS:
            continue
        v, w = camera_rates(gt, stamp, RATE_HALF_SPAN_S)
        du, dv = image_velocity(lens, v, w, cols.astype(float), rows.astype(float), z[rows, cols])
        shifts.append(best_shift(gradient, rows.astype(float), cols.astype(float)))
        velocities.append((du.mean(), dv.mean()))
        offsets.append(stamp - depth_stamps[j])
    return np.array(shifts), np.array(velocities), np.array(offsets)


def fit_age(shifts, velocities):
    """shift = age x image velocity + static offset, both image axes at once, by Huber's
    weights (a frame whose edges locked onto another edge would pull a plain least-squares
    fit): the age (s), the static offsets (px), R^2 and the residual's rms (px)."""
    n = len(shifts)
    design = np.zeros((2 * n, 3))
    design[:n, 0], design[n:, 0] = velocities[:, 0], velocities[:, 1]
    design[:n, 1], design[n:, 2] = 1, 1
    target = np.concatenate([shifts[:, 0], shifts[:, 1]])
    weight = np.ones(2 * n)
    for _ in range(HUBER_ITERATIONS):
        root = np.sqrt(weight)
        coef, *_ = np.linalg.lstsq(design * root[:, None], target * root, rcond=None)
        residual = target - design @ coef
        scale = HUBER_K * 1.4826 * np.median(np.abs(residual))   # 1.4826 MAD: sigma for normal errors
        weight = np.minimum(1.0, scale / np.maximum(np.abs(residual), 1e-12)) if scale > 0 else np.ones(2 * n)
    centred = target - np.concatenate([np.full(n, shifts[:, 0].mean()), np.full(n, shifts[:, 1].mean())])
    spread = (centred ** 2).sum()
    r2 = 1 - (residual ** 2).sum() / spread if spread > 0 else float("nan")  # nan: every shift the same
    return coef[0], coef[1:], r2, np.sqrt((residual ** 2).mean())


def report(label, directory, camera, every):
    shifts, velocities, offsets = measure(directory, camera, every)
    if len(shifts) < 5:
        sys.exit(f"{directory}: only {len(shifts)} frames with {MIN_EDGE_PIXELS}+ depth-edge pixels and ground truth")
    age, static, r2, rms = fit_age(shifts, velocities)
    print(f"{label}: {len(shifts)} frames, depth image {age * 1e3:.1f} ms older than the colour "
          f"(R^2 {r2:.2f}, residual {rms:.2f} px); stamps' offset {offsets.mean() * 1e3:+.1f} ms, "
          f"so {(age - offsets.mean()) * 1e3:.1f} ms the stamps do not show; "
          f"static misregistration {static[0]:+.2f}, {static[1]:+.2f} px")
    return age, offsets


def one_depth_period_later(source, out):
    """A copy of source whose depth stamps are one median depth period later."""
    depth = read_index(os.path.join(source, "depth.txt"))
    period = float(np.median(np.diff([s for s, _ in depth])))
    for name in ("rgb", "depth", "rgb.txt", "groundtruth.txt", "camera.txt"):
        if os.path.exists(os.path.join(source, name)):
            os.symlink(os.path.abspath(os.path.join(source, name)), os.path.join(out, name))
    with open(os.path.join(out, "depth.txt"), "w") as f:
        for stamp, name in depth:
            f.write(f"{stamp + period:.6f} {name}\n")
    return period


def self_test(directory, camera, every):
    age, offsets = report("as recorded", directory, camera, every)
    with tempfile.TemporaryDirectory() as out:
        period = one_depth_period_later(directory, out)
        later_age, later_offsets = report(f"depth stamps {period * 1e3:.1f} ms later", out, camera, every)
    # The pairing moved to the depth frame before: its content is older by the real interval
    # between the two, the period plus what the stamps' offset moved.
    expected = period + (later_offsets.mean() - offsets.mean())
    grew = later_age - age
    print(f"age grew {grew * 1e3:.1f} ms; the paired depth frames are {expected * 1e3:.1f} ms apart")
    if not abs(age) <= 0.002 or not 0.9 * expected <= grew <= 1.1 * expected:
        sys.exit("self-test FAILED")
    print("self-test passed")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory")
    parser.add_argument("--camera", help="fx,fy,cx,cy[,k1,k2,p1,p2,k3]")
    parser.add_argument("--every", type=int, default=1, help="use every Nth colour frame")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.camera:
        camera = tuple(float(c) for c in args.camera.split(","))
    elif os.path.exists(os.path.join(args.directory, "camera.txt")):
        rows = [l.split() for l in open(os.path.join(args.directory, "camera.txt")) if not l.startswith("#")]
        camera = tuple(float(c) for c in rows[0][:4])
    else:
        camera = TUM_FR1
    if args.self_test:
        self_test(args.directory, camera, args.every)
    else:
        report(os.path.basename(os.path.normpath(args.directory)), args.directory, camera, args.every)


if __name__ == "__main__":
    main()
