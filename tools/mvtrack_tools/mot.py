"""Multi-target evaluation: CLEAR MOT (via motmetrics) and OSPA of TRACKS against GROUND_TRUTH.

Matching: each GROUND_TRUTH frame is paired with the TRACKS message nearest in time (within half
a frame period; the daemon's frame time is the latest capture time of its views, so with capture
jitter it can differ from the nominal time by a few ms); each track's position is carried to the
ground-truth time with its velocity. Hypotheses are the CONFIRMED and COASTING tracks (TENTATIVE
ones are not yet claims). Distances are Euclidean in metres, a pair further apart than 0.5 m cannot
match (CLEAR 2007 3D person tracking); motmetrics is given the distances themselves (not squared),
so its MOTP is a mean distance in metres, reported here in mm.

OSPA (Schuhmacher et al. 2008) per frame with cut-off c = 0.5 m and order p = 2, averaged over
frames; a frame where both sets are empty scores 0.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .lcmio import TrackLog

MATCH_M = 0.5
SWITCH_KINDS = ("born", "took", "passed", "returned", "ghost")  # identity_switches
OSPA_C_M = 0.5
OSPA_P = 2.0
CONFIRMED, COASTING = 2, 3


@dataclass
class FrameSet:
    utime: int
    gt_ids: list[int]
    gt_pos: np.ndarray      # (n, 3)
    hyp_ids: list[int]
    hyp_pos: np.ndarray     # (m, 3), carried to utime
    have_tracks: bool       # a TRACKS message matched this frame


def nearest_time(utimes: np.ndarray, u: int) -> int:
    """Index of the time in sorted, non-empty `utimes` nearest to u."""
    i = int(np.searchsorted(utimes, u))
    cands = [j for j in (i - 1, i) if 0 <= j < len(utimes)]
    return min(cands, key=lambda j: abs(int(utimes[j]) - u))


def pair_frames(scene: TrackLog, tracks: TrackLog, frame_rate: float = 25.0) -> list[FrameSet]:
    half = 0.5e6 / frame_rate
    t_utimes = np.array(sorted(tracks.tracks), dtype=np.int64)
    out = []
    for u in sorted(scene.gt):
        ids, pos = scene.gt[u]
        hyp_ids, hyp_pos, have = [], [], False
        if len(t_utimes):
            tu = int(t_utimes[nearest_time(t_utimes, u)])
            if abs(tu - u) <= half:
                have = True
                dt = (u - tu) * 1e-6
                for t in tracks.tracks[tu]:
                    if t.status in (CONFIRMED, COASTING):
                        hyp_ids.append(int(t.id))
                        hyp_pos.append(np.asarray(t.position, float) + dt * np.asarray(t.velocity, float))
        out.append(FrameSet(u, list(ids), np.asarray(pos, float).reshape(-1, 3), hyp_ids,
                            np.asarray(hyp_pos, float).reshape(-1, 3), have))
    return out


def views_per_person(rig, frames: list[FrameSet]) -> list[np.ndarray]:
    """For each frame, how many of the rig's cameras have each ground-truth head in their picture
    (in front, inside the lens model's field, inside the image)."""
    out = []
    for fs in frames:
        n = np.zeros(len(fs.gt_ids), int)
        for cam in rig.cameras:
            if len(fs.gt_pos):
                n += cam.in_image(cam.project(fs.gt_pos))
        out.append(n)
    return out


def covered_only(frames: list[FrameSet], views: list[np.ndarray], min_views: int = 2,
                 max_m: float = MATCH_M) -> list[FrameSet]:
    """The frames with every person seen by fewer than min_views cameras made "don't care" (as the
    CLEAR evaluations' regions outside the cameras' common view): the person is removed, and so is
    any hypothesis within max_m of such a person (a track there is neither a hit nor a false one)."""
    out = []
    for fs, n in zip(frames, views):
        keep = n >= min_views
        hk = np.ones(len(fs.hyp_ids), bool)
        for p in fs.gt_pos[~keep]:
            if len(fs.hyp_pos):
                hk &= np.linalg.norm(fs.hyp_pos - p, axis=1) > max_m
        out.append(FrameSet(fs.utime, [i for i, k in zip(fs.gt_ids, keep) if k], fs.gt_pos[keep],
                            [i for i, k in zip(fs.hyp_ids, hk) if k], fs.hyp_pos[hk], fs.have_tracks))
    return out


def distance_matrix(gt: np.ndarray, hyp: np.ndarray, max_m: float = MATCH_M) -> np.ndarray:
    """Euclidean distances (m), NaN where beyond max_m (motmetrics' "cannot match")."""
    if len(gt) == 0 or len(hyp) == 0:
        return np.empty((len(gt), len(hyp)))
    d = np.linalg.norm(gt[:, None, :] - hyp[None, :, :], axis=2)
    d[d > max_m] = np.nan
    return d


def ospa(X: np.ndarray, Y: np.ndarray, c: float = OSPA_C_M, p: float = OSPA_P) -> float:
    """OSPA distance between two finite sets of points (rows)."""
    m, n = len(X), len(Y)
    if m == 0 and n == 0:
        return 0.0
    if m == 0 or n == 0:
        return float(c)
    if m > n:
        X, Y, m, n = Y, X, n, m
    D = np.minimum(np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=2), c) ** p
    r, s = linear_sum_assignment(D)
    return float(((D[r, s].sum() + c ** p * (n - m)) / n) ** (1.0 / p))


@dataclass
class MotResult:
    frames: int
    gt_objects: int          # distinct ground-truth identities
    gt_boxes: int            # ground-truth (frame, person) pairs
    mota: float
    motp_mm: float
    id_switches: int
    idf1: float
    false_positives: int
    misses: int
    fragmentations: int
    mostly_tracked: int
    ospa_m: float
    frames_without_tracks: int  # GROUND_TRUTH frames with no TRACKS message in time
    track_ids: int              # distinct confirmed identities the tracker used
    switches_born: int = 0      # the id_switches by kind (identity_switches)
    switches_took: int = 0
    switches_passed: int = 0
    switches_returned: int = 0
    switches_ghost: int = 0


def _accumulate(frames: list[FrameSet]):
    """motmetrics' accumulator of the frames' matching (0.5 m): one for every score of a run."""
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=True)
    for fs in frames:
        acc.update(fs.gt_ids, fs.hyp_ids, distance_matrix(fs.gt_pos, fs.hyp_pos))
    return acc


def clear_mot(frames: list[FrameSet]) -> MotResult:
    import motmetrics as mm

    acc = _accumulate(frames)
    ospas = [ospa(fs.gt_pos, fs.hyp_pos) for fs in frames]
    ids_seen: set[int] = set()
    for fs in frames:
        ids_seen.update(fs.hyp_ids)
    mh = mm.metrics.create()
    names = ["num_frames", "num_unique_objects", "num_objects", "mota", "motp", "num_switches", "idf1",
             "num_false_positives", "num_misses", "num_fragmentations", "mostly_tracked"]
    s = mh.compute(acc, metrics=names, name="all")
    g = lambda k: s[k].iloc[0]  # noqa: E731
    sw, _ = identity_switches(frames, acc=acc)
    kinds = {f"switches_{k}": sum(1 for x in sw if x.kind == k) for k in SWITCH_KINDS}
    return MotResult(int(g("num_frames")), int(g("num_unique_objects")), int(g("num_objects")), float(g("mota")),
                     float(g("motp")) * 1e3, int(g("num_switches")), float(g("idf1")), int(g("num_false_positives")),
                     int(g("num_misses")), int(g("num_fragmentations")), int(g("mostly_tracked")),
                     float(np.mean(ospas)) if ospas else float("nan"),
                     sum(1 for f in frames if not f.have_tracks), len(ids_seen), **kinds)


def as_dict(r: MotResult) -> dict:
    return asdict(r)


@dataclass
class Switch:
    """One identity switch (CLEAR MOT's, as motmetrics counts it) and how it came about."""
    frame: int
    utime: int
    person: int
    old_track: int | None   # the track the person had before (None: never had one)
    new_track: int
    kind: str               # "born": the new track is under `young_s` old (a birth after the person
                            # was lost); "took": the new track was following another person less
                            # than `young_s` before (a swap or a takeover); "passed": it followed
                            # another person longer ago (their identity, kept for recovery or
                            # re-acquisition, given to this person); "returned": it was this
                            # person's before; "ghost": it was older but had followed nobody
    was_following: int | None  # "took", "passed": the person the new track followed before


def identity_switches(frames: list[FrameSet], young_s: float = 1.0, acc=None) -> tuple[list[Switch], dict[int, list]]:
    """The switches of clear_mot's matching (its accumulator, when given), each classified
    (Switch.kind), and per person the runs of the identities that covered them:
    {person: [(track or None while missed, first, last frame)]}."""
    if acc is None:
        acc = _accumulate(frames)
    first_seen: dict[int, int] = {}
    for i, fs in enumerate(frames):
        for h in fs.hyp_ids:
            first_seen.setdefault(h, i)
    utimes = [fs.utime for fs in frames]
    follows: dict[int, int] = {}      # track -> the person it was last matched to
    follows_f: dict[int, int] = {}    # ... and the frame
    had: dict[int, int] = {}          # person -> the track last matched to them
    runs: dict[int, list] = {}
    out: list[Switch] = []
    for (f, _), row in acc.mot_events.iterrows():
        if row.Type not in ("MATCH", "SWITCH", "MISS"):
            continue
        o = int(row.OId)
        h = None if row.Type == "MISS" else int(row.HId)
        r = runs.setdefault(o, [])
        if r and r[-1][0] == h and r[-1][2] == f - 1:
            r[-1][2] = f
        else:
            r.append([h, f, f])
        if h is None:
            continue
        if row.Type == "SWITCH":
            age_s = (utimes[f] - utimes[first_seen[h]]) * 1e-6
            prev = follows.get(h)
            if age_s < young_s:
                kind = "born"
            elif prev is None:
                kind = "ghost"
            elif prev == o:
                kind = "returned"
            else:
                kind = "took" if (utimes[f] - utimes[follows_f[h]]) * 1e-6 < young_s else "passed"
            out.append(Switch(int(f), int(utimes[f]), o, had.get(o), h, kind,
                              prev if kind in ("took", "passed") else None))
        follows[h] = o
        follows_f[h] = int(f)
        had[o] = h
    return out, {o: [tuple(x) for x in r] for o, r in runs.items()}
