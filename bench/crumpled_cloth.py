#!/usr/bin/env python3
"""Issue 39's crumpled cloth at several steps: leaks, the fail-safe and the last resort, and their time.

    python3 bench/crumpled_cloth.py --drench build/demos/drench --dt 0.001,0.002,0.004,0.008 --jobs 2 \
        --out bench/results/debian12-2core/crumpled_cloth.csv
    python3 bench/crumpled_cloth.py --dt 0.004,0.008 --jobs 2 --limits-off --append \
        --out bench/results/debian12-2core/crumpled_cloth.csv

Each run simulates demos/scenes/crumpled_cloth.json (a 1 m cloth of 65 x 65 nodes held at one corner, no
bending stiffness, under a 30,000-particle jet of 3 m/s for 1 s) at one dt on one thread, with frames off,
and records what its summary.json says: the status, leaks (the target is 0), the fail-safe's activations,
the particles and nodes the last resort stopped, the fastest node, the largest edge strain and the times.
--limits-off runs with cloth.max_speed and cloth.max_strain off, to see a run the limits stop to its end.
With --jobs 2 two runs share the machine, so their wall times are each other's noise.
"""

import argparse
import csv
import json
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "demos" / "scenes" / "crumpled_cloth.json"

sys.path.insert(0, str(ROOT / "bench"))
from bench_surface import commit, cpu_model, write_csv  # noqa: E402  (the same provenance lines as the other CSVs)


def run(binary, dt, out, limits_off):
    command = [binary, "run", str(SCENE), "--out", str(out), "--quiet", "--threads", "1",
               "--set", f"time.dt={dt}", "--set", "time.frame_rate=0"]
    if limits_off:
        command += ["--set", "cloth.max_speed=null", "--set", "cloth.max_strain=null"]
    code = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
    summary = json.loads((out / "summary.json").read_text())
    t = summary["timings_s"]
    return {
        "dt_s": dt, "cloth_limits": "off" if limits_off else "default", "exit": code, "status": summary["status"].split(":")[0], "steps": summary["steps"],
        "leaks": summary["leaks"], "failsafe_activations": summary["failsafe_activations"],
        "stopped_particles": summary["stopped_particles"], "stopped_nodes": summary["stopped_nodes"],
        "ccd_impacts": summary["ccd_impacts"], "max_node_speed_mps": summary["max_speed_mps"]["node"],
        "max_cloth_strain": summary["max_cloth_strain"], "wall_s": summary["wall_s"],
        "fluid_s": t["fluid"], "cloth_s": t["cloth"], "coupling_s": t["coupling"], "ccd_s": t["ccd"],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--dt", default="0.001,0.002,0.004,0.008", help="steps to run (unit: s), by commas")
    parser.add_argument("--jobs", type=int, default=1, help="runs side by side")
    parser.add_argument("--limits-off", action="store_true", help="cloth.max_speed and max_strain null")
    parser.add_argument("--append", action="store_true", help="add the rows to --out (same columns)")
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    steps = [float(dt) for dt in args.dt.split(",")]
    with tempfile.TemporaryDirectory() as scratch:
        with ThreadPoolExecutor(max_workers=args.jobs) as pool:
            rows = list(pool.map(lambda dt: run(args.drench, dt, Path(scratch) / f"dt_{dt}", args.limits_off),
                                 steps))
    out = Path(args.out)
    command = f"python3 bench/crumpled_cloth.py --dt {args.dt} --jobs {args.jobs}" + (
        " --limits-off" if args.limits_off else "")
    if args.append:
        with out.open("a", newline="") as f:
            csv.DictWriter(f, fieldnames=list(rows[0])).writerows(rows)
        return
    write_csv(out, rows, [f"command: {command}", f"commit: {commit()}", f"cpu: {cpu_model()}"])


if __name__ == "__main__":
    main()
