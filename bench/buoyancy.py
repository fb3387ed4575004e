#!/usr/bin/env python3
"""Issue 40's buoyancy: a ball's settled draft against Archimedes' at three spacings and three densities.

    python3 bench/buoyancy.py --bench build/bench/bench_buoyancy \
        --out bench/results/debian12-2core/buoyancy.csv

Each run is bench/bench_buoyancy.cpp on one thread: a ball of 5 cm radius let down onto water 0.1 m deep in
a tank 0.2 m square (demos/buoyancy_tank.hpp, the scene of test
RigidBodies.ABallOfHalfTheWatersDensityFloatsHalfSubmergedAtTwoSpacings), 1.2 s in steps of 1 ms, its draft
(the water's surface less the ball's lowest point, over the ball's height) averaged over the last 0.3 s. The
expected draft is Archimedes': the ball floats with the submerged fraction of its volume equal to its density
over the water's, and the submerged part of a sphere is a cap, whose volume fraction for a draft fraction x of
the height is x^2 (3 - 2x); that cubic is solved for x (it is not linear: a ball of a quarter of the water's
density floats with a third of its height under water, not a quarter). One run at a time; the machine's load
before and after goes into the CSV's notes.
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

sys.path.insert(0, str(ROOT / "bench"))
from bench_surface import commit, cpu_model, write_csv  # noqa: E402  (the same provenance lines as the other CSVs)

SPACINGS = [0.01, 0.008, 0.006]  # unit: m
DENSITIES = [250.0, 500.0, 750.0]  # unit: kg/m^3


def expected_draft(submerged):
    """The draft of a floating sphere as a fraction x of its height, for `submerged`, the fraction of its volume
    under water (its density over the water's), in [0, 1]: the root in [0, 1] of x^2 (3 - 2x) = submerged (a
    cap of height 2 R x holds pi (2 R x)^2 (3 R - 2 R x) / 3 of the sphere's 4 pi R^3 / 3), by bisection, which
    is monotone there."""
    low, high = 0.0, 1.0
    for _ in range(100):
        mid = 0.5 * (low + high)
        if mid * mid * (3.0 - 2.0 * mid) < submerged:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def run(bench, spacing, density, solver, dt):
    command = [bench, "--spacing", f"{spacing:g}", "--density", f"{density:g}", "--threads", "1", "--solver",
               solver, "--dt", repr(dt)]
    result = subprocess.run(command, capture_output=True, text=True)
    if not result.stdout.strip():
        raise SystemExit(f"{' '.join(command)} printed nothing (exit {result.returncode}): {result.stderr.strip()}")
    out = json.loads(result.stdout)
    expected = expected_draft(density / out["rest_density_kg_m3"])
    draft = out["draft"]
    return {
        "solver": solver, "dt_s": dt, "spacing_m": spacing, "density_kg_m3": density, "particles": out["particles"],
        "draft": "" if draft is None else round(draft, 4), "expected_draft": round(expected, 4),
        "error": "" if draft is None else round(draft - expected, 4),
        "draft_min": round(out["draft_min"], 4), "draft_max": round(out["draft_max"], 4),
        "samples": out["samples"], "wall_s": round(out["wall_s"], 1), "failed_step": out["failed_step"],
        "failure": out["failure"],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", default=str(ROOT / "build" / "bench" / "bench_buoyancy"))
    parser.add_argument("--spacings", type=float, nargs="+", default=SPACINGS, help="unit: m")
    parser.add_argument("--densities", type=float, nargs="+", default=DENSITIES, help="the ball's (unit: kg/m^3)")
    parser.add_argument("--solver", default="pcisph", help="the water's pressure solver (scene name)")
    parser.add_argument("--dt", type=float, default=0.001, help="the step (unit: s)")
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    load_before = " ".join(f"{x:.2f}" for x in os.getloadavg())
    rows = []
    for spacing in args.spacings:
        for density in args.densities:
            row = run(args.bench, spacing, density, args.solver, args.dt)
            print(f"spacing {spacing * 1000:g} mm, density {density:g}: draft {row['draft']} (expected "
                  f"{row['expected_draft']}), {row['particles']} particles, {row['wall_s']} s", file=sys.stderr)
            rows.append(row)
    load_after = " ".join(f"{x:.2f}" for x in os.getloadavg())
    command = "python3 bench/buoyancy.py"
    if args.spacings != SPACINGS:
        command += " --spacings " + " ".join(f"{s:g}" for s in args.spacings)
    if args.densities != DENSITIES:
        command += " --densities " + " ".join(f"{d:g}" for d in args.densities)
    if args.solver != "pcisph":
        command += f" --solver {args.solver}"
    if args.dt != 0.001:
        command += f" --dt {args.dt!r}"
    write_csv(args.out, rows, [f"command: {command}", f"commit: {commit()}", f"cpu: {cpu_model()}", "threads: 1",
                               f"load_before: {load_before}", f"load_after: {load_after}"])


if __name__ == "__main__":
    main()
