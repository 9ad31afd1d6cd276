"""What Python adds to a planning run: N full Table 2 runs through `tissue.plan` and through
the `insert` binary, alternated, in one process on one machine.

    cargo build --release --bin insert
    python python/bench/overhead.py target/release/insert [-n 11]

Each Python run is `tissue.plan(tissue.Patient.shipped("table2"))` timed from the call to the
returned Plan (the patient made, the run, the report parsed into a dict, the arrays made).
Each `insert` run is the whole process, `insert --report FILE` with its output to /dev/null,
timed from the spawn to its exit (process start, the same patient, the same run, the report
written). Nothing is subtracted. Both report the stepping's own `wall_time_s`, printed too:
the two front ends run the same job, so what is left is each one's overhead. The issue's bound:
Python adds at most 5 % (ratio ≤ 1.05).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import tissue


def python_run() -> tuple[float, float]:
    start = time.perf_counter()
    plan = tissue.plan(tissue.Patient.shipped("table2"))
    wall = time.perf_counter() - start
    return wall, float(plan.report["wall_time_s"])


def insert_run(binary: str, report: str) -> tuple[float, float]:
    start = time.perf_counter()
    subprocess.run(
        [binary, "--report", report],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        check=True,
    )
    wall = time.perf_counter() - start
    with open(report) as f:
        return wall, float(json.load(f)["wall_time_s"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("insert", help="the insert binary (cargo build --release --bin insert)")
    parser.add_argument("-n", type=int, default=11, help="runs of each (default 11)")
    args = parser.parse_args()
    if not os.access(args.insert, os.X_OK):
        print(f"not an executable: {args.insert}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        report = os.path.join(tmp, "report.json")
        python_run(), insert_run(args.insert, report)  # warm up both (page cache, pools)
        py, ins = [], []
        for i in range(args.n):
            # Alternated, and which goes first alternates too.
            if i % 2 == 0:
                py.append(python_run())
                ins.append(insert_run(args.insert, report))
            else:
                ins.append(insert_run(args.insert, report))
                py.append(python_run())
    med = lambda xs, k: statistics.median(x[k] for x in xs)  # noqa: E731
    py_wall, ins_wall = med(py, 0), med(ins, 0)
    py_step, ins_step = med(py, 1), med(ins, 1)
    print(f"Table 2, {args.n} runs each, alternated (tissue {tissue.__version__})")
    print(f"  tissue.plan   wall median {py_wall:.3f} s   (stepping wall_time_s {py_step:.3f} s)")
    print(f"  insert        wall median {ins_wall:.3f} s   (stepping wall_time_s {ins_step:.3f} s)")
    print(f"  ratio python / insert: {py_wall / ins_wall:.3f} (walls), {py_step / ins_step:.3f} (stepping)")
    print(f"  overhead outside the stepping: python {py_wall - py_step:.3f} s, insert {ins_wall - ins_step:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
