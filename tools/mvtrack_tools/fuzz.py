"""Fuzz the daemon's engine (message decoding + frame assembly + tracking) with libFuzzer.

    tools/mvtrack fuzz [--target messages|checkpoint] [--seconds S | --runs N] [--jobs J] [--out DIR]

Writes a rig and a seed corpus into DIR, then runs the libFuzzer target on it:
- messages (default): build-fuzz/bin/mvtrack-fuzz, seeded with well-formed frame sets (people
  walking, masks with hue/saturation for the particle-filter mode); tests/fuzz/fuzz_daemon.c;
- checkpoint: build-fuzz/bin/mvtrack-fuzz-checkpoint, the --state loader, seeded with real
  checkpoints that build/bin/mvtrackd writes on short scenes; tests/fuzz/fuzz_checkpoint.c.
Prints the executions done and exits with the fuzzer's status (non-zero on a crash, leak,
sanitizer report or broken invariant; the crashing input is left in DIR).
"""
from __future__ import annotations

import argparse
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import lcm
import numpy as np

from .lcmio import camera_frame, mt
from .paths import REPO
from .render import encode_runs
from .rig import smartroom


def record(msg_bytes: bytes, cam_index: int, raw: bool = False) -> bytes:
    body = msg_bytes if raw else msg_bytes[8:]  # the target puts the fingerprint back
    h = (cam_index & 7) | (0x80 if raw else 0)
    return struct.pack(">BH", h, len(body)) + body


def scene_seed(rig, rng: np.random.Generator, pf: bool) -> bytes:
    out = bytearray([1 if pf else 0])
    for k, msg in scene_messages(rig, rng, pf, 3 if pf else 8):
        out += record(msg.encode(), k)
    return bytes(out)


def scene_messages(rig, rng: np.random.Generator, pf: bool, frames: int) -> list:
    """(camera index, camera_frame_t) of 1-3 people walking, with painted masks in pf mode."""
    out = []
    people = [np.array([rng.uniform(1, 5), rng.uniform(1, 4), rng.uniform(1.5, 1.9)]) for _ in range(rng.integers(1, 4))]
    vel = [rng.normal(0, 0.5, 3) * [1, 1, 0] for _ in people]
    t0 = int(rng.integers(0, 2**40))
    for f in range(frames):
        for k, cam in enumerate(rig.cameras):
            dets = []
            mask = np.zeros((18, 24), np.uint8)
            for p in people:
                u, v = cam.project(p)[0]
                if 0 <= u < cam.width and 0 <= v < cam.height:
                    dets.append((u + rng.normal(0, 2), v + rng.normal(0, 2)))
                    cu, cv = int(u / 32), int(v / 32)
                    mask[max(cv, 0):cv + 3, max(cu - 1, 0):cu + 1] = 1
            msg = camera_frame(t0 + f * 40000 + int(rng.integers(-3000, 3000)), f, cam, dets, 2.0)
            if pf:
                runs = encode_runs(mask)
                msg.mask_height, msg.mask_width = mask.shape
                msg.num_runs = len(runs)
                msg.runs = [int(r) for r in runs]
                msg.num_hs = mask.size
                msg.hue = rng.integers(0, 256, mask.size, dtype=np.uint8).tobytes()
                msg.saturation = rng.integers(0, 256, mask.size, dtype=np.uint8).tobytes()
            out.append((k, msg))
        people = [p + v * 0.04 for p, v in zip(people, vel)]
    return out


def checkpoint_seeds(out: Path, rig_path: Path, rig, daemon: Path, n: int = 6, seed: int = 2) -> Path:
    """Real checkpoints (daemon --state on short scenes, pkf and pf with 64 particles), each with a
    flag byte in front (tests/fuzz/fuzz_checkpoint.c): the loader's fuzzing starts from files that
    pass, so that its mutations reach every check. daemon: the mvtrackd of the fuzzing build (the
    same capacities as the target, so the same state size)."""
    corpus = out / "corpus-checkpoint"
    corpus.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for i in range(n):
        pf = i % 2 == 1
        log = out / f"ckpt-scene-{i}.lcm"
        w = lcm.EventLog(str(log), "w", overwrite=True)
        for k, msg in scene_messages(rig, rng, pf, 40):
            w.write_event(msg.utime, f"DETECTIONS_{rig.cameras[k].name}", msg.encode())
        w.close()
        state = out / f"ckpt-{i}"
        for suffix in ("", ".ids"):
            Path(f"{state}{suffix}").unlink(missing_ok=True)
        subprocess.run([str(daemon), "--rig", str(rig_path), "--in", f"file://{log}?speed=0", "--out",
                        f"file://{out}/ckpt-out.lcm?mode=w", "--mode", "pf" if pf else "pkf", "--particles", "64",
                        "--state", str(state)], check=True, capture_output=True)
        # flag bits 1 and 2: header and checksums fixed up by the target (the rig hash differs)
        (corpus / f"ckpt-{i:02d}").write_bytes(bytes([int(pf) | 6 | (i << 3) & 0xf8]) + state.read_bytes())
    return corpus


def write_corpus(out: Path, n: int = 24, seed: int = 1) -> Path:
    rig = smartroom()
    rig_path = out / "rig.yaml"
    rig.write(rig_path)
    corpus = out / "corpus"
    corpus.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    for i in range(n):
        (corpus / f"seed-{i:03d}").write_bytes(scene_seed(rig, rng, pf=(i % 3 == 2)))
    return rig_path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tools/mvtrack fuzz", description=__doc__.split("\n\n")[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--seconds", type=int, default=60, help="stop after this long (default 60)")
    g.add_argument("--runs", type=int, help="stop after this many executions (e.g. 10000000)")
    ap.add_argument("--jobs", type=int, default=1, help="parallel fuzzing processes (default 1)")
    ap.add_argument("--out", type=Path, default=REPO / "out" / "fuzz", help="rig, corpus and crashes (default out/fuzz)")
    ap.add_argument("--target", choices=["messages", "checkpoint"], default="messages")
    ap.add_argument("--fuzzer", type=Path, help="the libFuzzer binary (default: build-fuzz/bin/ of the target)")
    a = ap.parse_args(argv)
    if a.fuzzer is None:
        a.fuzzer = REPO / "build-fuzz" / "bin" / ("mvtrack-fuzz" if a.target == "messages" else "mvtrack-fuzz-checkpoint")
    if not a.fuzzer.exists():
        ap.error(f"{a.fuzzer} not built (tools/mvtrack fuzz builds it)")
    a.out.mkdir(parents=True, exist_ok=True)
    rig_path = write_corpus(a.out)
    corpus, max_len = a.out / "corpus", 16384
    if a.target == "checkpoint":
        daemon = a.fuzzer.parent / "mvtrackd"
        if not daemon.exists():
            ap.error(f"{daemon} not built: it writes the seed checkpoints")
        corpus = checkpoint_seeds(a.out, rig_path, smartroom(), daemon)
        max_len = max(p.stat().st_size for p in corpus.iterdir())
    env = dict(os.environ, MVTRACK_FUZZ_RIG=str(rig_path),
               ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=0:abort_on_error=0")
    args = [str(a.fuzzer), str(corpus), f"-artifact_prefix={a.out}/", f"-max_len={max_len}",
            "-rss_limit_mb=2048", "-print_final_stats=1"]
    if a.runs is not None:
        args.append(f"-runs={a.runs // max(a.jobs, 1)}")
    else:
        args.append(f"-max_total_time={a.seconds}")
    if a.jobs > 1:
        args += [f"-jobs={a.jobs}", f"-workers={a.jobs}"]
    print("fuzz: " + " ".join(args), file=sys.stderr)
    p = subprocess.run(args, env=env, stderr=subprocess.PIPE, text=True, cwd=a.out)
    log = p.stderr
    (a.out / "fuzz.log").write_text(log)
    if a.jobs > 1:  # each worker writes fuzz-N.log in cwd
        log = "".join(f.read_text() for f in sorted(a.out.glob("fuzz-*.log")))
    execs = sum(int(x) for x in re.findall(r"stat::number_of_executed_units:\s*(\d+)", log))
    crashed = p.returncode != 0
    tail = "\n".join(log.strip().splitlines()[-25:]) if crashed else ""
    print(f"fuzz: {execs} executions, exit {p.returncode}" + (f"\n{tail}" if crashed else ""))
    return p.returncode


if __name__ == "__main__":
    sys.exit(main())
