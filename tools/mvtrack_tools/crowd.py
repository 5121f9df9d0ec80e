"""Multi-person scenes: people who enter, walk, cross, stand and talk, and leave, seen by a rig
through an imperfect detector.

People are kinematic walkers (velocity relaxes toward the next waypoint at a walking speed, with
pauses); the tracked point is the head top, bobbing while walking. The detector model, per camera
and frame (each feature switchable, all drawn from one seeded generator):

- a person is seen when the head projects into the image in front of the camera; the silhouette
  is the image of the body's axis (feet to head) thickened by the body's width (0.44 m) at the
  depth of its middle, the blob's box that of a vertical cylinder;
- silhouettes that touch in a view merge into one blob; as in the PKF paper's Experiment 2 the
  detector reports the top of the region: the top-most head of the group;
- each blob is missed with probability `p_miss`;
- false alarms: Poisson(`fa_rate`) per camera and frame, uniform over the image;
- pixel noise N(0, sigma^2) on every reported point and on each edge of its box;
- capture-time jitter: each camera's frame is taken up to `jitter_ms` away from the nominal
  frame time (positions are taken at the jittered time);
- dropout: camera `dropout_cam` sends nothing during [dropout_s, dropout_s + dropout_len_s).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .rig import Rig

BODY_RADIUS_M = 0.22


@dataclass
class Person:
    gid: int                 # ground-truth identity (never reused)
    f0: int                  # first frame present
    pos: np.ndarray          # (n, 3) head-top positions from f0
    vel: np.ndarray          # (n, 3)

    @property
    def f1(self) -> int:     # one past the last frame present
        return self.f0 + len(self.pos)


@dataclass
class DetectorModel:
    sigma_px: float = 4.0
    p_miss: float = 0.10
    fa_rate: float = 0.3
    merge: bool = True
    jitter_ms: float = 3.0
    dropout_cam: int | None = 1
    dropout_s: float = 20.0
    dropout_len_s: float = 4.0


@dataclass
class Scene:
    rig: Rig
    n_frames: int
    people: list[Person]
    model: DetectorModel
    name: str = "scene"
    info: dict = field(default_factory=dict)

    def present(self, f: int) -> list[Person]:
        return [p for p in self.people if p.f0 <= f < p.f1]


class Walker:
    """A kinematic walker: velocity relaxes toward the next waypoint at a walking speed, pauses at
    waypoints, keeps its distance from other walkers (a short-range repulsion: people do not walk
    through each other), sways a little when standing; the head bobs while walking."""

    def __init__(self, rng: np.random.Generator, start, plan: list[tuple[np.ndarray, float]], height: float,
                 speed: float, tau_s: float = 0.6):
        self.rng = rng
        self.p = np.asarray(start, float)[:2].copy()
        self.v = np.zeros(2)
        self.plan = plan
        self.i = 0
        self.pause = 0.0
        self.height = height
        self.speed = speed
        self.tau = tau_s
        self.phase = rng.uniform(0, 2 * np.pi)
        self.sway = np.zeros(2)
        self.done = False
        self.stuck_s = 0.0
        self.exits = False  # the plan's last waypoint is a door the walker leaves through

    def step(self, dt: float, others: list["Walker"]) -> tuple[np.ndarray, np.ndarray]:
        want = np.zeros(2)
        if self.i < len(self.plan):
            target, hold = self.plan[self.i]
            d = np.asarray(target, float)[:2] - self.p
            dist = np.linalg.norm(d)
            if self.pause > 0.0:
                self.pause -= dt
                if self.pause <= 0.0:
                    self.i += 1
            elif dist < (0.3 if self.exits and self.i == len(self.plan) - 1 else 0.15) or \
                    (self.stuck_s > 2.0 and not (self.exits and self.i == len(self.plan) - 1)):
                # arrived, or blocked by others: give up that waypoint (never the exit door: people
                # leave through doors, they do not vanish where they stand)
                self.pause = max(hold, dt)
                self.stuck_s = 0.0
            else:
                want = d / dist * min(self.speed, dist / 0.8)  # slow down on arrival
                self.stuck_s = self.stuck_s + dt if np.linalg.norm(self.v) < 0.1 else 0.0
        else:
            self.done = True
        for o in others:  # personal space: push away inside 0.9 m, hard stop inside 0.45 m
            d = self.p - o.p
            r = np.linalg.norm(d)
            if 1e-6 < r < 0.9:
                want = want + d / r * 1.2 * (0.9 - r) / 0.9
        self.v += (want - self.v) * (dt / self.tau)
        step = self.v * dt
        for o in others:
            d = self.p + step - o.p
            r = np.linalg.norm(d)
            if r < 0.45 and r < np.linalg.norm(self.p - o.p):
                step = np.zeros(2)
                self.v *= 0.0
                break
        self.p = self.p + step
        s = np.linalg.norm(self.v)
        self.phase += 2 * np.pi * 1.8 * dt * (s / max(self.speed, 1e-6))
        if s < 0.1:  # standing people still sway (talking, shifting weight)
            self.sway += -0.5 * self.sway * dt + 0.02 * np.sqrt(dt) * self.rng.standard_normal(2)
        else:
            self.sway -= self.sway * dt
        amp = 0.025 * min(1.0, s / 0.5)
        pos = np.array([self.p[0] + self.sway[0], self.p[1] + self.sway[1], self.height + amp * np.sin(self.phase)])
        vel = np.array([self.v[0], self.v[1], amp * 2 * np.pi * 1.8 * np.cos(self.phase) * s / max(self.speed, 1e-6)])
        return pos, vel


def simulate_walkers(walkers: list[Walker], starts: list[int], n: int, dt: float, leave_when_done: list[bool]) -> list[Person]:
    """Steps the walkers jointly from their start frames; a walker that finished its plan and
    leaves disappears. Returns one Person per walker."""
    pos: list[list] = [[] for _ in walkers]
    vel: list[list] = [[] for _ in walkers]
    for w, leave in zip(walkers, leave_when_done):
        w.exits = leave
    active = [False] * len(walkers)
    gone = [False] * len(walkers)
    for f in range(n):
        for i, w in enumerate(walkers):
            if not gone[i] and f >= starts[i]:
                active[i] = True
        for i, w in enumerate(walkers):
            if not active[i]:
                continue
            others = [o for j, o in enumerate(walkers) if j != i and active[j]]
            p, v = w.step(dt, others)
            if w.done and leave_when_done[i]:
                active[i], gone[i] = False, True
                continue
            pos[i].append(p)
            vel[i].append(v)
    return [Person(i + 1, starts[i], np.array(pos[i]).reshape(-1, 3), np.array(vel[i]).reshape(-1, 3))
            for i in range(len(walkers))]


def _inside(rig: Rig, margin: float, rng: np.random.Generator) -> np.ndarray:
    lo = rig.volume_min[:2] + margin
    hi = rig.volume_max[:2] - margin
    return rng.uniform(lo, hi)


def _door(rig: Rig, which: int) -> np.ndarray:
    """Doors on the walls, 0.25 m inside the tracked volume."""
    lo, hi = rig.volume_min[:2], rig.volume_max[:2]
    mid = 0.5 * (lo + hi)
    doors = [np.array([lo[0] + 0.25, mid[1]]), np.array([hi[0] - 0.25, mid[1]]),
             np.array([mid[0], lo[1] + 0.25]), np.array([mid[0], hi[1] - 0.25])]
    return doors[which % len(doors)]


def crowd_scene(rig: Rig, seconds: float = 60.0, seed: int = 1, n_people: int = 5, model: DetectorModel | None = None,
                returning: int = 2) -> Scene:
    """`n_people` enter through doors during the first seconds, wander (crossing each other's
    paths, pausing), and leave; `returning` further people enter later while others leave."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rig.frame_rate
    n = int(round(seconds * rig.frame_rate))
    walkers, starts, leaves = [], [], []
    for i in range(n_people + returning):
        t_in = rng.uniform(0.0, 1.0) + 2.5 * i if i < n_people else seconds * rng.uniform(0.55, 0.75)
        door_in = _door(rig, int(rng.integers(4)))
        door_out = _door(rig, int(rng.integers(4)))
        plan = [(door_in + (_inside(rig, 0.8, rng) - door_in) * 0.3, 0.0)]
        leave = i < 3  # three of the first people leave before the end, through a door
        for _ in range(int(rng.integers(2, 4)) if leave else 30):
            plan.append((_inside(rig, 0.6, rng), float(rng.choice([0.0, 0.0, rng.uniform(1.0, 4.0)]))))
        if leave:
            plan.append((door_out, 0.0))
        walkers.append(Walker(rng, door_in, plan, rng.uniform(1.55, 1.90), rng.uniform(0.7, 1.2)))
        starts.append(int(t_in * rig.frame_rate))
        leaves.append(leave)
    people = [p for p in simulate_walkers(walkers, starts, n, dt, leaves) if len(p.pos)]
    return Scene(rig, n, people, model or DetectorModel(), "crowd")


def interaction_scene(rig: Rig, frames: int = 400, seed: int = 1, model: DetectorModel | None = None) -> Scene:
    """The PKF paper's Experiment 2 situation: two people meet, stand close and talk (heads about
    0.5-0.8 m apart), one walks around the other, they talk again and part. 400 frames."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rig.frame_rate
    lo, hi = rig.volume_min[:2], rig.volume_max[:2]
    c = 0.5 * (lo + hi) + rng.uniform(-0.4, 0.4, 2)
    th = rng.uniform(0, np.pi)
    u = np.array([np.cos(th), np.sin(th)])
    w = np.array([-u[1], u[0]])
    gap = rng.uniform(0.5, 0.8) / 2
    a_start, b_start = c - 2.0 * u, c + 2.0 * u
    talk1 = rng.uniform(3.0, 5.0)
    plan_a = [(c - gap * u, talk1 + 4.0), (c - 1.8 * u + 0.5 * w, 1e9)]
    # b: meets a, talks, walks around a (passing close behind), talks from the other side, leaves
    plan_b = [(c + gap * u, talk1), (c + 0.6 * w, 0.0), (c - gap * u - 0.55 * u + 0.1 * w, 0.0),
              (c - gap * u + 0.5 * w, 3.0), (c + 1.8 * u - 0.3 * w, 1e9)]
    wa = Walker(rng, a_start, plan_a, rng.uniform(1.60, 1.75), 0.9)
    wb = Walker(rng, b_start, plan_b, rng.uniform(1.70, 1.90), 0.9)
    people = simulate_walkers([wa, wb], [0, 0], frames, dt, [False, False])
    m = model or DetectorModel(dropout_cam=None)
    return Scene(rig, frames, people, m, "interaction")


@dataclass
class CameraFrame:
    utime_offset_us: int
    dets: list[tuple[float, float, tuple[float, float, float, float], int]]  # u, v, bbox, source gid (0: FA)


def body_box(cam, head: np.ndarray) -> tuple[float, float, float, float] | None:
    """Projected box of the body cylinder under the head point."""
    x, y, h = head
    pts = []
    for z in (0.0, h):
        for a in np.linspace(0, 2 * np.pi, 8, endpoint=False):
            pts.append([x + BODY_RADIUS_M * np.cos(a), y + BODY_RADIUS_M * np.sin(a), z])
    pts = np.array(pts)
    if np.any(cam.depth(pts) <= 0.1):
        return None
    uv = cam.project(pts)
    uv = uv[np.all(np.isfinite(uv), axis=1)]  # points outside the camera's field have no image
    if not len(uv):
        return None
    return float(uv[:, 0].min()), float(uv[:, 1].min()), float(uv[:, 0].max()), float(uv[:, 1].max())


def _seg_dist(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> float:
    """Distance between two 2D segments (sampled: accurate to a few pixels, which is enough)."""
    t = np.linspace(0.0, 1.0, 9)[:, None]
    P = p0 + (p1 - p0) * t
    Q = q0 + (q1 - q0) * t
    return float(np.min(np.linalg.norm(P[:, None, :] - Q[None, :, :], axis=2)))


def _overlap(a: dict, b: dict) -> bool:
    """The silhouettes touch: each is the image of the body's axis (feet to head) thickened by the
    body's projected width; they overlap where the axes come closer than the mean width."""
    return _seg_dist(a["foot"], a["uv"], b["foot"], b["uv"]) < 0.5 * (a["w"] + b["w"])


def detect(scene: Scene, rng: np.random.Generator) -> list[list[CameraFrame | None]]:
    """For each frame and camera: the camera's message content, or None (dropout)."""
    rig, m = scene.rig, scene.model
    out: list[list[CameraFrame | None]] = []
    stats = {"merged_blobs": 0, "missed": 0, "false_alarms": 0, "dropped_messages": 0, "true": 0}
    # a box's edges are blob pixels measured as the top is: each with the same pixel noise, from a
    # generator of its own (the scene's other draws do not depend on it)
    edge_rng = np.random.default_rng(rng.bit_generator.seed_seq.spawn(1)[0])
    for f in range(scene.n_frames):
        row: list[CameraFrame | None] = []
        t = f / rig.frame_rate
        present = scene.present(f)
        for k, cam in enumerate(rig.cameras):
            if m.dropout_cam is not None and k == m.dropout_cam % len(rig.cameras) and \
                    m.dropout_s <= t < m.dropout_s + m.dropout_len_s:
                row.append(None)
                stats["dropped_messages"] += 1
                continue
            dt_us = int(round(rng.uniform(-m.jitter_ms, m.jitter_ms) * 1e3)) if m.jitter_ms > 0 else 0
            blobs = []
            for p in present:
                i = f - p.f0
                head = p.pos[i] + p.vel[i] * dt_us * 1e-6
                if cam.depth(head)[0] <= 0.2:
                    continue
                uv = cam.project(head)[0]
                if not cam.in_image(uv[None])[0]:
                    continue
                box = body_box(cam, head)
                foot = np.array([head[0], head[1], 0.0])
                if box is None or cam.depth(foot)[0] <= 0.1:
                    continue
                mid = np.array([head[0], head[1], 0.5 * head[2]])
                w = 2 * BODY_RADIUS_M * float(cam.K[0, 0]) / float(cam.depth(mid)[0])
                blobs.append({"uv": uv, "foot": cam.project(foot)[0], "w": w, "box": box, "gids": [p.gid],
                              "members": None})
            if m.merge:  # merge touching blobs until none touch
                merged = True
                while merged:
                    merged = False
                    for a in range(len(blobs)):
                        for b in range(a + 1, len(blobs)):
                            if any(_overlap(x, y) for x in blobs[a]["members"] or [blobs[a]]
                                   for y in blobs[b]["members"] or [blobs[b]]):
                                A, B = blobs[a], blobs[b]
                                top = A if A["uv"][1] <= B["uv"][1] else B
                                box = (min(A["box"][0], B["box"][0]), min(A["box"][1], B["box"][1]),
                                       max(A["box"][2], B["box"][2]), max(A["box"][3], B["box"][3]))
                                blobs[a] = {"uv": top["uv"], "box": box, "gids": A["gids"] + B["gids"],
                                            "top": top.get("top", top["gids"][0]),
                                            "members": (A["members"] or [A]) + (B["members"] or [B])}
                                del blobs[b]
                                merged = True
                                stats["merged_blobs"] += 1
                                break
                        if merged:
                            break
            dets = []
            for b in blobs:
                if rng.random() < m.p_miss:
                    stats["missed"] += 1
                    continue
                p = b["uv"] + rng.standard_normal(2) * m.sigma_px
                e = edge_rng.standard_normal(4) * m.sigma_px
                box = (max(0.0, b["box"][0] + e[0]), max(0.0, b["box"][1] + e[1]),
                       min(cam.width - 1.0, b["box"][2] + e[2]), min(cam.height - 1.0, b["box"][3] + e[3]))
                if cam.in_image(p[None])[0]:
                    dets.append((float(p[0]), float(p[1]), box, int(b.get("top", b["gids"][0]))))
                    stats["true"] += 1
            for _ in range(rng.poisson(m.fa_rate)):
                u, v = rng.uniform(0, cam.width - 1), rng.uniform(0, cam.height - 1)
                hw = rng.uniform(10, 40)
                dets.append((float(u), float(v), (u - hw, v, u + hw, min(cam.height - 1.0, v + 6 * hw)), 0))
                stats["false_alarms"] += 1
            rng.shuffle(dets)
            row.append(CameraFrame(dt_us, dets))
        out.append(row)
    scene.info.update(stats)
    return out
