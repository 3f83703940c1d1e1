#!/usr/bin/env python3
"""Mutation testing for caustica: applies each mutation of tests/mutations.toml (a small, plausible
bug in the GLSL kernel or the Rust host), runs the tests that should catch it, and reports which
mutations survive. A surviving mutation is a bug the suite cannot see: kill it with a sharper test,
or mark it `equivalent` in the list with the reason it changes nothing (docs/testing.md).

GLSL mutations need no rebuild: the kernel reads its shader files from $CAUSTICA_SHADER_DIR when it
is set (src/render/kernel.rs), so the mutated copy lives in a scratch folder and the tests run as
built. Rust mutations are applied to the working tree, rebuilt, and always restored, and the restored code
is built again at the end, so that target/ holds no mutant.

Usage: scripts/mutate.py [--list] [--only ID ...] [--area AREA] [--timeout S] [--json FILE]
Exit status: 0 when every mutation is killed or marked equivalent, 1 otherwise, 2 on a bad list.
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LIST = ROOT / "tests" / "mutations.toml"
LAVAPIPE = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json"
# The current lavapipe scripts/test.sh runs the suite on where the system's is older than Mesa 24
# (scripts/current-lavapipe.sh): the walk queue's tests skip on Debian 12's 22.3.
CURRENT_LAVAPIPE_ENV = ROOT / ".lavapipe" / "env"


def lavapipe_env():
    """The environment the tests run in: VK_DRIVER_FILES as given, else the current lavapipe of
    .lavapipe/ where scripts/test.sh has put one, else the system's."""
    env = dict(os.environ)
    if "VK_DRIVER_FILES" in env:
        return env
    if CURRENT_LAVAPIPE_ENV.exists():
        dump = subprocess.run(["bash", "-c", f'. "{CURRENT_LAVAPIPE_ENV}" && env -0'], env=env, check=True, capture_output=True).stdout
        return dict(entry.split("=", 1) for entry in dump.decode().split("\0") if "=" in entry)
    env["VK_DRIVER_FILES"] = LAVAPIPE
    return env


def load(path):
    with open(path, "rb") as f:
        mutations = tomllib.load(f)["mutation"]
    ids = set()
    for m in mutations:
        for key in ("id", "area", "file", "find", "replace", "tests", "bug"):
            if key not in m:
                sys.exit(f"{path}: mutation {m.get('id', '?')}: missing key '{key}'")
        if m["id"] in ids:
            sys.exit(f"{path}: mutation id {m['id']} appears twice")
        ids.add(m["id"])
        text = (ROOT / m["file"]).read_text()
        count = text.count(m["find"])
        if count != 1:
            sys.exit(f"{path}: mutation {m['id']}: its 'find' text occurs {count} times in {m['file']} (must be once: the list has drifted from the code)")
    return mutations


def cargo_test(tests, env, timeout):
    """Runs `cargo test --release` with `tests` (arguments: '--test physics', 'name filters'...).
    Returns (passed, seconds, tail of the output)."""
    args = ["cargo", "test", "--release", "-q"] + tests
    start = time.monotonic()
    # In a session of its own, so that a timeout ends the test binaries cargo started too: killing
    # cargo alone left a hung mutant's test running, holding a core through every later
    # measurement. Being out of the terminal's process group, it misses a Ctrl-C: that ends it too.
    child = subprocess.Popen(args, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        stdout, _ = child.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(child.pid, signal.SIGKILL)
        child.communicate()
        return False, time.monotonic() - start, f"timed out after {timeout} s"
    except BaseException:
        os.killpg(child.pid, signal.SIGKILL)
        raise
    output = stdout.strip().splitlines()
    failures = [l for l in output if "panicked at" in l or l.startswith("test result") or "FAILED" in l]
    return child.returncode == 0, time.monotonic() - start, "\n".join((failures or output)[-6:])


def run(mutation, timeout):
    env = lavapipe_env()
    path = ROOT / mutation["file"]
    original = path.read_text()
    mutated = original.replace(mutation["find"], mutation["replace"], 1)
    if path.suffix in (".glsl", ".comp"):
        with tempfile.TemporaryDirectory(prefix="caustica-mutant-") as scratch:
            shaders = Path(scratch) / "shaders"
            shutil.copytree(ROOT / "shaders", shaders)
            (shaders / path.name).write_text(mutated)
            env["CAUSTICA_SHADER_DIR"] = str(shaders)
            return cargo_test(mutation["tests"], env, timeout)
    try:
        path.write_text(mutated)
        return cargo_test(mutation["tests"], env, timeout)
    finally:
        path.write_text(original)


def main():
    # A Rust mutation lives in the working tree until its `finally` restores it; a plain SIGTERM
    # (a timeout, a closed terminal) would skip that and leave the bug in the code. Exit through
    # Python instead, so the file is restored first.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    signal.signal(signal.SIGHUP, lambda *_: sys.exit(129))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument("--only", nargs="+", metavar="ID", help="run only these mutations")
    parser.add_argument("--area", help="run only the mutations of this area (sampling, materials, ...)")
    parser.add_argument("--timeout", type=int, default=900, help="seconds per mutation's tests (a timeout counts as killed)")
    parser.add_argument("--json", type=Path, help="also write the results here")
    args = parser.parse_args()
    mutations = load(LIST)
    if args.only:
        unknown = set(args.only) - {m["id"] for m in mutations}
        if unknown:
            sys.exit(f"unknown mutation id(s): {', '.join(sorted(unknown))}")
        mutations = [m for m in mutations if m["id"] in args.only]
    if args.area:
        mutations = [m for m in mutations if m["area"] == args.area]
    if args.list:
        for m in mutations:
            print(f"{m['id']:<32} {m['area']:<12} {m['file']}: {m['bug']}")
        return 0
    # The tests must pass unmutated, or every mutation would look killed: every test binary named
    # runs once, in one cargo call; name-filtered runs (unit tests) once each.
    env = lavapipe_env()
    subprocess.run(["cargo", "build", "--release", "--tests", "-q"], cwd=ROOT, env=env, check=True)
    binaries = sorted({m["tests"][i + 1] for m in mutations for i, a in enumerate(m["tests"]) if a == "--test"})
    filtered = sorted({tuple(m["tests"]) for m in mutations if "--test" not in m["tests"]})
    for tests in [[a for b in binaries for a in ("--test", b)]] + [list(t) for t in filtered]:
        if tests:
            passed, seconds, tail = cargo_test(tests, env, args.timeout * 3)
            if not passed:
                sys.exit(f"the unmutated tests fail ({' '.join(tests)}):\n{tail}")
            print(f"unmutated: {' '.join(tests)} pass ({seconds:.0f} s)", flush=True)
    results = []
    started = time.monotonic()
    try:
        for m in mutations:
            passed, seconds, tail = run(m, args.timeout)
            if not passed:
                verdict = "killed"
            elif "equivalent" in m:
                verdict = "equivalent"
            else:
                verdict = "SURVIVED"
            results.append({"id": m["id"], "area": m["area"], "verdict": verdict, "seconds": round(seconds, 1), "tests": " ".join(m["tests"]), "detail": tail})
            print(f"{verdict:<10} {seconds:6.1f} s  {m['id']:<32} {m['bug']}", flush=True)
            if verdict != "killed" and tail:
                print("           " + tail.replace("\n", "\n           "), flush=True)
    finally:
        # A Rust mutation's tests build target/release/caustica from the mutated code, and the
        # restored source is rebuilt only by the next cargo call: until then the binary there is
        # the last mutant (a benchmark that copied it would measure a bug). Rebuild it now.
        if any(not m["file"].endswith((".glsl", ".comp")) for m in mutations):
            subprocess.run(["cargo", "build", "--release", "--bins", "--tests", "-q"], cwd=ROOT, env=env, check=True)
    total = time.monotonic() - started
    survived = [r for r in results if r["verdict"] == "SURVIVED"]
    killed = sum(r["verdict"] == "killed" for r in results)
    print(f"\n{len(results)} mutations in {total / 60:.1f} min: {killed} killed, {len(results) - killed - len(survived)} equivalent, {len(survived)} survived")
    if args.json:
        args.json.write_text(json.dumps({"minutes": round(total / 60, 1), "results": results}, indent=1))
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
