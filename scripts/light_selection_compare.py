#!/usr/bin/env python3
"""Measures how well each light selection ("bvh", "power", "uniform") does on caustica scenes:
per-pixel relative MSE of equal-spp renders against one high-spp reference.

    python3 scripts/light_selection_compare.py SCENE.toml [SCENE.toml ...] [--spp N]
        [--reference-spp N] [--reference-selection S] [--caustica PATH] [--json FILE]

For each scene a copy with `light_selection` set is written next to it (so that its relative
paths resolve) and removed afterwards; each selection renders it at --spp (default 64, seed 1),
and the reference at --reference-spp (default 2048, seed 99) with --reference-selection (default
"bvh": any selection converges to the same image, and the reference's own noise adds the same
small term to every figure). `caustica compare` gives the relative MSE (mean over pixels of
(image - reference)^2 / (reference^2 + 0.01), luminance) and the ratio of means.
The Vulkan driver is whatever the environment selects (e.g. `. .lavapipe/env`).
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

SELECTIONS = ["bvh", "power", "uniform"]


def with_selection(text, selection):
    """The scene's TOML with [integrator] light_selection set to `selection`."""
    line = f'light_selection = "{selection}"'
    if re.search(r"^light_selection\s*=.*$", text, flags=re.M):
        return re.sub(r"^light_selection\s*=.*$", line, text, flags=re.M)
    if re.search(r"^\[integrator\]\s*$", text, flags=re.M):
        return re.sub(r"^\[integrator\]\s*$", "[integrator]\n" + line, text, count=1, flags=re.M)
    return text + f"\n[integrator]\n{line}\n"


def render(caustica, scene, selection, spp, seed, out):
    """Renders `scene` with `selection` into `out`; returns the seconds it took."""
    with open(scene) as f:
        text = with_selection(f.read(), selection)
    folder = os.path.dirname(os.path.abspath(scene))
    fd, copy = tempfile.mkstemp(suffix=".toml", prefix=".selection-", dir=folder)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        start = time.time()
        subprocess.run([caustica, "render", copy, "-o", out, "--spp", str(spp), "--seed", str(seed), "-q"],
                       check=True)
        return time.time() - start
    finally:
        os.remove(copy)


def compare(caustica, image, reference):
    """`caustica compare`'s relative MSE and ratio of means."""
    out = subprocess.run([caustica, "compare", image, reference], check=True, capture_output=True,
                         text=True).stdout
    rel = float(re.search(r"relative MSE:\s*(\S+)", out).group(1))
    ratio = float(re.search(r"ratio of means:\s*(\S+)", out).group(1))
    return rel, ratio


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--reference-spp", type=int, default=2048)
    parser.add_argument("--reference-selection", default="bvh", choices=SELECTIONS)
    parser.add_argument("--caustica", default="target/release/caustica")
    parser.add_argument("--json")
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as scratch:
        for scene in args.scenes:
            name = os.path.splitext(os.path.basename(scene))[0]
            reference = os.path.join(scratch, f"{name}-reference.pfm")
            ref_seconds = render(args.caustica, scene, args.reference_selection, args.reference_spp, 99, reference)
            row = {"scene": scene, "spp": args.spp, "reference_spp": args.reference_spp,
                   "reference_seconds": round(ref_seconds, 1)}
            for selection in SELECTIONS:
                image = os.path.join(scratch, f"{name}-{selection}.pfm")
                seconds = render(args.caustica, scene, selection, args.spp, 1, image)
                rel, ratio = compare(args.caustica, image, reference)
                row[selection] = {"relative_mse": rel, "ratio_of_means": ratio, "seconds": round(seconds, 1)}
            results.append(row)
            best_other = min(row["power"]["relative_mse"], row["uniform"]["relative_mse"])
            print(f"{name}: relative MSE at {args.spp} spp against {args.reference_spp} spp: "
                  + ", ".join(f"{s} {row[s]['relative_mse']:.5f} ({row[s]['seconds']} s)" for s in SELECTIONS)
                  + f"; better of power and uniform / bvh = {best_other / max(row['bvh']['relative_mse'], 1e-30):.2f}x",
                  flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
