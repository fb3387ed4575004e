#!/usr/bin/env python3
"""Runs the accuracy sweeps of docs/accuracy.md (issue 28) with `drench sweep` and keeps their CSVs.

    python3 bench/accuracy_sweep.py --drench build/demos/drench --out bench/results/debian12-2core \
        [--keep out/accuracy] [--duration 0.5] [--only stability --timeout 600 --jobs 2]
    python3 bench/accuracy_sweep.py --out bench/results/debian12-2core --only dam_reference
    python3 scripts/result_pages

Two sweeps of the Fig. 3 jet on a cloth (demos/scenes/jet_on_cloth.json), one run at a time on one thread
(`--threads`): the paper's Tables 1-2 are single-core figures, and a single-threaded run keeps its time when
another process shares the machine, where two OpenMP threads wait on each other at every barrier:
- one at a time: each setting varied alone around the scene (dt, cloth thickness, PCISPH eta, continuous
  handling, no-slip, PCISPH precision, pressure solver, cloth sub-steps, the surface's cell size), which
  also holds the paper's Table 1 rows -> accuracy_one_at_a_time.csv, and its pareto.png ->
  docs/images/accuracy_pareto.png;
- stability: for each pressure solver and cloth thickness, dt halving from 16 ms to 1 ms ->
  accuracy_stability.csv; scripts/result_pages finds the largest dt that still ends "ok", with no leak and
  nothing faster than the jet tests' speed bound. Its control, the jet with no cloth in its way, ->
  accuracy_free_jet.csv.
- PBF (issue 41), a phase of its own (`--only pbf`) that leaves the CSVs above as they are: the jet with
  PBF and DFSPH at the scene's dt, and PBF, DFSPH and PCISPH at a game's 1/60 s with the cloth in 16
  sub-steps (PBF's jet is stable there from about 16, tests/bullet_adapter/test_jet_on_cloth.cpp), beside
  the scene itself (PCISPH) rerun in the same sweep -> accuracy_pbf_jet.csv; and the stability sweep and its
  control for PBF alone -> accuracy_stability_pbf.csv, accuracy_free_jet_pbf.csv; and PBF's stability with
  the cloth in 16 sub-steps at 1/60 s, 8 and 4 ms -> accuracy_stability_pbf_cloth16.csv.
- against a reference (issue 42), each a phase of its own (`--only jet_reference`, `--only dam_reference`):
  one `drench reference` of the scene and a one-at-a-time `drench sweep --reference` of the settings a user
  would touch, with each run's error in the scene's observables. The jet on a cloth (the full scene, 0.5 s,
  frames at 25 per second): reference at dt / 8, eta / 10 in double, 4x the cloth's sub-steps ->
  accuracy_reference_one_at_a_time.csv. The dam break (5 cm particles, 1 s, frames at 25 per second, as
  bench/accuracy_convergence.py's): reference at dt / 16, eta / 10 in double; the surge front (m) on the
  Pareto axis, the gauges at x = 1.5 and 2.5 m and the L1 mass difference beside it; a run faster than 20
  m/s is drawn apart (`--speed-bound`) -> accuracy_reference_dam_one_at_a_time.csv. Each CSV's notes hold
  both commands and the reference's wall time and fastest particle.
The lines above each CSV's header are `# key: value` notes: the CPU, the commit, the command and the load
average before and after (the VM is shared; above about 1.5 the times are not worth keeping).
"""

import argparse
import csv
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_surface import commit, cpu_model, load_average  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SCENE = "demos/scenes/jet_on_cloth.json"
EFFECTS = '"viscosity","coupling","leak_audit"'

# Only values other than the scene's (defaults included): the scene itself is the sweep's first run.
ONE_AT_A_TIME = [
    "--one-at-a-time",
    "--vary", "time.dt=0.002,0.004,0.008",
    "--vary", "coupling.cloth_thickness=0.0005,0.005",
    "--vary", "fluid.pcisph.eta=0.01,0.03",
    "--vary", "coupling.continuous=false",
    "--case", f'no-slip:coupling.slip="no_slip";effects=[{EFFECTS},"friction"]',
    "--vary", 'fluid.pcisph.precision="double"',
    "--vary", 'fluid.pressure_solver="wcsph"',
    "--vary", "cloth.substeps=1,2",
    "--case", f'surface, 4 mm cells:effects=[{EFFECTS},"surface"];surface.cell_size=0.004',
    "--case", f'surface, 2.5 mm cells:effects=[{EFFECTS},"surface"];surface.cell_size=0.0025',
]

# A blow-up stops itself within seconds when a particle passes fluid.max_speed (status RUNAWAY_PARTICLE).
# --timeout (default 240 s, about ten times a sound PCISPH or DFSPH run on one thread) is the fallback for a
# run that crawls below that speed: stopped, and its row says so. A sound WCSPH run takes minutes (its
# sub-steps are bound by the speed of sound), so a sweep with WCSPH wants 600 s.
STABILITY = [
    "--timeout", "{timeout}",
    "--vary", 'fluid.pressure_solver={solvers}',
    "--vary", "coupling.cloth_thickness=0.0005,0.001,0.005",
    "--vary", "time.dt=0.016,0.008,0.004,0.002,0.001",
]

# PBF at a game's steps with the cloth in 16 sub-steps (the scene's 4 overstretch under PBF's jet at 8 and 16 ms).
STABILITY_PBF_CLOTH16 = [
    "--timeout", "{timeout}",
    "--set", 'fluid.pressure_solver="pbf"',
    "--set", "cloth.substeps=16",
    "--vary", "coupling.cloth_thickness=0.0005,0.001,0.005",
    "--vary", f"time.dt={repr(1.0 / 60.0)},0.008,0.004",
]

# The stability sweep's control: the same jet and steps with nothing in its way (the cloth is not coupled), so
# that what the table blames on contact is not the solver's or the nozzle's own doing.
FREE_JET = [
    "--timeout", "{timeout}",
    "--vary", 'fluid.pressure_solver={solvers}',
    "--vary", "time.dt=0.016,0.008,0.004,0.002,0.001",
    "--set", 'effects=["viscosity"]',
]


# At a game's frame: all digits, so that 0.5 s is 30 steps exactly.
GAME_DT = repr(1.0 / 60.0)
GAME_CLOTH = f"time.dt={GAME_DT};cloth.substeps=16"
PBF_JET = [
    "--one-at-a-time",
    "--vary", 'fluid.pressure_solver="dfsph","pbf"',
    "--case", f'pbf at 1/60 s, cloth 16 sub-steps:fluid.pressure_solver="pbf";{GAME_CLOTH}',
    "--case", f'dfsph at 1/60 s, cloth 16 sub-steps:fluid.pressure_solver="dfsph";{GAME_CLOTH}',
    "--case", f'pcisph at 1/60 s, cloth 16 sub-steps:fluid.pressure_solver="pcisph";{GAME_CLOTH}',
]


# Against a reference (issue 42). Frames at 25 per second: every 40 ms frame is a whole number of steps of
# every dt swept and of the reference's (jet: 8, 4, 2, 1 and 0.125 ms; dam: 10, 5, 2.5 and 0.3125 ms).
JET_REFERENCE = {
    "scene": SCENE,
    "sets": ["time.frame_rate=25"],
    "refinement": [],  # drench reference's defaults: dt / 8, eta / 10 in double, 4x the cloth's sub-steps
    "sweep": [
        "--one-at-a-time",
        "--vary", "time.dt=0.002,0.004,0.008",
        "--vary", "fluid.pcisph.eta=0.01",
        "--vary", 'fluid.pressure_solver="dfsph"',
        "--vary", "cloth.substeps=1,2,8",
    ],
    "csv": "accuracy_reference_one_at_a_time.csv",
}
# The dam break's water falls 1 m (4.4 m/s) and splashes up the far wall: the fastest particle of its PCISPH
# and DFSPH references is 9.2 and 10.2 m/s (accuracy_convergence.csv). 20 m/s, twice that, is no flow of
# this scene, only a blow-up's throw, whose front measures the throw rather than the surge.
DAM_SPEED_BOUND = "20"
DAM_REFERENCE = {
    "scene": "demos/scenes/dam_break.json",
    "sets": ["time.duration=1.0", "time.frame_rate=25"],
    # dt / 16: four times below the finest step swept (as accuracy_convergence.py's dam references); eta / 10
    # in double (PCISPH's 1e-4, the convergence study's tolerance) by drench reference's defaults.
    "refinement": ["--dt-divisor", "16"],
    "sweep": [
        "--one-at-a-time",
        "--vary", "time.dt=0.0025,0.01",
        "--vary", 'fluid.pressure_solver="dfsph","wcsph","pbf"',
        "--vary", "fluid.pcisph.eta=0.0001,0.01",
        "--vary", "fluid.viscosity.coefficient=0.001,0.1",
        "--vary", "fluid.cfl=0.2,0.8",
        "--error", "front_m",
        "--gauge", "1.5", "--gauge", "2.5", "--gauge-width", "0.2", "--gauge-depth", "1.5",
        "--speed-bound", DAM_SPEED_BOUND,
        "--timeout", "600",
    ],
    "csv": "accuracy_reference_dam_one_at_a_time.csv",
}


def shown(command):
    return " ".join("drench" if i == 0 else (f"'{a}'" if any(c in a for c in ' "[;') else a)
                    for i, a in enumerate(command))


def reference_sweep(drench, phase, base, out, threads):
    """One `drench reference` and one `drench sweep --reference` of `phase` (JET_REFERENCE, DAM_REFERENCE);
    the sweep's CSV with both commands, the reference's wall time and its fastest particle in the notes."""
    sets = [a for s in phase["sets"] for a in ("--set", s)]
    reference = base / (Path(phase["csv"]).stem + "_reference")
    sweep_dir = base / (Path(phase["csv"]).stem + "_sweep")
    notes = {"cpu": cpu_model(), "commit": commit(), "load_before": load_average()}
    command = [drench, "reference", phase["scene"], *sets, *phase["refinement"], "--threads", str(threads),
               "--quiet", "--overwrite", "--out", str(reference)]
    if subprocess.run(command, cwd=ROOT).returncode != 0 or not (reference / "reference.json").exists():
        sys.exit(f"the reference did not end ok: {' '.join(command)}")
    summary = json.loads((reference / "summary.json").read_text())
    notes["reference command"] = (f"{shown(command[:-1])} REF ({summary['wall_s']:.1f} s wall; fastest particle "
                                  f"{summary['max_speed_mps']['particle']:.2f} m/s; dt {summary['dt_s']['max']:g} s)")
    command = [drench, "sweep", phase["scene"], *sets, *phase["sweep"], "--reference", str(reference),
               "--threads", str(threads), "--overwrite", "--quiet", "--out", str(sweep_dir)]
    result = subprocess.run(command, cwd=ROOT)
    if result.returncode not in (0, 2):
        sys.exit(f"drench sweep failed ({result.returncode}): {' '.join(command)}")
    notes["sweep command"] = shown(command[:-1]).replace(str(reference), "REF") + " SWEEP"
    notes["load_after"] = load_average()
    # Frame by frame, from runs/NNN.comparison.json: where over the run the largest difference is, and which
    # way the scene's run is off (its series beside the reference's), which one number per run cannot say.
    error = phase["sweep"][phase["sweep"].index("--error") + 1] if "--error" in phase["sweep"] else "cloth_rms_m"
    series = {"front_m": "front_m", "cloth_rms_m": "centre_sag_m"}[error]
    for n, row in enumerate(csv.DictReader(open(sweep_dir / "sweep.csv")), start=1):
        path = sweep_dir / "runs" / f"{n:03d}.comparison.json"
        if not path.exists():
            continue
        comparison = json.loads(path.read_text())
        summary_path = sweep_dir / "runs" / f"{n:03d}" / "summary.json"
        if summary_path.exists():
            substeps = json.loads(summary_path.read_text()).get("fluid_substeps", {}).get("total")
            notes[f"fluid sub-steps {row['setting']}"] = substeps
        per_frame = comparison["observables"].get(error, {}).get("per_frame", [])
        notes[f"{error} per frame (mm) {row['setting']}"] = " ".join(
            "-" if v is None else f"{1000 * v:.0f}" for v in per_frame)
        if n == 1:
            for who in ("reference", "run"):
                values = comparison["series"][who][series]
                notes[f"{series} per frame (m) {'reference' if who == 'reference' else row['setting']}"] = " ".join(
                    "-" if v is None else f"{v:.3f}" for v in values)
    keep(sweep_dir / "sweep.csv", notes, out / phase["csv"])


def sweep(drench, arguments, out_dir, duration, threads, solvers="", jobs=1, timeout=240):
    arguments = [a.format(solvers=solvers, timeout=timeout) if "{" in a else a for a in arguments]
    command = [drench, "sweep", SCENE, *arguments, "--threads", str(threads), "--out", str(out_dir),
               "--overwrite"]
    if jobs > 1:
        command += ["--jobs", str(jobs)]
    if duration is not None:
        command += ["--set", f"time.duration={duration}"]
    notes = {"cpu": cpu_model(), "commit": commit(), "load_before": load_average()}
    # Exit status 2 only says that a run did not end "ok": those runs are rows, which is the point.
    result = subprocess.run(command, cwd=ROOT)
    if result.returncode not in (0, 2):
        sys.exit(f"drench sweep failed ({result.returncode}): {' '.join(command)}")
    notes["load_after"] = load_average()
    shown = ["drench" if i == 0 else (f"'{a}'" if any(c in a for c in ' "[;') else a) for i, a in enumerate(command)]
    notes["command"] = " ".join(shown)
    return notes


def keep(csv_path, notes, target):
    with open(target, "w") as f:
        for key, value in notes.items():
            f.write(f"# {key}: {value}\n")
        f.write(Path(csv_path).read_text())
    print(f"wrote {target} (load {notes['load_before']} before, {notes['load_after']} after)", file=sys.stderr)


def pbf_jet(drench, base, out, args):
    """PBF_JET `--repeat` times as alternating rounds (a sweep's own repeats run back to back, so a change of
    the shared VM's load would fall on one setting): one CSV whose `repeat` column is the round."""
    header, rows, notes = None, [], None
    for k in range(args.repeat):
        folder = base / f"pbf_jet_{k + 1}"
        round_notes = sweep(drench, PBF_JET, folder, args.duration, args.threads)
        notes = notes or round_notes
        notes["load_after"] = round_notes["load_after"]
        lines = (folder / "sweep.csv").read_text().splitlines()
        header = lines[0]
        columns = header.split(",")
        for row in csv.reader(lines[1:]):
            row[columns.index("repeat")] = str(k)
            rows.append(row)
    notes["command"] += f" (alternating rounds: {args.repeat})"
    merged = base / "pbf_jet.csv"
    with merged.open("w", newline="") as f:
        f.write(header + "\n")
        csv.writer(f, lineterminator="\n").writerows(rows)
    keep(merged, notes, out / "accuracy_pbf_jet.csv")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--out", required=True, help="folder of the CSVs, e.g. bench/results/debian12-2core")
    parser.add_argument("--keep", help="keep the sweeps' folders here (default: a temporary folder)")
    parser.add_argument("--duration", type=float, help="simulated time of every run (default: the scene's)")
    parser.add_argument("--stability-solvers", default='"wcsph","pcisph","dfsph"',
                        help="pressure solvers of the stability sweep and its control, as --vary values (WCSPH's runs take minutes each)")
    parser.add_argument("--threads", type=int, default=1, help="OpenMP threads of each run (default: 1)")
    parser.add_argument("--only", choices=["one_at_a_time", "stability", "free_jet", "pbf", "pbf_jet", "pbf_stability",
                                           "pbf_cloth16", "jet_reference", "dam_reference"],
                        help="run one sweep only (pbf: PBF's phase, pbf_jet and pbf_stability together;"
                             " jet_reference, dam_reference: against a reference; none of these is part of a run"
                             " of all)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="rounds of PBF's jet comparison (default 3; the page takes medians)")
    parser.add_argument("--timeout", type=int, default=240,
                        help="seconds after which a stability run is stopped (default 240; with WCSPH: 600)")
    parser.add_argument("--jobs", type=int, default=1,
                        help="runs side by side (default 1; more changes the times, not which runs hold)")
    args = parser.parse_args()
    drench = str(Path(args.drench).resolve())
    out = Path(args.out)
    with tempfile.TemporaryDirectory() as scratch:
        base = Path(args.keep).resolve() if args.keep else Path(scratch)
        if args.only in (None, "one_at_a_time"):
            notes = sweep(drench, ONE_AT_A_TIME, base / "one_at_a_time", args.duration, args.threads)
            keep(base / "one_at_a_time" / "sweep.csv", notes, out / "accuracy_one_at_a_time.csv")
            if (base / "one_at_a_time" / "pareto.png").exists():
                shutil.copyfile(base / "one_at_a_time" / "pareto.png", ROOT / "docs" / "images" / "accuracy_pareto.png")
        if args.only in (None, "stability"):
            notes = sweep(drench, STABILITY, base / "stability", args.duration, args.threads, args.stability_solvers,
                          args.jobs, args.timeout)
            keep(base / "stability" / "sweep.csv", notes, out / "accuracy_stability.csv")
        if args.only in (None, "free_jet"):
            notes = sweep(drench, FREE_JET, base / "free_jet", args.duration, args.threads, args.stability_solvers,
                          args.jobs, args.timeout)
            keep(base / "free_jet" / "sweep.csv", notes, out / "accuracy_free_jet.csv")
        if args.only in ("pbf", "pbf_jet"):
            pbf_jet(drench, base, out, args)
        if args.only in ("pbf", "pbf_stability"):
            notes = sweep(drench, STABILITY, base / "stability_pbf", args.duration, args.threads, '"pbf"', args.jobs,
                          args.timeout)
            keep(base / "stability_pbf" / "sweep.csv", notes, out / "accuracy_stability_pbf.csv")
            notes = sweep(drench, FREE_JET, base / "free_jet_pbf", args.duration, args.threads, '"pbf"', args.jobs,
                          args.timeout)
            keep(base / "free_jet_pbf" / "sweep.csv", notes, out / "accuracy_free_jet_pbf.csv")
        if args.only in ("pbf", "pbf_stability", "pbf_cloth16"):
            notes = sweep(drench, STABILITY_PBF_CLOTH16, base / "stability_pbf_cloth16", args.duration, args.threads,
                          jobs=args.jobs, timeout=args.timeout)
            keep(base / "stability_pbf_cloth16" / "sweep.csv", notes, out / "accuracy_stability_pbf_cloth16.csv")
        if args.only == "jet_reference":
            reference_sweep(drench, JET_REFERENCE, base, out, args.threads)
        if args.only == "dam_reference":
            reference_sweep(drench, DAM_REFERENCE, base, out, args.threads)


if __name__ == "__main__":
    main()
