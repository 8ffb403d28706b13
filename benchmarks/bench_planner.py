"""Timing of the off-line planner on the 100 m x 250 m caldera ROI.

Measures (median of --runs runs, after one warm-up):
- the full plan, classification to combined path (plus the lawnmower baseline), 0.5 m cells;
- the metrics of both paths (Table 3), 0.5 m cells;
- the full plan at 0.25 m cells (4x the cells), and its ratio to the 0.5 m time.
Targets (issue 3): plan <= 0.25 s, metrics <= 1 s, 0.25 m cells <= 5x the 0.5 m time.

    .venv/bin/python benchmarks/bench_planner.py [--runs 7]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.metrics import evaluate_plan
from drake_auv.terrain.synthetic import caldera_site


def _median_time(fn, runs: int) -> tuple[float, object]:
    result = fn()  # warm-up (imports, caches)
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="timed runs per figure (default 7)")
    args = parser.parse_args()
    site05 = caldera_site(0.5)
    site025 = caldera_site(0.25)
    t05, plan05 = _median_time(lambda: plan_coverage(site05, compute_metrics=False), args.runs)
    tm, metrics = _median_time(lambda: evaluate_plan(plan05), args.runs)
    t025, _ = _median_time(lambda: plan_coverage(site025, compute_metrics=False), args.runs)
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    print(f"full plan, 0.5 m cells ({site05.shape[1]} x {site05.shape[0]}): {t05:.3f} s "
          f"median of {args.runs} (target <= 0.25 s)")
    print(f"metrics of path and lawnmower, 0.5 m cells: {tm:.3f} s (target <= 1 s)")
    print(f"full plan, 0.25 m cells ({site025.shape[1]} x {site025.shape[0]}): {t025:.3f} s, "
          f"{t025 / t05:.2f}x the 0.5 m time (target <= 5x)")
    print(f"path {plan05.path.length:.0f} m ({len(plan05.path)} samples), lawnmower "
          f"{plan05.lawnmower.length:.0f} m; view {metrics.total.view_mean_deg:.1f} vs "
          f"{metrics.lawnmower.view_mean_deg:.1f} deg")


if __name__ == "__main__":
    main()
