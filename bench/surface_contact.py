#!/usr/bin/env python3
"""The claim of sec. 4, measured: surface crossings of the cloth and obstacles, contact-aware against plain.

    python3 bench/surface_contact.py --drench build/demos/drench \
        --out bench/results/debian12-2core/surface_contact.csv [--keep DIR]

Runs demos/scenes/v_plane.json (Fig. 8; its cell of 0.004 m, and 0.0025 m) and demos/scenes/jet_on_cloth.json
(the default cell, half its 5 mm spacing) with the "surface" effect, each with surface.contact_aware true and
false, and records per run the frames and the crossings summed over them
(`surface_intersections`, counted independently of the reconstruction; 0 means 0 in every frame). Times are
bench_surface's business. With --keep the output folders stay in DIR, for scripts/cross_section.
"""

import argparse
import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
JET_EFFECTS = 'effects=["viscosity","coupling","leak_audit","surface"]'
# (name, scene, extra arguments, cell size as written in the CSV, output folder suffix)
RUNS = [
    ("v_plane", ROOT / "demos" / "scenes" / "v_plane.json", [], "0.004", ""),
    ("v_plane", ROOT / "demos" / "scenes" / "v_plane.json", ["--set", "surface.cell_size=0.0025"], "0.0025",
     "_fine"),
    ("jet_on_cloth", ROOT / "demos" / "scenes" / "jet_on_cloth.json", ["--set", JET_EFFECTS], "0.0025", ""),
]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", required=True, help="the drench command")
    parser.add_argument("--out", required=True, help="CSV to write")
    parser.add_argument("--keep", help="folder to keep the runs' output in (default: a temporary one)")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        base = Path(args.keep) if args.keep else Path(scratch)
        for name, scene, extra, cell, suffix in RUNS:
            for aware in ("true", "false"):
                out = base / f"{name}_{'aware' if aware == 'true' else 'plain'}{suffix}"
                print(f"{name}, contact_aware={aware}", file=sys.stderr, flush=True)
                subprocess.run([args.drench, "run", str(scene), "--out", str(out), "--overwrite", "--quiet", *extra, "--set",
                                f"surface.contact_aware={aware}"], check=True, stdout=subprocess.DEVNULL)
                summary = json.loads((out / "summary.json").read_text())
                rows.append({
                    "scene": name,
                    "contact_aware": aware,
                    "cell_size_m": cell,
                    "frames": summary["frames"],
                    "particles_at_end": summary["particles"],
                    "leaks": summary.get("leaks", ""),
                    "surface_intersections": summary["surface_intersections"],
                })
    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
