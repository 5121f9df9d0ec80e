"""Particle-filter tracking (the second paper): rendered scenes through mvtrackd's pf modes.

Each scene is rendered (tools/mvtrack_tools/render.py: coloured bodies, fragmented motion masks,
furniture, shadows, clutter; blobs derived from the masks) and run through the daemon as:

  pkf            the projective Kalman filter on the blobs (reference)
  MS (paper)     --mode pf-ms --particle-model point --exclusion 0 --pixels independent: independent
                 motion-only filters whose particles are points of the body, as published
  MS+C (paper)   the same with --mode pf: with the hue/saturation cue
  MS+C point     --mode pf --particle-model point: the paper's particles with the exclusion prior and
                 the pixels shared out between targets
  MS             --mode pf-ms: column particles (head-top hypotheses), exclusion prior
  MS+C           --mode pf: the daemon's default particle filter (column, colour, exclusion)

Scored: CLEAR MOT (mvtrack_tools.mot), the position error against the ground-truth head point
(3D and horizontal), and how often the track's extent (pf: the P_H = 0.95 volume) contains the
true head point. Writes a Markdown table, summary.json, the occupancy density seen from above
(the paper's Fig. 2c) and a camera view with the projected volumes.

    tools/mvtrack pf [--seeds 3] [--scenes interaction crowd4 crowd] [--runs RUN ...] [--daemon-args ARGS]
                     [--out out/pf]
Rendered logs are kept under OUT/logs and reused while the code that makes them (scenes, rig,
renderer) is the same.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import shlex
import sys
from pathlib import Path

import numpy as np

from .crowd import DetectorModel, crowd_scene, interaction_scene
from .experiment1 import run_daemon
from .lcmio import LogWriter, mt, read_log
from .mot import as_dict, clear_mot, pair_frames
from .mot_run import run_scenes
from .render import Renderer, write_rendered
from .rig import smartroom

Q = np.array([0.5, 0.5, 0.05])
PAPER = ["--particle-model", "point", "--exclusion", "0", "--pixels", "independent"]
RUNS = [("pkf", "pkf", []), ("MS (paper)", "pf-ms", PAPER), ("MS+C (paper)", "pf", PAPER),
        ("MS+C point", "pf", ["--particle-model", "point"]), ("MS", "pf-ms", []), ("MS+C", "pf", [])]


def head_stats(gt, tr) -> dict:
    """Per ground-truth (frame, person) matched to the nearest track (horizontally, <= 0.5 m):
    3D and horizontal error, extent containment."""
    tu = np.array(sorted(tr.tracks), dtype=np.int64)
    e3, exy, inside = [], [], []
    for u, (ids, pos) in gt.gt.items():
        if not len(tu):
            break
        j = int(np.argmin(np.abs(tu - u)))
        tracks = [t for t in tr.tracks[int(tu[j])] if t.status in (2, 3)]
        for p in pos:
            if not tracks:
                continue
            d = [np.hypot(t.position[0] - p[0], t.position[1] - p[1]) for t in tracks]
            i = int(np.argmin(d))
            if d[i] > 0.5:
                continue
            t = tracks[i]
            e3.append(float(np.linalg.norm(np.asarray(t.position) - p)))
            exy.append(float(d[i]))
            inside.append(all(t.extent_min[a] <= p[a] <= t.extent_max[a] for a in range(3)))
    n = max(len(e3), 1)
    return {"err3d_mm": 1e3 * float(np.mean(e3)) if e3 else float("nan"),
            "errxy_mm": 1e3 * float(np.mean(exy)) if exy else float("nan"),
            "head_in_volume": sum(inside) / n, "matched": len(e3)}


def build_scene(kind: str, rig, seed: int):
    if kind == "interaction":
        return interaction_scene(rig, 400, seed, DetectorModel(dropout_cam=None))
    if kind == "crowd":  # tools/mvtrack mot's acceptance scene: 60 s, 5 people, 2 more later
        return crowd_scene(rig, 60.0, seed, model=DetectorModel(dropout_cam=None))
    return crowd_scene(rig, 30.0, seed, n_people=4, returning=0, model=DetectorModel(dropout_cam=None))


def _code_hash() -> str:
    """What a rendered log depends on besides the scene kind and seed: the scene, rig, body and
    renderer code (their sources' hash)."""
    here = Path(__file__).parent
    h = hashlib.sha1()
    for name in ("crowd.py", "scenes.py", "rig.py", "render.py"):
        h.update((here / name).read_bytes())
    return h.hexdigest()


def run_one(out: Path, kind: str, seed: int, plot: bool, runs: list[str], daemon_args: list[str] = ()) -> list[dict]:
    rig = smartroom()
    scene = build_scene(kind, rig, seed)
    log = out / "logs" / f"{kind}_{seed}.lcm"
    stamp = out / "logs" / f"{kind}_{seed}.json"
    key = f"{kind} {seed} {_code_hash()}"
    old = json.loads(stamp.read_text()) if log.exists() and stamp.exists() else {}
    if old.get("key") == key:
        stats = old["stats"]  # the same scene rendered by the same code
    else:
        w = LogWriter(str(log))
        stats = write_rendered(w, scene, Renderer(rig, seed=seed), seed, progress=False)
        w.close()
        stamp.write_text(json.dumps({"key": key, "stats": stats}, default=float))
    gt = read_log(str(log), lambda c: c == "GROUND_TRUTH")
    rows = []
    for name, mode, extra in RUNS:
        if name not in runs:
            continue
        trk = out / "logs" / f"{kind}_{seed}_{name.replace(' ', '_').replace('(', '').replace(')', '')}.lcm"
        run_daemon(out / "rig.yaml", log, trk, mode, Q,
                   extra + list(daemon_args) + (["--publish-particles", "200"] if mode != "pkf" else []))
        tr = read_log(str(trk), lambda c: c in ("TRACKS", "MVTRACK_STATUS"))
        r = as_dict(clear_mot(pair_frames(gt, tr, rig.frame_rate)))
        r.update(head_stats(gt, tr))
        r.update(scene=kind, seed=seed, run=name, **{f"sim_{k}": v for k, v in stats.items()})
        rows.append(r)
        if plot and name == "MS+C":
            plot_density(out / f"{kind}_{seed}_density.png", rig, trk, gt, f"{kind} seed {seed}, MS+C")
            plot_views(out / f"{kind}_{seed}_views.png", rig, scene, trk, seed)
    return rows


def _particles(path: Path) -> dict[int, tuple]:
    import lcm

    out = {}
    for ev in lcm.EventLog(str(path), "r"):
        if ev.channel == "MVTRACK_PARTICLES":
            m = mt.particles_t.decode(ev.data)
            out[m.utime] = (np.array(m.id), np.array(m.x), np.array(m.y), np.array(m.z), np.array(m.weight))
    return out


def plot_density(path: Path, rig, trk: Path, gt, title: str) -> None:
    """Occupancy density seen from above (3D Gaussian kernel over the particles, marginalised over
    height) at four moments, level curves per target, ground truth marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    parts = _particles(trk)
    if not parts:
        return
    times = sorted(parts)
    pick = [times[int(i * (len(times) - 1) / 3)] for i in range(4)]
    lo, hi = rig.volume_min, rig.volume_max
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], 150), np.linspace(lo[1], hi[1], 125))
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.4))
    bw = 0.06
    gts = sorted(gt.gt)
    for ax, u in zip(axes, pick):
        ids, x, y, _, w = parts[u]
        for k, tid in enumerate(sorted(set(ids.tolist()))):
            s = ids == tid
            dens = np.zeros_like(gx)
            for xi, yi, wi in zip(x[s], y[s], w[s]):
                dens += wi * np.exp(-((gx - xi) ** 2 + (gy - yi) ** 2) / (2 * bw * bw))
            dens /= 2 * np.pi * bw * bw
            ax.contour(gx, gy, dens, levels=np.linspace(dens.max() * 0.1, dens.max(), 6), colors=f"C{k}",
                       linewidths=1)
            ax.plot([], [], color=f"C{k}", label=f"track {tid}")
        g = gts[int(np.argmin(np.abs(np.array(gts) - u)))]
        gp = gt.gt[g][1]
        ax.plot(gp[:, 0], gp[:, 1], "k+", ms=10, label="true head")
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_title(f"t = {(u - times[0]) * 1e-6:.1f} s")
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(f"{title}: occupancy density from above (level curves, kernel {bw * 100:.0f} cm)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def plot_views(path: Path, rig, scene, trk: Path, seed: int) -> None:
    """Rendered camera views (hue/saturation shown as colour, the mask as brightness) with each
    track's P_H volume projected (its box's 8 corners' hull) at one frame."""
    import cv2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tr = read_log(str(trk), lambda c: c == "TRACKS")
    if not tr.tracks:
        return
    times = sorted(tr.tracks)
    f = len(times) // 2
    tracks = tr.tracks[times[f]]
    rend = Renderer(rig, seed=seed)
    rng = np.random.default_rng(0)
    pal = {p.gid: i for i, p in enumerate(sorted(scene.people, key=lambda p: p.gid))}
    people = [(p.gid, p.pos[f - p.f0], pal[p.gid]) for p in scene.present(f)]
    fig, axes = plt.subplots(1, len(rig.cameras), figsize=(4 * len(rig.cameras), 3.4))
    for k, (ax, cam) in enumerate(zip(axes, rig.cameras)):
        v = rend.render(k, people, rng)
        hsv = np.dstack([(v.hue.astype(int) * 180 // 256).astype(np.uint8), v.sat,
                         np.where(v.mask > 0, 230, 90).astype(np.uint8)])
        rgb = cv2.cvtColor(hsv, cv2.COLOR_HSV2RGB)
        s = rend.m.scale
        ax.imshow(rgb, extent=(-0.5, v.mask.shape[1] * s - 0.5, v.mask.shape[0] * s - 0.5, -0.5))
        for i, t in enumerate(tracks):
            lo, hi = np.asarray(t.extent_min), np.asarray(t.extent_max)
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
            if np.any(cam.depth(corners) <= 0.1):
                continue
            uv = cam.project(corners).astype(np.float32)
            if not np.all(np.isfinite(uv)):
                continue
            hull = cv2.convexHull(uv).reshape(-1, 2)
            ax.fill(hull[:, 0], hull[:, 1], fill=False, ec=f"C{i}", lw=1.5)
            head = cam.project(np.asarray(t.position)[None])[0]
            ax.plot(head[0], head[1], "x", color=f"C{i}")
        ax.set_xlim(0, cam.width)
        ax.set_ylim(cam.height, 0)
        ax.set_title(cam.name, fontsize=9)
        ax.axis("off")
    fig.suptitle(f"frame {f}: rendered views (mask bright), P_H volumes projected, x = reported head")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def table(rows: list[dict]) -> str:
    lines = ["| scene | seed | run | MOTA | ID switches | MOTP mm | 3D error mm | horizontal mm | head in volume | ids |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['seed']} | {r['run']} | {r['mota']:.3f} | {r['id_switches']} | "
                     f"{r['motp_mm']:.0f} | {r['err3d_mm']:.0f} | {r['errxy_mm']:.0f} | {100 * r['head_in_volume']:.1f} % | "
                     f"{r['track_ids']} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack pf", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("out/pf"), help="output folder (default out/pf)")
    ap.add_argument("--seeds", type=int, default=3, help="seeds per scene (default 3)")
    ap.add_argument("--scenes", nargs="+", default=["interaction"], choices=["interaction", "crowd4", "crowd"],
                    help="interaction: two people meet and talk (400 frames); crowd4: 4 people, 30 s; crowd: "
                         "tools/mvtrack mot's crowd scene (60 s, 5 people, 2 more later)")
    ap.add_argument("--daemon-args", default="", metavar="ARGS", help="more mvtrackd options for every run")
    ap.add_argument("--jobs", type=int, default=2, help="scenes in parallel (default 2)")
    ap.add_argument("--runs", nargs="+", default=[r[0] for r in RUNS], choices=[r[0] for r in RUNS], metavar="RUN",
                    help="which runs (default all: " + ", ".join(repr(r[0]) for r in RUNS) + ")")
    ap.add_argument("--no-plots", action="store_true")
    a = ap.parse_args(argv)
    rows = run_scenes(ap, a, run_one, not a.no_plots, a.runs, shlex.split(a.daemon_args))
    order = {name: i for i, (name, _, _) in enumerate(RUNS)}
    rows.sort(key=lambda r: (r["scene"], r["seed"], order[r["run"]]))
    (a.out / "summary.json").write_text(json.dumps(rows, indent=1, default=float))
    md = table(rows)
    (a.out / "pf.md").write_text(md + "\n")
    print(md)
    print(f"wrote {a.out / 'pf.md'}, {a.out / 'summary.json'} and plots in {a.out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
