#!/usr/bin/env python3
"""Renders one caustica scene with caustica and with Mitsuba 3, in one run: both renderers'
samples per second and per CPU-second and their ratios, and both images' error against one
high-spp reference. On a shared machine the per-CPU-second figures are the steadier (on lavapipe
the device is caustica's own threads, and Dr.Jit's pool is Mitsuba's).

    python3 scripts/mitsuba_compare.py [SCENE.toml] [--width W] [--height H] [--spp N]
        [--reference REF.pfm | --reference-spp N] [--rounds N] [--out DIR] [--json]

    python3 scripts/mitsuba_compare.py SCENE.xml [--width W] [--spp N] [--reference-spp N]
        [--path DIR]... [--out DIR] [--json]
    python3 scripts/mitsuba_compare.py --mitsuba-data CHECKOUT [--width W] [--spp N] ...

A Mitsuba 3 XML scene (or, with --mitsuba-data, each of the example scenes of a mitsuba-data
checkout) is given to both renderers as it is, apart from its film size and any <path>s
(MITSUBA_DATA_SCENES, xml_copy): Mitsuba renders the reference at --reference-spp (default 64 x
spp) and both render at --spp (default 64); each is compared with the reference, per pixel and by
8 x 8 block means (noise mostly averaged away, bias left). No speed is measured in this mode.

SCENE defaults to scenes/cornell.toml (the built-in Cornell box). caustica is timed by
`caustica bench --json` (0.3 s of warm-up samples, then the timed ones) and its image comes from
`caustica render`; Mitsuba's scene is built from the same TOML file, rendered once to compile its
kernels (Dr.Jit caches them), then rendered again and timed up to the image in memory (Dr.Jit
evaluates lazily: the time stops only once the image is a numpy array). Both errors are relative MSE
from `caustica compare` against a reference that caustica renders at --reference-spp (default
16 x spp; seed 99, unlike the measured renders' seed 1), or against --reference.

With --rounds N the two timed measurements alternate N times (caustica's bench, then Mitsuba's
timed render, again and again; Mitsuba's scene is loaded and compiled once). A shared 2-core
machine drifts by 10-30 % within seconds (docs/benchmarks/history.md, 2026-12-05, `9e81c69`), so one pair of
measurements can read the drift; the report gives every round's ratio and takes the round whose
ratio is the median (the lower middle one of an even count) as the result.

Needs: `pip install mitsuba numpy`; on Debian 12 also `apt-get install libllvm19` (Mitsuba's CPU
variant crashes on the system's LLVM 15; Dr.Jit finds LLVM 19 by itself once it is installed,
or set DRJIT_LIBLLVM_PATH). The Vulkan driver is whatever the environment selects (e.g.
VK_DRIVER_FILES); the report names it.

Mapped (anything else in the scene is an error naming it): the pinhole or thin-lens camera
(vertical fov), film size and spp and box/tent/gaussian filter, spheres, quads, PLY and OBJ meshes
with a `material` and their placements (several: Mitsuba instances), materials mixing diffuse
(albedo), a perfect mirror (reflectivity) and smooth glass (transparency, ior) with emission
(one-sided area lights), a constant sky, and the path integrator's depth and roulette settings.
The renderers then compute the same image; they still differ in how they sample it (Mitsuba picks
a light uniformly and plays roulette on throughput x eta^2 without caustica's floor of 0.05), which
changes noise and speed but not the expected value.
"""

import argparse
import contextlib
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DATA_PREFIX = "$CAUSTICA_DATA/"
# Side of the blocks whose means the bias figure compares.
BLOCK = 8
# mitsuba-data's example scenes (github.com/mitsuba-renderer/mitsuba-data): name, scene file and
# extra folders its files are in (the Veach scene's meshes are in docs/scenes/meshes).
MITSUBA_DATA_SCENES = [
    ("Cornell box", "scenes/cbox/cbox.xml", []),
    ("Veach MIS", "docs/scenes/include/veach_mis.xml", ["docs/scenes"]),
    ("material preview", "scenes/matpreview/matpreview.xml", []),
]


class Unmapped(Exception):
    """The scene uses something this script cannot give Mitsuba."""


# --- the scene file, read as caustica reads it -------------------------------------------------


def data_dir():
    """caustica's shared data folder: $CAUSTICA_DATA, or ../shared/data from the working directory
    (src/scene/mod.rs, data_dir)."""
    return Path(os.environ.get("CAUSTICA_DATA", "../shared/data"))


def resolve(base, file):
    """A path in a scene file: `$CAUSTICA_DATA/...`, absolute, or relative to the scene file."""
    if file.startswith(DATA_PREFIX):
        return data_dir() / file[len(DATA_PREFIX):]
    p = Path(file)
    return p if p.is_absolute() else base / p


def placement(entry):
    """Object to world of a mesh entry or instance: scale, then rotate about x, y and z (degrees),
    then translate, as caustica's `placement` (src/scene/mod.rs)."""
    import numpy as np

    scale = entry.get("scale", 1.0)
    s = np.diag(list(scale if isinstance(scale, list) else [scale] * 3) + [1.0])
    rx, ry, rz = (math.radians(a) for a in entry.get("rotate", [0.0, 0.0, 0.0]))
    cx, sx, cy, sy, cz, sz = math.cos(rx), math.sin(rx), math.cos(ry), math.sin(ry), math.cos(rz), math.sin(rz)
    r_x = np.array([[1, 0, 0, 0], [0, cx, -sx, 0], [0, sx, cx, 0], [0, 0, 0, 1]])
    r_y = np.array([[cy, 0, sy, 0], [0, 1, 0, 0], [-sy, 0, cy, 0], [0, 0, 0, 1]])
    r_z = np.array([[cz, -sz, 0, 0], [sz, cz, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    t = np.eye(4)
    t[:3, 3] = entry.get("translate", [0.0, 0.0, 0.0])
    return t @ r_z @ r_y @ r_x @ s


def has_vertex_normals(path):
    """Whether a PLY or OBJ file brings its own vertex normals. caustica interpolates them when it
    does and shades with the flat triangle normal when it does not; Mitsuba would compute smooth
    normals instead, so it is told to use face normals then."""
    if path.suffix.lower() == ".ply":
        with open(path, "rb") as f:
            header = b""
            while b"end_header" not in header:
                line = f.readline()
                if not line:
                    break
                header += line
        return re.search(rb"property\s+\w+\s+nx\b", header) is not None
    with open(path, errors="replace") as f:
        return any(line.startswith("vn ") for line in f)


# --- Mitsuba's scene ---------------------------------------------------------------------------


def rgb(value):
    return {"type": "rgb", "value": [float(c) for c in value]}


MATERIAL_KEYS = {"albedo", "reflectivity", "transparency", "ior", "emission", "two_sided", "roughness", "metal", "eta", "k", "coat"}


def material_bsdf(name, m):
    """caustica's R/T model as a Mitsuba BSDF: with probability R a perfect mirror, with T smooth
    glass, else diffuse; a linear mix, which Mitsuba's blendbsdf is. caustica scatters from both
    sides of a diffuse or mirror surface (Mitsuba's BSDFs are one-sided: `twosided`)."""
    key = f"materials.{name}"
    unknown = set(m) - MATERIAL_KEYS
    if unknown:
        raise Unmapped(f"{key}: unknown keys {sorted(unknown)}")
    for field, why in [("metal", "conductors"), ("eta", "conductors"), ("k", "conductors")]:
        if field in m:
            raise Unmapped(f"{key}.{field}: {why} are not mapped (only the perfect mirror is)")
    if m.get("roughness", 0.0) > 0.0:
        raise Unmapped(f"{key}.roughness = {m['roughness']}: rough (GGX) lobes are not mapped")
    if m.get("coat", False):
        raise Unmapped(f"{key}.coat: plastics are not mapped")
    albedo = m.get("albedo", [0.8, 0.8, 0.8])
    r, t, ior = m.get("reflectivity", 0.0), m.get("transparency", 0.0), m.get("ior", 1.5)
    base = 1.0 - r - t
    reflecting = None
    if base > 0.0:
        reflecting = {"type": "diffuse", "reflectance": rgb(albedo)}
    if r > 0.0:
        mirror = {"type": "conductor", "material": "none"}
        reflecting = mirror if reflecting is None else {"type": "blendbsdf", "weight": r / (r + base), "bsdf_0": reflecting, "bsdf_1": mirror}
    glass = {"type": "dielectric", "int_ior": float(ior), "ext_ior": 1.0} if t > 0.0 else None
    if glass is None:
        return {"type": "twosided", "bsdf": reflecting}
    if reflecting is None:
        return glass
    return {"type": "blendbsdf", "weight": t, "bsdf_0": {"type": "twosided", "bsdf": reflecting}, "bsdf_1": glass}


def emitter(name, m):
    emission = m.get("emission", [0.0, 0.0, 0.0])
    if max(emission) <= 0.0:
        return None
    if m.get("two_sided", False):
        raise Unmapped(f"materials.{name}.two_sided: two-sided emitters are not mapped (Mitsuba's area lights emit on one side)")
    return {"type": "area", "radiance": rgb(emission)}


def with_material(shape, materials, name, where):
    if name not in materials:
        raise Unmapped(f"{where}: unknown material '{name}'")
    bsdf, light = materials[name]
    shape["bsdf"] = bsdf
    if light is not None:
        shape["emitter"] = light
    return shape


def quad_to_world(q):
    """Mitsuba's rectangle is [-1, 1]^2 in the xy plane facing +z; caustica's quad is origin +
    s u + t v, s and t in [0, 1], facing u x v."""
    import numpy as np

    o, u, v = (np.array(q[k], dtype=float) for k in ("origin", "edge_u", "edge_v"))
    n = np.cross(u, v)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u / 2, v / 2, n / np.linalg.norm(n), o + (u + v) / 2
    return m


SCENE_KEYS = {"camera", "film", "integrator", "materials", "spheres", "quads", "triangles", "meshes", "environment"}


def mitsuba_scene(scene_path, width, height, spp):
    """The Mitsuba scene dictionary of a caustica TOML scene, or Unmapped naming what it cannot map."""
    import mitsuba as mi
    import numpy as np

    text = scene_path.read_text()
    doc = tomllib.loads(text)
    base = scene_path.parent
    unknown = set(doc) - SCENE_KEYS
    if unknown:
        raise Unmapped(f"unknown tables {sorted(unknown)}")

    cam = doc["camera"]
    to_world = mi.ScalarTransform4f().look_at(origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0.0, 1.0, 0.0]))
    film = doc.get("film", {})
    filters = {"box": {"type": "box"}, "tent": {"type": "tent", "radius": 1.0}, "gaussian": {"type": "gaussian", "stddev": 0.5}}
    integ = doc.get("integrator", {})
    sampler = {"sobol": "multijitter", "independent": "independent"}[integ.get("sampler", "sobol")]
    sensor = {
        "type": "perspective",
        "fov": float(cam.get("fov", 40.0)),
        "fov_axis": "y",  # caustica's fov is vertical
        "to_world": to_world,
        "sampler": {"type": sampler, "sample_count": spp},
        "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": filters[film.get("filter", "box")], "pixel_format": "rgb"},
    }
    if cam.get("aperture", 0.0) > 0.0:
        focus = cam.get("focus_distance", float(np.linalg.norm(np.subtract(cam["look_at"], cam["position"]))))
        sensor.update({"type": "thinlens", "aperture_radius": float(cam["aperture"]), "focus_distance": float(focus)})

    if not integ.get("nee", True):
        raise Unmapped("integrator.nee = false: Mitsuba's path integrator always samples the lights")
    if "clamp" in integ:
        raise Unmapped("integrator.clamp: Mitsuba's path integrator has no clamp (it changes the image)")
    # caustica's max_bounces and Mitsuba's max_depth both count a path's segments, the camera ray
    # and the one to a sampled light included (integrator.glsl samples no light at the last
    # vertex the cap allows): the same number.
    # Roulette: caustica's rr_start counts bounces traced before it starts, Mitsuba's rr_depth the
    # vertices: the same number.
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(integ.get("max_bounces", 1024)), "rr_depth": int(integ.get("rr_start", 4))},
        "sensor": sensor,
    }
    materials = {name: (material_bsdf(name, m), emitter(name, m)) for name, m in doc.get("materials", {}).items()}

    for k, s in enumerate(doc.get("spheres", [])):
        scene[f"sphere_{k}"] = with_material({"type": "sphere", "center": s["center"], "radius": float(s["radius"])}, materials, s["material"], f"spheres[{k}]")
    for k, q in enumerate(doc.get("quads", [])):
        scene[f"quad_{k}"] = with_material({"type": "rectangle", "to_world": mi.ScalarTransform4f(quad_to_world(q))}, materials, q["material"], f"quads[{k}]")
    if doc.get("triangles"):
        raise Unmapped(f"triangles ({len(doc['triangles'])}): single triangles are not mapped")
    for k, m in enumerate(doc.get("meshes", [])):
        key = f"meshes[{k}]"
        path = resolve(base, m["file"])
        kind = path.suffix.lower().lstrip(".")
        if kind not in ("ply", "obj"):
            raise Unmapped(f"{key}: {path.name}: only PLY and OBJ meshes are mapped")
        if "material" not in m:
            raise Unmapped(f"{key}: the file's own materials are not mapped; give the entry a material")
        if not path.is_file():
            raise Unmapped(f"{key}: {path} does not exist (is the shared data folder, $CAUSTICA_DATA, there?)")
        shape = with_material({"type": kind, "filename": str(path), "face_normals": not has_vertex_normals(path)}, materials, m["material"], key)
        outer = placement(m)
        instances = m.get("instances", [])
        if not instances:
            scene[f"mesh_{k}"] = dict(shape, to_world=mi.ScalarTransform4f(outer))
        elif "emitter" in shape:
            raise Unmapped(f"{key}: instances of an emitting mesh are not mapped (Mitsuba instances cannot emit)")
        else:
            # One mesh and BVH, several placements: what caustica does, so the two compare.
            scene[f"mesh_{k}_group"] = {"type": "shapegroup", "shape": shape}
            for j, inst in enumerate(instances):
                scene[f"mesh_{k}_instance_{j}"] = {"type": "instance", "shapegroup": {"type": "ref", "id": f"mesh_{k}_group"}, "to_world": mi.ScalarTransform4f(placement(inst) @ outer)}

    env = doc.get("environment")
    if env is not None:
        for field in ("probe", "latlong"):
            if field in env:
                raise Unmapped(f"environment.{field}: environment maps are not mapped (only a constant sky)")
        if "color" in env:
            scene["sky"] = {"type": "constant", "radiance": rgb([c * env.get("intensity", 1.0) for c in env["color"]])}
    return scene


# --- running both renderers --------------------------------------------------------------------


def write_pfm(path, image):
    """A linear RGB float image (rows top to bottom) as PFM: rows bottom to top, little-endian."""
    import numpy as np

    h, w, _ = image.shape
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(np.ascontiguousarray(image[::-1], dtype="<f4").tobytes())


def run(cmd, **kwargs):
    done = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kwargs)
    if done.returncode != 0:
        sys.exit(f"mitsuba_compare: {' '.join(map(str, cmd))} failed:\n{done.stderr}")
    return done.stdout


def compare(caustica, image, reference):
    """`caustica compare`: the project's relative MSE and ratio of means, so the figures are those
    of docs/benchmarks/history.md."""
    out = run([caustica, "compare", image, reference])
    figure = lambda label: float(re.search(rf"{label}:\s+(\S+)", out).group(1))
    ratio = re.search(r"ratio of means:\s+([0-9.eE+-]+)", out)
    return {"relative_mse": figure("relative MSE"), "ratio_of_means": float(ratio.group(1)) if ratio else None}


def size_args(width, height, spp):
    return ["--width", width, "--height", height, "--spp", spp]


def bench_caustica(caustica, scene, width, height, spp):
    return json.loads(run([caustica, "bench", scene, *size_args(width, height, spp), "--json"]))


def render_caustica(caustica, scene, width, height, spp, out):
    image = out / "caustica.pfm"
    run([caustica, "render", scene, "-o", image, *size_args(width, height, spp), "--seed", 1, "-q"])
    return image


def round_figures(bench, mitsuba):
    """One round's rates (samples per second, and per CPU-second where both are known) and ratios."""
    cpu = (bench.get("samples_per_cpu_second"), mitsuba["samples_per_cpu_second"])
    return {
        "caustica_samples_per_second": bench["samples_per_second"],
        "mitsuba_samples_per_second": mitsuba["samples_per_second"],
        "ratio": bench["samples_per_second"] / mitsuba["samples_per_second"],
        "ratio_per_cpu_second": cpu[0] / cpu[1] if all(cpu) else None,
    }


def loaded_llvm():
    """The LLVM library Dr.Jit loaded (Debian 12's LLVM 15 crashes Mitsuba; 19 works)."""
    try:
        with open("/proc/self/maps") as maps:
            return sorted({Path(line.split()[-1]).name for line in maps if "libLLVM" in line})
    except OSError:
        return []


@contextlib.contextmanager
def stdout_to_stderr():
    """Mitsuba's log (warnings such as "ASCII PLY is slow to parse") goes to the process's standard
    output, from C++: the file descriptor itself is pointed at stderr, so --json output stays one
    document."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


class MitsubaRun:
    """Mitsuba's side: the scene loaded and its kernels compiled once, then timed renders."""

    def __init__(self, scene_dict, width, height, spp, variant):
        import mitsuba as mi
        import numpy as np

        self.width, self.height, self.variant = width, height, variant
        started = time.perf_counter()
        self.scene = mi.load_dict(scene_dict)
        self.load_seconds = time.perf_counter() - started
        # Mitsuba's multi-jittered sampler rounds some counts up (512 becomes 528): the rate
        # counts the samples it takes.
        self.spp = self.scene.sensors()[0].sampler().sample_count()
        # The first render compiles the kernels (cached by Dr.Jit); the timed ones, with the
        # same shapes and seed, reuse them. np.array forces the evaluation.
        started = time.perf_counter()
        np.array(mi.render(self.scene, spp=self.spp, seed=1))
        self.first_seconds = time.perf_counter() - started

    def timed(self):
        """One timed render: its figures and its image (a numpy array)."""
        import drjit as dr
        import mitsuba as mi
        import numpy as np

        started, cpu_started = time.perf_counter(), time.process_time()
        image = np.array(mi.render(self.scene, spp=self.spp, seed=1))
        seconds = time.perf_counter() - started
        # All of this process's threads (Dr.Jit's pool included), as caustica's bench counts its
        # own: on a shared machine the per-CPU-second rates compare where wall-clock rates swing.
        cpu_seconds = time.process_time() - cpu_started
        samples = self.width * self.height * self.spp
        return {
            "version": mi.__version__,
            "drjit_version": dr.__version__,
            "variant": self.variant,
            "llvm": loaded_llvm(),
            "threads": os.cpu_count(),
            "spp": self.spp,
            "load_seconds": self.load_seconds,
            "first_render_seconds": self.first_seconds,
            "seconds": seconds,
            "samples_per_second": samples / seconds,
            "cpu_seconds": cpu_seconds,
            "samples_per_cpu_second": samples / cpu_seconds if cpu_seconds > 0 else None,
        }, image


# --- a Mitsuba XML scene, read by both renderers -------------------------------------------------


def xml_copy(scene_path, out, width, paths):
    """The XML scene written into `out` with its film `width` wide (the height keeping the film's
    aspect ratio, so `fov_axis` means the same) and `<path>`s to its own folder and to `paths`, so
    both renderers find its meshes and maps from there, and Mitsuba's default integrator (`path`)
    written out where it has none. Returns the copy and its (width, height)."""
    import xml.etree.ElementTree as ET

    tree = ET.parse(scene_path)
    root = tree.getroot()
    defaults = {d.get("name"): d.get("value") for d in root.iter("default")}
    value = lambda v: defaults.get(v[1:], v) if v.startswith("$") else v
    films = list(root.iter("film"))
    if len(films) != 1:
        raise Unmapped(f"{len(films)} films: the comparison needs exactly one")
    film = films[0]
    sizes = {e.get("name"): e for e in film.findall("integer") if e.get("name") in ("width", "height")}
    w0, h0 = (int(value(sizes[k].get("value"))) if k in sizes else d for k, d in (("width", 768), ("height", 576)))
    width = width or w0
    height = max(1, round(width * h0 / w0))
    for name, v in (("width", width), ("height", height)):
        element = sizes.get(name)
        if element is None:
            element = ET.SubElement(film, "integer", name=name)
        element.set("value", str(v))
    if root.find("integrator") is None:
        # What `mitsuba scene.xml` renders such a scene with (mi.render wants it written out).
        root.append(ET.Element("integrator", type="path"))
    for k, folder in enumerate([scene_path.parent, *paths]):
        root.insert(k, ET.Element("path", value=str(Path(folder).resolve())))
    copy = out / scene_path.name
    tree.write(copy)
    return copy, width, height


def caustica_warnings(stderr):
    return [line.removeprefix("caustica: warning: ") for line in stderr.splitlines() if line.startswith("caustica: warning: ")]


def render_mitsuba_xml(scene_file, spp, seed, variant, path):
    """Mitsuba's render of the scene file at `spp`, written to `path` (PFM); returns its seconds and
    the warnings Mitsuba logged."""
    import mitsuba as mi
    import numpy as np

    warnings = []

    class Collect(mi.Appender):
        def append(self, level, text):
            if level >= mi.LogLevel.Warn:
                warnings.append(text.strip())

        def log_progress(self, *args):
            pass

    logger = mi.logger() if hasattr(mi, "logger") else mi.Thread.thread().logger()
    logger.clear_appenders()
    logger.add_appender(Collect())
    started = time.perf_counter()
    scene = mi.load_file(str(scene_file))
    image = np.array(mi.render(scene, spp=spp, seed=seed))
    seconds = time.perf_counter() - started
    write_pfm(path, image[..., :3])
    return seconds, warnings


def read_pfm(path):
    import numpy as np

    with open(path, "rb") as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3)[::-1]


def block_relative_mse(image, reference, k=BLOCK):
    """`caustica compare`'s relative MSE of the k x k block means of the two images: averaging
    divides the noise's share by about k^2 and leaves a bias (a brighter wall, a wider highlight)
    as it is, so what is left beyond Mitsuba's own figure is bias."""
    a, b = read_pfm(image), read_pfm(reference)
    h, w = a.shape[0] // k * k, a.shape[1] // k * k
    means = lambda x: x[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))
    a, b = means(a), means(b)
    return float(((a - b) ** 2 / (b * b + 0.01)).mean())


def compare_xml(args, scene_path, out):
    """A Mitsuba XML scene: Mitsuba's high-spp reference, then both renderers at --spp, each
    against that reference (Mitsuba's own equal-spp error is the noise the other is measured
    against). Returns the figures."""
    import mitsuba as mi

    mi.set_variant(args.variant)
    out.mkdir(parents=True, exist_ok=True)
    try:
        copy, width, height = xml_copy(scene_path, out, args.width, args.path)
    except Unmapped as e:
        sys.exit(f"mitsuba_compare: {scene_path}: {e}")
    spp = args.spp or 64
    reference_spp = args.reference_spp or 64 * spp
    reference = out / "mitsuba-reference.pfm"
    with stdout_to_stderr():
        reference_seconds, mitsuba_warnings = render_mitsuba_xml(copy, reference_spp, 99, args.variant, reference)
        mitsuba_seconds, _ = render_mitsuba_xml(copy, spp, 1, args.variant, out / "mitsuba.pfm")
    started = time.perf_counter()
    done = subprocess.run([str(c) for c in [args.caustica, "render", copy, "-o", out / "caustica.pfm", "--spp", spp, "--seed", 1]], capture_output=True, text=True)
    caustica_seconds = time.perf_counter() - started
    if done.returncode != 0:
        sys.exit(f"mitsuba_compare: caustica cannot render {scene_path}:\n{done.stderr}")
    result = {
        "scene": str(scene_path),
        "width": width,
        "height": height,
        "spp": spp,
        "reference": {"image": str(reference), "spp": reference_spp, "renderer": f"Mitsuba {mi.__version__} {args.variant}", "seconds": reference_seconds},
        "images": str(out),
    }
    for name, seconds, warnings in (("caustica", caustica_seconds, caustica_warnings(done.stderr)), ("mitsuba", mitsuba_seconds, mitsuba_warnings)):
        image = out / f"{name}.pfm"
        result[name] = {**compare(args.caustica, image, reference), "block_relative_mse": block_relative_mse(image, reference), "seconds": seconds, "warnings": warnings}
    return result


def print_xml_result(result):
    print(f"scene:      {result['scene']} at {result['width']}x{result['height']}, {result['spp']} spp")
    print(f"reference:  {result['reference']['image']} ({result['reference']['spp']} spp, {result['reference']['renderer']})")
    print_error_table(result, ("caustica", "mitsuba"))


def print_error_table(result, renderers):
    """Each renderer's errors against the reference, a row each, then its warnings (scripts/pbrt_compare.py
    prints its results through this too)."""
    print(f"{'renderer':<10}  {'relative MSE':>12}  {f'{BLOCK}x{BLOCK} blocks':>12}  {'ratio of means':>14}  {'seconds':>8}")
    for name in renderers:
        r = result[name]
        ratio = "-" if r["ratio_of_means"] is None else f"{r['ratio_of_means']:.4f}"
        print(f"{name:<10}  {r['relative_mse']:>12.5f}  {r['block_relative_mse']:>12.5f}  {ratio:>14}  {r['seconds']:>8.1f}")
        for w in r["warnings"]:
            print(f"  warning: {w}")


def mitsuba_data_table(args):
    """Every scene of MITSUBA_DATA_SCENES from the mitsuba-data checkout at args.mitsuba_data, and
    a Markdown table of the figures (docs/benchmarks/history.md)."""
    root = Path(args.mitsuba_data)
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="mitsuba-compare-"))
    results = []
    for name, scene, paths in MITSUBA_DATA_SCENES:
        args.path = [str(root / p) for p in paths]
        result = compare_xml(args, root / scene, out / Path(scene).stem)
        print_xml_result(result)
        print(flush=True)
        results.append((name, scene, result))
    if args.json:
        print(json.dumps([r for _, _, r in results], indent=2))
        return
    print(f"| scene | size, spp | reference | caustica rel. MSE | Mitsuba rel. MSE | caustica {BLOCK}x{BLOCK}-block rel. MSE | Mitsuba {BLOCK}x{BLOCK}-block rel. MSE | caustica / reference mean |")
    print("|---|---|---|---|---|---|---|---|")
    for name, scene, r in results:
        c, m = r["caustica"], r["mitsuba"]
        print(f"| {name} (`{scene}`) | {r['width']}x{r['height']}, {r['spp']} | {r['reference']['spp']} spp | {c['relative_mse']:.4f} | {m['relative_mse']:.4f} | {c['block_relative_mse']:.5f} | {m['block_relative_mse']:.5f} | {c['ratio_of_means']:.4f} |")


def main():
    if any(a.lower().endswith(".xml") or a == "--mitsuba-data" for a in sys.argv[1:2]):
        return xml_main()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", nargs="?", default=str(REPO / "scenes" / "cornell.toml"), help="caustica TOML scene (default: scenes/cornell.toml)")
    parser.add_argument("--width", type=int, help="image width (default: the scene's film.width)")
    parser.add_argument("--height", type=int, help="image height (default: the scene's film.height)")
    parser.add_argument("--spp", type=int, help="samples per pixel (default: the scene's film.spp)")
    parser.add_argument("--reference", help="reference image (PFM or EXR) of the same size; default: rendered by caustica")
    parser.add_argument("--reference-spp", type=int, help="spp of the reference caustica renders (default: 16 x spp)")
    parser.add_argument("--caustica", default=str(REPO / "target" / "release" / "caustica"), help="the caustica binary (default: target/release/caustica)")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb, the CPU one)")
    parser.add_argument("--rounds", type=int, default=1, help="timed measurements of each renderer, alternating; the median round is the result (default: 1)")
    parser.add_argument("--out", help="folder for the images (default: a temporary folder, kept and printed)")
    parser.add_argument("--json", action="store_true", help="print the results as one JSON document")
    args = parser.parse_args()
    if args.rounds < 1:
        sys.exit(f"mitsuba_compare: --rounds {args.rounds}: at least one round is measured")

    scene_path = Path(args.scene)
    doc = tomllib.loads(scene_path.read_text())
    film = doc.get("film", {})
    width, height, spp = args.width or film.get("width", 512), args.height or film.get("height", 512), args.spp or film.get("spp", 64)
    try:
        import mitsuba as mi
    except ImportError:
        sys.exit("mitsuba_compare: Mitsuba 3 is not installed: pip install mitsuba numpy (and on Debian 12: apt-get install libllvm19)")
    mi.set_variant(args.variant)
    try:
        scene_dict = mitsuba_scene(scene_path, width, height, spp)
    except Unmapped as e:
        sys.exit(f"mitsuba_compare: {scene_path}: cannot give this scene to Mitsuba: {e}")

    if args.reference is not None:
        # Refused now rather than after minutes of rendering.
        ref_size = tuple(mi.Bitmap(args.reference).size())
        if ref_size != (width, height):
            sys.exit(f"mitsuba_compare: --reference {args.reference} is {ref_size[0]}x{ref_size[1]}, not {width}x{height}")
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="mitsuba-compare-"))
    out.mkdir(parents=True, exist_ok=True)
    load_before = os.getloadavg()
    caustica_image = render_caustica(args.caustica, scene_path, width, height, spp, out)
    with stdout_to_stderr():
        mitsuba_run = MitsubaRun(scene_dict, width, height, spp, args.variant)
    rounds = []
    for _ in range(args.rounds):
        bench = bench_caustica(args.caustica, scene_path, width, height, spp)
        with stdout_to_stderr():
            mitsuba, image = mitsuba_run.timed()
        rounds.append((bench, mitsuba, image))
    figures = [round_figures(b, m) for b, m, _ in rounds]
    # The median round by its ratio of samples per second (the lower middle one of an even count).
    by_ratio = sorted(range(len(rounds)), key=lambda k: figures[k]["ratio"])
    bench, mitsuba, image = rounds[by_ratio[(len(rounds) - 1) // 2]]
    mitsuba_image = out / "mitsuba.pfm"
    write_pfm(mitsuba_image, image)
    reference, reference_spp = args.reference, None
    if reference is None:
        reference_spp = args.reference_spp or 16 * spp
        reference = out / "reference.pfm"
        run([args.caustica, "render", scene_path, "-o", reference, *size_args(width, height, reference_spp), "--seed", 99, "-q"])
    load_after = os.getloadavg()
    errors = {"caustica": compare(args.caustica, caustica_image, reference), "mitsuba": compare(args.caustica, mitsuba_image, reference)}

    speed_ratio = bench["samples_per_second"] / mitsuba["samples_per_second"]
    per_cpu = (bench.get("samples_per_cpu_second"), mitsuba["samples_per_cpu_second"])
    cpu_ratio = per_cpu[0] / per_cpu[1] if all(per_cpu) else None
    result = {
        "scene": str(scene_path),
        "width": width,
        "height": height,
        "spp": spp,
        "reference": {"image": str(reference), "spp": reference_spp},
        "caustica": {**bench, **errors["caustica"], "image": str(caustica_image)},
        "mitsuba": {**mitsuba, **errors["mitsuba"], "image": str(mitsuba_image)},
        "caustica_over_mitsuba_samples_per_second": speed_ratio,
        "caustica_over_mitsuba_samples_per_cpu_second": cpu_ratio,
        "rounds": figures,
        "load_average_before": load_before,
        "load_average_after": load_after,
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return
    c, m = result["caustica"], result["mitsuba"]
    driver = f"{c.get('driver_name', '')}, {c.get('driver_info', '')}".strip(", ")
    ref = f"{reference} ({reference_spp} spp, caustica)" if reference_spp else reference
    print(f"scene:      {scene_path} at {width}x{height}, {spp} spp")
    print(f"reference:  {ref}")
    print(f"caustica:   {c['device']} ({driver})")
    rounded = f", {m['spp']} spp (its sampler's rounding)" if m["spp"] != spp else ""
    print(f"Mitsuba:    {m['version']} {m['variant']} on {m['threads']} threads ({', '.join(m['llvm']) or 'LLVM not found'}){rounded}")
    print(f"load:       {load_before[0]:.2f} before, {load_after[0]:.2f} after (1-minute averages)")
    print()
    print(f"{'renderer':<10}  {'Msamples/s':>10}  {'seconds':>8}  {'Msamples/CPU-s':>14}  {'relative MSE':>12}  {'ratio of means':>14}")
    for name, r in (("caustica", c), ("Mitsuba", m)):
        ratio = "-" if r["ratio_of_means"] is None else f"{r['ratio_of_means']:.4f}"
        cpu = "-" if r.get("samples_per_cpu_second") is None else f"{r['samples_per_cpu_second'] / 1e6:.3f}"
        print(f"{name:<10}  {r['samples_per_second'] / 1e6:>10.3f}  {r['seconds']:>8.2f}  {cpu:>14}  {r['relative_mse']:>12.5f}  {ratio:>14}")
    print()
    if len(rounds) > 1:
        each = ", ".join(f"{r['ratio']:.3f}" for r in result["rounds"])
        print(f"rounds (caustica / Mitsuba, samples per second): {each}; the median round is shown")
    print(f"caustica / Mitsuba, samples per second: {speed_ratio:.3f}")
    if cpu_ratio is not None:
        print(f"caustica / Mitsuba, samples per CPU-second: {cpu_ratio:.3f}")
    print(f"images in {out}")


def xml_main():
    parser = argparse.ArgumentParser(description="A Mitsuba 3 XML scene rendered by Mitsuba (reference and equal spp) and caustica.")
    parser.add_argument("scene", nargs="?", help="Mitsuba 3 XML scene")
    parser.add_argument("--mitsuba-data", help="instead of a scene: a checkout of github.com/mitsuba-renderer/mitsuba-data, whose example scenes are all compared, with a Markdown table")
    parser.add_argument("--width", type=int, help="image width; the height keeps the film's aspect ratio (default: the scene's)")
    parser.add_argument("--spp", type=int, help="samples per pixel of the compared renders (default: 64)")
    parser.add_argument("--reference-spp", type=int, help="spp of Mitsuba's reference (default: 64 x spp)")
    parser.add_argument("--path", action="append", default=[], help="another folder the scene's files are looked for in (Mitsuba's <path>)")
    parser.add_argument("--caustica", default=str(REPO / "target" / "release" / "caustica"), help="the caustica binary (default: target/release/caustica)")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (default: llvm_ad_rgb, the CPU one)")
    parser.add_argument("--out", help="folder for the images (default: a temporary folder, kept and printed)")
    parser.add_argument("--json", action="store_true", help="print the results as one JSON document")
    args = parser.parse_args()
    if args.mitsuba_data:
        return mitsuba_data_table(args)
    if args.scene is None:
        parser.error("give a scene or --mitsuba-data")
    result = compare_xml(args, Path(args.scene), Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="mitsuba-compare-")))
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print_xml_result(result)


if __name__ == "__main__":
    main()
