#!/usr/bin/python3
"""Motion-blurs a TUM sequence's colour frames as a longer exposure would: how the covariance
follows blur, on real frames with real ground truth.

    bench/blur_frames.py SOURCE_DIR OUT_DIR EXPOSURE_S

Each colour frame is smeared along the image motion the ground truth gives at its stamp: the
camera's velocity and turn rate in its own frame (TUM's poses are the colour camera's optical
centre), projected at the image centre for a scene 1.5 m away (fr1's desk), times the
exposure. The smear is a line kernel centred on the frame's stamp, so blur adds no delay. The
depth images, index files and ground truth are linked or copied unchanged (the Kinect's depth
is not a camera exposure). Prints the blur lengths in pixels.

One blur per frame, the same over the whole image: it leaves out rolling shutter and the
parallax between near and far points, so it is a stress test of the covariance's response to
blur, not a model of a particular fast sequence.
"""
import os
import sys

import numpy as np
from PIL import Image

from tum_groundtruth import camera_rates, read_groundtruth, read_index

FOCAL_PX = 517.3       # fr1's colour camera
SCENE_DEPTH_M = 1.5    # what the image centre sees on fr1's desk sequences
RATE_HALF_SPAN_S = 0.02


def image_motion_px_per_s(gt, t):
    """Image velocity at the centre: -f (v_x / Z + w_y), -f (v_y / Z - w_x), camera frame."""
    v, w = camera_rates(gt, t, RATE_HALF_SPAN_S)
    return -FOCAL_PX * np.array([v[0] / SCENE_DEPTH_M + w[1], v[1] / SCENE_DEPTH_M - w[0]])


def smear(image, motion_px):
    """Mean of the image shifted along motion_px, centred: a line kernel of that length."""
    length = float(np.linalg.norm(motion_px))
    if length < 0.5:
        return image
    reach = int(np.ceil(length / 2)) + 1
    padded = np.pad(image.astype(np.float32), ((reach, reach), (reach, reach), (0, 0)), mode="edge")
    h, w = image.shape[:2]
    total = np.zeros((h, w, image.shape[2]), np.float32)
    steps = max(2, int(np.ceil(4 * length)))
    for s in np.linspace(-0.5, 0.5, steps):
        dx, dy = (int(round(c)) for c in s * motion_px)
        total += padded[reach + dy:reach + dy + h, reach + dx:reach + dx + w]
    return np.clip(total / steps + 0.5, 0, 255).astype(np.uint8)


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    source, out, exposure_s = sys.argv[1], sys.argv[2], float(sys.argv[3])
    source = os.path.abspath(source)
    os.makedirs(os.path.join(out, "rgb"), exist_ok=True)
    for name in ("rgb.txt", "depth.txt", "groundtruth.txt"):
        with open(os.path.join(source, name), "rb") as f, open(os.path.join(out, name), "wb") as g:
            g.write(f.read())
    if not os.path.exists(os.path.join(out, "depth")):
        os.symlink(os.path.join(source, "depth"), os.path.join(out, "depth"))
    gt = read_groundtruth(os.path.join(source, "groundtruth.txt"))
    lengths = []
    for stamp, name in read_index(os.path.join(source, "rgb.txt")):
        motion = image_motion_px_per_s(gt, stamp) * exposure_s
        lengths.append(np.linalg.norm(motion))
        image = np.asarray(Image.open(os.path.join(source, name)).convert("RGB"))
        Image.fromarray(smear(image, motion)).save(os.path.join(out, name))
    print(f"{len(lengths)} frames blurred over {exposure_s * 1000:g} ms: blur length median "
          f"{np.median(lengths):.1f} px, 90 % {np.percentile(lengths, 90):.1f} px, max {max(lengths):.1f} px")


if __name__ == "__main__":
    main()
