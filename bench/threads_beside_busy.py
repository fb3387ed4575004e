#!/usr/bin/env python3
"""drench's threads alone and beside a busy thread: the thread pool against the OpenMP build before it.

    python3 bench/threads_beside_busy.py --before OPENMP_BUILD/demos/drench --after build/demos/drench \
        --rounds 3 --out bench/results/debian12-2core/threads_beside_busy.csv

Each round runs the jet on a cloth cut to 150 steps (demos/scenes/jet_on_cloth.json, frames off) with 1 and
2 threads, with each binary, first alone, then beside one busy loop (a shell spinning on one core, as a
game's thread or a second drench would). The binaries alternate, so that the machine's drift hits both.
Issue 41's targets: beside one busy thread, 2 threads never slower than 1; alone, the pool about as fast as
OpenMP.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "demos" / "scenes" / "jet_on_cloth.json"

sys.path.insert(0, str(ROOT / "bench"))
from bench_surface import commit, cpu_model, write_csv  # noqa: E402  (the same provenance lines as the other CSVs)


def wall(binary, threads, out):
    command = [binary, "run", str(SCENE), "--out", str(out), "--quiet", "--steps", "150", "--threads",
               str(threads), "--set", "time.frame_rate=0"]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads((out / "summary.json").read_text())["wall_s"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="drench built with OpenMP's parallel loops")
    parser.add_argument("--after", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", required=True, help="CSV to write")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for r in range(1, args.rounds + 1):
            for condition in ("alone", "beside one busy thread"):
                busy = None
                if condition != "alone":
                    busy = subprocess.Popen(["sh", "-c", "while :; do :; done"])
                try:
                    for threads in (1, 2):
                        for name, binary in (("openmp", args.before), ("pool", args.after)):
                            out = Path(scratch) / f"{r}_{len(rows)}"
                            seconds = wall(binary, threads, out)
                            print(f"round {r}, {condition}, {name}, {threads} thread(s): {seconds:.2f} s",
                                  file=sys.stderr, flush=True)
                            rows.append({"round": r, "condition": condition, "build": name, "threads": threads,
                                         "wall_s": seconds, "load_1min": os.getloadavg()[0]})
                finally:
                    if busy:
                        busy.kill()
                        busy.wait()
    write_csv(args.out, rows, [f"command: python3 bench/threads_beside_busy.py --rounds {args.rounds}",
                               f"commit: {commit()}", f"cpu: {cpu_model()}"])


if __name__ == "__main__":
    main()
