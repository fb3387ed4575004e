#!/usr/bin/env python3
"""Issue 41's frame budget: ms per frame by stage of the game-like level at 1/60 s, per solver, alone and busy.

    python3 bench/game_frame.py --bench build-bench/bench/bench_game_frame \
        --out bench/results/debian12-2core/game_frame.csv [--frames 600] [--warmup 60] [--solvers dfsph,pcisph,pbf]
        [--busy N] [--rounds N]

Runs bench/bench_game_frame.cpp once, or --rounds times one after another (a `round` column tells them apart)
(Google Benchmark, JSON output): demos/bullet_playground's level (a hammock,
a curtain, two balls, a crate, two jets of 1 cm particles, wetting), one coupled step of 1/60 s per frame, for
each solver with drench on 1 thread and on its default (the CPUs), alone and beside one busy thread per CPU
(--busy: that many instead).
Each row: the median and 99th percentile ms per frame of each stage (CoupledStepReport::seconds: emit, fluid,
cloth, rigid, coupling, other, total) over the timed frames, the leaks of the whole run (target 0), the fastest
particle, the fluid's sub-steps per frame, how often the continuous handling reached its fail-safe and its
impact zones (shares of the timed frames). The benchmarks run one after another, in the order solver, threads,
condition; the machine's load before and after goes into the CSV's notes.
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
DEFAULTS = {"frames": 600, "warmup": 60, "solvers": "dfsph,pcisph,pbf", "busy": 0, "rounds": 1}


def row_of(benchmark, blow_ups):
    """One CSV row from a benchmark of the JSON output, named game_frame/<solver>/threads:<n>/<alone|busy:<n>>;
    blow_ups: the binary's lines on the runs that blew up, by benchmark name."""
    name = benchmark["run_name"]
    _, solver, threads, condition = name.split("/")[:4]
    status = benchmark.get("error_message", "error") if benchmark.get("error_occurred") else "ok"
    if benchmark.get("blew_up_at_s", 0) > 0:
        status = blow_ups.get(name.split("/iterations:")[0], f"blew up at t = {benchmark['blew_up_at_s']:.4f} s")
    if "frames" not in benchmark:  # an error without counters
        return {"solver": solver, "threads": threads.split(":")[1], "condition": condition, "status": status}
    # A blow-up keeps its counters: the frames until then.
    row = {"solver": solver, "threads": int(benchmark["drench_threads"]), "condition": condition,
           "busy_threads": int(benchmark["busy_threads"]), "status": status,
           "blew_up_at_s": round(benchmark["blew_up_at_s"], 4),
           "frames": int(benchmark["frames"]), "warmup_frames": int(benchmark["warmup_frames"]),
           "particles_max": int(benchmark["particles_max"]), "particles_end": int(benchmark["particles"]),
           # 0 when the solver's token left the audit out (-leak_audit): its leaks are then not counted.
           "leak_audit": int(benchmark.get("leak_audit", 1)),
           "leaks": int(benchmark["leaks"]),
           # Of the leaks: water a face passed between two steps (a body's face an impact zone had moved).
           "jump_leaks": int(benchmark.get("jump_leaks", 0)),
           # Water the impact zones removed, caught between faces that move differently.
           "squeezed_out": int(benchmark.get("squeezed_out", 0)),
           "failed_frames": int(benchmark["failed_frames"]),
           "fastest_particle_mps": round(benchmark["fastest_particle_mps"], 3),
           "fastest_node_mps": round(benchmark["fastest_node_mps"], 3),
           "fluid_substeps_per_frame": round(benchmark["fluid_substeps_per_frame"], 2),
           "density_error_mean": float(f"{benchmark['density_error_mean']:.3g}"),
           # The continuous handling's last resorts (sec. 3.3's rounds, then the fail-safe, then impact zones):
           # how often the level needs them.
           "ccd_rounds_per_frame": round(benchmark.get("ccd_rounds_per_frame", float("nan")), 2),
           "failsafe_frame_share": round(benchmark.get("failsafe_frame_share", float("nan")), 3),
           "zone_frame_share": round(benchmark.get("zone_frame_share", float("nan")), 3),
           "failsafe_particles_per_frame": round(benchmark.get("failsafe_particles_per_frame", float("nan")), 2),
           # What the impact zones moved the bodies' nodes by (sum of |shift|, m per frame), which their engine
           # ignores: 0 since the zones take a body's motion as given (water placed against a moved face ended
           # inside its body).
           "zone_ignored_shift_m_per_frame": float(f"{benchmark.get('zone_ignored_shift_per_frame', float('nan')):.3g}"),
           "mean_ms": round(benchmark["real_time"], 3),
           # The calling thread's CPU time per frame: beside other load, a frame's wall time over it tells how
           # much of a core drench's first thread got (about 1 for one thread on a quiet machine).
           "cpu_ms_mean": round(benchmark["cpu_time"], 3)}
    for stage in STAGES:
        row[f"{stage}_ms_median"] = round(benchmark[f"{stage}_ms_median"], 3)
        row[f"{stage}_ms_p99"] = round(benchmark[f"{stage}_ms_p99"], 3)
    # The median frame by the particles in the level at its end, in bins of 500 (frames_upto_<n>,
    # total_ms_median_upto_<n>): what a frame costs at a given count.
    for key in sorted((k for k in benchmark if k.startswith("frames_upto_")), key=lambda k: int(k.split("_")[-1])):
        upto = key.split("_")[-1]
        row[key] = int(benchmark[key])
        row[f"total_ms_median_upto_{upto}"] = round(benchmark[f"total_ms_median_upto_{upto}"], 3)
    # A build configured with -DDRENCH_POOL_STATS=ON adds the pool's loops and waits per frame (pool_*).
    for key in sorted(k for k in benchmark if k.startswith("pool_")):
        row[key] = round(benchmark[key], 4)
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", default=str(ROOT / "build-bench" / "bench" / "bench_game_frame"))
    parser.add_argument("--frames", type=int, default=DEFAULTS["frames"], help="timed frames per benchmark")
    parser.add_argument("--warmup", type=int, default=DEFAULTS["warmup"], help="untimed frames before them")
    parser.add_argument("--solvers", default=DEFAULTS["solvers"],
                        help="comma-separated scene names; pbf:<substeps>x<iterations> for PBF at another setting; "
                             "-<part> leaves viscosity, leak_audit, wetting or substep_obstacle out, e.g. pbf-wetting")
    parser.add_argument("--busy", type=int, default=DEFAULTS["busy"],
                        help="spinning threads beside drench in the busy condition (0: one per CPU)")
    parser.add_argument("--filter", help="--benchmark_filter for the binary (a regex over the names)")
    parser.add_argument("--rounds", type=int, default=DEFAULTS["rounds"],
                        help="runs of the whole set, one after another (a ratio near 1 needs its spread)")
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error(f"--rounds must be at least 1, got {args.rounds}")
    load_before = " ".join(f"{x:.2f}" for x in os.getloadavg())
    rows = []
    for round_ in range(args.rounds):
        rows += [dict(r, round=round_) for r in run_once(args)]
    load_after = " ".join(f"{x:.2f}" for x in os.getloadavg())
    keys = list(max(rows, key=len))  # a failed benchmark's row has fewer keys; its other cells stay empty
    rows = [{key: r.get(key, "") for key in keys} for r in rows]
    options = "".join(f" --{key} {getattr(args, key)}" for key in DEFAULTS if getattr(args, key) != DEFAULTS[key])
    if args.filter:
        options += f" --filter '{args.filter}'"
    write_csv(args.out, rows, [f"command: python3 bench/game_frame.py{options}", f"commit: {commit()}",
                               f"cpu: {cpu_model()}", f"load_before: {load_before}", f"load_after: {load_after}"])


def run_once(args):
    """One run of the binary over the benchmarks args selects: their rows."""
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "game_frame.json"
        command = [args.bench, "--frames", str(args.frames), "--warmup", str(args.warmup), "--solvers",
                   args.solvers, f"--benchmark_out={out}", "--benchmark_out_format=json"]
        if args.busy:
            command += ["--busy", str(args.busy)]
        if args.filter:
            command.append(f"--benchmark_filter={args.filter}")
        # Google Benchmark's console table and the binary's own lines go to stderr, so that the run can be
        # followed; the lines on blow-ups ("<name>: the fluid or a cloth blew up at ...") are kept for the CSV.
        blow_ups = {}
        with subprocess.Popen(command, stdout=sys.stderr, stderr=subprocess.PIPE, text=True) as process:
            for line in process.stderr:
                sys.stderr.write(line)
                name, _, what = line.rstrip("\n").partition(": ")
                if what.startswith("the fluid or a cloth blew up"):
                    blow_ups[name] = what.replace("the fluid or a cloth ", "")
        if process.returncode != 0:
            raise SystemExit(f"{' '.join(command)}: exit {process.returncode}")
        report = json.loads(out.read_text())
    rows = [row_of(b, blow_ups) for b in report["benchmarks"]]
    if not rows:
        raise SystemExit(f"{' '.join(command)}: no benchmark ran (filter {args.filter!r}?)")
    return rows


if __name__ == "__main__":
    main()
