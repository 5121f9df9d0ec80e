"""Plots people would rather look at than read (PNG, matplotlib Agg)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .rig import Rig  # noqa: E402

MODE_STYLE = {
    "pkf": dict(color="tab:blue", label="PKF, Jacobian H (default)"),
    "pkf-paper": dict(color="tab:red", label="PKF, paper's H (Eq. 18)"),
    "pkf-centred": dict(color="tab:purple", label="PKF, Eq. 18 centred pixels"),
    "kf": dict(color="tab:orange", label="triangulate + KF (baseline)"),
}


def draw_room(ax, rig: Rig) -> None:
    lo, hi = rig.volume_min, rig.volume_max
    ax.plot([lo[0], hi[0], hi[0], lo[0], lo[0]], [lo[1], lo[1], hi[1], hi[1], lo[1]], color="0.3", lw=1.2)
    for cam in rig.cameras:
        c = cam.centre
        axis = cam.R[2]  # optical axis in the world
        ax.plot(c[0], c[1], "k^", ms=7)
        if np.hypot(axis[0], axis[1]) > 1e-3:
            a = axis[:2] / np.hypot(axis[0], axis[1]) * 0.4
            ax.annotate("", xy=(c[0] + a[0], c[1] + a[1]), xytext=(c[0], c[1]),
                        arrowprops=dict(arrowstyle="->", color="k", lw=1))
        ax.text(c[0], c[1] + 0.12, cam.name, fontsize=7, ha="center")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def zenithal(path: Path, rig: Rig, gt: np.ndarray, paths: dict[str, np.ndarray], title: str) -> None:
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    draw_room(ax, rig)
    ax.plot(gt[:, 0], gt[:, 1], color="k", lw=2.2, label="ground truth")
    for mode, p in paths.items():
        st = MODE_STYLE.get(mode, dict(label=mode))
        ax.plot(p[:, 0], p[:, 1], lw=1.0, alpha=0.85, **st)
    ax.set_title(title)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def error_vs_noise(path: Path, table: dict, modes: list[str], levels: list[float]) -> None:
    """table[(occlusion, var, mode)] = dict(mean_mm, std_mm)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=False)
    for ax, occ, title in [(axes[0], False, "(a) Gaussian noise"), (axes[1], True, "(b) Gaussian noise + occlusions")]:
        for mode in modes:
            m = np.array([table[(occ, v, mode)]["mean_mm"] for v in levels])
            s = np.array([table[(occ, v, mode)]["std_mm"] for v in levels])
            st = MODE_STYLE.get(mode, dict(label=mode))
            ax.errorbar(levels, m, yerr=s, marker="o", capsize=3, lw=1.4, **st)
        ax.set_xlabel("pixel noise variance $\\sigma^2$ (px$^2$)")
        ax.set_ylabel("3D error (mm), mean $\\pm$ std")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def error_over_time(path: Path, t: np.ndarray, errs: dict[str, np.ndarray], bound: np.ndarray | None,
                    title: str) -> None:
    fig, ax = plt.subplots(figsize=(10, 3.6))
    for mode, e in errs.items():
        st = MODE_STYLE.get(mode, dict(label=mode))
        ax.plot(t, e, lw=0.8, **st)
    if bound is not None:
        ax.plot(t, bound, color="k", ls="--", lw=1.2, label="PCRLB (RMSE)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("3D error (mm)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _id_colour(i: int):
    cmap = plt.get_cmap("tab20")
    return cmap((i * 7) % 20)


def zenithal_multi(path: Path, rig: Rig, scene, tracks, title: str) -> None:
    """Ground truth (grey, labelled G<id>) under the confirmed tracks, one colour per identity
    (labelled T<id> where they start); coasting frames dotted."""
    fig, ax = plt.subplots(figsize=(8, 7))
    draw_room(ax, rig)
    gt: dict[int, list] = {}
    for u in sorted(scene.gt):
        for i, p in zip(*scene.gt[u]):
            gt.setdefault(int(i), []).append(p)
    for i, ps in gt.items():
        ps = np.array(ps)
        ax.plot(ps[:, 0], ps[:, 1], color="0.75", lw=4, solid_capstyle="round", zorder=1)
        ax.text(ps[0, 0], ps[0, 1], f"G{i}", fontsize=8, color="0.4", zorder=3)
    trk: dict[int, list] = {}
    for u in sorted(tracks.tracks):
        for t in tracks.tracks[u]:
            if t.status in (2, 3):
                trk.setdefault(int(t.id), []).append((t.position[0], t.position[1], t.status))
    for i, ps in trk.items():
        ps = np.array(ps)
        c = _id_colour(i)
        ax.plot(ps[:, 0], ps[:, 1], color=c, lw=1.2, zorder=2)
        coast = ps[:, 2] == 3
        ax.plot(ps[coast, 0], ps[coast, 1], ".", color=c, ms=2, zorder=2)
        ax.text(ps[0, 0], ps[0, 1], f"T{i}", fontsize=8, color=c, fontweight="bold", zorder=3)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def timeline(path: Path, scene, tracks, frame_rate: float, title: str) -> None:
    """Top: ground-truth presence per person. Bottom: each track identity's life: tentative
    (pale), confirmed (solid), coasting (grey), birth (>) and death (x)."""
    us = sorted(tracks.tracks)
    if not us:
        return
    t0 = min(min(scene.gt) if scene.gt else us[0], us[0])
    sec = lambda u: (u - t0) * 1e-6  # noqa: E731
    life: dict[int, list] = {}
    for u in us:
        for t in tracks.tracks[u]:
            life.setdefault(int(t.id), []).append((sec(u), int(t.status)))
    gt: dict[int, list] = {}
    for u in sorted(scene.gt):
        for i in scene.gt[u][0]:
            gt.setdefault(int(i), []).append(sec(u))
    ids = sorted(i for i, v in life.items() if any(s in (2, 3) for _, s in v))
    fig, (a0, a1) = plt.subplots(2, 1, figsize=(10, 2 + 0.22 * (len(ids) + len(gt))), sharex=True,
                                 gridspec_kw=dict(height_ratios=[max(1, len(gt)), max(1, len(ids))]))
    dt = 1.0 / frame_rate
    for row, (i, ts) in enumerate(sorted(gt.items())):
        a0.broken_barh([(t, dt) for t in ts], (row - 0.35, 0.7), color="0.55")
    a0.set_yticks(range(len(gt)), [f"G{i}" for i in sorted(gt)], fontsize=7)
    a0.set_title(title, fontsize=10)
    colour = {1: None, 2: None, 3: "0.7"}
    for row, i in enumerate(ids):
        c = _id_colour(i)
        v = life[i]
        for s in (1, 2, 3):
            segs = [(t, dt) for t, st in v if st == s]
            if segs:
                a1.broken_barh(segs, (row - 0.35, 0.7), color=colour[s] or c, alpha=0.35 if s == 1 else 1.0)
        a1.plot(v[0][0], row, ">", color="k", ms=4)
        if v[-1][0] < sec(us[-1]) - 1e-6:
            a1.plot(v[-1][0] + dt, row, "x", color="k", ms=5)
    a1.set_yticks(range(len(ids)), [f"T{i}" for i in ids], fontsize=7)
    a1.set_xlabel("time (s)    pale: tentative, colour: confirmed, grey: coasting, >: birth, x: deletion")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
