"""Rendering people as coloured 3D bodies: motion masks, hue/saturation images and the blob
detections a real detector would derive from them (the input of the particle-filter mode).

Each person is three solids under the head-top point (x, y, h): a head sphere (radius 0.11 m),
a torso cylinder (radius 0.19 m, from 0.52 h to h - 0.22 m, shoulders as its top cap) and a legs
cylinder (radius 0.14 m, floor to 0.52 h), coloured skin / shirt / trousers. Static furniture
(boxes) stands in the room. Per camera the renderer casts one ray per mask pixel (through
OpenCV's lens model, cv2.undistortPoints) and keeps the nearest hit; a person's solids are
tested only on the rays of their footprint (Renderer.footprint), where every hit on them lies.

The motion-segmentation mask is what a background subtractor gives, not the true silhouette:
- furniture in front of a person hides them (it is static: never foreground);
- holes: low-frequency noise removes `hole_frac` of the body's pixels (fragmented blobs);
- fragmentation model (`fragments`): "holes" (only the holes above), "rows" (also: each camera
  loses the body's pixels on a few fixed bands of image rows, as where a railing or a wall stripe
  the colour of the clothes crosses the picture: every body is cut at the same rows), or
  "camouflage" (also: a person's trousers or shirt, chosen per person, match the background and
  are never foreground: a head over legs with nothing between, or a head and torso without legs);
- a soft shadow on the floor next to the feet is foreground (grey, unsaturated);
- speckle: `speckle` of the background pixels flip to foreground;
- clutter: Poisson(`clutter_rate`) small blobs per camera and frame (reflections, a moving chair).
Hue and saturation carry Gaussian noise; the background has its own texture.

Detections: connected components (8-connected, after a 3x3 closing) of at least `min_area` mask
pixels; the reported point is the top of the component (the head, as the PKF paper's detector),
its hue/saturation the circular mean over the component. Merged blobs, misses (a body cut by
holes or furniture) and false alarms (clutter) come out of the pixels, not from dice.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from .progress import bar as progress_bar
from .rig import Camera, Rig

HEAD_R, TORSO_R, LEGS_R = 0.11, 0.19, 0.14
SKIN = (0.06, 0.40)

# clearly different clothing (hue, saturation): shirt, trousers
PALETTE = [((0.00, 0.75), (0.62, 0.55)), ((0.33, 0.65), (0.08, 0.55)), ((0.60, 0.70), (0.00, 0.05)),
           ((0.15, 0.80), (0.70, 0.45)), ((0.80, 0.55), (0.45, 0.50)), ((0.50, 0.60), (0.95, 0.50)),
           ((0.90, 0.65), (0.25, 0.45)), ((0.70, 0.70), (0.12, 0.30))]


@dataclass
class Box:
    lo: np.ndarray
    hi: np.ndarray


@dataclass
class MaskModel:
    scale: int = 4               # image pixels per mask pixel
    hole_frac: float = 0.08      # fraction of body pixels lost to holes
    speckle: float = 0.0005      # background pixels flipped to foreground
    clutter_rate: float = 0.3    # clutter blobs per camera and frame
    shadow: bool = True
    hue_noise: float = 0.015
    sat_noise: float = 0.04
    min_area: int = 12           # mask pixels for a detection
    fragments: str = "holes"     # holes | rows | camouflage (see the module's text)


def default_furniture(rig: Rig) -> list[Box]:
    """A cabinet against one wall and a table in a corner of the volume."""
    lo, hi = np.asarray(rig.volume_min, float), np.asarray(rig.volume_max, float)
    L, W = hi[0] - lo[0], hi[1] - lo[1]
    cab = Box(np.array([lo[0] + 0.45 * L, hi[1] - 0.45, 0.0]), np.array([lo[0] + 0.45 * L + 0.9, hi[1] - 0.05, 1.8]))
    table = Box(np.array([lo[0] + 0.1, lo[1] + 0.1, 0.0]), np.array([lo[0] + 1.1, lo[1] + 0.8, 0.75]))
    return [cab, table]


def _rays(cam: Camera, scale: int) -> np.ndarray:
    """Unit world directions (Hm, Wm, 3) through the centres of the mask pixels."""
    wm, hm = cam.width // scale, cam.height // scale
    u = (np.arange(wm) * scale + (scale - 1) / 2.0).astype(np.float64)
    v = (np.arange(hm) * scale + (scale - 1) / 2.0).astype(np.float64)
    uu, vv = np.meshgrid(u, v)
    pts = np.stack([uu.ravel(), vv.ravel()], 1).reshape(-1, 1, 2)
    xn = cv2.undistortPointsIter(pts, cam.K, cam.dist, None, None,
                                 (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-9)).reshape(-1, 2)
    d = np.concatenate([xn, np.ones((len(xn), 1))], 1) @ cam.R  # R^T x, row-wise
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d.reshape(hm, wm, 3)


# points over a person's bounding cylinder, as (cos, sin, height / h): 24 bearings at 9 heights
_RIM = np.array([(np.cos(a), np.sin(a), z) for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)
                 for z in np.linspace(0, 1, 9)])


def _footprint_margin(cam: Camera, D: np.ndarray, scale: int) -> int | None:
    """Mask pixels to widen a projected footprint by in this camera: two, plus how far (in mask
    pixels) a mask pixel's ray projects from that pixel's centre (the fixed-point inverse lens
    leaves the corners of a strong lens off). None when that is over two mask pixels anywhere or a
    ray is outside the lens's field: then every person is cast over the whole picture."""
    hm, wm = D.shape[:2]
    uv = cam.project(cam.centre + D.reshape(-1, 3))
    if not np.isfinite(uv).all():
        return None
    jj, ii = np.meshgrid(np.arange(wm), np.arange(hm))
    centre = np.column_stack([jj.ravel(), ii.ravel()]) * scale + (scale - 1) / 2.0
    err = float(np.abs(uv - centre).max()) / scale
    return None if err > 2.0 else 2 + int(np.ceil(err))


def _hit_cylinder(C, D, cx, cy, r, z0, z1) -> np.ndarray:
    """Ray parameter of the first hit on a vertical cylinder (side or top cap), inf if none."""
    ox, oy = C[0] - cx, C[1] - cy
    a = D[..., 0] ** 2 + D[..., 1] ** 2
    b = 2 * (D[..., 0] * ox + D[..., 1] * oy)
    c = ox * ox + oy * oy - r * r
    disc = b * b - 4 * a * c
    t = np.full(D.shape[:-1], np.inf)
    ok = disc >= 0
    ts = np.where(ok, (-b - np.sqrt(np.maximum(disc, 0))) / np.maximum(2 * a, 1e-12), np.inf)
    z = C[2] + ts * D[..., 2]
    side = ok & (ts > 0) & (z >= z0) & (z <= z1)
    t[side] = ts[side]
    for zc in (z1, z0):  # caps
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = (zc - C[2]) / D[..., 2]
        px, py = ox + tc * D[..., 0], oy + tc * D[..., 1]
        cap = (tc > 0) & (px * px + py * py <= r * r) & (tc < t)
        t[cap] = tc[cap]
    return t


def _hit_sphere(C, D, centre, r) -> np.ndarray:
    o = C - centre
    b = D @ o
    c = o @ o - r * r
    disc = b * b - c
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    return np.where(t > 0, t, np.inf)


def _hit_box(C, D, box: Box) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / D
        t0 = (box.lo - C) * inv
        t1 = (box.hi - C) * inv
    tmin = np.nanmax(np.minimum(t0, t1), axis=-1)
    tmax = np.nanmin(np.maximum(t0, t1), axis=-1)
    hit = (tmax >= np.maximum(tmin, 0)) & (tmin > 0)
    return np.where(hit, tmin, np.inf)


def encode_runs(mask: np.ndarray) -> np.ndarray:
    """Row-major run lengths alternating background, foreground, ... starting with background."""
    flat = mask.ravel().astype(np.int8)
    change = np.flatnonzero(np.diff(flat)) + 1
    edges = np.concatenate([[0], change, [flat.size]])
    runs = np.diff(edges)
    if flat.size and flat[0]:
        runs = np.concatenate([[0], runs])
    return runs.astype(np.int32)


def decode_runs(runs: np.ndarray, width: int, height: int) -> np.ndarray:
    vals = np.arange(len(runs)) % 2
    return np.repeat(vals, runs).astype(np.uint8).reshape(height, width)


@dataclass
class CameraView:
    mask: np.ndarray        # (Hm, Wm) uint8 0/1
    hue: np.ndarray         # (Hm, Wm) uint8
    sat: np.ndarray         # (Hm, Wm) uint8
    label: np.ndarray       # (Hm, Wm) int: person gid on the true silhouette, 0 elsewhere
    dets: list = field(default_factory=list)  # (u, v, bbox, hue, sat, gid of the top pixel or 0)


class Renderer:
    def __init__(self, rig: Rig, model: MaskModel | None = None, furniture: list[Box] | None = None,
                 seed: int = 1):
        self.rig = rig
        self.m = model or MaskModel()
        self.furniture = default_furniture(rig) if furniture is None else furniture
        rng = np.random.default_rng(seed + 7919)
        self.rays, self.centres, self.static_t, self.bg_h, self.bg_s = [], [], [], [], []
        self.cut_rows: list[np.ndarray] = []
        self.margin: list[int | None] = []
        self.floor: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        for cam in rig.cameras:
            D = _rays(cam, self.m.scale)
            C = cam.centre
            self.margin.append(_footprint_margin(cam, D, self.m.scale))
            with np.errstate(divide="ignore", invalid="ignore"):  # where each ray meets the floor
                tf = -C[2] / D[..., 2]
            self.floor.append((tf, C[0] + tf * D[..., 0], C[1] + tf * D[..., 1]))
            t = np.full(D.shape[:-1], np.inf)
            for b in self.furniture:
                t = np.minimum(t, _hit_box(C, D, b))
            self.rays.append(D)
            self.centres.append(C)
            self.static_t.append(t)
            # background texture: beige walls and grey floor, smooth variation
            hm, wm = D.shape[:2]
            tex = cv2.resize(rng.uniform(0, 1, (max(2, hm // 12), max(2, wm // 12))), (wm, hm))
            self.bg_h.append((0.09 + 0.05 * tex) % 1.0)
            self.bg_s.append(0.08 + 0.12 * tex)
            # "rows": three bands of 1-2 mask rows where bodies are cut, in the lower 80 % of the picture
            band = np.zeros(hm, bool)
            for _ in range(3):
                r0 = int(rng.uniform(0.2, 0.95) * hm)
                band[r0:r0 + int(rng.integers(1, 3))] = True
            self.cut_rows.append(band)

    def footprint(self, k: int, x: float, y: float, h: float) -> tuple[slice, slice]:
        """The mask pixels a person (head top at x, y, h) can cover in camera k: the picture box
        around points over their bounding cylinder (the torso's radius, floor to head), widened by
        the camera's margin; the whole picture when the camera's rays cannot be trusted to a
        projection (margin None) or part of the person is outside its field (behind it)."""
        hm, wm = self.rays[k].shape[:2]
        whole = (slice(0, hm), slice(0, wm))
        if self.margin[k] is None:
            return whole
        uv = self.rig.cameras[k].project(np.column_stack([x + TORSO_R * _RIM[:, 0], y + TORSO_R * _RIM[:, 1],
                                                          h * _RIM[:, 2]]))
        if not np.isfinite(uv).all():
            return whole
        s, mg = self.m.scale, self.margin[k]
        # mask pixel j covers picture pixels j s .. j s + s - 1 (its centre j s + (s - 1) / 2)
        c0, c1 = int(np.floor(uv[:, 0].min() / s)) - mg, int(np.floor(uv[:, 0].max() / s)) + mg + 1
        r0, r1 = int(np.floor(uv[:, 1].min() / s)) - mg, int(np.floor(uv[:, 1].max() / s)) + mg + 1
        return slice(max(r0, 0), max(min(r1, hm), 0)), slice(max(c0, 0), max(min(c1, wm), 0))

    def render(self, k: int, people: list[tuple[int, np.ndarray, int]], rng: np.random.Generator) -> CameraView:
        """people: (gid, head-top position, palette index). One camera's mask, colour and blobs."""
        m = self.m
        D, C = self.rays[k], self.centres[k]
        hm, wm = D.shape[:2]
        zbuf = self.static_t[k].copy()
        label = np.zeros((hm, wm), np.int32)
        hue = self.bg_h[k].copy()
        sat = self.bg_s[k].copy()
        fg = np.zeros((hm, wm), bool)
        boxes = {}
        for gid, head, pal in people:
            x, y, h = (float(v) for v in head)
            shirt, trousers = PALETTE[pal % len(PALETTE)]
            # the rays of the person's footprint only: every ray outside it misses them
            box = boxes[gid] = self.footprint(k, x, y, h)
            Db = D[box]
            parts = [(_hit_sphere(C, Db, np.array([x, y, h - HEAD_R]), HEAD_R), SKIN),
                     (_hit_cylinder(C, Db, x, y, TORSO_R, 0.52 * h, h - 0.22), shirt),
                     (_hit_cylinder(C, Db, x, y, LEGS_R, 0.0, 0.52 * h), trousers)]
            zb, lb, hb, sb = zbuf[box], label[box], hue[box], sat[box]  # views: written through
            for t, (ph, ps) in parts:
                near = t < zb
                zb[near] = t[near]
                lb[near] = gid
                hb[near] = ph
                sb[near] = ps
        body = label > 0
        if m.fragments == "camouflage":
            # per person (by identity, so it lasts): 0 nothing, 1 trousers, 2 shirt like the background
            for gid, head, _ in people:
                which = (gid * 2654435761) % 3
                if which:
                    h = float(head[2])
                    lo, hi = (0.0, 0.52 * h) if which == 1 else (0.52 * h, h - 0.22)
                    box = boxes[gid]
                    t = _hit_cylinder(C, D[box], float(head[0]), float(head[1]), TORSO_R if which == 2 else LEGS_R,
                                      lo, hi)
                    with np.errstate(invalid="ignore"):  # no hit on either (inf - inf): not this part
                        body[box] &= ~((label[box] == gid) & (np.abs(t - zbuf[box]) < 1e-6))
        if m.fragments == "rows":
            body &= ~self.cut_rows[k][:, None]
        fg |= body
        if m.shadow:  # floor patch beside the feet, unsaturated, where nothing nearer is drawn
            tf, fx, fy = self.floor[k]
            for gid, head, _ in people:
                sx, sy = head[0] + 0.25, head[1] + 0.15
                sh = (tf > 0) & (tf < zbuf) & (((fx - sx) / 0.35) ** 2 + ((fy - sy) / 0.25) ** 2 <= 1.0)
                fg |= sh
                sat[sh] = 0.05
        if m.hole_frac > 0 and body.any():
            field_ = cv2.resize(rng.uniform(0, 1, (max(2, hm // 6), max(2, wm // 6))), (wm, hm),
                                interpolation=cv2.INTER_CUBIC)
            thr = np.quantile(field_[body], m.hole_frac)
            fg &= ~(body & (field_ < thr))
        if m.speckle > 0:
            fg |= rng.random((hm, wm)) < m.speckle
        for _ in range(rng.poisson(m.clutter_rate)):
            cu, cv_ = rng.uniform(0, wm), rng.uniform(0, hm)
            ru, rv = rng.uniform(1.5, 5), rng.uniform(1.5, 7)
            yy, xx = np.ogrid[:hm, :wm]
            blob = ((xx - cu) / ru) ** 2 + ((yy - cv_) / rv) ** 2 <= 1.0
            fg |= blob
            hue[blob] = rng.uniform()
            sat[blob] = rng.uniform(0.1, 0.6)
        hue = (hue + rng.normal(0, m.hue_noise, hue.shape)) % 1.0
        sat = np.clip(sat + rng.normal(0, m.sat_noise, sat.shape), 0, 1)
        view = CameraView(fg.astype(np.uint8), np.minimum(np.floor(hue * 256), 255).astype(np.uint8),
                          np.round(sat * 255).astype(np.uint8), label)
        view.dets = self.blobs(k, view)
        return view

    def blobs(self, k: int, view: CameraView) -> list:
        m = self.m
        closed = cv2.morphologyEx(view.mask, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
        n, lab, stats, _ = cv2.connectedComponentsWithStats(closed, connectivity=8)
        out = []
        s = m.scale
        for i in range(1, n):
            x0, y0, w, h, area = stats[i]
            if area < m.min_area:
                continue
            comp = lab == i
            rows = np.flatnonzero(comp.any(axis=1))
            top = rows[0]
            cols = np.flatnonzero(comp[top:top + 2].any(axis=0))
            u_m = float(cols.mean())
            ang = view.hue[comp].astype(float) / 256.0 * 2 * np.pi
            h_mean = float(np.arctan2(np.sin(ang).mean(), np.cos(ang).mean()) / (2 * np.pi)) % 1.0
            s_mean = float(view.sat[comp].mean() / 255.0)
            u = (u_m + 0.5) * s - 0.5
            v = top * s - 0.5 + 0.5 * s / 2
            bbox = (x0 * s - 0.5, y0 * s - 0.5, (x0 + w) * s - 0.5, (y0 + h) * s - 0.5)
            tl = view.label[top:top + 2][:, cols]
            gid = int(tl.max()) if tl.size else 0
            out.append((u, v, bbox, h_mean, s_mean, gid))
        return out


def mask_frame(utime: int, frame: int, cam: Camera, view: CameraView, scale: int, sigma_px: float,
               colour: bool = True):
    """camera_frame_t with the view's blobs, its mask as runs and (optionally) hue/saturation."""
    from .lcmio import camera_frame

    msg = camera_frame(utime, frame, cam, [(u, v, box) for (u, v, box, _, _, _) in view.dets], sigma_px)
    for d, (_, _, _, h, s, _) in zip(msg.detections, view.dets):
        d.hue, d.saturation = (float(h), float(s)) if colour else (-1.0, -1.0)
    msg.mask_height, msg.mask_width = (int(x) for x in view.mask.shape)
    runs = encode_runs(view.mask)
    msg.num_runs = len(runs)
    msg.runs = [int(r) for r in runs]
    if colour:
        msg.num_hs = int(view.mask.size)
        msg.hue = view.hue.tobytes()
        msg.saturation = view.sat.tobytes()
    return msg


def write_rendered(sink, scene, renderer: Renderer, seed: int, colour: bool = True, progress: bool = True) -> dict:
    """Like simulate.write_multi, but each camera's message is rendered: blobs from the mask, the
    mask and hue/saturation. Capture jitter and the dropout come from scene.model. Returns stats."""
    
    from .lcmio import ground_truth
    from .simulate import T0_UTIME

    rig, dm = scene.rig, scene.model
    rng = np.random.default_rng(seed + 104729)
    dt_us = int(round(1e6 / rig.frame_rate))
    sigma_px = float(renderer.m.scale)
    pal = {p.gid: i for i, p in enumerate(sorted(scene.people, key=lambda p: p.gid))}
    stats = {"blobs": 0, "blobs_without_person": 0, "mask_bytes_max": 0, "dropped_messages": 0}
    for f in progress_bar(range(scene.n_frames), desc="render", unit="fr", enabled=progress, leave=False):
        utime = T0_UTIME + f * dt_us
        present = scene.present(f)
        pos = np.array([p.pos[f - p.f0] for p in present]).reshape(-1, 3)
        sink.write(utime, "GROUND_TRUTH", ground_truth(utime, f, [p.gid for p in present], pos))
        t = f / rig.frame_rate
        for k in rng.permutation(len(rig.cameras)):
            cam = rig.cameras[k]
            if dm.dropout_cam is not None and k == dm.dropout_cam % len(rig.cameras) and \
                    dm.dropout_s <= t < dm.dropout_s + dm.dropout_len_s:
                stats["dropped_messages"] += 1
                continue
            off_us = int(round(rng.uniform(-dm.jitter_ms, dm.jitter_ms) * 1e3)) if dm.jitter_ms > 0 else 0
            people = [(p.gid, p.pos[f - p.f0] + p.vel[f - p.f0] * off_us * 1e-6, pal[p.gid]) for p in present]
            view = renderer.render(int(k), people, rng)
            stats["blobs"] += len(view.dets)
            stats["blobs_without_person"] += sum(1 for d in view.dets if d[5] == 0)
            msg = mask_frame(utime + off_us, f, cam, view, renderer.m.scale, sigma_px, colour)
            data = msg.encode()
            stats["mask_bytes_max"] = max(stats["mask_bytes_max"], len(data))
            sink.write(utime + off_us, f"DETECTIONS_{cam.name}", msg)
    return stats
