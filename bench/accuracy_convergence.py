#!/usr/bin/env python3
"""Convergence of drench against a reference run (issue 42): error against dt, per pressure solver, and
against the cloth's sub-steps, on log-log axes with the measured order. Not a CI job: minutes of runs.

    python3 bench/accuracy_convergence.py --drench build/demos/drench --out bench/results/debian12-2core \
        [--keep out/convergence] [--only jet|dam|substeps] [--solvers pcisph,dfsph,wcsph,pbf] [--part NAME]

For each case one `drench reference` of the scene with the case's `--set`s that refines only the parameter
studied (dt / 8, or / 16 for the dam break; or 8x the cloth's sub-steps), every run iterating to the same
tight tolerance (PCISPH eta 1e-4, DFSPH 5e-5, in double), then one `drench sweep --reference` over that
parameter, one run at a time on one thread:
- jet: the Fig. 3 jet on a cloth made small (1 cm particles, a 15 x 15 cloth of 0.3 m, 0.2 s, frames at
  50 per second, so that every frame is a whole number of every step); observable cloth_rms_m (m);
- dam: the dam break (5 cm particles, 1 s, frames at 25 per second); observable front_m (m), gauges at x =
  1.5 and 2.5 m (columns 4 spacings wide across the tank's 1.5 m: the water's volume in them over that
  cross-section); its reference at dt / 16 (0.3 ms), four times below the finest step swept;
- substeps: the small jet (PCISPH) at dt 1 ms, cloth.substeps 1, 2, 4, 8 against 32 sub-steps.
PBF (`fluid.pressure_solver: "pbf"`) has no tolerance: its step is time.dt / fluid.pbf.substeps (4) with 4
iterations each, so its series is convergence in dt at fixed sub-steps and iterations, against a reference at
dt / 8 (dt / 16 for the dam) with the same sub-steps and iterations.
The measured order is the least-squares slope of log(error) against log(dt) (or against log(1 / sub-steps))
over the runs that ended "ok"; the integrators' expected order is 1 (symplectic Euler for the fluid, Bullet's
position-based cloth). Writes accuracy_convergence.csv (one row per run, and one per reference with setting
"reference", so that the wall times of the whole set can be summed) and, with gnuplot,
accuracy_convergence.png, with `# key: value` notes (CPU, commit, load, the commands) above the header. Each
invocation is a part (`--part`, default the --only case or "all"): its notes are prefixed with the part's
name, and an existing CSV keeps the rows of the cases this invocation did not run and the other parts' notes
(but their orders and commands of the cases it ran again).
"""

import argparse
import csv
import io
import json
import math
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_surface import commit, cpu_model, load_average  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
JET = "demos/scenes/jet_on_cloth.json"
DAM = "demos/scenes/dam_break.json"
SMALL_JET = ["fluid.particle_spacing=0.01", "emitters[0].max_particles=3000", "cloth.nodes=[15,15]",
             "cloth.size=[0.3,0.3]", "time.duration=0.2", "time.frame_rate=50"]
DAM_SETS = ["time.duration=1.0", "time.frame_rate=25"]
JET_DTS = ["0.004", "0.002", "0.001", "0.0005"]
DAM_DTS = ["0.01", "0.005", "0.0025", "0.00125"]
SUBSTEPS = ["1", "2", "4", "8"]
# Every run and its reference iterate to the reference's tolerance in double: a study of dt alone, else the
# error against the reference stops at the floor the solver's eta leaves (the dam break's front did: 8 to
# 14 cm at every dt from 10 to 1.25 ms against a reference with eta / 10).
TIGHT = ['fluid.pcisph={"eta":0.0001,"precision":"double"}', 'fluid.dfsph={"eta":0.00005,"precision":"double"}']
# The reference of a study of dt refines dt alone (a study of the cloth's sub-steps, those alone).
DT_ONLY = ["--eta-divisor", "1", "--substeps-factor", "1", "--dt-divisor"]


def run(command, log):
    with open(log, "w") as f:
        result = subprocess.run(command, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT)
    if result.returncode not in (0, 2):
        sys.exit(f"failed ({result.returncode}): {' '.join(command)}; see {log}")
    return result.returncode


def sets(assignments):
    out = []
    for a in assignments:
        out += ["--set", a]
    return out


def shown(command):
    return " ".join("drench" if i == 0 else (f"'{a}'" if any(c in a for c in ' "[;') else a)
                    for i, a in enumerate(command))


def order(points):
    """Least-squares slope of log(error) against log(step) over positive, finite points."""
    xy = [(math.log(x), math.log(y)) for x, y in points if x > 0 and y > 0 and math.isfinite(y)]
    if len(xy) < 2:
        return float("nan")
    mx = sum(x for x, _ in xy) / len(xy)
    my = sum(y for _, y in xy) / len(xy)
    sxx = sum((x - mx) ** 2 for x, _ in xy)
    return sum((x - mx) * (y - my) for x, y in xy) / sxx if sxx > 0 else float("nan")


def case(drench, base, name, scene, case_sets, vary, error, threads, refinement, gauges=(), gauge_options=()):
    """One reference (`refinement`: drench reference's options) and one sweep; the sweep's rows with the
    case's name."""
    reference = base / f"{name}_reference"
    command = [drench, "reference", scene, *sets(case_sets), *refinement, "--threads", str(threads), "--quiet",
               "--overwrite", "--out", str(reference)]
    if run(command, base / f"{name}_reference.log") != 0:
        sys.exit(f"the reference of {name} did not end ok: {base / (name + '_reference.log')}")
    commands = [shown(command)]
    summary = json.loads((reference / "summary.json").read_text())
    reference_row = {"case": name, "setting": "reference", "status": summary["status"],
                     "wall_s": summary["wall_s"], "error_key": error,
                     "max_particle_speed_mps": summary["max_speed_mps"]["particle"]}
    sweep = base / f"{name}_sweep"
    command = [drench, "sweep", scene, *sets(case_sets), "--vary", vary, "--reference", str(reference),
               "--error", error, "--threads", str(threads), "--overwrite", "--quiet", "--out", str(sweep)]
    for g in gauges:
        command += ["--gauge", str(g)]
    command += list(gauge_options)
    run(command, base / f"{name}_sweep.log")
    commands.append(shown(command))
    rows = list(csv.DictReader(open(sweep / "sweep.csv")))
    for r in rows:
        r["case"] = name
        r["error_key"] = error
    return [reference_row] + rows, commands


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--out", required=True, help="folder of the CSV and PNG, e.g. bench/results/debian12-2core")
    parser.add_argument("--keep", help="keep the runs here (default: a temporary folder)")
    parser.add_argument("--solvers", default="pcisph,dfsph,wcsph", help="pressure solvers, comma-separated")
    parser.add_argument("--only", choices=["jet", "dam", "substeps"], help="one case only")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--part", help="name of this invocation's notes (one word; default: --only or all)")
    args = parser.parse_args()
    part = args.part or args.only or "all"
    drench = str(Path(args.drench).resolve())
    notes = {"script": " ".join(["python3 bench/accuracy_convergence.py"] + sys.argv[1:]), "cpu": cpu_model(),
             "commit": commit(), "load_before": load_average()}
    rows, commands = [], []
    with tempfile.TemporaryDirectory() as scratch:
        base = Path(args.keep).resolve() if args.keep else Path(scratch)
        base.mkdir(parents=True, exist_ok=True)
        for solver in args.solvers.split(","):
            solver_set = [f'fluid.pressure_solver="{solver}"'] + TIGHT
            if args.only in (None, "jet"):
                r, c = case(drench, base, f"jet_{solver}", JET, SMALL_JET + solver_set,
                            "time.dt=" + ",".join(JET_DTS), "cloth_rms_m", args.threads, DT_ONLY + ["8"])
                rows += r
                commands += c
            if args.only in (None, "dam"):
                r, c = case(drench, base, f"dam_{solver}", DAM, DAM_SETS + solver_set,
                            "time.dt=" + ",".join(DAM_DTS), "front_m", args.threads, DT_ONLY + ["16"],
                            gauges=(1.5, 2.5), gauge_options=("--gauge-width", "0.2", "--gauge-depth", "1.5"))
                rows += r
                commands += c
        if args.only in (None, "substeps"):
            r, c = case(drench, base, "substeps_pcisph", JET, SMALL_JET + ['fluid.pressure_solver="pcisph"'] + TIGHT,
                        "cloth.substeps=" + ",".join(SUBSTEPS), "cloth_rms_m", args.threads,
                        ["--dt-divisor", "1", "--eta-divisor", "1", "--substeps-factor", "8"])
            rows += r
            commands += c
        notes["load_after"] = load_average()

        # The measured orders, per case and observable.
        summary = []
        for name in dict.fromkeys(r["case"] for r in rows):
            these = [r for r in rows if r["case"] == name and r["status"] == "ok" and r["setting"] != "reference"]
            for key in ("cloth_rms_m", "cloth_sag_m", "mass_l1_kg", "front_m", "gauge_height_m"):
                points = []
                for r in these:
                    if not r.get(key):
                        continue
                    if name.startswith("substeps"):
                        step = 1.0 / float(r.get("cloth.substeps") or 4)
                    else:
                        step = float(r.get("time.dt") or 0)
                    points.append((step, float(r[key])))
                if len(points) >= 2:
                    summary.append((name, key, order(points), len(points)))
        for name, key, p, n in summary:
            print(f"{name:18s} {key:15s} order {p:5.2f} over {n} runs (expected 1)")
            notes[f"order {name} {key}"] = f"{p:.2f} over {n} runs"
        for i, c in enumerate(commands):
            notes[f"command {i + 1}"] = c

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        # The other parts' notes and the cases this invocation did not run stay.
        kept_notes, kept_rows = [], []
        existing = out / "accuracy_convergence.csv"
        if existing.exists():
            lines = existing.read_text().splitlines()
            ran = {r["case"] for r in rows}

            def stale(line):
                """Another part's note on a case this invocation ran again: its order or its commands."""
                return any(f" order {c} " in line or f"/{c}_reference" in line or f"/{c}_sweep " in line
                           or line.endswith(f"/{c}_sweep") for c in ran)

            kept_notes = [line for line in lines if line.startswith("# ") and not line.startswith(f"# {part} ")
                          and not stale(line)]
            kept_rows = [r for r in csv.DictReader(line for line in lines if not line.startswith("#"))
                         if r["case"] not in ran]
        rows = kept_rows + rows
        columns = ["case", "setting", "time.dt", "cloth.substeps", "status", "wall_s", "error_key", "cloth_rms_m",
                   "cloth_max_m", "cloth_sag_m", "held_kg", "past_edges_kg", "mass_l1_kg", "front_m",
                   "gauge_height_m", "worst_relative_error", "worst_observable", "density_error_mean",
                   "max_particle_speed_mps"]
        text = io.StringIO()
        for line in kept_notes:
            text.write(line + "\n")
        for key, value in notes.items():
            text.write(f"# {part} {key}: {value}\n")
        writer = csv.DictWriter(text, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        for r in rows:
            writer.writerow({c: r.get(c, "") for c in columns})
        (out / "accuracy_convergence.csv").write_text(text.getvalue())
        print(f"wrote {out / 'accuracy_convergence.csv'}", file=sys.stderr)

        gnuplot = shutil.which("gnuplot")
        if gnuplot:
            data = base / "convergence.dat"
            blocks = []
            for name in dict.fromkeys(r["case"] for r in rows):
                these = [r for r in rows if r["case"] == name and r["status"] == "ok" and r.get(r["error_key"])
                         and r["setting"] != "reference"]
                lines = []
                for r in these:
                    step = 1.0 / float(r.get("cloth.substeps") or 4) if name.startswith("substeps") \
                        else float(r.get("time.dt") or 0)
                    lines.append(f"{step} {r[r['error_key']]}")
                if lines:
                    blocks.append((name, these[0]["error_key"], "\n".join(lines)))
            data.write_text("\n\n\n".join(b[2] for b in blocks) + "\n")
            plots = ", ".join(f"'{data}' index {i} using 1:2 with linespoints lw 2 pt 7 title '{n} ({k})'"
                              for i, (n, k, _) in enumerate(blocks))
            script = (f"set terminal pngcairo size 1000,700 font ',10' noenhanced\n"
                      f"set output '{out / 'accuracy_convergence.png'}'\nset logscale xy\nset grid\n"
                      "set xlabel 'time.dt (s); substeps: 1 / cloth.substeps'\n"
                      "set ylabel 'largest error over the frames against the reference'\n"
                      "set key bottom right\nset title 'Error against the step, log-log (slope = order)'\n"
                      f"plot {plots}\n")
            (base / "convergence.gp").write_text(script)
            subprocess.run([gnuplot, str(base / "convergence.gp")], check=False)


if __name__ == "__main__":
    main()
