#!/usr/bin/env python3
"""Time to solution of drench's pressure solvers on the 59K dam break (issue 29), beside SPlisHSPlasH's DFSPH.

Each solver simulates 0.5 s (the work of ../shared/notes/peer-sph.md) at an average density error of at most
0.05% in every sub-step; PCISPH and DFSPH as published, without drench's relief and compression limits (for
coupled scenes), so that the error their iterations stop at is the error against the rest density. The step is the solver's own: the benchmark finds, per solver, the largest at which
it stays within the error, then times those steps side by side in alternating rounds with the yardstick of
peer-sph.md (drench's PCISPH run as it was there), from which SPlisHSPlasH's DFSPH time follows by its
measured ratio.

1. Search: every `tts/<solver>/...` benchmark of bench_dam_break once: PCISPH and DFSPH over adaptive steps
   of at most 2.5, 5 and 10 ms under CFL numbers 0.4 and 0.6, WCSPH over speeds of sound at CFL 0.4. A run
   stops at its first sub-step above the error, so settings past a solver's limit cost little.
2. Per solver the setting within the error that reached the end soonest (for WCSPH, whose step shrinks as
   its speed of sound grows, that is the lowest speed of sound within the error).
3. Rounds: the yardstick (`pcisph_59k`) and the PCISPH and DFSPH picks, alternating, `--rounds` times;
   WCSPH's pick only with `--wcsph-rounds` (its runs take minutes).

PBF (issue 41) is not held to the error: it runs a fixed count of sub-steps and iterations at a game's step
(`tts/pbf/hz:<1/dt>/sub:<n>/it:<n>`, 0.5 s at dt 1/60 s and 1/120 s), so its density error is a result. Each
of its settings that stayed ok (finite, under fluid.max_speed) is timed in the rounds beside the others.
`--pbf-only` keeps the CSV's other rows and adds a PBF phase: its search, then rounds of the yardstick, the
kept DFSPH pick rerun and the PBF settings (phases "pbf search" and "pbf round"), so that PBF's ratios come
from runs made side by side.

    python3 bench/time_to_solution.py --bench build/bench/bench_dam_break \\
        --out bench/results/debian12-2core/time_to_solution.csv
    python3 scripts/result_pages

One thread (OMP_NUM_THREADS=1): two threads on a VM shared with other work lose several times their speed
to each other's barriers, one keeps its time. Each row also has its loop's CPU time (cpu_s), which a
busy VM does not stretch as it stretches the wall time.
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_surface import commit, cpu_model, load_average  # noqa: E402

ETA_PCT = 0.05
COLUMNS = [
    "phase", "round", "name", "solver", "dt_max_ms", "cfl", "speed_of_sound_mps", "within_error", "wall_s", "cpu_s", "sim_s",
    "wall_s_per_sim_s", "steps", "substeps", "mean_dt_ms", "pressure_iterations_per_substep",
    "divergence_iterations_per_substep", "density_error_mean_pct", "density_error_max_pct", "max_speed_mps",
    "ok", "pbf_substeps", "pbf_iterations", "load_before", "load_after",
]


def run_benchmarks(bench, pattern, env):
    """The rows of bench_dam_break's benchmarks matching `pattern` (a regex), as dicts of COLUMNS, with the load
    average before and after (the VM is shared)."""
    load_before = load_average()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.json"
        command = [str(bench), f"--benchmark_filter={pattern}", f"--benchmark_out={out}",
                   "--benchmark_out_format=json"]
        result = subprocess.run(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if result.returncode != 0 or not out.exists():
            raise SystemExit(f"{' '.join(command)} failed ({result.returncode}):\n{result.stderr}")
        data = json.loads(out.read_text())
    rows = []
    for b in data["benchmarks"]:
        name = b["name"].replace("/iterations:1/manual_time", "")
        if "error_message" in b:
            raise SystemExit(f"{name}: {b['error_message']}")
        row = {key: b.get(key, "") for key in COLUMNS}
        row["name"] = name
        row["load_before"], row["load_after"] = load_before, load_average()
        row["wall_s"] = b["real_time"]  # manual time in seconds (Unit kSecond): the loop, without setup
        if name.startswith("tts/"):
            row["solver"] = name.split("/")[1]
        else:  # the yardstick, pcisph_59k: fixed 2.5 ms steps, 0.5 s, always within the error it iterates to
            row["solver"] = "pcisph (peer-sph.md yardstick)"
            row["dt_max_ms"] = 2.5
            row["cfl"] = 0.4
            row["sim_s"] = 0.5
            row["steps"] = 200
            row["substeps"] = round(200 * b["substeps_per_step"])
            row["mean_dt_ms"] = 2.5
            # SkipWithError (an error_message above) on a step that was not ok(): converged and finite
            row["within_error"] = 1 if b["density_error_max_pct"] <= ETA_PCT * (1 + 1e-9) else 0
            row["max_speed_mps"] = ""
        if row["ok"] == "" and row["solver"] != "pbf":
            row["ok"] = row["within_error"]  # the others stop at their first step outside the error
        rows.append(row)
    return rows


def pick(rows, solver):
    """The search row of `solver` within the error that took the least wall time, or None."""
    within = [r for r in rows if r["solver"] == solver and r["within_error"] != "" and float(r["within_error"]) == 1]
    return min(within, key=lambda r: float(r["wall_s"])) if within else None


def pbf_settings(rows):
    """The names of the PBF search rows that stayed ok to the end, in search order."""
    return [r["name"] for r in rows if r["solver"] == "pbf" and r["ok"] == 1]


def run_rounds(bench, timed, rounds, phase, env, started):
    """`rounds` alternating rounds of the benchmarks named in `timed`, as rows of phase `phase`."""
    rows = []
    for k in range(1, rounds + 1):
        for name in timed:
            (row,) = run_benchmarks(bench, exact(name), env)
            row["phase"], row["round"] = phase, k
            rows.append(row)
            print(f"{phase} {k}/{rounds} {name}: {row['wall_s']:.1f} s "
                  f"({(time.time() - started) / 60:.0f} min so far)", flush=True)
    return rows


def read_rows(path):
    """The comment lines and rows (as written: text) of an earlier CSV of this script."""
    lines = path.read_text().splitlines()
    comments = [line for line in lines if line.startswith("#")]
    rows = [{key: r.get(key) or "" for key in COLUMNS}
            for r in csv.DictReader(line for line in lines if not line.startswith("#"))]
    return comments, rows


def exact(name):
    return "^" + re.escape(name) + "(/|$)"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bench", type=Path, required=True, help="bench_dam_break executable")
    parser.add_argument("--out", type=Path, required=True, help="CSV to write (written whole at the end)")
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds of the picks (default 3)")
    parser.add_argument("--wcsph-rounds", action="store_true", help="time WCSPH's pick in every round too")
    parser.add_argument("--pbf-only", action="store_true",
                        help="keep --out's other rows; run PBF's search and rounds beside the yardstick and DFSPH")
    args = parser.parse_args()
    env = dict(os.environ, OMP_NUM_THREADS="1")

    started = time.time()
    if args.pbf_only:
        return pbf_only(args, env, started)
    print("search: every tts/ benchmark once", flush=True)
    rows = []
    for row in run_benchmarks(args.bench, "^tts/", env):
        row["phase"], row["round"] = "search", 0
        rows.append(row)
        print(f"  {row['name']}: within {row['within_error']}, {row['sim_s']:.3f} s simulated "
              f"in {row['wall_s']:.1f} s", flush=True)
    picks = {solver: pick(rows, solver) for solver in ("pcisph", "dfsph", "wcsph")}
    for solver, row in picks.items():
        print(f"pick {solver}: {row['name'] if row else 'none within the error'}", flush=True)
    timed = ["pcisph_59k"] + [picks[s]["name"] for s in ("pcisph", "dfsph") if picks[s]]
    if args.wcsph_rounds and picks["wcsph"]:
        timed.append(picks["wcsph"]["name"])
    timed += pbf_settings(rows)
    rows += run_rounds(args.bench, timed, args.rounds, "round", env, started)
    comment = (f"# bench/time_to_solution.py --rounds {args.rounds}{' --wcsph-rounds' if args.wcsph_rounds else ''}"
               f" at {commit()}, one thread, {cpu_model()}, {time.strftime('%Y-%m-%d')}")
    write(args.out, [comment], rows, started)


def pbf_only(args, env, started):
    """PBF's phase: its search, then rounds of the yardstick, the kept DFSPH pick and PBF's settings."""
    load_before = load_average()
    comments, kept = read_rows(args.out)
    kept = [r for r in kept if r["solver"] != "pbf" and not r["phase"].startswith("pbf")]
    dfsph = pick(kept, "dfsph")
    if dfsph is None:
        raise SystemExit(f"{args.out} has no DFSPH pick to run beside PBF")
    print("pbf search: every tts/pbf/ benchmark once", flush=True)
    rows = []
    for row in run_benchmarks(args.bench, "^tts/pbf/", env):
        row["phase"], row["round"] = "pbf search", 0
        rows.append(row)
        print(f"  {row['name']}: ok {row['ok']}, {row['sim_s']:.3f} s simulated in {row['wall_s']:.1f} s, "
              f"density error {row['density_error_mean_pct']:.3f}% / {row['density_error_max_pct']:.3f}%", flush=True)
    timed = ["pcisph_59k", dfsph["name"]] + pbf_settings(rows)
    rows += run_rounds(args.bench, timed, args.rounds, "pbf round", env, started)
    comment = (f"# bench/time_to_solution.py --pbf-only --rounds {args.rounds} (phases \"pbf search\", \"pbf round\")"
               f" at {commit()}, one thread, {cpu_model()}, {time.strftime('%Y-%m-%d')},"
               f" load {load_before} before and {load_average()} after")
    write(args.out, [c for c in comments if "--pbf-only" not in c] + [comment], kept + rows, started)


def write(out, comments, rows, started):
    temporary = out.with_name(out.name + ".tmp")
    with temporary.open("w", newline="") as f:
        for line in comments:
            f.write(line + "\n")
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    temporary.replace(out)
    print(f"wrote {out} in {(time.time() - started) / 60:.0f} min", flush=True)


if __name__ == "__main__":
    sys.exit(main())
