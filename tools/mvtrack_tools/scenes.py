"""Ground-truth motion and per-camera detections for simulated scenes.

Experiment 1 (PKF paper, Sec. 4): one person walks in the room; the head-top point is projected
into every camera with Gaussian pixel noise of variance sigma^2 and, optionally, occlusions
simulated as high-amplitude bursts of 10 frames covering a fraction P_occlusion = 0.3 of each
camera's frames.

The walk is a linear Gaussian process (so that the posterior Cramer-Rao bound is exact for it):
per axis a damped oscillator about the room centre driven by white acceleration noise,
    dp = v dt,  dv = (-w^2 (p - c) - 2 z w v) dt + dW,  E[dW^2] = q dt,
discretised exactly (matrix exponential, Van Loan). Paths that leave the room (minus a margin)
are rejected and redrawn.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from .rig import Rig


@dataclass
class AxisModel:
    omega: float   # rad/s
    zeta: float
    q: float       # m^2/s^3
    centre: float  # m

    def stationary_cov(self) -> np.ndarray:
        w, z, q = self.omega, self.zeta, self.q
        return np.diag([q / (4 * z * w ** 3), q / (4 * z * w)])

    def discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """F (2x2) and Q (2x2) of the exact discretisation over dt (Van Loan)."""
        A = np.array([[0.0, 1.0], [-self.omega ** 2, -2 * self.zeta * self.omega]])
        G = np.array([[0.0], [1.0]])
        M = np.zeros((4, 4))
        M[:2, :2] = -A
        M[:2, 2:] = G @ G.T * self.q
        M[2:, 2:] = A.T
        E = expm(M * dt)
        F = E[2:, 2:].T
        Q = F @ E[:2, 2:]
        return F, 0.5 * (Q + Q.T)


@dataclass
class WalkModel:
    axes: tuple[AxisModel, AxisModel, AxisModel]

    @staticmethod
    def for_room(vmin: np.ndarray, vmax: np.ndarray, head_height: float = 1.70) -> "WalkModel":
        size = np.asarray(vmax) - np.asarray(vmin)
        centre = 0.5 * (np.asarray(vmin) + np.asarray(vmax))
        axes = []
        for i in range(2):  # horizontal: position std 0.2 x room size, ~0.5-0.7 m/s per axis
            w, z = 0.6, 0.6
            std = 0.2 * size[i]
            axes.append(AxisModel(w, z, std ** 2 * 4 * z * w ** 3, centre[i]))
        w, z = 3.0, 0.5  # vertical: head bobbing, 2 cm std
        axes.append(AxisModel(w, z, 0.02 ** 2 * 4 * z * w ** 3, head_height))
        return WalkModel(tuple(axes))

    def transition(self, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """6-state [x y z vx vy vz] F, Q and the offset b so that s' = F s + b + w."""
        F = np.zeros((6, 6))
        Q = np.zeros((6, 6))
        b = np.zeros(6)
        for i, ax in enumerate(self.axes):
            Fi, Qi = ax.discrete(dt)
            idx = [i, i + 3]
            F[np.ix_(idx, idx)] = Fi
            Q[np.ix_(idx, idx)] = Qi
            b[idx] = (np.eye(2) - Fi) @ np.array([ax.centre, 0.0])
        return F, Q, b

    def stationary_cov(self) -> np.ndarray:
        P = np.zeros((6, 6))
        for i, ax in enumerate(self.axes):
            P[np.ix_([i, i + 3], [i, i + 3])] = ax.stationary_cov()
        return P

    def sample(self, rng: np.random.Generator, n: int, dt: float, vmin, vmax, margin: float = 0.4,
               tries: int = 500) -> np.ndarray:
        """(n, 6) states inside [vmin + margin, vmax - margin] horizontally."""
        F, Q, b = self.transition(dt)
        Lq = np.linalg.cholesky(Q + 1e-18 * np.eye(6))
        P0 = self.stationary_cov()
        L0 = np.linalg.cholesky(P0)
        mean = np.array([ax.centre for ax in self.axes] + [0.0, 0.0, 0.0])
        lo = np.asarray(vmin)[:2] + margin
        hi = np.asarray(vmax)[:2] - margin
        for _ in range(tries):
            s = np.empty((n, 6))
            s[0] = mean + L0 @ rng.standard_normal(6)
            for k in range(1, n):
                s[k] = F @ s[k - 1] + b + Lq @ rng.standard_normal(6)
            if np.all(s[:, :2] >= lo) and np.all(s[:, :2] <= hi):
                return s
        raise RuntimeError("could not draw a path that stays in the room")


@dataclass
class Occlusions:
    """Per camera, bursts of `length` frames that replace the true detection by a displaced one
    (a wrong blob), covering a long-run fraction `p` of frames."""
    p: float = 0.3
    length: int = 10
    amp_px: tuple[float, float] = (40.0, 150.0)

    def masks(self, rng: np.random.Generator, n_frames: int, n_cams: int) -> tuple[np.ndarray, np.ndarray]:
        start_p = self.p / (self.length * (1.0 - self.p))
        occ = np.zeros((n_frames, n_cams), dtype=bool)
        off = np.zeros((n_frames, n_cams, 2))
        for k in range(n_cams):
            f = 0
            while f < n_frames:
                if rng.random() < start_p:
                    a = rng.uniform(*self.amp_px)
                    th = rng.uniform(0, 2 * np.pi)
                    occ[f:f + self.length, k] = True
                    off[f:f + self.length, k] = a * np.array([np.cos(th), np.sin(th)])
                    f += self.length
                else:
                    f += 1
        return occ, off


def head_detections(rig: Rig, X: np.ndarray, var_px2: float, rng: np.random.Generator,
                    occlusion: Occlusions | None = None) -> list[list[list[tuple[float, float, bool]]]]:
    """For each frame and camera, the list of (u, v, is_true) detections of the head points X (n, 3)."""
    n = len(X)
    sd = float(np.sqrt(var_px2))
    occ, off = (occlusion.masks(rng, n, len(rig.cameras)) if occlusion else
                (np.zeros((n, len(rig.cameras)), bool), np.zeros((n, len(rig.cameras), 2))))
    out: list[list[list[tuple[float, float, bool]]]] = [[[] for _ in rig.cameras] for _ in range(n)]
    for k, cam in enumerate(rig.cameras):
        uv = cam.project(X)
        front = cam.depth(X) > 0.2
        vis = front & cam.in_image(uv)
        noise = rng.standard_normal((n, 2)) * sd
        for f in range(n):
            if not vis[f]:
                continue
            p = uv[f] + noise[f]
            if occ[f, k]:
                p = p + off[f, k]
            if cam.in_image(p[None])[0]:
                out[f][k].append((float(p[0]), float(p[1]), not occ[f, k]))
    return out
