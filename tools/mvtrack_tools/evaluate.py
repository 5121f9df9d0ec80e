"""Evaluate TRACKS against GROUND_TRUTH: 3D error (Table 1 form) and the posterior Cramer-Rao
lower bound (Tichavsky et al. 1998) of the simulated scene.

    python -m mvtrack_tools.evaluate --scene out/scene.lcm --tracks out/tracks.lcm --rig out/rig.yaml --var 100
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass

import numpy as np

from .lcmio import TrackLog, read_log
from .rig import Rig
from .scenes import WalkModel

MATCH_M = 0.5  # CLEAR 2007 3D person-tracking match threshold


@dataclass
class SingleTargetResult:
    frames: int            # ground-truth frames
    matched: int           # frames with a confirmed/coasting track within MATCH_M
    mean_mm: float
    std_mm: float
    rmse_mm: float
    pcrlb_rmse_mm: float   # bound over the same frames (nan if not computed)
    ratio: float           # rmse / pcrlb_rmse
    first_matched: int     # index of the first matched frame


def q_from_second_differences(d2: np.ndarray, dt: float) -> np.ndarray:
    """Per-axis white-acceleration density (m^2/s^3) from second differences (n, 3) of positions
    sampled every dt: for that model Var(second difference) = 2/3 q dt^3."""
    return 1.5 * d2.var(axis=0) / dt ** 3


def learn_q(pos: np.ndarray, dt: float) -> np.ndarray:
    """q_from_second_differences of one trajectory (n, 3)."""
    return q_from_second_differences(pos[2:] - 2 * pos[1:-1] + pos[:-2], dt)


def pcrlb_position_mse(rig: Rig, model: WalkModel, pos: np.ndarray, var_px2: float,
                       seen: np.ndarray | None = None) -> np.ndarray:
    """Per-frame bound on E|p - p_hat|^2 (m^2) for the linear-Gaussian walk observed by the rig
    with pixel noise var_px2; seen[f, k] says whether camera k measured frame f (default: the
    head projects into the image)."""
    F, Q, _ = model.transition(1.0 / rig.frame_rate)
    n = len(pos)
    if seen is None:
        seen = np.zeros((n, len(rig.cameras)), dtype=bool)
        for k, cam in enumerate(rig.cameras):
            seen[:, k] = (cam.depth(pos) > 0.2) & cam.in_image(cam.project(pos))
    return pcrlb_known(rig, pos, [F] * n, [Q] * n, model.stationary_cov(), var_px2, seen)


def pcrlb_known(rig: Rig, pos: np.ndarray, Fs, Qs, P0: np.ndarray, var_px2: float, seen: np.ndarray) -> np.ndarray:
    """Per-frame bound on E|p - p_hat|^2 (m^2) of a linear-Gaussian motion with the frame's
    transition F_k, Q_k (from frame k-1) observed by the cameras seen[k] with pixel noise
    var_px2: J_{k+1} = (Q_k + F_k J_k^-1 F_k^T)^-1 + sum H^T R^-1 H (Tichavsky et al.)."""
    J = np.linalg.inv(P0)
    out = np.empty(len(pos))
    for f in range(len(pos)):
        if f > 0:
            J = np.linalg.inv(Qs[f] + Fs[f] @ np.linalg.inv(J) @ Fs[f].T)
        for k, cam in enumerate(rig.cameras):
            if seen[f, k]:
                H = cam.project_jacobian(pos[f])
                J[:3, :3] += H.T @ H / var_px2
        out[f] = np.trace(np.linalg.inv(J)[:3, :3])
    return out


def match_single(log: TrackLog, scene: TrackLog) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """GT positions (n,3), estimates (n,3) (nan when unmatched) and utimes of a one-person scene.
    The estimate of a frame is the nearest confirmed or coasting track."""
    utimes = np.array(sorted(scene.gt))
    gt = np.array([scene.gt[u][1][0] for u in utimes])
    est = np.full_like(gt, np.nan)
    for i, u in enumerate(utimes):
        best, bd = None, np.inf
        for t in log.tracks.get(int(u), []):
            if t.status not in (2, 3):
                continue
            d = np.linalg.norm(np.array(t.position) - gt[i])
            if d < bd:
                best, bd = t, d
        if best is not None and bd <= MATCH_M:
            est[i] = best.position
    return gt, est, utimes


def evaluate_single(scene_log: str, tracks_log: str, rig: Rig, var_px2: float | None,
                    seen: np.ndarray | None = None, skip_s: float = 0.0) -> SingleTargetResult:
    scene = read_log(scene_log, lambda c: c == "GROUND_TRUTH")
    log = read_log(tracks_log, lambda c: c == "TRACKS")
    gt, est, _ = match_single(log, scene)
    ok = ~np.isnan(est[:, 0])
    skip = int(round(skip_s * rig.frame_rate))
    ok[:skip] = False
    err = np.linalg.norm(est - gt, axis=1)[ok] * 1e3
    rmse = float(np.sqrt(np.mean(err ** 2))) if len(err) else float("nan")
    bound = float("nan")
    if var_px2 is not None:
        model = WalkModel.for_room(rig.volume_min, rig.volume_max)
        b = pcrlb_position_mse(rig, model, gt, var_px2, seen)
        bound = float(np.sqrt(np.mean(b[ok]))) * 1e3 if ok.any() else float("nan")
    first = int(np.argmax(ok)) if ok.any() else -1
    return SingleTargetResult(len(gt), int(ok.sum()), float(err.mean()) if len(err) else float("nan"),
                              float(err.std()) if len(err) else float("nan"), rmse, bound, rmse / bound, first)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack evaluate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="log with GROUND_TRUTH (the simulator's output)")
    ap.add_argument("--tracks", required=True, help="log with TRACKS (mvtrackd's output)")
    ap.add_argument("--rig", required=True, help="rig file")
    ap.add_argument("--var", type=float, help="pixel noise variance of the scene, for the PCRLB")
    ap.add_argument("--json", action="store_true", help="print JSON")
    a = ap.parse_args(argv)
    r = evaluate_single(a.scene, a.tracks, Rig.read(a.rig), a.var)
    if a.json:
        print(json.dumps(asdict(r)))
    else:
        print(f"frames {r.frames}, matched {r.matched}, error mean {r.mean_mm:.2f} mm, std {r.std_mm:.2f} mm, "
              f"RMSE {r.rmse_mm:.2f} mm, PCRLB {r.pcrlb_rmse_mm:.2f} mm, ratio {r.ratio:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
