"""Footprint of the core on a Cortex-M: code and data per module, sizeof of the tracker state at
the default and at a small MCU capacity, the worst-case stack of one mvt_tracker_step (static,
from GCC's call-graph info, and measured on QEMU by stack painting).

    tools/mvtrack footprint [--out out/footprint.md]

Reads the cross builds that `tools/mvtrack footprint` makes: build-cortex-m4 (default capacities),
build-cortex-m4-small (4 cameras, 8 targets, 16 detections per camera) and build-cortex-m7.
"""
from __future__ import annotations

import argparse
import re
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BUILDS = [("cortex-m4", "build-cortex-m4", "mps2-an386", "default"),
          ("cortex-m4", "build-cortex-m4-small", "mps2-an386", "MCU: 4 cameras, 8 targets, 16 detections"),
          ("cortex-m7", "build-cortex-m7", "mps2-an500", "default")]


def module_sizes(build: Path) -> list[tuple[str, int, int, int]]:
    lib = build / "libmvtrack_core.a"
    out = subprocess.run(["arm-none-eabi-size", str(lib)], check=True, capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines()[1:]:
        f = line.split()
        rows.append((f[5].split(" ")[0].replace(".c.obj", ".c"), int(f[0]), int(f[1]), int(f[2])))
    return rows


def static_stack(build: Path, root: str = "mvt_tracker_step") -> tuple[int, list[str], set[str]]:
    """Deepest path from root through the call graph (.ci files), summing frame sizes."""
    frames: dict[str, int] = {}
    edges: dict[str, list[str]] = {}
    for ci in (build / "CMakeFiles" / "mvtrack_core.dir").rglob("*.ci"):
        for line in ci.read_text().splitlines():
            m = re.match(r'node: \{ title: "([^"]+)" label: "[^"]*?(\d+) bytes \(([a-z,]+)\)', line)
            if m:
                frames[m.group(1)] = int(m.group(2))
                continue
            m = re.match(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"', line)
            if m:
                edges.setdefault(m.group(1), []).append(m.group(2))
    unknown: set[str] = set()
    memo: dict[str, tuple[int, list[str]]] = {}

    def deepest(fn: str, seen: tuple) -> tuple[int, list[str]]:
        if fn in memo:
            return memo[fn]
        if fn in seen:
            raise RuntimeError(f"recursion through {fn}")
        if fn not in frames:
            unknown.add(fn)
            return 0, [fn]
        best = (0, [])
        for g in edges.get(fn, []):
            d = deepest(g, seen + (fn,))
            if d[0] > best[0]:
                best = d
        memo[fn] = (frames[fn] + best[0], [fn] + best[1])
        return memo[fn]

    total, path = deepest(root, ())
    return total, [p.split(":")[-1] for p in path], unknown


def qemu_figures(build: Path, board: str) -> dict[str, str]:
    elf = build / "bin" / "mvtrack_mcu_tests.elf"
    r = subprocess.run(["qemu-system-arm", "-M", board, "-nographic", "-no-reboot", "-monitor", "none", "-serial", "none",
                        "-semihosting-config", "enable=on,target=native", "-kernel", str(elf)],
                       capture_output=True, text=True, timeout=600)
    text = r.stdout + r.stderr
    if r.returncode != 0 or "PASS" not in text:
        raise SystemExit(f"MCU tests failed on {board} ({build}):\n{text}")
    figs = {}
    for line in text.splitlines():
        if line.startswith("figure "):
            k, _, v = line[7:].partition(" ")
            figs[k] = v
    return figs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=REPO / "out" / "footprint.md")
    a = ap.parse_args(argv)
    lines = ["# mvtrack core footprint (arm-none-eabi-gcc, -O2, float core)", ""]
    for cpu, bdir, board, caps in BUILDS:
        build = REPO / bdir
        figs = qemu_figures(build, board)
        rows = module_sizes(build)
        st, path, unknown = static_stack(build)
        lines += [f"## {cpu} ({board}), capacity {caps}", "",
                  "| module | .text | .data | .bss |", "| --- | ---: | ---: | ---: |"]
        for name, t, d, b in rows:
            lines.append(f"| {name} | {t} | {d} | {b} |")
        lines.append(f"| **total** | **{sum(r[1] for r in rows)}** | **{sum(r[2] for r in rows)}** | "
                     f"**{sum(r[3] for r in rows)}** |")
        lines += ["", f"- capacity: {figs.get('capacity', '?')}",
                  f"- `sizeof(mvt_tracker_t)` = {figs.get('sizeof_tracker')} B, `sizeof(mvt_frame_t)` = "
                  f"{figs.get('sizeof_frame')} B, `sizeof(mvt_output_t)` = {figs.get('sizeof_output')} B "
                  "(the caller's; the core has no .data/.bss of its own)",
                  f"- stack of one `mvt_tracker_step`: static worst case {st} B (GCC call-graph info, libm/libc "
                  f"leaves not counted: {', '.join(sorted(unknown)) or 'none'}); measured on QEMU {figs.get('stack_step_bytes')} B "
                  "(stack painting over the 250-frame tracker test)",
                  f"- deepest static path: {' > '.join(path)}", ""]
    text = "\n".join(lines)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(text + "\n")
    print(text)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
