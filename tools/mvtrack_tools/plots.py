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
