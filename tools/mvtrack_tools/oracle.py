"""Reference filters for `mvtrack motion --oracles`: what knowledge of the scene's generator is worth.

The motion tables compare the daemon with the PCRLB of the true model. That bound is a filter
that knows everything the generator knows: Experiment 1's walk is pulled towards the room's
centre (a damped spring, `scenes.WalkModel`), and the mixed-motion bound is told the schedule
(when the person stops, turns or sits). These reference filters run on the same detections,
single person, every detection used (no gate: a Gaussian scene has nothing else to take), each
camera linearised at the filter's own estimate:

- `ekf-true`: exp1, the EKF of the generator's own model (the spring included);
- `ekf-cv-learnt`: exp1, the constant-velocity EKF with q learnt from a training scene's truth;
- `ekf-no-centre`: exp1, the generator's walk without its pull to the room's centre: each
  horizontal velocity reverts to zero at the walk's own damping rate 2 zeta omega, driven by its
  own q (an integrated Ornstein-Uhlenbeck velocity), the height as in `ekf-cv-learnt`. Everything
  the generator knows but where the room's centre is;
- `kf-schedule`: mixed, the EKF told the schedule (each frame's true F, b, Q): it should sit on
  the bound, and so checks the bound and the scenes;
- `imm-generator`: mixed, an IMM of the generator's own seven segment models (stand, walk, turn,
  stop, sit down, seated, get up) with switching rates from the segments' mean durations: the
  schedule is not told. It is what a model bank that knew the simulator could reach.

numpy (scipy's matrix exponential through `motion.discretise`); ~2 s per 60 s scene and filter.
"""
from __future__ import annotations

import numpy as np

from . import motion
from .rig import Rig
from .scenes import WalkModel

LOG2PI = float(np.log(2.0 * np.pi))


def _update(rig: Rig, dets_f, var: float, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Sequential EKF update with every detection of one frame; returns x, P, log-likelihood."""
    ll = 0.0
    R = var * np.eye(2)
    for k, cam in enumerate(rig.cameras):
        for (u, v, _) in dets_f[k]:
            if cam.depth(x[None, :3])[0] <= 0.2:
                continue
            if not cam.in_field(x[None, :3])[0]:
                continue  # outside the lens model's valid field: the projection is meaningless there
            h = cam.project(x[None, :3])[0]
            H = np.zeros((2, 6))
            H[:, :3] = cam.project_jacobian(x[:3])
            y = np.array([u, v]) - h
            S = H @ P @ H.T + R
            Si = np.linalg.inv(S)
            K = P @ H.T @ Si
            x = x + K @ y
            IKH = np.eye(6) - K @ H
            P = IKH @ P @ IKH.T + K @ R @ K.T
            ll += -0.5 * (y @ Si @ y + np.log(np.linalg.det(S)) + 2 * LOG2PI)
    return x, 0.5 * (P + P.T), ll


def ekf(rig: Rig, dets, var: float, F, b, Q, x0: np.ndarray, P0: np.ndarray) -> np.ndarray:
    """(n, 3) estimates of an EKF with per-frame F[f], b[f], Q[f] (lists) from x0, P0."""
    n = len(dets)
    x, P = x0.copy(), P0.copy()
    out = np.empty((n, 3))
    for f in range(n):
        if f > 0:
            x = F[f] @ x + b[f]
            P = F[f] @ P @ F[f].T + Q[f]
        x, P, _ = _update(rig, dets[f], var, x, P)
        out[f] = x[:3]
    return out


def cv_model(q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    F = np.eye(6)
    F[:3, 3:] = dt * np.eye(3)
    Q = np.zeros((6, 6))
    for i in range(3):
        Q[i, i] = q[i] * dt ** 3 / 3
        Q[i, i + 3] = Q[i + 3, i] = q[i] * dt ** 2 / 2
        Q[i + 3, i + 3] = q[i] * dt
    return F, np.zeros(6), Q


def no_centre_model(wm: WalkModel, q_height: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """F, b, Q of Experiment 1's walk without the pull to the room's centre (module docstring)."""
    F = np.eye(6)
    Q = np.zeros((6, 6))
    for i in range(3):
        damping, q = (2 * wm.axes[i].zeta * wm.axes[i].omega, wm.axes[i].q) if i < 2 else (0.0, q_height)
        Fi, _, Qi = motion.discretise(np.array([[0.0, 1.0], [0.0, -damping]]), np.zeros(2), q, dt)
        idx = [i, i + 3]
        F[np.ix_(idx, idx)] = Fi
        Q[np.ix_(idx, idx)] = Qi
    return F, np.zeros(6), Q


def exp1_references(rig: Rig, dets, var: float, states: np.ndarray, q_learnt: np.ndarray) -> dict[str, np.ndarray]:
    dt = 1.0 / rig.frame_rate
    wm = WalkModel.for_room(rig.volume_min, rig.volume_max)
    F, Q, b = wm.transition(dt)
    P0 = wm.stationary_cov()
    x0 = np.r_[[ax.centre for ax in wm.axes], 0.0, 0.0, 0.0]
    n = len(dets)
    Fc, bc, Qc = cv_model(q_learnt, dt)
    Fo, bo, Qo = no_centre_model(wm, float(q_learnt[2]), dt)
    return {
        "ekf-true": ekf(rig, dets, var, [F] * n, [b] * n, [Q] * n, x0, P0),
        "ekf-cv-learnt": ekf(rig, dets, var, [Fc] * n, [bc] * n, [Qc] * n, x0, P0),
        "ekf-no-centre": ekf(rig, dets, var, [Fo] * n, [bo] * n, [Qo] * n, x0, P0),
    }


# The generator's segments as a Markov chain: (name, kind, sit_dir, mean duration s, next: {name: share}).
# Durations are the means of motion.next_segments' uniform draws.
GENERATOR_MODELS = [
    ("stand", "stand", 0.0, 5.0, {"turn": 0.75, "sitdown": 0.25}),
    ("walk", "walk", 0.0, 3.0 / 0.8, {"turn": 0.5, "stop": 0.5}),  # a walk re-draws itself 20 % of the time
    ("turn", "turn", 0.0, 0.65, {"walk": 1.0}),
    ("stop", "stop", 0.0, 1.0, {"stand": 1.0}),
    ("sitdown", "sit", -1.0, motion.SIT_S, {"seated": 1.0}),
    ("seated", "stand", 0.0, 7.0, {"getup": 1.0}),
    ("getup", "sit", +1.0, motion.SIT_S, {"stand": 1.0}),
]


def imm_generator(rig: Rig, dets, var: float, x0: np.ndarray, P0: np.ndarray) -> np.ndarray:
    """IMM (Blom & Bar-Shalom) of the generator's segment models, schedule not told."""
    dt = 1.0 / rig.frame_rate
    names = [m[0] for m in GENERATOR_MODELS]
    M = len(names)
    Fs, bs, Qs = [], [], []
    Pi = np.zeros((M, M))
    for i, (_, kind, sd, dur, nxt) in enumerate(GENERATOR_MODELS):
        F, b, Q = motion.transition(kind, dt, sd)
        Fs.append(F)
        bs.append(b)
        Qs.append(Q + 1e-12 * np.eye(6))
        leave = 1.0 - np.exp(-dt / dur)
        Pi[i, i] = 1.0 - leave
        for name, share in nxt.items():
            Pi[i, names.index(name)] += leave * share
    mu = np.zeros(M)
    mu[names.index("stand")] = 1.0
    mu = 0.98 * mu + 0.02 / M
    xs = [x0.copy() for _ in range(M)]
    Ps = [P0.copy() for _ in range(M)]
    n = len(dets)
    out = np.empty((n, 3))
    for f in range(n):
        if f > 0:
            c = Pi.T @ mu
            w = (Pi * mu[:, None]) / np.maximum(c[None, :], 1e-300)  # w[i, j] = P(i | j)
            nx, nP = [], []
            for j in range(M):
                xm = sum(w[i, j] * xs[i] for i in range(M))
                Pm = sum(w[i, j] * (Ps[i] + np.outer(xs[i] - xm, xs[i] - xm)) for i in range(M))
                nx.append(Fs[j] @ xm + bs[j])
                nP.append(Fs[j] @ Pm @ Fs[j].T + Qs[j])
            xs, Ps = nx, nP
        else:
            c = mu.copy()
        lls = np.empty(M)
        for j in range(M):
            xs[j], Ps[j], lls[j] = _update(rig, dets[f], var, xs[j], Ps[j])
        lw = np.log(np.maximum(c, 1e-300)) + lls
        lw -= lw.max()
        mu = np.exp(lw)
        mu /= mu.sum()
        out[f] = sum(mu[j] * xs[j][:3] for j in range(M))
    return out


def mixed_references(rig: Rig, dets, var: float, states: np.ndarray, Fs, Qs, bs, P0: np.ndarray) -> dict[str, np.ndarray]:
    return {
        "kf-schedule": ekf(rig, dets, var, Fs, bs, Qs, states[0].copy(), P0),
        "imm-generator": imm_generator(rig, dets, var, states[0].copy(), P0),
    }
