"""tools/mvtrack detect: runs build/bin/mvtrack-detect with a progress bar on file sources.

Every argument goes to mvtrack-detect unchanged (see `build/bin/mvtrack-detect --help`); this
wrapper adds --progress and turns its 'progress I TOTAL' lines into a bar, passing every other line
of its stderr through. Its exit status is mvtrack-detect's.

    tools/mvtrack detect --rig RIG.yaml --video cam0=cam0.avi ... --out 'file://det.lcm?mode=w'
"""
from __future__ import annotations

import subprocess
import sys


from .progress import bar as progress_bar
from .paths import BUILD

DETECT = BUILD / "bin" / "mvtrack-detect"


def run(args: list[str], progress: bool = True, desc: str = "detect") -> int:
    """Runs mvtrack-detect with args; returns its exit status."""
    if not DETECT.exists():
        print(f"{DETECT} not built: run tools/mvtrack build", file=sys.stderr)
        return 2
    if any(x in ("-h", "--help") for x in args) or not progress:
        return subprocess.call([str(DETECT), *args])
    proc = subprocess.Popen([str(DETECT), *args, "--progress"], stderr=subprocess.PIPE, text=True)
    bar = None
    assert proc.stderr is not None
    for line in proc.stderr:
        if line.startswith("progress "):
            _, done, total = line.split()
            if bar is None:
                bar = progress_bar(total=int(float(total)) or None, desc=desc, unit="fr", leave=False)
            bar.update(int(done) - bar.n)
        else:
            sys.stderr.write(line)
    if bar is not None:
        bar.close()
    return proc.wait()


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
