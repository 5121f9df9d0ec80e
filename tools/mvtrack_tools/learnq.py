"""Learns mvtrackd's --q (white-noise acceleration density per axis, m^2/s^3) from ground truth.

For the constant-velocity model with white acceleration of density q, the second difference of
positions sampled every dt has variance 2/3 q dt^3 per axis (evaluate.q_from_second_differences). Each person's
track in the log's GROUND_TRUTH messages gives second differences over consecutive frames; they
are pooled over people. Prints the value to pass as `mvtrackd --q X,Y,Z`.

    tools/mvtrack learn-q LOG.lcm [--frame-rate 25]
"""
from __future__ import annotations

import argparse
import sys

import numpy as np

from .evaluate import q_from_second_differences
from .lcmio import read_log


def second_differences(gt: dict, period_us: float) -> np.ndarray:
    """Second differences of each person's positions over frames exactly one period apart."""
    per: dict[int, list[tuple[int, np.ndarray]]] = {}
    for u in sorted(gt):
        ids, pos = gt[u]
        for i, p in zip(ids, np.asarray(pos, float).reshape(-1, 3)):
            per.setdefault(int(i), []).append((u, p))
    out = []
    for seq in per.values():
        for (u0, p0), (u1, p1), (u2, p2) in zip(seq, seq[1:], seq[2:]):
            if abs((u1 - u0) - period_us) < 0.25 * period_us and abs((u2 - u1) - period_us) < 0.25 * period_us:
                out.append(p2 - 2 * p1 + p0)
    return np.asarray(out).reshape(-1, 3)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack learn-q", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log", help="LCM log with GROUND_TRUTH messages (the simulator's, or your own labels)")
    ap.add_argument("--frame-rate", type=float, default=25.0, help="frames per second of the truth (default 25)")
    a = ap.parse_args(argv)
    if not a.frame_rate > 0:
        ap.error("--frame-rate must be > 0")
    try:
        log = read_log(a.log, lambda c: c == "GROUND_TRUTH")
    except (OSError, ValueError) as e:
        print(f"mvtrack learn-q: cannot read {a.log}: {e}", file=sys.stderr)
        return 2
    dt = 1.0 / a.frame_rate
    d2 = second_differences(log.gt, dt * 1e6)
    if len(d2) < 10:
        print(f"mvtrack learn-q: {a.log} has {len(d2)} usable second differences (need >= 10 "
              "GROUND_TRUTH frames of a person, one period apart)", file=sys.stderr)
        return 2
    q = q_from_second_differences(d2, dt)
    print(f"{len(d2)} second differences; q = {q[0]:.4g}, {q[1]:.4g}, {q[2]:.4g} m^2/s^3")
    print(f"mvtrackd --q {q[0]:.4g},{q[1]:.4g},{q[2]:.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
