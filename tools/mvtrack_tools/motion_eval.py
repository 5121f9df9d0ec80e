"""Motion models against the bound: Experiment 1 and mixed motion, several rooms, no learnt q.

For every room (the SmartRoom and random rigs), scene kind (exp1: the paper's linear-Gaussian
walk; mixed: stand, walk, sharp turns, stops, starts, sitting down, tools/mvtrack_tools/motion.py),
pixel noise level and seed, one person is simulated and mvtrackd runs on the log once per
variant:

  imm         the daemon's defaults (--mode pkf): the IMM bank, nothing learnt
  cv          --motion cv: one constant-velocity model with the default q (0.5, 0.5, 0.05)
  cv-learnt   --q learnt from a separate training scene of the same kind and room (what the paper
              does, and what a user without ground truth cannot)

Gaussian noise: RMSE / PCRLB, the bound of the true (schedule-conditioned) model over the cameras
that measured each frame. With occlusion bursts (each camera, 30 % of frames, a displaced blob in
place of the head): mean error and the bound that knows which views were corrupted (the PCRLB
over the clean views only). A standing test adds jitter: the std of the estimate of a person who
stands still for 10 s (after 5 s to settle).

--oracles adds reference filters on the Gaussian scenes (tools/mvtrack_tools/oracle.py, numpy,
every detection used): what knowing the generator is worth. exp1: ekf-true (the walk's own model,
its pull to the room's centre included), ekf-no-centre (the same walk without that pull) and
ekf-cv-learnt; mixed: kf-schedule (told when the
person stops, turns or sits: it should sit on the bound) and imm-generator (an IMM of the
generator's own segment models, not told the schedule).

    tools/mvtrack motion [--rooms 3] [--seeds 3] [--levels 50 150 300] [--out out/motion]
"""
from __future__ import annotations

import argparse
import json
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from . import motion, oracle
from .evaluate import learn_q, match_single, pcrlb_known
from .experiment1 import run_daemon
from .lcmio import LogWriter, read_log
from .paths import DAEMON
from .progress import bar as progress_bar
from .rig import Rig, random_rig, smartroom
from .scenes import Occlusions, WalkModel, head_detections
from .simulate import write_scene

LEVELS = [50.0, 100.0, 150.0, 200.0, 250.0, 300.0]
VARIANTS = {"imm": [], "cv": ["--motion", "cv"], "cv-learnt": None}


def coverage(rig: Rig, views: int = 2, margin: float = 0.4) -> float:
    """Share of a 20 x 20 grid of head points (1.7 m) over the walkable floor in >= views pictures."""
    lo, hi = rig.volume_min[:2] + margin, rig.volume_max[:2] - margin
    g = np.stack(np.meshgrid(np.linspace(lo[0], hi[0], 20), np.linspace(lo[1], hi[1], 20)), -1).reshape(-1, 2)
    X = np.c_[g, np.full(len(g), 1.7)]
    cnt = sum(((cam.depth(X) > 0.2) & cam.in_image(cam.project(X))).astype(int) for cam in rig.cameras)
    return float(np.mean(cnt >= views))


def rooms(n: int) -> list[tuple[str, Rig]]:
    """The SmartRoom and random rigs (4-6 cameras, random rooms and lenses) that show >= 99 % of
    their floor in two pictures: the motion models are measured here, not the rig's coverage
    (a person seen by one camera has no bound worth the name)."""
    out = [("smartroom", smartroom())]
    seed = 101
    while len(out) < n:
        rng = np.random.default_rng(seed)
        rig = random_rig(rng, int(rng.integers(4, 7)))
        if coverage(rig) >= 0.99:
            out.append((f"random{seed}", rig))
        seed += 1
    return out


def draw(kind: str, rig: Rig, seconds: float, seed: int):
    """states (n, 6), the bound's transitions (Fs, Qs, P0), the rng, and each frame's offset b
    (s' = F s + b + w) for the mixed scenes (None otherwise)."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rig.frame_rate
    n = int(round(seconds * rig.frame_rate))
    if kind == "exp1":
        model = WalkModel.for_room(rig.volume_min, rig.volume_max)
        states = model.sample(rng, n, dt, rig.volume_min, rig.volume_max)
        F, Q, _ = model.transition(dt)
        return states, [F] * n, [Q] * n, model.stationary_cov(), rng, None
    if kind == "stand":
        states, Fs, Qs, P0 = motion.sample_standing(rng, n, dt, rig.volume_min, rig.volume_max)
        return states, Fs, Qs, P0, rng, None
    states, Fs, Qs, _, P0, bs = motion.sample_mixed(rng, n, dt, rig.volume_min, rig.volume_max, with_offsets=True)
    return states, Fs, Qs, P0, rng, bs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack motion", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("out/motion"), help="output folder")
    ap.add_argument("--rooms", type=int, default=3, help="the SmartRoom and N-1 random rigs (default 3)")
    ap.add_argument("--seeds", type=int, default=3, help="scenes per cell (default 3)")
    ap.add_argument("--seconds", type=float, default=60.0, help="length of each scene (default 60)")
    ap.add_argument("--levels", type=float, nargs="+", default=LEVELS, help="noise variances, px^2")
    ap.add_argument("--kinds", nargs="+", default=["exp1", "mixed"], choices=["exp1", "mixed"])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--no-occlusion", action="store_true", help="Gaussian noise only")
    ap.add_argument("--extra", default="", help="more daemon arguments for every variant (quoted)")
    ap.add_argument("--jobs", type=int, default=2, help="scenes in parallel (default 2)")
    ap.add_argument("--oracles", action="store_true",
                    help="add the reference filters (oracle.py) on the Gaussian scenes (~2 s a filter and scene)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    if not DAEMON.exists():
        ap.error(f"{DAEMON} not built: run tools/mvtrack build")
    out = a.out
    (out / "logs").mkdir(parents=True, exist_ok=True)
    extra = a.extra.split()
    room_list = rooms(a.rooms)
    rig_paths, learnt = {}, {}
    for name, rig in room_list:
        rig_paths[name] = out / f"rig_{name}.yaml"
        rig.write(rig_paths[name])
        for kind in a.kinds:  # q learnt from a training scene's truth (seed not used for evaluation)
            st = draw(kind, rig, a.seconds, 999)[0]
            learnt[(name, kind)] = learn_q(st[:, :3], 1.0 / rig.frame_rate)

    jobs = [(name, kind, occ, var, seed) for name, _ in room_list for kind in a.kinds
            for occ in ((False,) if a.no_occlusion else (False, True)) for var in a.levels
            for seed in range(1, a.seeds + 1)]
    jobs += [(name, "stand", False, 100.0, seed) for name, _ in room_list for seed in range(1, a.seeds + 1)]
    rig_of = dict(room_list)

    def one(job):
        name, kind, occ, var, seed = job
        rig = rig_of[name]
        tag = f"{name}_{kind}_var{int(var)}_{'occ' if occ else 'gauss'}_s{seed}"
        scene = out / "logs" / f"scene_{tag}.lcm"
        seconds = 15.0 if kind == "stand" else a.seconds
        states, Fs, Qs, P0, rng, bs = draw(kind, rig, seconds, seed)
        dets = head_detections(rig, states[:, :3], var, rng, Occlusions() if occ else None)
        w = LogWriter(str(scene))
        write_scene(w, rig, states, dets, var, progress=False, frame_order_seed=seed)
        w.close()
        truth = read_log(str(scene), lambda c: c == "GROUND_TRUTH")
        clean = np.array([[any(t for (_, _, t) in dets[f][k]) for k in range(len(rig.cameras))]
                          for f in range(len(states))])
        bound = pcrlb_known(rig, states[:, :3], Fs, Qs, P0, var, clean)
        res = {}
        for v in a.variants:
            args = VARIANTS[v]
            tr = out / "logs" / f"tracks_{tag}_{v}.lcm"
            if args is None:  # the single model with the learnt q
                key = kind if kind != "stand" else ("mixed" if "mixed" in a.kinds else a.kinds[0])
                run_daemon(rig_paths[name], scene, tr, "pkf-learnt-q", learnt[(name, key)], extra)
            else:
                run_daemon(rig_paths[name], scene, tr, "pkf", None, args + extra)
            gt, est, _ = match_single(read_log(str(tr), lambda c: c == "TRACKS"), truth)
            res[v] = (gt, est)
        if a.oracles and not occ and kind == "exp1":
            for v, est in oracle.exp1_references(rig, dets, var, states, learnt[(name, kind)]).items():
                res[v] = (states[:, :3], est)
        elif a.oracles and not occ and kind == "mixed":
            for v, est in oracle.mixed_references(rig, dets, var, states, Fs, Qs, bs, P0).items():
                res[v] = (states[:, :3], est)
        return job, res, bound

    cells: dict[tuple, dict] = {}
    jitter: dict[tuple, list] = {}
    bar = progress_bar(total=len(jobs), desc="motion", unit="scene", enabled=not a.quiet)
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for (name, kind, occ, var, seed), res, bound in ex.map(one, jobs):
            for v, (gt, est) in res.items():
                ok = ~np.isnan(est[:, 0])
                if kind == "stand":
                    f0 = int(5 * 25)
                    w = slice(f0, f0 + 250)
                    e = est[w][~np.isnan(est[w][:, 0])]
                    jit = float(np.sqrt(np.var(e, axis=0).sum())) * 1e3 if len(e) > 10 else float("nan")
                    err = float(np.sqrt(np.nanmean(np.sum((est[w] - gt[w]) ** 2, axis=1)))) * 1e3
                    jitter.setdefault((name, v), []).append((jit, err, float(np.std(gt[w], axis=0).sum() * 1e3)))
                    continue
                c = cells.setdefault((name, kind, occ, var, v), dict(e2=[], b=[], miss=0))
                e = np.linalg.norm(est - gt, axis=1)
                c["e2"].append(e[ok])
                c["b"].append(bound[ok])
                c["miss"] += int((~ok).sum())
            bar.update(1)
    bar.close()

    rows = []
    for (name, kind, occ, var, v), c in sorted(cells.items(), key=str):
        e = np.concatenate(c["e2"])
        b = np.concatenate(c["b"])
        rmse = float(np.sqrt(np.mean(e ** 2)))
        bnd = float(np.sqrt(np.mean(b)))
        rows.append(dict(room=name, kind=kind, occlusion=occ, var=var, variant=v, rmse_mm=rmse * 1e3,
                         mean_mm=float(e.mean()) * 1e3, bound_mm=bnd * 1e3, ratio=rmse / bnd,
                         mean_ratio=float(e.mean()) / bnd, unmatched=c["miss"], frames=int(len(e))))
    stand = [dict(room=n, variant=v, jitter_mm=float(np.mean([x[0] for x in lst])),
                  rmse_mm=float(np.mean([x[1] for x in lst])), truth_sway_mm=float(np.mean([x[2] for x in lst])))
             for (n, v), lst in sorted(jitter.items())]
    (out / "results.json").write_text(json.dumps(dict(rows=rows, stand=stand, learnt_q={
        f"{k[0]}/{k[1]}": q.tolist() for k, q in learnt.items()}), indent=1))

    columns = list(a.variants) + ([] if not a.oracles else
                                  [v for v in ("ekf-true", "ekf-no-centre", "ekf-cv-learnt", "kf-schedule", "imm-generator")
                                   if any(r["variant"] == v for r in rows)])
    lines = []
    for occ in sorted({r["occlusion"] for r in rows}):
        what = "mean error / bound over the clean views" if occ else "RMSE / PCRLB"
        lines.append(f"**{'occlusion bursts' if occ else 'Gaussian noise'}**: {what} "
                     f"(unmatched frames in brackets)\n")
        lines.append("| room | scene | sigma^2 | " + " | ".join(columns) + " |")
        lines.append("|---" * (3 + len(columns)) + "|")
        for name, _ in room_list:
            for kind in a.kinds:
                for var in a.levels:
                    cells_txt = []
                    for v in columns:
                        r = next((r for r in rows if r["room"] == name and r["kind"] == kind and r["occlusion"] == occ
                                  and r["var"] == var and r["variant"] == v), None)
                        if r is None:
                            cells_txt.append("-")
                            continue
                        val = r["mean_ratio"] if occ else r["ratio"]
                        cells_txt.append(f"{val:.3f}" + (f" ({r['unmatched']})" if r["unmatched"] else ""))
                    lines.append(f"| {name} | {kind} | {var:g} | " + " | ".join(cells_txt) + " |")
        lines.append("")
    lines.append("**standing still 10 s**: std of the estimate (jitter) / RMSE, mm; the head's own sway "
                 f"{np.mean([s['truth_sway_mm'] for s in stand]):.1f} mm\n")
    lines.append("| room | " + " | ".join(a.variants) + " |")
    lines.append("|---" * (1 + len(a.variants)) + "|")
    for name, _ in room_list:
        cells_txt = []
        for v in a.variants:
            s = next((s for s in stand if s["room"] == name and s["variant"] == v), None)
            cells_txt.append("-" if s is None else f"{s['jitter_mm']:.1f} / {s['rmse_mm']:.1f}")
        lines.append(f"| {name} | " + " | ".join(cells_txt) + " |")
    text = "\n".join(lines)
    (out / "table.md").write_text(text + "\n")
    print(text)
    print(f"wrote {out / 'table.md'}, {out / 'results.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
