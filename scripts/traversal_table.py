#!/usr/bin/env python3
"""One table of `caustica bench --suite --json` runs: a row per scene, a column per run.

    python3 scripts/traversal_table.py RUN.json [RUN.json ...]

scripts/gpu-measure.sh (STEPS=traversal) runs the suite once per traversal candidate (the
compute walk's kernel options, src/render/kernel_options.rs, and the device's ray queries) and
writes this table of them. A column is named by its file (trav-NAME.json: NAME), a cell is the
scene's samples per second by the device's own timestamps where it has them (a GPU), else by the
wall clock, in millions, with its ratio to the first column. A scene a run failed or skipped has an
empty cell. The last line names the device and driver of the first run.
"""

import json
import sys
from pathlib import Path


def rate(row):
    """Samples per second: by GPU timestamps where measured, else by the wall clock."""
    return row.get("samples_per_gpu_second") or row.get("samples_per_second")


def main():
    paths = [Path(p) for p in sys.argv[1:]]
    if not paths:
        sys.exit(__doc__)
    runs = []
    for path in paths:
        try:
            document = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as e:
            print(f"{path}: no results ({e})", file=sys.stderr)
            continue
        name = path.stem.removeprefix("trav-")
        runs.append((name, document, {row["scene"]: row for row in document.get("rows", [])}))
    if not runs:
        sys.exit("traversal_table.py: none of the runs has results")
    scenes = []
    for _, _, rows in runs:
        scenes += [s for s in rows if s not in scenes]
    timed_by = "GPU timestamps" if any(row.get("samples_per_gpu_second") for _, _, rows in runs for row in rows.values()) else "wall clock"
    print(f"M samples/s ({timed_by}); in brackets, the ratio to {runs[0][0]}")
    print()
    print("| scene | " + " | ".join(name for name, _, _ in runs) + " |")
    print("|---" * (len(runs) + 1) + "|")
    for scene in scenes:
        base = runs[0][2].get(scene)
        cells = []
        for _, _, rows in runs:
            row = rows.get(scene)
            if row is None or not rate(row):
                cells.append("")
                continue
            cell = f"{rate(row) / 1e6:.3f}"
            if base is not None and rate(base):
                cell += f" ({rate(row) / rate(base):.2f}x)"
            cells.append(cell)
        print(f"| {scene} | " + " | ".join(cells) + " |")
    first = runs[0][1]
    print()
    print(f"device: {first.get('device')} ({first.get('driver_name')}, {first.get('driver_info')})")


if __name__ == "__main__":
    main()
