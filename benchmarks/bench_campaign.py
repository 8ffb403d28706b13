"""Campaign throughput on Dask: runs per minute with 2 local workers over 1 (issue 12's
target: >= 1.7x on a 2-core machine).

The same runs (breakwater, capped at `--sim-s` simulated seconds, seeds 0..runs-1) on a
LocalCluster of 1 then 2 worker processes; the cluster is started and warmed up (one task
per worker imports Drake) before the clock starts. Prints the machine line and the load
average, which decide the figure on a shared machine.

    .venv/bin/python benchmarks/bench_campaign.py [--runs 6] [--sim-s 60]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path


def throughput(runs, workers: int) -> float:
    """Runs per minute of `runs` on a fresh LocalCluster of `workers` processes."""
    from drake_auv.campaign import ResultsFile, connect, run_campaign
    from drake_auv.campaign.task import run_task

    client, cluster = connect(workers=workers)
    try:
        client.wait_for_workers(workers)
        warm, = runs[:1]
        client.gather([client.submit(run_task, {**warm.mission, "limits": {
            **warm.mission["limits"], "max_time_s": 1.0}}, workers=[a], pure=False)
            for a in client.scheduler_info()["workers"]])
        with tempfile.TemporaryDirectory() as out:
            results = ResultsFile(Path(out) / "results.csv", [])
            start = time.perf_counter()
            counts = run_campaign(runs, results, client, progress=False)
            wall = time.perf_counter() - start
        if counts["ok"] != len(runs):
            raise RuntimeError(f"{counts['failed']} run(s) failed")
        return 60.0 * len(runs) / wall
    finally:
        client.close()
        cluster.close()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--sim-s", type=float, default=60.0)
    args = parser.parse_args(argv)
    from drake_auv.campaign import expand_runs

    runs = expand_runs("breakwater", list(range(args.runs)), [],
                       [f"limits.max_time_s={args.sim_s:g}", "sonar_noise=realistic"])
    load_before = os.getloadavg()
    one = throughput(runs, 1)
    two = throughput(runs, 2)
    load_after = os.getloadavg()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"{time.strftime('%Y-%m-%d %H:%M')}; load average (1, 5, 15 min) before "
          f"{', '.join(f'{v:.1f}' for v in load_before)}, after "
          f"{', '.join(f'{v:.1f}' for v in load_after)}")
    print(f"{args.runs} breakwater runs of {args.sim_s:g} s simulated each")
    print(f"1 worker: {one:.2f} runs/min; 2 workers: {two:.2f} runs/min; ratio {two / one:.2f}x "
          "(target >= 1.7x on a quiet 2-core machine)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
