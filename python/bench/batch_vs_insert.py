"""Issue 34, item 5: a batch of 16 Table 2 variants through Dask against the same 16 as `insert`
runs in two processes side by side, on the same machine. Bar: batch time <= 1.2 x insert time.

    python python/bench/batch_vs_insert.py [--insert target/release/insert] [--repeat 3]

Both sides run one planner thread per process (RAYON_NUM_THREADS=1) and two processes: the
Dask side a LocalCluster of two worker processes of one thread each, the `insert` side two
shell loops of 8 runs each, started together. The planner would otherwise use every core in
each process, and two processes of two threads on two cores only fight over them. The Dask
side's time is `tissue.batch.run` on a started cluster (it includes the workers' first
`import tissue` and every result file written); the cluster's start is printed apart.

Each side's figures are checked to be the same (same case, same numbers).
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
from pathlib import Path

VOLUMES = list(range(60, 220, 10))  # 16 variants, cm3


def insert_side(insert: str, volumes: list[int], work: Path, env: dict, flags: str = "") -> tuple[float, dict]:
    # two loops of 8, interleaved (60, 80, … and 70, 90, …): larger volumes take longer, and
    # halves by size would leave one loop with the long runs
    loops = [volumes[0::2], volumes[1::2]]
    started = time.perf_counter()
    procs = []
    for n, vs in enumerate(loops):
        script = "set -e\n" + "".join(
            f'"{insert}" --volume {v}{flags} --quiet --report "{work}/insert_{v}.json"\n' for v in vs
        )
        procs.append(subprocess.Popen(["sh", "-c", script], env=env, stdout=subprocess.DEVNULL))
    for p in procs:
        if p.wait() != 0:
            raise SystemExit(f"an insert loop failed with exit code {p.returncode}")
    wall = time.perf_counter() - started
    reports = {v: json.loads((work / f"insert_{v}.json").read_text()) for v in volumes}
    gains = {v: r["area_gain_cm2"] for v, r in reports.items()}
    gains["run_s"] = sum(r["wall_time_s"] for r in reports.values())
    return wall, gains


def main() -> int:
    repo = Path(__file__).resolve().parents[2]
    target = Path(os.environ.get("CARGO_TARGET_DIR", repo / "target"))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--insert", default=str(target / "release" / "insert"), help="the insert binary")
    parser.add_argument("--repeat", type=int, default=3, help="rounds of both sides (the medians are compared)")
    parser.add_argument("--max-steps", type=int, help="a step limit for every run (a quicker check; default: the library's)")
    args = parser.parse_args()
    if not os.access(args.insert, os.X_OK):
        raise SystemExit(f"no insert binary at {args.insert}: cargo build --release --bin insert, or --insert PATH")

    import distributed

    import tissue
    import tissue.batch

    env = dict(os.environ, RAYON_NUM_THREADS="1")
    os.environ["RAYON_NUM_THREADS"] = "1"
    extra = {} if args.max_steps is None else {"max_steps": args.max_steps}
    flags = "" if args.max_steps is None else f" --max-steps {args.max_steps}"
    cases = [{"patient": "table2", "volume_cm3": v, **extra} for v in VOLUMES]
    print(f"tissue {tissue.__version__}, {len(VOLUMES)} Table 2 variants (volumes {VOLUMES[0]}..{VOLUMES[-1]} cm3), "
          f"{os.cpu_count()} cores, RAYON_NUM_THREADS=1 on both sides")

    t = time.perf_counter()
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}
    )
    client = distributed.Client(cluster)
    print(f"dask LocalCluster start: {time.perf_counter() - t:.2f} s (not counted)")

    insert_times, batch_times = [], []
    try:
        for r in range(args.repeat):
            with tempfile.TemporaryDirectory() as d:
                work = Path(d)
                # alternate which side goes first, so that a drift in the machine's load (or
                # the workers' first `import tissue`, counted in round 1) does not favour one
                def batch_side() -> tuple[float, list]:
                    t = time.perf_counter()
                    rows = tissue.batch.run(cases, work / "out", client, as_frame=False)
                    return time.perf_counter() - t, rows

                if r % 2 == 0:
                    wall_i, gains_i = insert_side(args.insert, VOLUMES, work, env, flags)
                    wall_b, rows = batch_side()
                else:
                    wall_b, rows = batch_side()
                    wall_i, gains_i = insert_side(args.insert, VOLUMES, work, env, flags)
            failed = [row for row in rows if row["error"] is not None]
            if failed:
                raise SystemExit(f"batch cases failed: {failed}")
            gains_b = {row["volume_cm3"]: row["area_gain_cm2"] for row in rows}
            worst = max(abs(gains_b[v] - gains_i[v]) for v in VOLUMES)
            insert_times.append(wall_i)
            batch_times.append(wall_b)
            run_b = sum(row["wall_time_s"] for row in rows)
            print(f"round {r + 1}: insert x2 {wall_i:.2f} s, dask batch {wall_b:.2f} s, "
                  f"ratio {wall_b / wall_i:.3f}; largest area-gain difference {worst:.3g} cm2; "
                  f"the runs' own wall_time_s summed: insert {gains_i['run_s']:.2f} s, batch {run_b:.2f} s")
    finally:
        client.close()
        cluster.close()

    mi, mb = statistics.median(insert_times), statistics.median(batch_times)
    ratio = mb / mi
    print(f"median: insert x2 {mi:.2f} s, dask batch {mb:.2f} s, ratio {ratio:.3f} (bar <= 1.2): "
          + ("PASS" if ratio <= 1.2 else "FAIL"))
    return 0 if ratio <= 1.2 else 1


if __name__ == "__main__":
    sys.exit(main())
