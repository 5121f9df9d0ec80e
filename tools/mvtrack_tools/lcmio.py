"""Reading and writing mvtrack LCM messages and logs."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterable

import lcm
import numpy as np

from .paths import import_types

mt = import_types()


def camera_frame(utime: int, frame: int, cam, dets: Iterable[tuple], sigma_px: float,
                 bbox_half_w: float = 20.0) -> "mt.camera_frame_t":
    """dets: (u, v) or (u, v, bbox) items; without a bbox a head-topped box is made up."""
    m = mt.camera_frame_t()
    m.utime = int(utime)
    m.frame = int(frame)
    m.camera = cam.name
    m.width = int(cam.width)
    m.height = int(cam.height)
    m.detections = []
    for det in dets:
        u, v = det[0], det[1]
        d = mt.detection_t()
        d.u, d.v = float(u), float(v)
        d.sigma_px = float(sigma_px)
        if len(det) > 2:
            d.bbox = [float(x) for x in det[2]]
        else:
            d.bbox = [float(u - bbox_half_w), float(v), float(u + bbox_half_w), float(v + 6 * bbox_half_w)]
        d.score = 1.0
        d.hue = -1.0
        d.saturation = -1.0
        m.detections.append(d)
    m.num_detections = len(m.detections)
    m.mask_width = m.mask_height = 0
    m.num_runs = 0
    m.runs = []
    m.num_hs = 0
    m.hue = b""
    m.saturation = b""
    return m


def ground_truth(utime: int, frame: int, ids: list[int], pos: np.ndarray) -> "mt.ground_truth_t":
    m = mt.ground_truth_t()
    m.utime = int(utime)
    m.frame = int(frame)
    m.num_targets = len(ids)
    m.id = [int(i) for i in ids]
    m.position = [[float(x) for x in p] for p in np.atleast_2d(pos)] if len(ids) else []
    return m


class LogWriter:
    def __init__(self, path: str):
        self.log = lcm.EventLog(path, "w", overwrite=True)

    def write(self, utime: int, channel: str, msg) -> None:
        self.log.write_event(int(utime), channel, msg.encode())

    def close(self) -> None:
        self.log.close()


class LivePublisher:
    """Publishes at the scene's pace (real time) on an LCM URL."""

    def __init__(self, url: str, speed: float = 1.0):
        if "udpm://" in url and "ttl=0" not in url:
            raise ValueError("LCM multicast URLs must carry ttl=0")
        self.lc = lcm.LCM(url)
        self.speed = speed
        self.t0_wall: float | None = None
        self.t0_utime: int | None = None

    def write(self, utime: int, channel: str, msg) -> None:
        if self.t0_wall is None:
            self.t0_wall, self.t0_utime = time.monotonic(), utime
        due = self.t0_wall + (utime - self.t0_utime) * 1e-6 / self.speed
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        self.lc.publish(channel, msg.encode())

    def close(self) -> None:
        pass


@dataclass
class TrackLog:
    """TRACKS and GROUND_TRUTH of a log, by frame time."""
    tracks: dict[int, list] = field(default_factory=dict)      # utime -> list of track_t
    gt: dict[int, tuple[list[int], np.ndarray]] = field(default_factory=dict)
    status: list = field(default_factory=list)


def read_log(path: str, want: Callable[[str], bool] | None = None) -> TrackLog:
    out = TrackLog()
    for ev in lcm.EventLog(path, "r"):
        ch = ev.channel
        if want is not None and not want(ch):
            continue
        if ch == "TRACKS":
            m = mt.tracks_t.decode(ev.data)
            out.tracks[m.utime] = list(m.tracks)
        elif ch == "GROUND_TRUTH":
            m = mt.ground_truth_t.decode(ev.data)
            out.gt[m.utime] = (list(m.id), np.array(m.position, dtype=float).reshape(-1, 3))
        elif ch == "MVTRACK_STATUS":
            out.status.append(mt.status_t.decode(ev.data))
    return out


def split_log(src, a, b, cut_us: int, gap_us: int) -> None:
    """A scene log in two: events captured before cut_us into a, from cut_us + gap_us on into b
    (capture time: a camera message's utime, ground truth's utime; other channels are left out).
    A restart of the daemon between the two halves is then a restart with gap_us unobserved."""
    wa, wb = lcm.EventLog(str(a), "w", overwrite=True), lcm.EventLog(str(b), "w", overwrite=True)
    for ev in lcm.EventLog(str(src), "r"):
        if ev.channel.startswith("DETECTIONS_"):
            u = mt.camera_frame_t.decode(ev.data).utime
        elif ev.channel == "GROUND_TRUTH":
            u = mt.ground_truth_t.decode(ev.data).utime
        else:
            continue
        if u < cut_us:
            wa.write_event(ev.timestamp, ev.channel, ev.data)
        elif u >= cut_us + gap_us:
            wb.write_event(ev.timestamp, ev.channel, ev.data)
    wa.close()
    wb.close()
