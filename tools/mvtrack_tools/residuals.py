"""Per camera: how far its detections lie from the heads, as the tracks (or the ground truth) put them.

A camera whose points are not head tops shows here before it shows in the tracks: a detector that
reports the top of a silhouette seen from the ceiling (from above, the top of a blob is a shoulder
or the far side of the body, not the head), a calibration that drifted (the camera was knocked),
a wrong rig entry. For every message of every camera, each reference head (a confirmed track
carried to the message's capture time with its velocity, or with --truth the GROUND_TRUTH head)
that projects into the picture is paired with the camera's nearest detection within --radius
pixels. Printed per camera: heads in the picture, the share paired, the median distance, the
mean offset (a bias: where the camera's points lie relative to the heads), the 90th percentile
and the share beyond 10 px. A camera whose median is over three times the others' is flagged.

The tracks are the tracker's own estimates: a camera that pulls them toward its wrong points
looks better than it is, and with fewer than three other cameras the tracks follow it. The
ground truth (--truth, simulated or labelled logs) has no such bias.

    tools/mvtrack residuals --rig RIG.yaml --detections DET.lcm --tracks TRACKS.lcm [--plot FILE.png]
    tools/mvtrack residuals --rig RIG.yaml --detections SCENE.lcm --truth [--tracks SCENE.lcm]
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass

import numpy as np

from .lcmio import mt, read_log
from .mot import nearest_time
from .rig import Rig

CONFIRMED = 2


@dataclass
class CameraResiduals:
    camera: str
    messages: int
    heads: int            # reference heads in the camera's picture
    paired: int           # ... with a detection within the radius
    median_px: float      # median distance, detection to head
    mean_du_px: float     # mean offset (detection minus head): the camera's bias
    mean_dv_px: float
    p90_px: float
    beyond_10px: float    # share of the paired beyond 10 px
    flagged: bool = False


def reference_heads(log, truth: bool) -> tuple[np.ndarray, list]:
    """Sorted utimes and, per utime, (positions (n, 3), velocities (n, 3))."""
    if truth:
        us = sorted(log.gt)
        return np.array(us, np.int64), [(log.gt[u][1], np.zeros_like(log.gt[u][1])) for u in us]
    us = sorted(log.tracks)
    refs = []
    for u in us:
        ts = [t for t in log.tracks[u] if t.status == CONFIRMED]
        refs.append((np.array([t.position for t in ts], float).reshape(-1, 3),
                     np.array([t.velocity for t in ts], float).reshape(-1, 3)))
    return np.array(us, np.int64), refs


def residuals(rig: Rig, detections_path: str, ref_log, truth: bool, radius_px: float = 80.0,
              max_dt_us: int | None = None) -> tuple[list[CameraResiduals], dict[str, np.ndarray]]:
    """The per-camera summary and each camera's paired offsets (n, 2) in pixels."""
    import lcm

    us, refs = reference_heads(ref_log, truth)
    if max_dt_us is None:
        max_dt_us = int(0.5e6 / rig.frame_rate)
    names = [c.name for c in rig.cameras]
    offsets: dict[str, list] = {n: [] for n in names}
    heads = dict.fromkeys(names, 0)
    messages = dict.fromkeys(names, 0)
    for ev in lcm.EventLog(detections_path, "r"):
        if not ev.channel.startswith("DETECTIONS_"):
            continue
        try:
            m = mt.camera_frame_t.decode(ev.data)
        except ValueError:
            continue
        if m.camera not in names or len(us) == 0:
            continue
        cam = rig.cameras[names.index(m.camera)]
        messages[m.camera] += 1
        j = nearest_time(us, int(m.utime))
        if abs(int(us[j]) - int(m.utime)) > max_dt_us:
            continue
        pos, vel = refs[j]
        if not len(pos):
            continue
        uv = cam.project(pos + (int(m.utime) - int(us[j])) * 1e-6 * vel)
        inside = np.isfinite(uv).all(axis=1) & cam.in_image(np.nan_to_num(uv, nan=-1e9))
        det = np.array([[d.u, d.v] for d in m.detections], float).reshape(-1, 2)
        det = det[np.isfinite(det).all(axis=1)]
        for h in uv[inside]:
            heads[m.camera] += 1
            if not len(det):
                continue
            dd = np.hypot(det[:, 0] - h[0], det[:, 1] - h[1])
            k = int(np.argmin(dd))
            if dd[k] <= radius_px:
                offsets[m.camera].append(det[k] - h)
    out, arrays = [], {}
    for n in names:
        a = np.array(offsets[n], float).reshape(-1, 2)
        arrays[n] = a
        r = np.hypot(a[:, 0], a[:, 1])
        nan = float("nan")
        out.append(CameraResiduals(n, messages[n], heads[n], len(a),
                                   float(np.median(r)) if len(r) else nan,
                                   float(a[:, 0].mean()) if len(a) else nan, float(a[:, 1].mean()) if len(a) else nan,
                                   float(np.percentile(r, 90)) if len(r) else nan,
                                   float((r > 10.0).mean()) if len(r) else nan))
    for c in out:
        others = [o.median_px for o in out if o is not c and np.isfinite(o.median_px)]
        c.flagged = bool(others) and np.isfinite(c.median_px) and c.median_px > 3.0 * float(np.median(others))
    return out, arrays


def plot(path: str, res: list[CameraResiduals], arrays: dict[str, np.ndarray], radius_px: float) -> None:
    from .plots import plt

    n = len(res)
    fig, axes = plt.subplots(1, n, figsize=(3.0 * n, 3.3), squeeze=False)
    lim = radius_px
    for ax, c in zip(axes[0], res):
        a = arrays[c.camera]
        ax.scatter(a[:, 0], a[:, 1], s=2, alpha=0.3, color="tab:red" if c.flagged else "tab:blue")
        ax.add_patch(plt.Circle((0, 0), 10.0, fill=False, ls="--", color="0.4"))
        ax.axhline(0, color="0.8", lw=0.5)
        ax.axvline(0, color="0.8", lw=0.5)
        ax.set_xlim(-lim, lim)
        ax.set_ylim(lim, -lim)  # image v grows downward
        ax.set_aspect("equal")
        ax.set_title(f"{c.camera}: median {c.median_px:.1f} px" + (" (flagged)" if c.flagged else ""), fontsize=8)
        ax.set_xlabel("du px (detection - head)", fontsize=7)
    axes[0][0].set_ylabel("dv px", fontsize=7)
    fig.suptitle("Detections around the heads (dashed: 10 px)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack residuals", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rig", required=True, help="rig file (cv::FileStorage YAML, docs/interfaces.md section 2)")
    ap.add_argument("--detections", required=True, help="log with DETECTIONS_<camera> messages")
    ap.add_argument("--tracks", help="log with TRACKS (or with GROUND_TRUTH for --truth; default: --detections)")
    ap.add_argument("--truth", action="store_true", help="pair with the GROUND_TRUTH heads instead of the tracks")
    ap.add_argument("--radius", type=float, default=80.0, help="largest pairing distance, px (default 80)")
    ap.add_argument("--plot", help="write a PNG of each camera's offsets")
    ap.add_argument("--json", action="store_true", help="print JSON instead of a table")
    a = ap.parse_args(argv)
    if not a.radius > 0:
        ap.error("--radius must be > 0")
    try:
        rig = Rig.read(a.rig)
    except Exception as e:  # noqa: BLE001 - any unreadable rig is the user's input error
        ap.error(f"cannot read the rig {a.rig}: {e}")
    ref_path = a.tracks or a.detections
    try:
        ref = read_log(ref_path, lambda c: c == ("GROUND_TRUTH" if a.truth else "TRACKS"))
    except (OSError, ValueError) as e:
        ap.error(f"cannot read {ref_path}: {e}")
    if (a.truth and not ref.gt) or (not a.truth and not ref.tracks):
        ap.error(f"{ref_path} holds no {'GROUND_TRUTH' if a.truth else 'TRACKS'}")
    try:
        res, arrays = residuals(rig, a.detections, ref, a.truth, a.radius)
    except (OSError, ValueError) as e:
        ap.error(f"cannot read {a.detections}: {e}")
    if not any(c.messages for c in res):
        ap.error(f"{a.detections} holds no DETECTIONS_<camera> message of the rig's cameras")
    if a.plot:
        plot(a.plot, res, arrays, a.radius)
    if a.json:
        json.dump([asdict(c) for c in res], sys.stdout, indent=1)
        print()
        return 0
    ref_name = "ground-truth heads" if a.truth else "confirmed tracks"
    print(f"detections against the {ref_name}, paired within {a.radius:g} px")
    print(f"{'camera':12s} {'messages':>8s} {'heads':>7s} {'paired':>7s} {'median':>7s} {'mean du':>8s} "
          f"{'mean dv':>8s} {'p90':>6s} {'>10px':>6s}")
    for c in res:
        print(f"{c.camera:12s} {c.messages:8d} {c.heads:7d} {c.paired:7d} {c.median_px:7.1f} {c.mean_du_px:8.1f} "
              f"{c.mean_dv_px:8.1f} {c.p90_px:6.1f} {100 * c.beyond_10px:5.0f}%" + ("  <- flagged" if c.flagged else ""))
    for c in res:
        if c.flagged:
            print(f"{c.camera}: its points lie {c.median_px:.1f} px (median) from the heads, over three times the "
                  f"other cameras'; check its calibration and what its detector reports as the head")
    if a.plot:
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
