#!/usr/bin/python3
"""How much one loop closure can remove of an odometry's drift, by kind of drift (Monte Carlo, no SLAM involved).

    /usr/bin/python3 scripts/loop_closure_bound.py [--trials 300] [--frames 360] [--seed 1]

A camera goes once round an ellipse (2.2 x 1.7 m, the synthetic sequence's) and comes back to its start. Its
odometry drifts either as a random walk of the position (independent errors per frame) or as a random walk of the
heading, which the motion then integrates into position (visual odometry's usual drift). One loop closure is
modelled as what a pose graph does with evenly weighted odometry: the error at the loop's end is known and spread
linearly over the lap (first the heading, then the position). Printed: the ratio ATE RMSE after / before the
closure (both after the best rigid alignment, as the ATE is), its median and 10th / 90th percentiles.

What it shows (docs/mapping.md): the part of a random-walk drift between the loop's ends is a bridge that the loop
cannot observe, so the ratio depends on the kind of drift and varies widely between runs of one kind; it does not
depend on the drift's size, which is why it is a statement about single-loop sequences, not about our estimator.
"""
import argparse

import numpy as np


def ate(truth, estimate):
    """RMSE of the positions after the rigid (rotation + translation) alignment that minimises it (Umeyama)."""
    mean_t, mean_e = truth.mean(0), estimate.mean(0)
    u, _, vt = np.linalg.svd((estimate - mean_e).T @ (truth - mean_t))
    d = np.eye(3)
    if np.linalg.det(vt.T @ u.T) < 0:
        d[2, 2] = -1
    rotation = vt.T @ d @ u.T
    aligned = (rotation @ (estimate - mean_e).T).T + mean_t
    return float(np.sqrt(((aligned - truth) ** 2).sum(1).mean()))


def rotate_steps(steps, yaw):
    c, s = np.cos(yaw), np.sin(yaw)
    return np.c_[c * steps[:, 0] - s * steps[:, 1], s * steps[:, 0] + c * steps[:, 1], steps[:, 2]]


def ratios(kind, truth, trials, rng):
    frames = len(truth)
    ramp = np.linspace(0.0, 1.0, frames)
    steps = np.diff(truth, axis=0, prepend=truth[:1])
    out = []
    for _ in range(trials):
        if kind == "position":
            drift = np.cumsum(rng.normal(0.0, 1e-3, (frames, 3)), 0)
            drifted = truth + drift
            closed = drifted - ramp[:, None] * drift[-1]
        else:
            yaw = np.cumsum(rng.normal(0.0, 2e-4, frames))
            drifted = truth[0] + np.cumsum(rotate_steps(steps, yaw), 0)
            corrected = truth[0] + np.cumsum(rotate_steps(steps, yaw - ramp * yaw[-1]), 0)
            closed = corrected - ramp[:, None] * (corrected[-1] - truth[-1])
        out.append(ate(truth, closed) / ate(truth, drifted))
    return np.array(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=300)
    parser.add_argument("--frames", type=int, default=360)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if args.trials < 1 or args.frames < 3:
        parser.error("--trials must be >= 1 and --frames >= 3")
    rng = np.random.default_rng(args.seed)
    angle = np.linspace(0.0, 2.0 * np.pi, args.frames)
    truth = np.c_[2.2 * np.cos(angle), 1.7 * np.sin(angle), np.zeros(args.frames)]
    for kind, name in (("position", "position random walk"), ("heading", "heading random walk")):
        r = ratios(kind, truth, args.trials, rng)
        p10, p90 = np.percentile(r, [10, 90])
        print(f"{name}: ATE after / before one loop closure, median {np.median(r):.2f} "
              f"(10th-90th percentile {p10:.2f}-{p90:.2f}; {args.trials} trials)")


if __name__ == "__main__":
    main()
