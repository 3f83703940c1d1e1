#!/usr/bin/env python3
"""A/B of two kernels on a CPU device (lavapipe), measured so that the machine's drift cancels.

    python3 scripts/cpu_ab.py B_SHADERS [--a A_SHADERS] [--a-bin BIN] [--b-bin BIN]
        [--a-option KEY=VALUE ...] [--b-option KEY=VALUE ...]
        [--scene mesh|sky|box|FILE.toml ...] [--rounds N] [--seconds S] [--width W] [--height H]

Each side is a caustica binary (default target/release/caustica) and a kernel: a folder of the
kernel's shader files (read through $CAUSTICA_SHADER_DIR) or `embedded`, the binary's own, with the
kernel options given for that side (`--kernel-option KEY=VALUE`, e.g. `--b-option bvh-width=8`:
the A/B of one binary's run-time choices, src/render/kernel_options.rs). In
each round the two sides render the same scene at the same time, each for the same wall time
(`caustica render --time`), sharing the machine's cores; a side's rate is the samples it rendered,
and a round's figure the ratio B / A. The script prints each round's ratio and their median and
geometric mean.

Why at the same time: the shared 2-core machines this project is measured on drift by 10-30 %
within seconds (docs/benchmarks/history.md), so an A/B of runs one after the other reads the drift as
often as the change. Two processes running side by side see the same drift; each gets about
half the cores, so the ratio is that of the work each kernel does per CPU-second. It is not a
wall-clock figure: a change that only keeps the device's threads busier (the tiles of
src/render/tile_taking.rs) reads as level here, since the other side fills the idle core, and is
measured with `caustica bench` runs instead.

Before the rounds, each side renders once unmeasured: lavapipe caches a compiled kernel on disk,
and a kernel's first compilation takes seconds out of its side's time.

The driver is the one the environment selects (VK_DRIVER_FILES; source `.lavapipe/env` for Mesa
25). The meshes' scenes need $CAUSTICA_DATA (default ../shared/data).
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# Named scenes: the mesh box and mesh under a sky (docs/benchmarks/history.md) and the Cornell box.
SCENES = {"mesh": "scenes/bunny_cornell.toml", "sky": "scenes/bunny_sky.toml", "box": "scenes/cornell.toml"}
# A render's summary line: "wrote FILE (WxH, N spp ...".
RENDERED = re.compile(r"\(\d+x\d+, (\d+) spp")


def side_env(shaders):
    env = dict(os.environ)
    env.setdefault("CAUSTICA_DATA", str(REPO.parent / "shared" / "data"))
    env.pop("CAUSTICA_SHADER_DIR", None)
    if shaders != "embedded":
        env["CAUSTICA_SHADER_DIR"] = str(Path(shaders).resolve())
    return env


def start(side, scene, args):
    """Starts a render of `scene` by `side` (binary, shaders, kernel options, output image) for
    args.seconds."""
    binary, shaders, options, output = side
    command = [binary, "render", scene, "--width", str(args.width), "--height", str(args.height),
               "--spp", "1000000", "--time", f"{args.seconds}s", "--output", output]
    for option in options:
        command += ["--kernel-option", option]
    return subprocess.Popen(command, cwd=REPO, env=side_env(shaders), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def samples(process, side):
    output = process.communicate()[0]
    found = RENDERED.search(output)
    if process.returncode != 0 or not found:
        sys.exit(f"side {side} failed (exit status {process.returncode}):\n{output}")
    return int(found.group(1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("b", metavar="B_SHADERS", help="side B's shader folder, or `embedded`")
    parser.add_argument("--a", default="embedded", help="side A's shader folder (default: embedded)")
    parser.add_argument("--a-bin", default="target/release/caustica")
    parser.add_argument("--b-bin", default=None, help="side B's binary (default: --a-bin)")
    parser.add_argument("--a-option", action="append", default=[], help="a kernel option KEY=VALUE for side A (repeatable)")
    parser.add_argument("--b-option", action="append", default=[], help="a kernel option KEY=VALUE for side B (repeatable)")
    parser.add_argument("--scene", action="append", help="mesh, sky, box or a scene file (default: mesh and sky)")
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--seconds", type=float, default=12)
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--height", type=int, default=128)
    args = parser.parse_args()
    b_bin = args.b_bin or args.a_bin
    out = Path(os.environ.get("TMPDIR", "/tmp"))
    for name in args.scene or ["mesh", "sky"]:
        scene = SCENES.get(name, name)
        sides = [(args.a_bin, args.a, args.a_option, str(out / "cpu_ab-a.pfm")),
                 (b_bin, args.b, args.b_option, str(out / "cpu_ab-b.pfm"))]
        # Unmeasured, both at once: fills lavapipe's disk cache with each side's kernel.
        warm_up = [start(side, scene, args) for side in sides]
        for process, label in zip(warm_up, "AB"):
            samples(process, label)
        ratios = []
        for _ in range(args.rounds):
            a, b = [start(side, scene, args) for side in sides]
            ratios.append(samples(b, "B") / samples(a, "A"))
        print(f"{name}: B/A median {statistics.median(ratios):.3f}, geometric mean {statistics.geometric_mean(ratios):.3f} "
              f"[{', '.join(f'{r:.3f}' for r in ratios)}]", flush=True)


if __name__ == "__main__":
    main()
