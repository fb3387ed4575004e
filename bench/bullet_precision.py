#!/usr/bin/env python3
"""The default jet on a cloth with double- and single-precision Bullet, side by side, alternating.

    python3 bench/bullet_precision.py --double build/demos/drench \
        --single build/tests/drench_single_bullet --rounds 3 \
        --out bench/results/debian12-2core/bullet_precision.csv

Each run simulates demos/scenes/jet_on_cloth.json (0.5 s, dt 1 ms) and records its wall time, the cloth's
time, the leak audit's count and the cloth centre node's height in every frame; the single-precision rows
also give the largest difference of that height from the double run of the same round.
"""

import argparse
import json
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
from bench_surface import write_csv  # noqa: E402  (the CSV written through a temporary name, as the others)
SCENE = ROOT / "demos" / "scenes" / "jet_on_cloth.json"
CENTRE = 28 * 57 + 28  # the 57 x 57 patch's centre node


def centre_height(ply):
    """y of the centre node in a binary cloth PLY written by drench (x y z nx ny nz as float32 per vertex)."""
    data = ply.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    if "property float x" not in header or "binary_little_endian" not in header:
        raise SystemExit(f"{ply}: not a cloth frame of drench's binary PLY format")
    stride = 6 * 4
    return struct.unpack_from("<f", data, end + CENTRE * stride + 4)[0]


def run(binary, out):
    subprocess.run([binary, "run", str(SCENE), "--out", str(out), "--overwrite", "--quiet"], check=True,
                   stdout=subprocess.DEVNULL)
    summary = json.loads((out / "summary.json").read_text())
    heights = [centre_height(p) for p in sorted((out / "frames").glob("cloth_*.ply"))]
    return summary, heights


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--double", required=True, help="drench built with DRENCH_BULLET_PRECISION=double")
    parser.add_argument("--single", required=True, help="drench built with single-precision Bullet")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for r in range(1, args.rounds + 1):
            heights = {}
            for precision, binary in (("double", args.double), ("single", args.single)):
                print(f"round {r}/{args.rounds}: {precision}", file=sys.stderr, flush=True)
                summary, heights[precision] = run(binary, Path(scratch) / f"{precision}_{r}")
                rows.append({
                    "precision": precision, "round": r, "wall_s": summary["wall_s"],
                    "cloth_s": summary["timings_s"]["cloth"], "fluid_s": summary["timings_s"]["fluid"],
                    "coupling_s": summary["timings_s"]["coupling"], "leaks": summary["leaks"],
                    "centre_sag_m": -heights[precision][-1], "max_centre_height_difference_m": "",
                })
            difference = max(abs(a - b) for a, b in zip(heights["double"], heights["single"]))
            rows[-1]["max_centre_height_difference_m"] = difference
    write_csv(args.out, rows)


if __name__ == "__main__":
    main()
