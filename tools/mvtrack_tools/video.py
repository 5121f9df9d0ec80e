"""Rendered multi-view video: the simulator's scenes as the RGB video each camera of a rig would
record, for the detector (mvtrack-detect) and the whole pixels-to-tracks chain.

Every pixel is a ray through the camera's real lens model (cv2.undistortPoints on the rig's
distortion), so straight walls bend as they do in the camera. The scene:

- a textured room: tiled floor with grout and wear, walls of several paints with skirting, doors
  and posters, a ceiling; furniture (a tall cabinet and a table, render.default_furniture) that
  hides people; Lambert shading from a ceiling light;
- people: head (skin, hair), a torso of two capsules, two arms and two legs that swing with a
  walking gait (stride from the walking speed, heading from the velocity); distinct clothing from a
  palette that includes colours close to the floor and walls (real segmentation fragments there),
  some striped; the tracked point is the head top, as in the ground truth;
- soft shadows on the floor away from the light;
- the camera: slow illumination drift and frame-to-frame flicker (per camera), vignetting,
  Gaussian sensor noise, and lossy compression (MJPEG in AVI through cv2.VideoWriter, quality
  `jpeg_quality`).

Each video starts with `lead_in_s` of the empty room (as a detector running continuously has seen
it): video frame i is scene frame i - lead. Capture jitter comes from the scene's DetectorModel (each camera's frame is the scene at a
slightly different time); cameras never drop out here (a video file has every frame).

Output: one `<camera>.avi` per rig camera, and GROUND_TRUTH messages (head tops) in an LCM log.
Cameras render in parallel processes.
"""
from __future__ import annotations

import colorsys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .progress import bar as progress_bar
from .crowd import Scene
from .render import Box, default_furniture
from .rig import Camera, Rig

LIGHT_DIR = np.array([0.25, 0.15, 1.0]) / np.linalg.norm([0.25, 0.15, 1.0])


@dataclass
class VideoModel:
    noise_dn: float = 2.5          # sensor noise, 1 sigma, in 8-bit levels
    drift: float = 0.06            # illumination drift amplitude (relative gain)
    drift_period_s: float = 31.0
    flicker: float = 0.012         # frame-to-frame gain jitter (relative, 1 sigma)
    vignette: float = 0.25         # brightness loss at the image corners
    jpeg_quality: int = 80
    shadows: bool = True
    lead_in_s: float = 2.0         # empty room before the scene's frame 0 (the background model's start)


def _hsv(h: float, s: float, v: float) -> np.ndarray:
    return np.array(colorsys.hsv_to_rgb(h % 1.0, s, v), np.float32)


# clothing: shirt, trousers, hair, striped shirt. Several are close to the room's floor and walls.
CLOTHES = [(_hsv(0.0, 0.75, 0.75), _hsv(0.62, 0.55, 0.35), _hsv(0.08, 0.6, 0.15), False),
           (_hsv(0.33, 0.55, 0.55), _hsv(0.0, 0.0, 0.55), _hsv(0.1, 0.5, 0.35), True),    # grey trousers ~ floor
           (_hsv(0.6, 0.65, 0.6), _hsv(0.08, 0.35, 0.25), _hsv(0.12, 0.5, 0.7), False),
           (_hsv(0.11, 0.25, 0.8), _hsv(0.6, 0.5, 0.25), _hsv(0.05, 0.4, 0.2), False),   # beige shirt ~ walls
           (_hsv(0.8, 0.45, 0.55), _hsv(0.0, 0.0, 0.15), _hsv(0.0, 0.0, 0.1), True),
           (_hsv(0.5, 0.5, 0.55), _hsv(0.1, 0.45, 0.45), _hsv(0.07, 0.6, 0.25), False),
           (_hsv(0.95, 0.5, 0.7), _hsv(0.6, 0.2, 0.5), _hsv(0.1, 0.3, 0.5), False),
           (_hsv(0.15, 0.8, 0.8), _hsv(0.0, 0.0, 0.25), _hsv(0.06, 0.5, 0.3), True)]
SKIN = _hsv(0.06, 0.45, 0.75)


def _capsule(C, D, A, B, r):
    """Ray parameter of the first hit on the capsule A-B of radius r (inf if none), vectorised over
    the rays D (N, 3) from C."""
    ba = B - A
    oa = C - A
    baba = ba @ ba
    bard = D @ ba
    baoa = oa @ ba
    rdoa = D @ oa
    oaoa = oa @ oa
    a = baba - bard * bard
    b = baba * rdoa - baoa * bard
    c = baba * oaoa - baoa * baoa - r * r * baba
    h = b * b - a * c
    t = np.full(len(D), np.inf, np.float32)
    ok = h >= 0
    with np.errstate(divide="ignore", invalid="ignore"):
        tb = (-b - np.sqrt(np.where(ok, h, 0))) / a
    y = baoa + tb * bard
    body = ok & (y > 0) & (y < baba) & (tb > 0)
    t[body] = tb[body]
    # end caps: spheres at A and B
    for P in (A, B):
        oc = C - P
        bb = D @ oc
        cc = oc @ oc - r * r
        hh = bb * bb - cc
        ts = -bb - np.sqrt(np.maximum(hh, 0))
        cap = (hh >= 0) & (ts > 0) & (ts < t)
        t[cap] = ts[cap]
    return t


def _sphere(C, D, S, r):
    o = C - S
    b = D @ o
    c = o @ o - r * r
    h = b * b - c
    t = -b - np.sqrt(np.maximum(h, 0))
    return np.where((h >= 0) & (t > 0), t, np.inf).astype(np.float32)


def _segment_point(P, A, B):
    ba = B - A
    s = np.clip(((P - A) @ ba) / max(ba @ ba, 1e-12), 0, 1)
    return A + s[:, None] * ba


@dataclass
class Pose:
    gid: int
    head: np.ndarray      # head top (x, y, h)
    heading: float        # radians, walking direction
    phase: float          # gait phase, radians
    stride: float         # foot swing amplitude, metres
    clothes: int


def poses(scene: Scene, f: int, offset_s: float, clothes: dict[int, int], gait: dict) -> list[Pose]:
    out = []
    for p in scene.present(f):
        i = f - p.f0
        head, heading, phase, speed = gait[p.gid]
        pos = p.pos[i] + p.vel[i] * offset_s
        out.append(Pose(p.gid, pos, float(heading[i]), float(phase[i]), 0.28 * min(float(speed[i]) / 1.1, 1.0),
                        clothes[p.gid]))
    return out


def gait_tables(scene: Scene, dt: float) -> dict:
    """Per person: heading (held while standing), gait phase (from the distance walked) and speed."""
    out = {}
    for p in scene.people:
        v = p.vel[:, :2]
        speed = np.linalg.norm(v, axis=1)
        heading = np.zeros(len(v))
        h = float(np.arctan2(v[0, 1], v[0, 0])) if len(v) else 0.0
        for i in range(len(v)):
            if speed[i] > 0.15:
                h = float(np.arctan2(v[i, 1], v[i, 0]))
            heading[i] = h
        stride_len = 1.3  # metres per gait cycle
        phase = 2 * np.pi * np.cumsum(speed * dt) / stride_len
        out[p.gid] = (p.pos, heading, phase, speed)
    return out


class RoomView:
    """One camera's static view: rays, the background image (linear RGB in [0, 1]), its depth, and
    the floor coordinates where the floor is what the pixel sees."""

    def __init__(self, cam: Camera, rig: Rig, furniture: list[Box], seed: int):
        self.cam = cam
        w, h = cam.width, cam.height
        uu, vv = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        pts = np.stack([uu.ravel(), vv.ravel()], 1).reshape(-1, 1, 2)
        xn = cv2.undistortPointsIter(pts, cam.K, cam.dist, None, None,
                                     (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-9)).reshape(-1, 2)
        d = np.concatenate([xn, np.ones((len(xn), 1))], 1) @ cam.R
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        self.rays = d.astype(np.float32)                       # (h*w, 3)
        self.C = cam.centre.astype(np.float32)
        lo = np.asarray(rig.volume_min, float) - 0.3
        hi = np.asarray(rig.volume_max, float) + 0.3
        hi[2] = max(float(max(c.centre[2] for c in rig.cameras)) + 0.3, 2.6)
        lo[2] = 0.0
        self.room_lo, self.room_hi = lo, hi
        rng = np.random.default_rng(seed)
        t, rgb = self._room(rng)
        for bi, b in enumerate(furniture):
            tb, nb = self._box(b)
            near = tb < t
            t[near] = tb[near]
            base = _hsv(0.08, 0.45, 0.45) if bi % 2 == 0 else _hsv(0.0, 0.0, 0.6)
            grain = self._noise_at(rng, (self.C + tb[near, None] * self.rays[near])[:, :2].sum(1), 0.05)
            rgb[near] = base * (0.85 + 0.15 * grain[:, None]) * self._shade(nb[near])[:, None]
        self.depth = t.astype(np.float32)
        P = self.C + self.depth[:, None] * self.rays
        self.floor = P[:, 2] < 1e-3
        self.floor_xy = P[:, :2].astype(np.float32)
        self.background = rgb.astype(np.float32)
        yy, xx = np.mgrid[0:h, 0:w]
        self.r2 = (((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)).ravel()

    def _shade(self, n: np.ndarray) -> np.ndarray:
        return 0.55 + 0.45 * np.clip(n @ LIGHT_DIR, 0, 1)

    @staticmethod
    def _noise_at(rng, coord: np.ndarray, scale: float) -> np.ndarray:
        """Smooth random texture in [0, 1] along a 1D coordinate (cheap surface grain)."""
        table = rng.uniform(0, 1, 4096)
        x = (coord / scale) % 4095
        i = x.astype(int)
        f = x - i
        return table[i] * (1 - f) + table[i + 1] * f

    def _box(self, b: Box):
        D, C = self.rays, self.C
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = (b.lo - C) / D
            t1 = (b.hi - C) / D
        tmin3 = np.minimum(t0, t1)
        tmin = np.nanmax(tmin3, axis=1)
        tmax = np.nanmin(np.maximum(t0, t1), axis=1)
        hit = (tmax >= np.maximum(tmin, 0)) & (tmin > 0)
        axis = np.nanargmax(tmin3, axis=1)
        n = np.zeros_like(D)
        n[np.arange(len(D)), axis] = -np.sign(D[np.arange(len(D)), axis])
        return np.where(hit, tmin, np.inf), n

    def _room(self, rng):
        D, C = self.rays, self.C
        lo, hi = self.room_lo, self.room_hi
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = np.stack([(lo[0] - C[0]) / D[:, 0], (hi[0] - C[0]) / D[:, 0], (lo[1] - C[1]) / D[:, 1],
                           (hi[1] - C[1]) / D[:, 1], (lo[2] - C[2]) / D[:, 2], (hi[2] - C[2]) / D[:, 2]], 1)
        tt[~(tt > 0)] = np.inf
        face = np.argmin(tt, axis=1)
        t = tt[np.arange(len(D)), face]
        P = C + t[:, None] * D
        rgb = np.zeros((len(D), 3), np.float32)
        paints = [_hsv(rng.uniform(0.05, 0.15), rng.uniform(0.1, 0.3), rng.uniform(0.75, 0.9)),
                  _hsv(rng.uniform(0.5, 0.65), rng.uniform(0.05, 0.2), rng.uniform(0.7, 0.85)),
                  _hsv(rng.uniform(0.0, 1.0), rng.uniform(0.1, 0.35), rng.uniform(0.65, 0.85)),
                  _hsv(rng.uniform(0.05, 0.15), rng.uniform(0.05, 0.15), rng.uniform(0.8, 0.9))]
        # floor: 0.5 m tiles, two tones, grout lines, wear
        fl = face == 4
        x, y = P[fl, 0], P[fl, 1]
        tile = (np.floor(x / 0.5) + np.floor(y / 0.5)) % 2
        grout = (np.abs(x / 0.5 - np.round(x / 0.5)) < 0.02) | (np.abs(y / 0.5 - np.round(y / 0.5)) < 0.02)
        wear = self._noise_at(rng, x * 3.1 + y * 7.3, 0.07)
        floor_a = _hsv(rng.uniform(0.05, 0.12), rng.uniform(0.05, 0.2), rng.uniform(0.5, 0.6))
        c = floor_a * (0.9 + 0.1 * tile[:, None]) * (0.9 + 0.2 * wear[:, None])
        c[grout] *= 0.6
        rgb[fl] = c
        # walls: paint, skirting, a door in the middle of each wall, posters
        for wi, f in enumerate((0, 1, 2, 3)):
            m = face == f
            along = P[m, 1] if f < 2 else P[m, 0]
            z = P[m, 2]
            mid = 0.5 * ((lo[1] + hi[1]) if f < 2 else (lo[0] + hi[0]))
            c = np.tile(paints[wi], (m.sum(), 1)) * (0.95 + 0.1 * self._noise_at(rng, along * 5 + z * 11, 0.03))[:, None]
            door = (np.abs(along - mid) < 0.45) & (z < 2.05)
            c[door] = _hsv(0.07, 0.55, 0.4) * (0.9 + 0.1 * self._noise_at(rng, z[door] * 40, 0.02))[:, None]
            c[z < 0.1] = _hsv(0.0, 0.0, 0.3)
            for _ in range(2):
                pc = mid + rng.choice([-1, 1]) * rng.uniform(1.0, 2.0)
                pz = rng.uniform(1.2, 1.7)
                poster = (np.abs(along - pc) < 0.3) & (np.abs(z - pz) < 0.4)
                c[poster] = _hsv(rng.uniform(), rng.uniform(0.4, 0.9), rng.uniform(0.4, 0.9))
            normal = np.zeros(3)
            normal[f // 2] = 1.0 if f % 2 == 0 else -1.0
            rgb[m] = c * float(0.55 + 0.45 * max(0.0, normal @ LIGHT_DIR) + 0.2)
        ce = face == 5
        rgb[ce] = _hsv(0.1, 0.03, 0.92)
        return t.astype(np.float64), rgb

    def bbox(self, pts: np.ndarray) -> tuple[int, int, int, int] | None:
        cam = self.cam
        if np.any(cam.depth(pts) <= 0.05):
            return None
        uv = cam.project(pts)
        if not np.all(np.isfinite(uv)):  # partly beyond the lens model's field: cast the whole image
            return 0, 0, cam.width, cam.height
        x0, y0 = np.floor(uv.min(0)).astype(int) - 6
        x1, y1 = np.ceil(uv.max(0)).astype(int) + 6
        x0, y0 = max(x0, 0), max(y0, 0)
        x1, y1 = min(x1, cam.width), min(y1, cam.height)
        if x0 >= x1 or y0 >= y1:
            return None
        return x0, y0, x1, y1


def _body(pose: Pose):
    """Primitives of one person: (kind, params, colour role). Kinds: 's' sphere, 'c' capsule."""
    x, y, h = (float(v) for v in pose.head)
    fwd = np.array([np.cos(pose.heading), np.sin(pose.heading), 0.0])
    lat = np.array([-fwd[1], fwd[0], 0.0])
    base = np.array([x, y, 0.0])
    hip, sh = 0.52 * h, h - 0.27
    swing = pose.stride * np.sin(pose.phase)
    z = np.array([0.0, 0.0, 1.0])
    prims = [("s", (base + z * (h - 0.105), 0.105), "head")]
    for s in (-1, 1):
        prims.append(("c", (base + s * 0.065 * lat + z * (hip + 0.1), base + s * 0.065 * lat + z * (sh - 0.03), 0.125),
                      "shirt"))
        foot = base + s * 0.09 * lat + fwd * (s * swing) + z * 0.06
        prims.append(("c", (base + s * 0.09 * lat + z * hip, foot, 0.07), "trousers"))
        hand = base + s * 0.23 * lat - fwd * (0.7 * s * swing) + z * (hip - 0.02)
        prims.append(("c", (base + s * 0.2 * lat + z * (sh - 0.02), hand, 0.045), "shirt"))
    prims.append(("c", (base + z * (sh + 0.02), base + z * (h - 0.2), 0.05), "skin"))
    return prims


class VideoRenderer:
    def __init__(self, rig: Rig, seed: int, model: VideoModel | None = None, furniture: list[Box] | None = None):
        self.rig = rig
        self.m = model or VideoModel()
        self.furniture = default_furniture(rig) if furniture is None else furniture
        self.seed = seed

    def camera(self, k: int) -> "CameraRenderer":
        return CameraRenderer(self, k)


class CameraRenderer:
    def __init__(self, parent: VideoRenderer, k: int):
        self.m = parent.m
        self.rig = parent.rig
        self.view = RoomView(parent.rig.cameras[k], parent.rig, parent.furniture, parent.seed * 31 + 5)
        self.rng = np.random.default_rng(parent.seed * 1009 + k)
        cam = self.view.cam
        self.noise = []  # (positive, negative) parts of Gaussian noise frames, uint8, added with saturation
        for _ in range(6):
            nz = np.round(self.rng.normal(0, self.m.noise_dn, (cam.height, cam.width, 3)))
            self.noise.append((np.clip(nz, 0, 255).astype(np.uint8), np.clip(-nz, 0, 255).astype(np.uint8)))
        self.phase = self.rng.uniform(0, 2 * np.pi)
        # BGR, in 8-bit levels, vignetted: the frame is this times the illumination gain
        self.vig = (255.0 * (1.0 - self.m.vignette * self.view.r2)).astype(np.float32).reshape(-1, 1)
        self.bg = np.ascontiguousarray(self.view.background[:, ::-1] * self.vig)

    def frame(self, people: list[Pose], t_s: float) -> np.ndarray:
        """One BGR uint8 frame."""
        v, m = self.view, self.m
        cam = v.cam
        W, H = cam.width, cam.height
        img = self.bg.copy()
        depth = v.depth.copy()
        if m.shadows:
            for p in people:
                x, y = float(p.head[0]), float(p.head[1])
                away = np.array([x, y]) - 0.5 * (v.room_lo[:2] + v.room_hi[:2])
                away = away / max(np.linalg.norm(away), 1e-6)
                cx, cy = x + 0.18 * away[0], y + 0.18 * away[1]
                ring = np.array([[cx + 0.6 * np.cos(a), cy + 0.6 * np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 12)])
                bb = v.bbox(ring)
                if bb is None:
                    continue
                x0, y0, x1, y1 = bb
                idx = (np.arange(y0, y1)[:, None] * W + np.arange(x0, x1)[None, :]).ravel()
                fl = idx[v.floor[idx]]
                if not len(fl):
                    continue
                q = v.floor_xy[fl] - np.array([cx, cy], np.float32)
                along = q @ away.astype(np.float32)
                across = q @ np.array([-away[1], away[0]], np.float32)
                d2 = (along / 0.42) ** 2 + (across / 0.28) ** 2
                img[fl] *= (1.0 - 0.45 * np.exp(-1.5 * d2))[:, None]
        for p in people:  # z-buffered, one primitive at a time over its own projected box
            shirt, trousers, hair, striped = CLOTHES[p.clothes % len(CLOTHES)]
            fwd = np.array([np.cos(p.heading), np.sin(p.heading), 0.0], np.float32)
            for kind, par, role in _body(p):
                if kind == "s":
                    S, r = par
                    lo_, hi_ = S - r, S + r
                else:
                    A, B, r = par
                    lo_, hi_ = np.minimum(A, B) - r, np.maximum(A, B) + r
                corners = np.array([[a, b, c] for a in (lo_[0], hi_[0]) for b in (lo_[1], hi_[1])
                                    for c in (lo_[2], hi_[2])])
                bb = v.bbox(corners)
                if bb is None:
                    continue
                x0, y0, x1, y1 = bb
                idx = (np.arange(y0, y1)[:, None] * W + np.arange(x0, x1)[None, :]).ravel()
                D = v.rays[idx]
                t = _sphere(v.C, D, *par) if kind == "s" else _capsule(v.C, D, *par)
                near = t < depth[idx]
                if not near.any():
                    continue
                sel, tb = idx[near], t[near]
                P = v.C + tb[:, None] * D[near]
                if kind == "s":
                    n = (P - par[0]) / par[1]
                    c = np.tile(SKIN, (len(sel), 1))
                    c[(n[:, 2] > 0.25) | (n @ fwd < -0.2)] = hair
                else:
                    n = (P - _segment_point(P, A, B)) / r
                    c = np.tile({"shirt": shirt, "trousers": trousers, "skin": SKIN}[role], (len(sel), 1))
                    if role == "shirt" and striped:
                        c *= (0.75 + 0.25 * (np.sin(P[:, 2] * 45.0) > 0))[:, None]
                shade = 0.5 + 0.5 * np.clip(n @ LIGHT_DIR, 0, 1)
                img[sel] = c[:, ::-1] * (shade[:, None] * self.vig[sel]).astype(np.float32)
                depth[sel] = tb
        gain = 1.0 + m.drift * np.sin(2 * np.pi * t_s / m.drift_period_s + self.phase) \
            + m.flicker * float(self.rng.normal())
        out = cv2.convertScaleAbs(img.reshape(H, W, 3), alpha=float(gain))
        pos, neg = self.noise[int(self.rng.integers(len(self.noise)))]
        return cv2.subtract(cv2.add(out, pos), neg)


def _render_camera(args) -> dict:
    rig, scene, k, seed, out_dir, model, progress_q = args
    import time

    cam = rig.cameras[k]
    r = VideoRenderer(rig, seed, model).camera(k)
    path = Path(out_dir) / f"{cam.name}.avi"
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), rig.frame_rate, (cam.width, cam.height))
    if not wr.isOpened():
        raise RuntimeError(f"cv2.VideoWriter cannot write MJPEG to {path}")
    wr.set(cv2.VIDEOWRITER_PROP_QUALITY, model.jpeg_quality)
    dt = 1.0 / rig.frame_rate
    clothes = {p.gid: i for i, p in enumerate(sorted(scene.people, key=lambda p: p.gid))}
    gait = gait_tables(scene, dt)
    rng = np.random.default_rng(seed * 7 + k)
    t0 = time.perf_counter()
    lead = lead_in_frames(rig, model)
    for f in range(-lead, 0):
        wr.write(r.frame([], f * dt))
    for f in range(scene.n_frames):
        off = rng.uniform(-scene.model.jitter_ms, scene.model.jitter_ms) * 1e-3 if scene.model.jitter_ms > 0 else 0.0
        wr.write(r.frame(poses(scene, f, off, clothes, gait), f * dt + off))
        if progress_q is not None and f % 10 == 9:
            progress_q.put(10)
    wr.release()
    return {"camera": cam.name, "path": str(path), "frames": scene.n_frames, "lead_in_frames": lead,
            "render_ms_per_frame": 1e3 * (time.perf_counter() - t0) / max(scene.n_frames, 1)}


def lead_in_frames(rig: Rig, model: VideoModel) -> int:
    """Frames of empty room before the scene: video frame i shows scene frame i - lead_in_frames."""
    return int(round(model.lead_in_s * rig.frame_rate))


def write_video(out_dir: Path, scene: Scene, seed: int, model: VideoModel | None = None, jobs: int = 2,
                progress: bool = True) -> list[dict]:
    """Renders every camera of scene.rig to out_dir/<camera>.avi (in `jobs` processes)."""
    import multiprocessing as mp

    
    model = model or VideoModel()
    out_dir.mkdir(parents=True, exist_ok=True)
    rig = scene.rig
    ctx = mp.get_context("fork")
    with ctx.Manager() as mgr:
        q = mgr.Queue() if progress else None
        with ctx.Pool(max(1, jobs)) as pool:
            res = pool.map_async(_render_camera, [(rig, scene, k, seed, out_dir, model, q) for k in range(len(rig.cameras))])
            total = scene.n_frames * len(rig.cameras)
            with progress_bar(total=total, desc="render video", unit="fr", enabled=progress, leave=False) as bar:
                while not res.ready():
                    res.wait(0.5)
                    while q is not None and not q.empty():
                        bar.update(q.get())
            return res.get()


def write_truth(sink, scene: Scene) -> None:
    """GROUND_TRUTH at each frame's nominal time (the detector stamps frame i the same way)."""
    from .lcmio import ground_truth
    from .simulate import T0_UTIME

    dt_us = int(round(1e6 / scene.rig.frame_rate))
    for f in range(scene.n_frames):
        utime = T0_UTIME + f * dt_us
        present = scene.present(f)
        pos = np.array([p.pos[f - p.f0] for p in present]).reshape(-1, 3)
        sink.write(utime, "GROUND_TRUTH", ground_truth(utime, f, [p.gid for p in present], pos))
