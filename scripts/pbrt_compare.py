#!/usr/bin/env python3
"""Renders pbrt-v4 scenes with caustica and with pbrt-v4 itself and measures both images' error
against one high-spp pbrt-v4 reference: how far caustica's import and rendering of a pbrt scene is
from what pbrt renders.

    python3 scripts/pbrt_compare.py SCENE.pbrt [SCENE.pbrt ...] [--width W] [--spp N]
        [--reference-spp N] [--pbrt PATH] [--caustica PATH] [--threads N] [--out DIR]
        [--previews] [--json]

Each scene is given to both renderers as it is, apart from its film size: a copy with the Film
directive's xresolution/yresolution set to --width (default 256) wide, the height keeping the
film's aspect ratio (pbrt's fov is along the shorter side, so the view is unchanged), is written
next to the scene (pbrt resolves relative paths from the first file's folder, caustica from the
scene's folder) and removed afterwards. pbrt renders the reference at --reference-spp (default
16 x spp, seed 99) and both renderers render at --spp (default 64, seed 1), pbrt with its own
sampler (the scene's, `--spp` overriding pixelsamples) and caustica with its own; each image is
compared with the reference per pixel (`caustica compare`: relative MSE, ratio of means) and by
8 x 8 block means (noise mostly averaged away, bias left), as scripts/mitsuba_compare.py does for
Mitsuba scenes. pbrt's own equal-spp error is the noise floor caustica's is measured against; a
caustica block figure well above pbrt's is a bias (a light's scale, a material mapping, a missing
feature), and the ratio of means says which way.

All images are written as PFM (both renderers write it), rows top to bottom when read back here.
With --previews each one also gets a PNG preview (exposure-free, clamped sRGB) and each scene a
caustica/reference ratio image of the 8 x 8 block means (grey = equal, red = caustica brighter,
blue = darker, saturating at a factor 2), written with numpy and zlib only.

pbrt is `pbrt` on PATH, or $PBRT, or --pbrt. The Vulkan driver is whatever the environment selects
(e.g. `. .lavapipe/env` for Mesa's lavapipe).
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

from mitsuba_compare import BLOCK, print_error_table

REPO = Path(__file__).resolve().parent.parent
# pbrt-v4's RGBFilm default resolution (film.cpp).
PBRT_DEFAULT_RESOLUTION = (1280, 720)


class SceneError(Exception):
    """The scene cannot be prepared for the comparison."""


# --- the scene file ----------------------------------------------------------------------------

TOKEN = re.compile(r'\s+|#[^\n]*|"[^"]*"|\[|\]|[^\s"\[\]#]+')


def tokens(text):
    """pbrt's tokens with their spans: quoted strings, brackets and bare words; comments and
    whitespace are dropped."""
    for m in TOKEN.finditer(text):
        t = m.group(0)
        if t[0].isspace() or t[0] == "#":
            continue
        yield t, m.start(), m.end()


def is_directive(t):
    return re.fullmatch(r"[A-Z][A-Za-z]*", t) is not None


def film_directive(text):
    """The main file's Film directive: (start, end, type, params) with params a list of
    (declaration, value text); None when the file has none."""
    toks = list(tokens(text))
    for i, (t, start, _) in enumerate(toks):
        if t != "Film":
            continue
        if i + 1 >= len(toks) or not toks[i + 1][0].startswith('"'):
            raise SceneError("Film without a type")
        kind = toks[i + 1][0].strip('"')
        params, j, end = [], i + 2, toks[i + 1][2]
        while j < len(toks) and toks[j][0].startswith('"'):
            decl = toks[j][0].strip('"')
            j += 1
            if j >= len(toks):
                raise SceneError(f"Film parameter {decl} without a value")
            if toks[j][0] == "[":
                k = j
                while k < len(toks) and toks[k][0] != "]":
                    k += 1
                if k == len(toks):
                    raise SceneError(f"Film parameter {decl}: unclosed [")
                value = " ".join(t for t, _, _ in toks[j + 1 : k])
                end, j = toks[k][2], k + 1
            else:
                value, end, j = toks[j][0], toks[j][2], j + 1
            params.append((decl, value))
        return start, end, kind, params
    return None


def scene_copy(scene_path, width):
    """The scene with its film `width` wide (height keeping the aspect ratio), written next to the
    scene. Returns (copy, width, height, notes)."""
    text = scene_path.read_text()
    notes = []
    film = film_directive(text)
    if film is None:
        if "Film" in {t for t, _, _ in tokens(text)}:
            raise SceneError("could not read the Film directive")
        m = re.search(r"^\s*WorldBegin\b", text, re.M)
        if m is None:
            raise SceneError("no Film and no WorldBegin in the main file (an Include'd Film is not handled)")
        start = end = m.start()
        kind, params = "rgb", []
        notes.append("no Film directive: pbrt's default rgb film, resized, inserted before WorldBegin")
    else:
        start, end, kind, params = film
    values = {d.split()[-1]: v for d, v in params}
    w0 = int(values.get("xresolution", PBRT_DEFAULT_RESOLUTION[0]))
    h0 = int(values.get("yresolution", PBRT_DEFAULT_RESOLUTION[1]))
    width = width or w0
    height = max(1, round(width * h0 / w0))
    kept = []
    for decl, value in params:
        name = decl.split()[-1]
        if name in ("xresolution", "yresolution"):
            continue
        if name in ("cropwindow", "pixelbounds"):
            notes.append(f"Film {name} dropped: the whole image is compared")
            continue
        kept.append(f'"{decl}" [ {value} ]')
    kept += [f'"integer xresolution" [ {width} ]', f'"integer yresolution" [ {height} ]']
    directive = f'Film "{kind}"\n    ' + "\n    ".join(kept) + "\n"
    copy = scene_path.parent / f".pbrt_compare.{os.getpid()}.{scene_path.name}"
    copy.write_text(text[:start] + directive + text[end:])
    return copy, width, height, notes


# --- images ------------------------------------------------------------------------------------


def read_pfm(path):
    import numpy as np

    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    channels = 3 if kind == b"PF" else 1
    image = data[: w * h * channels].reshape(h, w, channels)[::-1].astype(np.float64)
    return image if channels == 3 else np.repeat(image, 3, axis=2)


def block_means(image, k=BLOCK):
    h, w = image.shape[0] // k * k, image.shape[1] // k * k
    return image[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def block_relative_mse(image, reference, k=BLOCK):
    """`caustica compare`'s relative MSE of the k x k block means of the two images: averaging
    divides the noise's share by about k^2 and leaves a bias as it is."""
    a, b = block_means(read_pfm(image), k), block_means(read_pfm(reference), k)
    return float(((a - b) ** 2 / (b * b + 0.01)).mean())


def write_png(path, rgb8):
    """An 8-bit RGB image (rows top to bottom) as PNG, with zlib only."""
    h, w, _ = rgb8.shape
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))
    chunk = lambda tag, data: struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def srgb8(linear):
    import numpy as np

    x = np.clip(linear, 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (s * 255 + 0.5).astype(np.uint8)


def previews(out, names, reference):
    """PNG previews of the images and a block-ratio map caustica / reference."""
    import numpy as np

    for name in names:
        write_png(out / f"{name}.png", srgb8(read_pfm(out / f"{name}.pfm")))
    c = block_means(read_pfm(out / "caustica.pfm")).mean(axis=2)
    r = block_means(read_pfm(reference)).mean(axis=2)
    ratio = np.log2((c + 1e-4) / (r + 1e-4)).clip(-1, 1)  # -1: half, +1: double
    up, down = ratio.clip(0, 1), (-ratio).clip(0, 1)
    rgb = np.stack([0.5 + 0.5 * up - 0.5 * down, 0.5 - 0.5 * np.abs(ratio), 0.5 + 0.5 * down - 0.5 * up], axis=2)
    rgb = np.repeat(np.repeat(rgb, BLOCK, axis=0), BLOCK, axis=1)
    write_png(out / "ratio-caustica-over-reference.png", (rgb * 255 + 0.5).astype(np.uint8))


# --- the renderers -----------------------------------------------------------------------------


def run(cmd, what):
    started = time.perf_counter()
    done = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        raise SceneError(f"{what} failed ({' '.join(map(str, cmd))}):\n{done.stderr.strip() or done.stdout.strip()}")
    return done, seconds


def render_pbrt(args, scene, spp, seed, path):
    cmd = [args.pbrt, "--spp", spp, "--seed", seed, "--outfile", path, "--quiet"]
    if args.threads:
        cmd += ["--nthreads", args.threads]
    done, seconds = run(cmd + [scene], "pbrt")
    warnings = [l.strip() for l in (done.stderr + done.stdout).splitlines() if "warning" in l.lower()]
    return seconds, warnings


def render_caustica(args, scene, spp, seed, path):
    done, seconds = run([args.caustica, "render", scene, "-o", path, "--spp", spp, "--seed", seed, "-q"], "caustica")
    warnings = [l.removeprefix("caustica: warning: ") for l in done.stderr.splitlines() if l.startswith("caustica: warning: ")]
    return seconds, warnings


def compare(caustica, image, reference):
    """`caustica compare`: the project's relative MSE and ratio of means (docs/benchmarks/history.md)."""
    done, _ = run([caustica, "compare", image, reference], "caustica compare")
    figure = lambda label: float(re.search(rf"{label}:\s+(\S+)", done.stdout).group(1))
    ratio = re.search(r"ratio of means:\s+([0-9.eE+-]+)", done.stdout)
    return {"relative_mse": figure("relative MSE"), "ratio_of_means": float(ratio.group(1)) if ratio else None}


def compare_scene(args, scene_path, out):
    out.mkdir(parents=True, exist_ok=True)
    copy, width, height, notes = scene_copy(scene_path, args.width)
    try:
        spp = args.spp
        reference_spp = args.reference_spp or 16 * spp
        reference = out / "pbrt-reference.pfm"
        if args.reuse_reference and reference.is_file():
            reference_seconds, reference_warnings = None, []
            notes.append(f"reference reused from {reference}")
        else:
            reference_seconds, reference_warnings = render_pbrt(args, copy, reference_spp, 99, reference)
        pbrt_seconds, pbrt_warnings = render_pbrt(args, copy, spp, 1, out / "pbrt.pfm")
        caustica_seconds, caustica_warnings = render_caustica(args, copy, spp, 1, out / "caustica.pfm")
    finally:
        copy.unlink(missing_ok=True)
    result = {
        "scene": str(scene_path),
        "width": width,
        "height": height,
        "spp": spp,
        "notes": notes,
        "reference": {"image": str(reference), "spp": reference_spp, "renderer": "pbrt-v4", "seconds": reference_seconds, "warnings": reference_warnings},
        "images": str(out),
    }
    for name, seconds, warnings in (("caustica", caustica_seconds, caustica_warnings), ("pbrt", pbrt_seconds, pbrt_warnings)):
        image = out / f"{name}.pfm"
        result[name] = {**compare(args.caustica, image, reference), "block_relative_mse": block_relative_mse(image, reference), "seconds": seconds, "warnings": warnings}
    if args.previews:
        previews(out, ["pbrt-reference", "pbrt", "caustica"], reference)
    return result


def print_result(r):
    print(f"scene:      {r['scene']} at {r['width']}x{r['height']}, {r['spp']} spp")
    ref = r["reference"]
    took = "reused" if ref["seconds"] is None else f"{ref['seconds']:.1f} s"
    print(f"reference:  {ref['image']} ({ref['spp']} spp, pbrt-v4, {took})")
    for n in r["notes"]:
        print(f"note:       {n}")
    print_error_table(r, ("caustica", "pbrt"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scenes", nargs="+", help="pbrt-v4 scene files")
    parser.add_argument("--width", type=int, default=256, help="image width; the height keeps the film's aspect ratio (default: 256; 0: the scene's)")
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel of the compared renders (default: 64)")
    parser.add_argument("--reference-spp", type=int, help="spp of pbrt's reference (default: 16 x spp)")
    parser.add_argument("--pbrt", default=os.environ.get("PBRT", "pbrt"), help="the pbrt-v4 binary (default: $PBRT, else pbrt on PATH)")
    parser.add_argument("--caustica", default=str(REPO / "target" / "release" / "caustica"), help="the caustica binary (default: target/release/caustica)")
    parser.add_argument("--threads", type=int, help="pbrt's --nthreads (default: pbrt's, all cores)")
    parser.add_argument("--out", help="folder for the images, one subfolder per scene (default: a temporary folder, kept and printed)")
    parser.add_argument("--reuse-reference", action="store_true", help="keep a pbrt-reference.pfm already in the scene's output folder instead of rendering it again")
    parser.add_argument("--previews", action="store_true", help="also write PNG previews and a block-ratio map per scene")
    parser.add_argument("--json", action="store_true", help="print the results as one JSON document")
    args = parser.parse_args()

    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="pbrt-compare-"))
    results, failures = [], []
    for scene in args.scenes:
        scene_path = Path(scene).resolve()
        try:
            result = compare_scene(args, scene_path, out / scene_path.stem)
        except SceneError as e:
            failures.append({"scene": scene, "error": str(e)})
            print(f"pbrt_compare: {scene}: {e}", file=sys.stderr)
            continue
        results.append(result)
        if not args.json:
            print_result(result)
            print(flush=True)
    if args.json:
        print(json.dumps({"results": results, "failures": failures}, indent=2))
    elif results:
        print(f"| scene | size, spp | reference | caustica rel. MSE | pbrt rel. MSE | caustica {BLOCK}x{BLOCK}-block rel. MSE | pbrt {BLOCK}x{BLOCK}-block rel. MSE | caustica / reference mean | pbrt / reference mean |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in results:
            c, p = r["caustica"], r["pbrt"]
            print(f"| `{Path(r['scene']).name}` | {r['width']}x{r['height']}, {r['spp']} | {r['reference']['spp']} spp | {c['relative_mse']:.4f} | {p['relative_mse']:.4f} | {c['block_relative_mse']:.5f} | {p['block_relative_mse']:.5f} | {c['ratio_of_means']:.4f} | {p['ratio_of_means']:.4f} |")
        print(f"images in {out}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
