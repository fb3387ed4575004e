#!/usr/bin/env python3
"""Issue 42's whole set, run once and timed: the jet's and the dam break's one-at-a-time sweeps against their
references, the convergence studies and the dam break beside Martin & Moyce, one thread each, one after the
other. Not a CI job: about three quarters of an hour.

    time python3 bench/accuracy_whole_set.py --drench build/demos/drench \
        --record bench/results/debian12-2core [--out DIR] [--keep DIR]

Each part is the documented command of its table (bench/accuracy_sweep.py --only jet_reference and
--only dam_reference, bench/accuracy_convergence.py --only jet, dam and substeps, bench/martin_moyce.py),
writing its CSV into --out (default: a temporary folder, so that a timing run leaves the recorded CSVs as
they are; --out bench/results/debian12-2core replaces them). Writes accuracy_whole_set.csv into --record: one
row per part with its command, wall time and load average before and after, and `# key: value` notes with
the whole set's wall time, the CPU, the commit and the 1-minute load average sampled every 30 s (mean and
largest: the VM is shared, and a load above 1 on its 2 cores slows a one-thread run).
"""

import argparse
import csv
import io
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_surface import commit, cpu_model, load_average  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

# (part, script and its arguments); --drench, --out, --keep and --threads 1 are added. The dam break's
# convergence has no WCSPH series, as docs/accuracy.md's (WCSPH's dam runs are bound by its speed of sound).
PARTS = [
    ("dam one-at-a-time and its reference", ["bench/accuracy_sweep.py", "--only", "dam_reference"]),
    ("jet one-at-a-time and its reference", ["bench/accuracy_sweep.py", "--only", "jet_reference"]),
    ("convergence, jet", ["bench/accuracy_convergence.py", "--only", "jet", "--solvers", "pcisph,dfsph,wcsph,pbf"]),
    ("convergence, dam", ["bench/accuracy_convergence.py", "--only", "dam", "--solvers", "pcisph,dfsph,pbf"]),
    ("convergence, cloth sub-steps", ["bench/accuracy_convergence.py", "--only", "substeps"]),
    ("dam break beside Martin & Moyce", ["bench/martin_moyce.py", "--solvers", "pcisph,dfsph"]),
]


class LoadSampler:
    """The 1-minute load average every `period` seconds, in a thread, while the set runs."""

    def __init__(self, period=30.0):
        self.period, self.values, self._stop = period, [], threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while True:
            self.values.append(float(load_average()))
            if self._stop.wait(self.period):
                return

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drench", default=str(ROOT / "build" / "demos" / "drench"))
    parser.add_argument("--record", required=True, help="folder of accuracy_whole_set.csv")
    parser.add_argument("--out", help="folder of the parts' CSVs (default: a temporary folder)")
    parser.add_argument("--keep", help="keep the parts' runs here (default: a temporary folder)")
    args = parser.parse_args()
    drench = str(Path(args.drench).resolve())
    notes = {"script": " ".join(["python3 bench/accuracy_whole_set.py"] + sys.argv[1:]), "cpu": cpu_model(),
             "commit": commit(), "load_before": load_average()}
    rows = []
    with tempfile.TemporaryDirectory() as scratch, LoadSampler() as sampler:
        out = Path(args.out).resolve() if args.out else Path(scratch) / "out"
        keep = Path(args.keep).resolve() if args.keep else Path(scratch) / "keep"
        out.mkdir(parents=True, exist_ok=True)
        start = time.monotonic()
        for k, (part, command) in enumerate(PARTS):
            command = [sys.executable, *command, "--drench", drench, "--out", str(out), "--keep",
                       str(keep / f"part{k + 1}"), "--threads", "1"]
            before = load_average()
            t0 = time.monotonic()
            print(f"[{k + 1}/{len(PARTS)}] {part}", file=sys.stderr, flush=True)
            result = subprocess.run(command, cwd=ROOT)
            rows.append({"part": part, "status": "ok" if result.returncode == 0 else f"exit {result.returncode}",
                         "wall_s": f"{time.monotonic() - t0:.1f}", "load_before": before,
                         "load_after": load_average(),
                         "command": " ".join(["python3", *command[1:]]).replace(str(out), "OUT")
                         .replace(str(keep), "KEEP").replace(drench, "build/demos/drench")})
            print(f"    {rows[-1]['status']} in {rows[-1]['wall_s']} s", file=sys.stderr, flush=True)
        total = time.monotonic() - start
    notes["load_after"] = load_average()
    notes["wall_s"] = f"{total:.1f} ({total / 60:.1f} min)"
    values = sampler.values
    notes["load_sampled"] = (f"mean {sum(values) / len(values):.2f}, largest {max(values):.2f} over {len(values)}"
                             " samples, every 30 s")
    text = io.StringIO()
    for key, value in notes.items():
        text.write(f"# {key}: {value}\n")
    writer = csv.DictWriter(text, fieldnames=["part", "status", "wall_s", "load_before", "load_after", "command"],
                            lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    record = Path(args.record)
    record.mkdir(parents=True, exist_ok=True)
    (record / "accuracy_whole_set.csv").write_text(text.getvalue())
    print(f"wrote {record / 'accuracy_whole_set.csv'}: the whole set in {total / 60:.1f} min", file=sys.stderr)
    if any(r["status"] != "ok" for r in rows):
        sys.exit("a part failed: see accuracy_whole_set.csv")


if __name__ == "__main__":
    main()
