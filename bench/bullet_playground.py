#!/usr/bin/env python3
"""Issue 40's game-like demo: ms per frame by stage at 1/60 s, with and without its rigid bodies.

    python3 bench/bullet_playground.py --demo build/demos/bullet_playground --rounds 2 \
        --out bench/results/debian12-2core/bullet_playground.csv

Each run steps demos/bullet_playground.cpp's scene (a ground plane, a table, a hammock and a curtain under two
jets, wetting on; 4 s in steps of 1/60 s, one step per frame) on one thread, once with its two balls and its
crate and once without them (--no-rigid: the ground and the table stay), alternating, and records from its
summary.json the median and 99th percentile of each stage's wall time per frame (CoupledStepReport::seconds:
emit, fluid, cloth = Bullet's world step, rigid = the bodies' own work, coupling = the coupler and the leak
audit for cloths and bodies together, other = the rest of the step), the particles, the leaks and the fastest
particle and node. One run at a time; the machine's load before and after goes into the CSV's notes.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

sys.path.insert(0, str(ROOT / "bench"))
from bench_surface import commit, cpu_model, write_csv  # noqa: E402  (the same provenance lines as the other CSVs)

STAGES = ["emit", "fluid", "cloth", "rigid", "coupling", "other", "total"]


def run(demo, rigid, seconds, out):
    # Frames off but frame 0 (--frames-every past the last step): summary.json is written beside them.
    command = [demo, "--out", str(out), "--seconds", str(seconds), "--threads", "1", "--frames-every", "1000000"]
    if not rigid:
        command.append("--no-rigid")
    code = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if not (out / "summary.json").exists():
        raise SystemExit(f"{' '.join(command)} wrote no summary (exit {code.returncode}): {code.stderr.strip()}")
    summary = json.loads((out / "summary.json").read_text())
    row = {
        "rigid_bodies": "yes" if rigid else "no", "exit": code.returncode, "status": summary["status"].split(":")[0],
        "frames": summary["steps"], "sim_time_s": round(summary["sim_time_s"], 6),
        "particles": summary["particles"], "created": summary["created"], "leaks": summary["leaks"],
        "max_particle_speed_mps": round(summary["max_speed_mps"]["particle"], 3),
        "max_node_speed_mps": round(summary["max_speed_mps"]["node"], 3), "wall_s": round(summary["wall_s"], 2),
    }
    for stage in STAGES:
        row[f"{stage}_ms_median"] = round(summary["ms_per_frame"][stage]["median"], 3)
        row[f"{stage}_ms_p99"] = round(summary["ms_per_frame"][stage]["p99"], 3)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--demo", default=str(ROOT / "build" / "demos" / "bullet_playground"))
    parser.add_argument("--seconds", type=float, default=4.0, help="simulated time per run (unit: s)")
    parser.add_argument("--rounds", type=int, default=1, help="pairs of runs (with, then without the bodies)")
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    load_before = " ".join(f"{x:.2f}" for x in os.getloadavg())
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for r in range(1, args.rounds + 1):
            for rigid in (True, False):
                row = {"round": r, **run(args.demo, rigid, args.seconds, Path(scratch) / f"{r}_{rigid}")}
                print(f"round {r}, rigid bodies {row['rigid_bodies']}: total {row['total_ms_median']} ms per frame "
                      f"(median), leaks {row['leaks']}", file=sys.stderr)
                rows.append(row)
    load_after = " ".join(f"{x:.2f}" for x in os.getloadavg())
    command = f"python3 bench/bullet_playground.py --rounds {args.rounds}" + (
        f" --seconds {args.seconds:g}" if args.seconds != 4.0 else "")
    write_csv(args.out, rows, [f"command: {command}", f"commit: {commit()}", f"cpu: {cpu_model()}",
                               f"load_before: {load_before}", f"load_after: {load_after}"])


if __name__ == "__main__":
    main()
