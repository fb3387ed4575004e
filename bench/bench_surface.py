#!/usr/bin/env python3
"""Runs bench_surface (issue 25) and writes its CSV with the machine and its load noted on top.

    python3 bench/bench_surface.py --bench build/bench/bench_surface \
        --out bench/results/debian12-2core/surface.csv [--repetitions 7]

Two threads (OpenMP, and TBB through bench_surface's tbb::global_control), every row repeated with Google
Benchmark's random interleaving so that the paths compared share the machine's moods, medians only. The lines
above the CSV's header are `# key: value` notes: the CPU model (lscpu), the commit, and the load average before
and after (this VM is shared; above about 1.5 the times are not worth keeping). scripts/result_pages reads
the notes and the medians into docs/performance.md.
"""

import argparse
import csv
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def load_average():
    return Path("/proc/loadavg").read_text().split()[0]


def cpu_model():
    text = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    fields = dict(re.findall(r"^([^:\n]+):\s+(.*)$", text, flags=re.M))
    return f"{fields['Model name']} (family {fields['CPU family']}, model {fields['Model']})"


def commit():
    result = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True)
    # Results and the pages made from them do not change the build under test.
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no", "--", ".",
                            ":!bench/results", ":!docs"], capture_output=True, text=True).stdout.strip()
    return result.stdout.strip() + (" (with uncommitted changes)" if dirty else "")


def write_csv(out, rows, notes=()):
    """Writes rows (dicts with the same keys) to the CSV `out` under `# ` note lines, through a temporary name,
    so that a run stopped halfway leaves the earlier results whole."""
    out = Path(out)
    temporary = out.with_suffix(".csv.tmp")
    with temporary.open("w", newline="") as f:
        for note in notes:
            f.write(f"# {note}\n")
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    temporary.replace(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bench", default=str(ROOT / "build" / "bench" / "bench_surface"))
    parser.add_argument("--out", required=True, help="CSV to write")
    parser.add_argument("--repetitions", type=int, default=7)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    notes = {"cpu": cpu_model(), "commit": commit(), "threads": str(args.threads), "load_before": load_average()}
    with tempfile.TemporaryDirectory() as scratch:
        raw = Path(scratch) / "surface.csv"
        subprocess.run([args.bench, f"--benchmark_repetitions={args.repetitions}",
                        "--benchmark_enable_random_interleaving=true",
                        "--benchmark_report_aggregates_only=true", f"--benchmark_out={raw}",
                        "--benchmark_out_format=csv"],
                       check=True, env={**os.environ, "OMP_NUM_THREADS": str(args.threads)})
        notes["load_after"] = load_average()
        lines = raw.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("name,"))
    rows = [line for line in lines[header + 1:] if "_median" in line.split(",")[0]]
    with open(args.out, "w") as f:
        for key, value in notes.items():
            f.write(f"# {key}: {value}\n")
        f.write("\n".join([lines[header]] + rows) + "\n")
    print(f"wrote {args.out} (load {notes['load_before']} before, {notes['load_after']} after)", file=sys.stderr)


if __name__ == "__main__":
    main()
