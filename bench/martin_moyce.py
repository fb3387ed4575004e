#!/usr/bin/env python3
"""The dam break's surge front beside Martin & Moyce 1952 (issue 42). Not a CI job: a minute of runs.

    python3 bench/martin_moyce.py --drench build/demos/drench --out bench/results/debian12-2core \
        [--spacings 0.025,0.0125] [--solvers pcisph,dfsph] [--keep out/martin_moyce]

Martin & Moyce's column (bench/martin_moyce_1952_surge_front.csv, their Fig. 3 as PySPH digitised it) is a
wide and n^2 a = 2a high and fills its channel's width, so the flow is two-dimensional. drench's dam break
(demos/scenes/dam_break.json) is a 1 m cube in a 1.5 m wide tank, n^2 = 1 and free to spread sideways; this
script runs that scene with its column and tank set to theirs at a = 0.25 m: the column 0.25 x 0.5 m, the
tank 4 m long (Z up to 16, past their last point) and 0.1 m wide, the column across it. The front is the
largest x of a particle plus half a spacing (the edge of the volume a particle stands for, so Z = 1 at
t = 0); drench's Z is interpolated linearly between frames (100 per second) at each of their T. Writes
martin_moyce.csv (one row per run and data point, with the run's status, wall time and fastest particle) with
`# key: value` notes above the header.
"""

import argparse
import csv
import io
import json
import math
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_surface import commit, cpu_model, load_average  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "bench" / "martin_moyce_1952_surge_front.csv"
SCENE = "demos/scenes/dam_break.json"
A = 0.25  # m: the column's width (their a)
DEPTH = 0.1  # m: the channel's width, in z
G = 9.81  # m/s^2, the scene's gravity
FRAME_RATE = 100
PLY_TYPES = {"float": "f", "float32": "f", "double": "d", "float64": "d", "uint": "I", "uint32": "I",
             "int": "i", "int32": "i", "uchar": "B", "uint8": "B"}


def read_data():
    lines = [line for line in DATA.read_text().splitlines() if not line.startswith("#")]
    return [(float(r["T"]), float(r["Z"])) for r in csv.DictReader(lines)]


def largest_x(path):
    """Largest x of a binary little-endian PLY point cloud's vertices (drench's fluid frames)."""
    blob = path.read_bytes()
    end = blob.index(b"end_header\n") + len(b"end_header\n")
    count, fields = 0, []
    for line in blob[:end].decode("ascii").splitlines():
        words = line.split()
        if words[:2] == ["element", "vertex"]:
            count = int(words[2])
        elif words[:1] == ["property"] and count and len(words) == 3:
            fields.append((PLY_TYPES[words[1]], words[2]))
        elif words[:1] == ["element"] and fields:
            break
    fmt = "<" + "".join(t for t, _ in fields)
    x = [name for _, name in fields].index("x")
    size = struct.calcsize(fmt)
    return max(v[x] for v in struct.iter_unpack(fmt, blob[end:end + count * size])) if count else float("nan")


def run_case(drench, base, solver, spacing, threads):
    out = base / f"{solver}_{spacing}"
    sets = [f"fluid.particle_spacing={spacing}", f'fluid.pressure_solver="{solver}"',
            f"emitters[0].max=[{A},{2 * A},{DEPTH}]", f"boundaries[0].max=[4.0,{4 * A},{DEPTH}]",
            "time.duration=1.1", f"time.frame_rate={FRAME_RATE}"]
    command = [drench, "run", SCENE]
    for s in sets:
        command += ["--set", s]
    command += ["--threads", str(threads), "--quiet", "--overwrite", "--out", str(out)]
    start = time.monotonic()
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    wall = time.monotonic() - start
    if result.returncode not in (0, 2):
        sys.exit(f"failed ({result.returncode}): {' '.join(command)}\n{result.stderr}")
    summary = json.loads((out / "summary.json").read_text())
    status = summary["status"]
    fastest = summary["max_speed_mps"]["particle"]
    frames = sorted((out / "frames").glob("fluid_*.ply"))
    fronts = [(int(f.stem.split("_")[1]) / FRAME_RATE, (largest_x(f) + 0.5 * spacing) / A) for f in frames]
    shown = " ".join("drench" if i == 0 else (f"'{a}'" if any(c in a for c in ' "[') else a)
                     for i, a in enumerate(command[:-1])) + " OUT"
    return fronts, status.split(":")[0], wall, fastest, shown


def at(series, t):
    """series (time, value) interpolated linearly at t; NaN outside it."""
    for (t0, v0), (t1, v1) in zip(series, series[1:]):
        if t0 <= t <= t1:
            return v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    return float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--out", required=True, help="folder of the CSV, e.g. bench/results/debian12-2core")
    parser.add_argument("--keep", help="keep the runs here (default: a temporary folder)")
    parser.add_argument("--spacings", default="0.025,0.0125", help="particle spacings (m), comma-separated")
    parser.add_argument("--solvers", default="pcisph", help="pressure solvers, comma-separated")
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    drench = str(Path(args.drench).resolve())
    data = read_data()
    scale = math.sqrt(2 * G / A)  # T = t sqrt(2 g / a)
    notes = {"cpu": cpu_model(), "commit": commit(), "load_before": load_average(),
             "a_m": A, "n2": 2, "channel_width_m": DEPTH}
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        base = Path(args.keep).resolve() if args.keep else Path(scratch)
        base.mkdir(parents=True, exist_ok=True)
        for solver in args.solvers.split(","):
            for spacing in args.spacings.split(","):
                fronts, status, wall, fastest, command = run_case(drench, base, solver, float(spacing),
                                                                  args.threads)
                notes[f"command {solver} {spacing}"] = command
                errors = []
                for T, Z in data:
                    z = at(fronts, T / scale)
                    if math.isfinite(z):
                        errors.append(z - Z)
                    rows.append({"solver": solver, "spacing_m": spacing, "status": status, "wall_s": f"{wall:.1f}",
                                 "max_particle_speed_mps": f"{fastest:.1f}", "T": T, "Z_martin_moyce": Z, "Z_drench": "" if math.isnan(z) else f"{z:.3f}"})
                rms = math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else float("nan")
                notes[f"rms {solver} {spacing}"] = f"{rms:.3f} over {len(errors)} points"
                print(f"{solver} spacing {spacing}: {status}, {wall:.1f} s wall, RMS of Z - Z_MM {rms:.3f} "
                      f"over {len(errors)} points", file=sys.stderr)
    notes["load_after"] = load_average()
    text = io.StringIO()
    for key, value in notes.items():
        text.write(f"# {key}: {value}\n")
    writer = csv.DictWriter(text, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "martin_moyce.csv").write_text(text.getvalue())
    print(f"wrote {out / 'martin_moyce.csv'}", file=sys.stderr)


if __name__ == "__main__":
    main()
