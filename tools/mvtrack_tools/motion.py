"""Mixed motion for one person: stand, walk, turn sharply, stop, start, sit down and get up.

The path is a jump-Markov linear-Gaussian process: a schedule of segments and, within each, a
known linear transition s' = F s + b + w, w ~ N(0, Q), on [X Y Z Vx Vy Vz] (exact discretisation
of per-axis linear stochastic differential equations, Van Loan). Given the schedule the posterior
Cramer-Rao bound is exact (a filter told when the person stops, turns or sits can only do better
than one that is not, so a tracker's ratio to it is conservative). No segment carries a known
place: a model that pulls the head towards a known point (an anchor) would give the bound
knowledge no tracker has, so every position is a random walk from where the last segment left it.

Segments (horizontal axes; the height has its own):
  stand   velocity 0 (F_vv = 0, a 5 mm/s sway), position diffusion (5 mm)^2/s; height likewise
  walk    constant velocity with white acceleration 0.05 m^2/s^3 (speed drifts ~0.2 m/s per
          second); height: diffusion (1 cm)^2/s, no vertical speed of its own
  turn    a manoeuvre: white acceleration 2 m^2/s^3 for 0.5-0.8 s (a sharp turn, a start from
          standing, a change of pace)
  stop    velocity relaxes to 0 with time constant 0.25 s (1 s), then stand
  sit     the head goes down (up for rise) at 0.6 +- 0.15 m/s for 0.75 s (time constant 0.15 s), then sits
          (stand) for 4-10 s and rises the same way
Each segment is redrawn (up to 200 times) until the head stays in the room (minus a margin) and
below 2 m/s, else replaced by a stop, else by standing still; this conditions the noise a little,
as Experiment 1's path rejection does.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm


def discretise(A: np.ndarray, c: np.ndarray, q: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact F, b and Q over dt of d[p, v] = (A [p, v] + c) dt + [0, dW], E dW^2 = q dt."""
    n = 2
    M = np.zeros((n + 1, n + 1))
    M[:n, :n] = A
    M[:n, n] = c
    E = expm(M * dt)
    F, b = E[:n, :n], E[:n, n]
    G = np.array([[0.0, 0.0], [0.0, q]])
    V = np.zeros((2 * n, 2 * n))
    V[:n, :n] = -A
    V[:n, n:] = G
    V[n:, n:] = A.T
    W = expm(V * dt)
    Q = W[n:, n:].T @ W[:n, n:]
    return F, b, 0.5 * (Q + Q.T)


STAND_SWAY = 0.005      # m/s of velocity that does not persist
STAND_DIFF = 0.005 ** 2  # m^2/s
WALK_Q = 0.05
WALK_Z_DIFF = 0.01 ** 2
TURN_Q = 2.0
STOP_TAU = 0.25
SIT_SPEED, SIT_SPEED_STD, SIT_TAU, SIT_S = 0.6, 0.15, 0.15, 0.75


def still_axis(diff: float, sway: float, dt: float):
    """F, b, Q of an axis that stands: p' = p + N(0, diff dt), v' = N(0, sway^2)."""
    return np.array([[1.0, 0.0], [0.0, 0.0]]), np.zeros(2), np.diag([diff * dt, sway * sway])


def axis(kind: str, dt: float, vertical: bool, sit_dir: float = 0.0):
    if kind == "stand" or (vertical and kind in ("walk", "turn", "stop")):
        return still_axis(WALK_Z_DIFF if vertical and kind != "stand" else STAND_DIFF, STAND_SWAY, dt)
    if kind == "sit":
        if not vertical:
            return still_axis(STAND_DIFF, STAND_SWAY, dt)
        A = np.array([[0.0, 1.0], [0.0, -1.0 / SIT_TAU]])
        return discretise(A, np.array([0.0, sit_dir * SIT_SPEED / SIT_TAU]), 2 * SIT_SPEED_STD ** 2 / SIT_TAU, dt)
    if kind == "stop":
        A = np.array([[0.0, 1.0], [0.0, -1.0 / STOP_TAU]])
        return discretise(A, np.zeros(2), 2 * 0.02 ** 2 / STOP_TAU, dt)
    q = WALK_Q if kind == "walk" else TURN_Q
    return discretise(np.array([[0.0, 1.0], [0.0, 0.0]]), np.zeros(2), q, dt)


def transition(kind: str, dt: float, sit_dir: float = 0.0):
    F = np.zeros((6, 6))
    Q = np.zeros((6, 6))
    b = np.zeros(6)
    for i in range(3):
        Fi, bi, Qi = axis(kind, dt, i == 2, sit_dir)
        idx = [i, i + 3]
        F[np.ix_(idx, idx)] = Fi
        Q[np.ix_(idx, idx)] = Qi
        b[idx] = bi
    return F, b, Q


@dataclass
class Segment:
    kind: str       # stand | walk | turn | stop | sit (down: sit_dir -1, up: +1)
    frames: int
    sit_dir: float = 0.0


def next_segments(rng: np.random.Generator, last: str, dt: float, seated: bool) -> list[Segment]:
    f = lambda s: max(1, int(round(s / dt)))  # noqa: E731
    if seated:
        return [Segment("sit", f(SIT_S), +1.0), Segment("stand", f(rng.uniform(0.5, 2.0)))]
    if last == "stand":
        r = rng.random()
        if r < 0.25:  # sit down, stay, and get up later
            return [Segment("sit", f(SIT_S), -1.0), Segment("stand", f(rng.uniform(4.0, 10.0)))]
        return [Segment("turn", f(rng.uniform(0.5, 0.8))), Segment("walk", f(rng.uniform(1.5, 5.0)))]
    r = rng.random()
    if r < 0.4:  # a sharp turn or a change of pace
        return [Segment("turn", f(rng.uniform(0.5, 0.8))), Segment("walk", f(rng.uniform(1.5, 5.0)))]
    if r < 0.6:
        return [Segment("walk", f(rng.uniform(1.5, 4.0)))]
    return [Segment("stop", f(1.0)), Segment("stand", f(rng.uniform(1.0, 12.0)))]


def sample_mixed(rng: np.random.Generator, n: int, dt: float, vmin, vmax, margin: float = 0.4,
                 tries: int = 200, with_offsets: bool = False):
    """(states (n, 6), Fs, Qs, kinds, P0) of a mixed-motion path that stays inside the room; with
    with_offsets, also each frame's offset b (s' = F s + b + w: the seated head's known speed)."""
    lo = np.asarray(vmin, float)[:2] + margin
    hi = np.asarray(vmax, float)[:2] - margin
    centre = 0.5 * (lo + hi)
    P0 = np.diag([0.01 ** 2] * 3 + [0.01 ** 2] * 3)
    s = np.empty((n, 6))
    s[0] = np.r_[centre + rng.uniform(-0.3, 0.3, 2) * (hi - lo), 1.70, 0, 0, 0] + np.sqrt(np.diag(P0)) * rng.standard_normal(6)
    Fs, Qs, bs, kinds = [np.eye(6)], [np.zeros((6, 6))], [np.zeros(6)], ["stand"]
    f0, last, seated = 1, "stand", False
    first = Segment("stand", int(round(rng.uniform(2.0, 5.0) / dt)))
    pending = [first]
    while f0 < n:
        if not pending:
            pending = next_segments(rng, last, dt, seated)
        seg = pending.pop(0)
        m = min(seg.frames, n - f0)
        out = None
        # the segment as planned; else a stop; else standing still where the head is (its
        # velocity is forgotten at once, so it cannot overshoot)
        for kind in (seg.kind, "stop", "stand"):
            if kind != seg.kind:
                seg = Segment(kind, m)
                pending = []
            F, b, Q = transition(seg.kind, dt, seg.sit_dir)
            L = np.linalg.cholesky(Q + 1e-18 * np.eye(6))
            for _ in range(tries):
                x = s[f0 - 1].copy()
                draw = np.empty((m, 6))
                for k in range(m):
                    x = F @ x + b + L @ rng.standard_normal(6)
                    draw[k] = x
                if (np.all(draw[:, :2] >= lo) and np.all(draw[:, :2] <= hi)
                        and np.all(np.hypot(draw[:, 3], draw[:, 4]) < 2.0)):
                    out = draw
                    break
            if out is not None:
                break
        if out is None:
            raise RuntimeError("could not continue a mixed-motion path inside the room")
        s[f0:f0 + m] = out
        Fs += [F] * m
        Qs += [Q] * m
        bs += [b] * m
        kinds += [seg.kind] * m
        if seg.kind == "sit":
            seated = seg.sit_dir < 0
        f0 += m
        last = seg.kind if seg.kind != "turn" else "walk"
    if with_offsets:
        return s, Fs, Qs, kinds, P0, bs
    return s, Fs, Qs, kinds, P0


def sample_standing(rng: np.random.Generator, n: int, dt: float, vmin, vmax, sway: float = 0.001):
    """A person who stands still (the head wanders sway m in a second: 1 mm) near the room's
    centre: the estimate's spread is then the filter's jitter, not the person's motion."""
    centre = 0.5 * (np.asarray(vmin, float) + np.asarray(vmax, float))
    F, b, Q = transition("stand", dt)
    Q = np.diag([sway ** 2 * dt] * 3 + [sway ** 2] * 3)
    L = np.linalg.cholesky(Q)
    s = np.empty((n, 6))
    s[0] = np.r_[centre[:2] + rng.uniform(-0.5, 0.5, 2), 1.70, 0, 0, 0]
    for k in range(1, n):
        s[k] = F @ s[k - 1] + b + L @ rng.standard_normal(6)
    P0 = np.diag([0.01 ** 2] * 3 + [0.01 ** 2] * 3)
    return s, [F] * n, [Q] * n, P0
