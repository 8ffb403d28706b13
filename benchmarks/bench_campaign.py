"""Campaign throughput on Dask: runs per minute with 2 local workers over 1 (issue 12's
target: >= 1.7x on a 2-core machine).

The same runs (breakwater, capped at `--sim-s` simulated seconds, seeds 0..runs-1) on a
LocalCluster of 1 then 2 worker processes; the cluster is started and warmed up (one task
per worker imports Drake) before the clock starts. Prints the machine line and the load
average, which decide the figure on a shared machine, and a control without Dask: the speed-up
of two plain processes running one run each over one process running both (what the machine
gives two processes at that moment; the Dask ratio cannot exceed it).

    .venv/bin/python benchmarks/bench_campaign.py [--runs 6] [--sim-s 60]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from _reference import machine


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


def plain_speedup(runs) -> float:
    """Wall time of the first two runs one after the other in one process over both at once
    in two processes (one thread each)."""
    from concurrent.futures import ProcessPoolExecutor

    from drake_auv.campaign.task import run_task

    missions = [run.mission for run in runs[:2]]
    with ProcessPoolExecutor(1) as pool:
        list(pool.map(run_task, missions[:1]))  # warm-up: imports
        start = time.perf_counter()
        list(pool.map(run_task, missions))
        one = time.perf_counter() - start
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(run_task, missions))
        start = time.perf_counter()
        list(pool.map(run_task, missions))
        two = time.perf_counter() - start
    return one / two


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--sim-s", type=float, default=60.0)
    args = parser.parse_args(argv)
    from drake_auv.campaign import expand_runs

    runs = expand_runs("breakwater", list(range(args.runs)), [],
                       [f"limits.max_time_s={args.sim_s:g}", "sonar_noise=realistic"])
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[name] = "1"  # as Dask's nanny sets it for its workers
    load_before = os.getloadavg()
    one = throughput(runs, 1)
    two = throughput(runs, 2)
    control = plain_speedup(runs)
    load_after = os.getloadavg()
    print(machine())
    print(f"load average (1, 5, 15 min) before {', '.join(f'{v:.1f}' for v in load_before)}, "
          f"after {', '.join(f'{v:.1f}' for v in load_after)}")
    print(f"{args.runs} breakwater runs of {args.sim_s:g} s simulated each")
    print(f"1 worker: {one:.2f} runs/min; 2 workers: {two:.2f} runs/min; ratio {two / one:.2f}x "
          "(target >= 1.7x on a quiet 2-core machine)")
    print(f"control without Dask: 2 plain processes {control:.2f}x faster than 1 on 2 runs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
