#!/usr/bin/python3
"""Does the reported covariance follow motion blur? Compares two runs' --evaluation files: the
sequence as recorded and the same frames blurred by bench/blur_frames.py.

    bench/blur_check.py SHARP_EVALUATION.csv BLURRED_EVALUATION.csv [LOW,HIGH MIN_BELOW_GATE_%]

Prints, for both runs, the pairs evaluated, the error's rms and the median reported sigma per
axis, and the joint NEES per pair (mean, % below the chi2(6) 95 % gate). Comparing the two
runs alone says little: blur costs inliers, so even the paper's model reports more after it.
What matters is whether the blurred run's covariance is still the size of its error. Given
bounds, the blurred run's mean pair NEES must lie in [LOW, HIGH] with at least MIN_BELOW_GATE_%
of its pairs below the gate; exit status 1 otherwise.
"""
import sys

import numpy as np

from evaluation_csv import AXES, CHI2_6_95, read_evaluation


def summary(path):
    d, _ = read_evaluation(path)
    error_rms = [np.sqrt(np.nanmean(d["e_" + a] ** 2)) for a in AXES]
    sigma_median = [np.nanmedian(d["sd_" + a]) for a in AXES]
    nees = d["nees"][np.isfinite(d["nees"])]
    return {"pairs": len(nees), "error_rms": error_rms, "sigma_median": sigma_median,
            "nees_mean": float(np.mean(nees)), "below_gate": float(np.mean(nees < CHI2_6_95) * 100)}


def axes_text(values):
    # metres and radians to mm and mrad
    return " ".join(f"{v * 1000:6.2f}" for v in values)


def main():
    if len(sys.argv) not in (3, 5):
        sys.exit(__doc__)
    sharp, blurred = summary(sys.argv[1]), summary(sys.argv[2])
    print("run      pairs | error rms, mm and mrad [tx ty tz rx ry rz]  | median sigma, mm and mrad"
          "               | NEES mean, % below gate")
    for name, s in (("sharp", sharp), ("blurred", blurred)):
        print(f"{name:8s} {s['pairs']:5d} | {axes_text(s['error_rms'])} | {axes_text(s['sigma_median'])} | "
              f"{s['nees_mean']:.2f}, {s['below_gate']:.1f}")
    if len(sys.argv) == 5:
        low, high = (float(x) for x in sys.argv[3].split(","))
        min_below = float(sys.argv[4])
        verdict = (f"blurred: NEES mean {blurred['nees_mean']:.2f} (asked {low:g} to {high:g}), "
                   f"{blurred['below_gate']:.1f} % below the gate (asked >= {min_below:g})")
        if not (low <= blurred["nees_mean"] <= high and blurred["below_gate"] >= min_below):
            print("the covariance does not hold under blur: " + verdict)
            sys.exit(1)
        print("the covariance holds under blur: " + verdict)


if __name__ == "__main__":
    main()
