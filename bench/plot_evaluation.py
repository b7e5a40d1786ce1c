#!/usr/bin/python3
"""Plots of one run's evaluation against ground truth (rgbd-odometry --evaluation FILE).

    bench/plot_evaluation.py EVALUATION.csv OUT_PREFIX [TITLE]

writes OUT_PREFIX_errors.png (per-axis error with the reported +-1 sigma / +-3 sigma, the
ground truth's allowance included: Willis & Brink's Figure 4), OUT_PREFIX_nees.png (joint NEES
per pair and over 1-s windows against the chi2(6) bounds) and OUT_PREFIX_trajectory.png
(integrated estimate against ground truth). Debian's python3-matplotlib; nothing is computed
here that the program did not write: the figures show its numbers.
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evaluation_csv import CHI2_6_95, read_evaluation  # noqa: E402

CHI2_6_05 = 1.6354   # lower 5 % bound


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    d, (allow_t, allow_r) = read_evaluation(sys.argv[1])
    prefix = sys.argv[2]
    title = sys.argv[3] if len(sys.argv) == 4 else sys.argv[1]
    t = d["t_s"] - d["t_s"][0]

    axes = ["tx", "ty", "tz", "rx", "ry", "rz"]
    fig, grid = plt.subplots(3, 2, figsize=(12, 9), sharex=True)
    for i, a in enumerate(axes):
        ax = grid[i % 3][i // 3]
        rotation = a.startswith("r")
        unit, k = ("deg", 180 / np.pi) if rotation else ("mm", 1e3)
        allow = allow_r if rotation else allow_t
        sd = np.sqrt(d["sd_" + a] ** 2 + allow**2) * k
        e = d["e_" + a] * k
        ax.fill_between(t, -3 * sd, 3 * sd, color="tab:blue", alpha=0.15, label="±3σ")
        ax.fill_between(t, -sd, sd, color="tab:blue", alpha=0.35, label="±1σ")
        ax.plot(t, e, color="black", lw=0.8, label="error")
        inside = np.mean(np.abs(e) <= 3 * sd) * 100
        ax.set_ylabel(f"{a} error [{unit}]")
        ax.set_title(f"{a}: {inside:.1f} % within 3σ, mean e²/σ² {np.mean((e / sd) ** 2):.2f}", fontsize=9)
        if i == 0:
            ax.legend(loc="upper right", fontsize=8)
    for ax in grid[2]:
        ax.set_xlabel("time [s]")
    fig.suptitle(f"{title}: frame-to-frame error and reported σ (ground-truth allowance "
                 f"{allow_t * 1e3:.2f} mm, {np.degrees(allow_r):.3f}°)")
    fig.tight_layout()
    fig.savefig(prefix + "_errors.png", dpi=90)

    fig, ax = plt.subplots(figsize=(12, 4.5))
    ax.semilogy(t, d["nees"], ".", ms=3, color="tab:blue", label="per pair")
    w = d["window_nees"]
    ax.semilogy(t, w, "-", lw=1.2, color="tab:orange", label="1-s window ending here")
    ax.axhline(CHI2_6_95, color="red", ls="--", lw=1, label="χ²(6) 95 % / 5 %")
    ax.axhline(CHI2_6_05, color="red", ls="--", lw=1)
    ax.axhline(6, color="gray", lw=0.8)
    pair_in = np.mean(d["nees"] < CHI2_6_95) * 100
    win = w[~np.isnan(w)]
    win_text = f", windows mean {win.mean():.2f}, {np.mean(win < CHI2_6_95) * 100:.1f} % below" if win.size else ""
    ax.set_title(f"{title}: joint 6-D NEES — pairs mean {np.mean(d['nees']):.2f}, {pair_in:.1f} % below the gate"
                 + win_text, fontsize=10)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("NEES")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(prefix + "_nees.png", dpi=90)

    fig, (top, side) = plt.subplots(1, 2, figsize=(12, 5))
    for ax, (i, j) in ((top, ("x", "z")), (side, ("x", "y"))):
        ax.plot(d["gt_" + i], d["gt_" + j], color="black", lw=1.5, label="ground truth")
        ax.plot(d[i], d[j], color="tab:orange", lw=1.0, label="odometry (integrated)")
        ax.set_xlabel(f"{i} [m]")
        ax.set_ylabel(f"{j} [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    top.set_title("camera frame of the first image: x right, z forward")
    side.set_title("x right, y down")
    top.legend(fontsize=8)
    fig.suptitle(f"{title}: trajectory")
    fig.tight_layout()
    fig.savefig(prefix + "_trajectory.png", dpi=90)


if __name__ == "__main__":
    main()
