"""Regenerates the project's measured figures: runs the measurement suites and writes their tables.

    tools/mvtrack report            every suite at full size (18 minutes on 2 cores once the scenes
                                    and videos are rendered, and 26 more for the held-out rigs; the
                                    first time about 90 more, most of it rendering video): rewrites
                                    the tables of docs/results.md between its `report:NAME` markers
                                    and its header line (date, commit, machine; --only leaves the
                                    header)
    tools/mvtrack report --quick    a few minutes: the simulated suites cut down, written to
                                    out/report-quick/results.md; exits 1 when a figure is below its
                                    floor (run by `tools/mvtrack test`)

Suites: Experiment 1 of the PKF paper (pkf against the triangulate-then-KF baseline), the many-people
acceptance scenes, random rooms and rigs, (full only) fifteen more rooms and rigs held out from all
tuning, rendered masks' fragments, (full only) rendered video
through the detector, the detector on vtest.avi against its public annotation, vtest.avi tracked in
3D, and (full only) the core's speed. Each runs the project's own tool (`tools/mvtrack experiment1`,
`mot`, `fragments`, `pixels`, `vtest`, `vtest3d`, `bench`) into out/report[-quick]/NAME/; the
floors below are stated once, here, and printed beside the figures they bound.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

from .paths import BUILD, REPO

# random rooms and rigs of docs/results.md (rig seed: cameras)
RIGS = {11: 5, 12: 5, 13: 4, 14: 6, 15: 8, 16: 5, 17: 6, 18: 4, 19: 7, 20: 5, 21: 5, 22: 4, 23: 6, 24: 7, 25: 8}
QUICK_RIGS = {13: 4, 16: 5}
# rooms and rigs no model was tuned on: the check on RIGS' figures
HELD_OUT_RIGS = {26: 4, 27: 5, 28: 6, 29: 7, 30: 8, 31: 5, 32: 4, 33: 6, 34: 5, 35: 7, 36: 8, 37: 4, 38: 6, 39: 5,
                 40: 5}

# Floors: what a regression must not go below. Each is a bound the default tracker meets with a
# margin on every run measured (the quick suites' figures sit well above them); crossing one means
# something broke, not noise.
FLOORS = {
    "experiment1.pkf_rmse_over_pcrlb_max": 1.20,   # Gaussian noise: pkf within 20 % of the bound
    "mot.mota_min": 0.95,                           # each acceptance run
    "mot.switches_max": 1,                          # ... identity switches per run
    "random_rigs.mota_mean_min": 0.95,
    "fragments.mota_mean_min": 0.93,
    "fragments.column_ghosts_max": 0,
}
# vtest.avi's bars are tests/python/test_detect.py's (recall, false blobs, MOTA in 3D), checked on
# every test run: the report writes those figures and does not state the bars again


def py(module: str, args: list[str], out: Path) -> subprocess.CompletedProcess:
    """Runs `python -m mvtrack_tools.MODULE ARGS` from tools/, its output captured into out/log.txt."""
    out.mkdir(parents=True, exist_ok=True)
    r = subprocess.run([sys.executable, "-m", f"mvtrack_tools.{module}"] + args, cwd=REPO / "tools",
                       capture_output=True, text=True)
    (out / "log.txt").write_text(r.stdout + r.stderr)
    if r.returncode != 0:
        raise SystemExit(f"mvtrack report: {module} failed ({r.returncode}); see {out / 'log.txt'}")
    return r


def last_json(text: str) -> dict:
    return json.loads(text.strip().splitlines()[-1])


def table(head: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


# ---- suites: each returns (markdown, figures, failures) ----------------------------------------

def experiment1(out: Path, quick: bool, quiet: bool):
    args = ["--out", str(out), "--quiet"] + (["--seeds", "2", "--seconds", "30", "--levels", "100", "300",
                                             "--modes", "pkf", "kf"] if quick else [])
    py("experiment1", args, out)
    res = json.loads((out / "results.json").read_text())
    rows = res["rows"]
    cmd = "tools/mvtrack experiment1" + (" --seeds 2 --seconds 30 --levels 100 300 --modes pkf kf" if quick else "")
    md = f"Command: `{cmd}`.\n\n" + (out / "table.md").read_text().strip()
    ratios = [r["ratio_to_pcrlb"] for r in rows if r["mode"] == "pkf" and not r["occlusion"] and "ratio_to_pcrlb" in r]
    lost = {(r["var"], r["mode"]): r["unmatched_frames"] for r in rows if r["occlusion"]}
    fails = []
    if max(ratios) > FLOORS["experiment1.pkf_rmse_over_pcrlb_max"]:
        fails.append(f"experiment1: pkf RMSE / PCRLB {max(ratios):.3f} > "
                     f"{FLOORS['experiment1.pkf_rmse_over_pcrlb_max']}")
    for (var, mode), n in lost.items():
        if mode == "pkf" and (var, "kf") in lost and n > lost[(var, "kf")]:
            fails.append(f"experiment1: with bursts at sigma^2 {var:g}, pkf loses {n} frames, kf {lost[(var, 'kf')]}")
    return md, {"pkf_rmse_over_pcrlb_max": max(ratios)}, fails


def mot(out: Path, quick: bool, quiet: bool):
    seeds = "1" if quick else "3"
    py("mot_run", ["--out", str(out), "--scenes", "crowd", "interaction", "--seeds", seeds, "--no-plots"], out)
    rows = json.loads((out / "summary.json").read_text())
    md = (f"Command: `tools/mvtrack mot --scenes crowd interaction --seeds {seeds}` (smart room, 5 cameras; "
          "CLEAR MOT at 0.5 m, OSPA c = 0.5 m).\n\n")
    md += table(["scene", "seed", "MOTA", "MOTP (mm)", "ID switches", "IDF1", "false positives", "misses", "OSPA (m)"],
                [[r["scene"], r["seed"], f"{r['mota']:.3f}", f"{r['motp_mm']:.1f}", r["id_switches"], f"{r['idf1']:.3f}",
                  r["false_positives"], r["misses"], f"{r['ospa_m']:.3f}"] for r in rows])
    fails = [f"mot: {r['scene']} seed {r['seed']}: MOTA {r['mota']:.3f} < {FLOORS['mot.mota_min']}"
             for r in rows if r["mota"] < FLOORS["mot.mota_min"]]
    fails += [f"mot: {r['scene']} seed {r['seed']}: {r['id_switches']} switches > {FLOORS['mot.switches_max']}"
              for r in rows if r["id_switches"] > FLOORS["mot.switches_max"]]
    return md, {"mota_min": min(r["mota"] for r in rows)}, fails


def random_rigs(out: Path, quick: bool, quiet: bool):
    return rig_suite(out, QUICK_RIGS if quick else RIGS, "1" if quick else "3", quiet, "random rigs")


def held_out_rigs(out: Path, quick: bool, quiet: bool):
    """Fifteen more random rooms and rigs, the same crowd scenes (full only)."""
    return rig_suite(out, HELD_OUT_RIGS, "3", quiet, "held-out rigs")


def rig_suite(out: Path, rigs: dict[int, int], seeds: str, quiet: bool, label: str):
    rows = []
    for n, c in rigs.items():
        d = out / f"rig{n}"
        py("mot_run", ["--out", str(d), "--scenes", "crowd", "--seeds", seeds, "--rig-seed", str(n),
                       "--cameras", str(c), "--no-plots"], d)
        rows += [dict(r, rig=n, cameras=c) for r in json.loads((d / "summary.json").read_text())]
        if not quiet:
            print(f"[report] random rig {n}: done", file=sys.stderr)
    mean = sum(r["mota"] for r in rows) / len(rows)
    worst = min(rows, key=lambda r: r["mota"])
    md = (f"Command: `tools/mvtrack mot --scenes crowd --seeds {seeds} --rig-seed N --cameras C` for N:C = "
          + ", ".join(f"{n}:{c}" for n, c in rigs.items()) + ".\n\n")
    md += table(["runs", "mean MOTA", "worst run", "ID switches", "lowest IDF1", "false positives", "misses"],
                [[len(rows), f"{mean:.4f}", f"{worst['mota']:.3f} (rig {worst['rig']} seed {worst['seed']})",
                  sum(r["id_switches"] for r in rows), f"{min(r['idf1'] for r in rows):.3f}",
                  sum(r["false_positives"] for r in rows), sum(r["misses"] for r in rows)]])
    fails = [] if mean >= FLOORS["random_rigs.mota_mean_min"] else \
        [f"{label}: mean MOTA {mean:.4f} < {FLOORS['random_rigs.mota_mean_min']}"]
    return md, {"mota_mean": mean}, fails


def fragments(out: Path, quick: bool, quiet: bool):
    args = ["--out", str(out)] + (["--models", "rows", "--scenes", "interaction", "crowd", "--seeds", "1"] if quick else [])
    py("fragments", args, out)
    rows = json.loads((out / "summary.json").read_text())
    mean = sum(r["mota"] for r in rows) / len(rows)
    ghosts = sum(r["column_ghosts"] for r in rows)
    cmd = "tools/mvtrack fragments" + (" --models rows --scenes interaction crowd --seeds 1" if quick else "")
    md = (f"Command: `{cmd}` (rendered masks' connected components, bodies broken by a fragmentation model; "
          "smart room).\n\n")
    md += table(["model", "scene", "seed", "MOTA", "ID switches", "per minute", "IDF1", "false positives", "misses",
                 "column ghosts"],
                [[r["model"], r["scene"], r["seed"], f"{r['mota']:.3f}", r["id_switches"], f"{r['switches_per_min']:.2f}",
                  f"{r['idf1']:.3f}", r["false_positives"], r["misses"], r["column_ghosts"]] for r in rows])
    md += f"\n\nMean MOTA {mean:.4f}, lowest {min(r['mota'] for r in rows):.3f}, {sum(r['id_switches'] for r in rows)} switches."
    fails = [] if mean >= FLOORS["fragments.mota_mean_min"] else \
        [f"fragments: mean MOTA {mean:.4f} < {FLOORS['fragments.mota_mean_min']}"]
    if ghosts > FLOORS["fragments.column_ghosts_max"]:
        fails.append(f"fragments: {ghosts} confirmed tracks in a person's column below the head")
    return md, {"mota_mean": mean, "column_ghosts": ghosts}, fails


def annotation_missing(path: Path):
    """The suites on vtest.avi need its public annotation beside the repository."""
    if path.is_file():
        return None
    return f"Not run: the annotation {path} is not on this machine.", {}, []


def pixels(out: Path, quick: bool, quiet: bool):
    """Rendered video -> mvtrack-detect -> mvtrackd, the smart room and random rigs 11 and 21 (full only:
    the first run renders 18 videos, about 75 minutes; they are kept in out/report/pixels/video)."""
    py("pixels", ["--out", str(out), "--rigs", "0", "11", "21", "--no-plots", "--quiet"], out)
    rows = json.loads((out / "summary.json").read_text())
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["rig"], r["scene"], r["mode"]), []).append(r)

    def seeds(rs, key, fmt):
        return " / ".join(fmt.format(r[key]) for r in sorted(rs, key=lambda r: r["seed"]))
    md = ("Command: `tools/mvtrack pixels --rigs 0 11 21` (rig 0 the smart room, N `--rig-seed N`; crowd and "
          "interaction, seeds 1 / 2 / 3; CLEAR MOT at 0.5 m against the head tops).\n\n")
    md += table(["rig", "scene", "mode", "MOTA", "MOTP (mm)", "ID switches", "IDF1", "FP", "misses"],
                [["smart room" if rig == 0 else f"random {rig}", scene, mode, seeds(rs, "mota", "{:.3f}"),
                  seeds(rs, "motp_mm", "{:.0f}"), seeds(rs, "id_switches", "{}"), seeds(rs, "idf1", "{:.2f}"),
                  seeds(rs, "false_positives", "{}"), seeds(rs, "misses", "{}")]
                 for (rig, scene, mode), rs in sorted(groups.items())])
    fig = {}
    for mode in sorted({r["mode"] for r in rows}):
        rs = [r for r in rows if r["mode"] == mode]
        fig[mode] = {"mota_mean": sum(r["mota"] for r in rs) / len(rs), "mota_min": min(r["mota"] for r in rs),
                     "switches": sum(r["id_switches"] for r in rs)}
    md += "\n\n" + "; ".join(f"`{m}`: mean MOTA {f['mota_mean']:.3f}, lowest {f['mota_min']:.3f}, "
                              f"{f['switches']} switches over {sum(1 for r in rows if r['mode'] == m)} runs"
                              for m, f in fig.items()) + "."
    return md, fig, []


def vtest(out: Path, quick: bool, quiet: bool):
    from .vtest_eval import GT_JSON
    if (skip := annotation_missing(GT_JSON)) is not None:
        return skip
    r = last_json(py("vtest_eval", ["--json", "--peers"], out).stdout)
    md = ("Command: `tools/mvtrack vtest --peers` (vtest.avi against the public annotation of "
          "every frame from 20 on; heads within 15 px; each detector on one core, decoding excluded).\n\n")
    names = {"mvtrack-detect": "mvtrack-detect (masks and colour on)",
             "textbook mog2": "MOG2 with shadows, opening and closing, components, the component's top",
             "textbook knn": "KNN, the same pipeline",
             "textbook hog": "HOG with OpenCV's default people detector, the box's top-centre",
             "textbook hog, h/8": "the same, the head an eighth of the box below its top (the window's margin)"}
    rows = []
    for name, det in r["detectors"].items():
        name = names.get(name, name)
        for part, v in det.items():
            if isinstance(v, dict):
                rows.append([name if part.endswith("794") and part.startswith("20-") else "", part,
                             f"{v['recall']:.3f}", f"{v['false_blobs_per_frame']:.2f}",
                             f"{v['head_error_px_median']:.1f}", f"{det['ms_per_frame']:.1f}"])
    md += table(["detector", "frames", "recall", "false blobs per frame", "median head error (px)", "ms per frame"], rows)
    return md, {"recall": r["recall"], "false_blobs_per_frame": r["false_blobs_per_frame"]}, []


def vtest3d(out: Path, quick: bool, quiet: bool):
    from .vtest3d import GT
    if (skip := annotation_missing(GT)) is not None:
        return skip
    r = last_json(py("vtest3d", ["--out", str(out), "--json"], out).stdout)
    md = ("Command: `tools/mvtrack vtest3d` (one camera, its rig fitted to the annotation's feet; CLEAR MOT on the "
          "ground plane at 1 m).\n\n")
    md += table(["frames", "MOTA", "MOTP (m)", "ID switches", "IDF1", "false positives", "misses"],
                [[k, f"{v['mota']:.3f}", f"{v['motp_m']:.3f}", v["switches"], f"{v['idf1']:.3f}", v["false_positives"],
                  v["misses"]] for k, v in (("0-794", r["all"]), ("0-399", r["frames_0_399"]),
                                             ("400-794", r["frames_400_794"]))])
    return md, {"mota": r["all"]["mota"]}, []


def bench(out: Path, quick: bool, quiet: bool):
    names = ["filter_update_5cam", "tracker_frame_5cam_1target", "tracker_frame_8cam_16people",
             "tracker_frame_8cam_16people_masks", "pf_frame_5cam_4targets", "detect_frame_768x576"]
    out.mkdir(parents=True, exist_ok=True)
    r = subprocess.run([str(BUILD / "bin" / "mvtrack-bench")] + names, capture_output=True, text=True)
    (out / "log.txt").write_text(r.stdout + r.stderr)
    if r.returncode != 0:
        raise SystemExit(f"mvtrack report: mvtrack-bench failed ({r.returncode}); see {out / 'log.txt'}")
    rows = [json.loads(x) for x in r.stdout.splitlines() if x.startswith("{")]
    md = ("Command: `tools/mvtrack bench " + " ".join(names) + "` (one core; the median over the runs, and the "
          "99th percentile where each run is one frame; `.vs_` lines are ratios timed in alternating blocks).\n\n")

    def us(b, key):
        if key not in b:
            return ""
        return f"{b[key]:.0f} ns" if b[key] < 1e4 else f"{b[key] / 1e3:.1f} µs"
    md += table(["benchmark", "median", "p99", "runs"],
                [[b["bench"], us(b, "median_ns") or (f"× {b['median_ratio']:.2f}" if "median_ratio" in b else ""),
                  us(b, "p99_ns"), b.get("runs", "")] for b in rows if "median_ns" in b or "median_ratio" in b])
    return md, {b["bench"]: b["median_ns"] for b in rows if "median_ns" in b}, []


SUITES = [("experiment1", experiment1), ("mot", mot), ("random_rigs", random_rigs), ("held_out_rigs", held_out_rigs),
          ("fragments", fragments), ("pixels", pixels), ("vtest", vtest), ("vtest3d", vtest3d), ("bench", bench)]
# timings on a shared CI machine say nothing; rendering video takes an hour; vtest.avi's suites run in
# test_detect.py with their bars
QUICK_SKIP = {"bench", "held_out_rigs", "pixels", "vtest", "vtest3d"}


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def commit() -> str:
    def git(*a):
        return subprocess.run(["git", *a], cwd=REPO, capture_output=True, text=True).stdout.strip()
    h = git("rev-parse", "--short=12", "HEAD") or "unknown"
    return h + (" (with uncommitted changes)" if git("status", "--porcelain", "--untracked-files=no") else "")


def header() -> str:
    return (f"Generated by `tools/mvtrack report` on {datetime.date.today().isoformat()}, commit {commit()}, "
            f"on {machine()}.")


def splice(text: str, name: str, body: str) -> str:
    """Replaces the block between `<!-- report:NAME -->` and `<!-- /report:NAME -->` in text."""
    pat = re.compile(rf"(<!-- report:{name} -->\n)(?:.*?\n)?(<!-- /report:{name} -->)", re.S)  # empty or not
    if not pat.search(text):
        raise SystemExit(f"mvtrack report: docs/results.md has no report:{name} block")
    return pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), text)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="mvtrack report", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="cut-down suites, checked against their floors")
    ap.add_argument("--only", nargs="+", choices=[s[0] for s in SUITES], metavar="SUITE",
                    help="run only these suites (" + ", ".join(s[0] for s in SUITES) + ")")
    ap.add_argument("--out", type=Path, help="working folder (default out/report or out/report-quick)")
    ap.add_argument("--results", type=Path, help="the file to write (default docs/results.md; with --quick, "
                    "OUT/results.md)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    out = (a.out or REPO / ("out/report-quick" if a.quick else "out/report")).resolve()
    target = (a.results or (out / "results.md" if a.quick else REPO / "docs/results.md")).resolve()
    if not a.quick and not target.is_file():
        print(f"mvtrack report: {target} is missing (it holds the report:NAME blocks the tables go in)", file=sys.stderr)
        return 2
    suites = [s for s in SUITES if (a.only is None or s[0] in a.only) and not (a.quick and s[0] in QUICK_SKIP)]
    blocks, figures, fails = {}, {}, []
    for i, (name, fn) in enumerate(suites):
        t0 = time.monotonic()
        if not a.quiet:
            print(f"[report] {i + 1}/{len(suites)} {name} ...", file=sys.stderr)
        md, fig, f = fn(out / name, a.quick, a.quiet)
        blocks[name], figures[name], fails = md, fig, fails + f
        if not a.quiet:
            print(f"[report] {name}: {json.dumps(fig, default=float)} ({time.monotonic() - t0:.0f} s)", file=sys.stderr)
    (out / "figures.json").write_text(json.dumps({"floors": FLOORS, "figures": figures, "below": fails}, indent=1,
                                                 default=float))
    if a.quick:
        text = "# Results (quick)\n\n" + header() + "\n\n" + "\n\n".join(
            f"## {name}\n\n{md}" for name, md in blocks.items()) + "\n"
    else:
        text = target.read_text()
        if a.only is None:  # the header dates the last run of every suite
            text = re.sub(r"(?m)^Generated by `tools/mvtrack report`.*$", header(), text, count=1)
        for name, md in blocks.items():
            text = splice(text, name, md)
    tmp = target.with_suffix(".tmp")
    tmp.write_text(text)
    tmp.replace(target)
    print(f"wrote {target}")
    for f in fails:
        print(f"BELOW FLOOR: {f}")
    if a.quick:
        print("report: " + ("FAIL" if fails else "PASS") + f" ({len(FLOORS)} floors, {out / 'figures.json'})")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
