"""Campaign throughput on Dask: breakwater dives per core-hour and the efficiency of 2
workers against 1 (targets: >= 1.7x the runs per minute of 1 worker on this 2-core machine,
and an efficiency >= 0.85 on an external cluster).

The same runs (breakwater, realistic sonars, seeds 0..runs-1, whole dives or capped at
`--sim-s` simulated seconds) on a LocalCluster of 1 then 2 worker processes, and on an
external cluster as a user starts one (`dask scheduler --host 127.0.0.1`, then `dask worker`
processes of one thread, the second added between the two measurements); each worker is
warmed up (one short task imports Drake) before the clock starts. Dives per core-hour are
dives per hour over the workers (one single-threaded process a core); the efficiency is the
2-worker throughput over twice the 1-worker one. Prints the machine line and the load
average, which decide the figure on a shared machine, and a control without Dask: the speed-up
of two plain processes running one run each over one process running both (what the machine
gives two processes at that moment; the Dask ratio cannot exceed it).

    .venv/bin/python benchmarks/bench_campaign.py [--runs 6] [--sim-s 0 (whole dives)]
        [--cluster local|external|both]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from _reference import machine


ROOT = Path(__file__).resolve().parent.parent
START_TIMEOUT_S = 60.0


def timed_campaign(client, runs, workers: int) -> float:
    """Runs per minute of `runs` on `client` once `workers` workers are up and warm."""
    from drake_auv.campaign import ResultsFile, run_campaign
    from drake_auv.campaign.task import run_task

    client.wait_for_workers(workers, timeout=START_TIMEOUT_S)
    warm = runs[0].mission
    client.gather([client.submit(run_task, {**warm, "limits": {
        **warm["limits"], "max_time_s": 1.0}}, workers=[a], pure=False)
        for a in client.scheduler_info()["workers"]])
    with tempfile.TemporaryDirectory() as out:
        results = ResultsFile(Path(out) / "results.csv", [])
        start = time.perf_counter()
        counts = run_campaign(runs, results, client, progress=False)
        wall = time.perf_counter() - start
    if counts["ok"] != len(runs):
        raise RuntimeError(f"{counts['failed']} run(s) failed")
    return 60.0 * len(runs) / wall


def throughput(runs, workers: int) -> float:
    """Runs per minute of `runs` on a fresh LocalCluster of `workers` processes."""
    from drake_auv.campaign import connect

    client, cluster = connect(workers=workers)
    try:
        return timed_campaign(client, runs, workers)
    finally:
        client.close()
        cluster.close()


@contextmanager
def external_scheduler(folder: Path):
    """(address, start_worker): a `dask scheduler` on 127.0.0.1 (a free port, no dashboard)
    and a function starting one `dask worker` process of one thread on it; every process
    started here is terminated on exit."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}  # the workers import this tree's drake_auv
    dask = [sys.executable, "-m", "dask"]
    file = folder / "scheduler.json"
    processes = [subprocess.Popen(
        dask + ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                "--scheduler-file", str(file)], env=env, cwd=folder,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]

    def start_worker():
        processes.append(subprocess.Popen(
            dask + ["worker", "--scheduler-file", str(file), "--host", "127.0.0.1",
                    "--nthreads", "1", "--nworkers", "1", "--no-dashboard"], env=env,
            cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))

    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while not file.exists():
            if time.monotonic() > deadline or processes[0].poll() is not None:
                raise RuntimeError("the dask scheduler did not start")
            time.sleep(0.2)
        time.sleep(0.2)  # the file is written whole by then
        yield json.loads(file.read_text())["address"], start_worker
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()


def external_throughput(runs) -> tuple[float, float]:
    """Runs per minute of `runs` on an external cluster with 1, then 2 workers."""
    from drake_auv.campaign import connect

    with tempfile.TemporaryDirectory() as folder, \
            external_scheduler(Path(folder)) as (address, start_worker):
        client, _ = connect(scheduler=address)
        try:
            start_worker()
            one = timed_campaign(client, runs, 1)
            start_worker()
            two = timed_campaign(client, runs, 2)
        finally:
            client.close()
    return one, two


def report(label: str, one: float, two: float) -> None:
    print(f"{label}: 1 worker {one:.2f} runs/min ({60 * one:.1f} dives per core-hour); "
          f"2 workers {two:.2f} runs/min ({30 * two:.1f} per core-hour); ratio "
          f"{two / one:.2f}x, efficiency {two / (2 * one):.2f} (target >= 0.85)")


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
    parser.add_argument("--sim-s", type=float, default=0.0,
                        help="simulated seconds a run, 0: whole dives")
    parser.add_argument("--cluster", choices=("local", "external", "both"), default="both")
    parser.add_argument("--no-control", action="store_true",
                        help="skip the control without Dask")
    args = parser.parse_args(argv)
    from drake_auv.campaign import expand_runs

    overrides = ["sonar_noise=realistic"]
    if args.sim_s > 0:
        overrides.append(f"limits.max_time_s={args.sim_s:g}")
    runs = expand_runs("breakwater", list(range(args.runs)), [], overrides)
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[name] = "1"  # as Dask's nanny sets it for its workers
    load_before = os.getloadavg()
    figures = {}
    if args.cluster in ("local", "both"):
        figures["LocalCluster"] = throughput(runs, 1), throughput(runs, 2)
    if args.cluster in ("external", "both"):
        figures["external cluster (dask scheduler / dask worker on 127.0.0.1)"] = \
            external_throughput(runs)
    control = None if args.no_control else plain_speedup(runs)
    load_after = os.getloadavg()
    print(machine())
    print(f"load average (1, 5, 15 min) before {', '.join(f'{v:.1f}' for v in load_before)}, "
          f"after {', '.join(f'{v:.1f}' for v in load_after)}")
    print(f"{args.runs} breakwater runs, "
          + (f"{args.sim_s:g} s simulated each" if args.sim_s > 0 else "whole dives"))
    for label, (one, two) in figures.items():
        report(label, one, two)
    if control is not None:
        print(f"control without Dask: 2 plain processes {control:.2f}x faster than 1 on 2 runs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
