"""Timing of the off-line planner on the 100 m x 250 m caldera ROI.

Measures (median of --runs runs, after one warm-up):
- the full plan, classification to combined path, 0.5 m cells (and with the lawnmower);
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


def _median_time(fn, runs: int) -> tuple[float, float, object]:
    """Median wall time and median CPU time of the process (s), and the last result. The CPU
    time is the robust figure on a shared machine: waiting for a core does not count."""
    result = fn()  # warm-up (imports, caches)
    wall, cpu = [], []
    for _ in range(runs):
        t0, c0 = time.perf_counter(), time.process_time()
        result = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="timed runs per figure (default 7)")
    args = parser.parse_args()
    site05 = caldera_site(0.5)
    site025 = caldera_site(0.25)
    w05, c05, _ = _median_time(lambda: plan_coverage(site05, baseline=False, compute_metrics=False),
                               args.runs)
    wb, cb, plan05 = _median_time(lambda: plan_coverage(site05, compute_metrics=False), args.runs)
    wm, cm, metrics = _median_time(lambda: evaluate_plan(plan05), args.runs)
    w025, c025, _ = _median_time(
        lambda: plan_coverage(site025, baseline=False, compute_metrics=False), args.runs)
    print(f"python {platform.python_version()}, median of {args.runs} runs, wall / CPU seconds")
    print(f"plan, classification to combined path, 0.5 m cells ({site05.shape[1]} x "
          f"{site05.shape[0]}): {w05:.3f} / {c05:.3f} s (target <= 0.25 s)")
    print(f"  the same plus the lawnmower baseline: {wb:.3f} / {cb:.3f} s")
    print(f"metrics of path and lawnmower, 0.5 m cells: {wm:.3f} / {cm:.3f} s (target <= 1 s)")
    print(f"plan at 0.25 m cells ({site025.shape[1]} x {site025.shape[0]}): {w025:.3f} / "
          f"{c025:.3f} s, {c025 / c05:.2f}x the 0.5 m CPU time (target <= 5x)")
    print(f"path {plan05.path.length:.0f} m ({len(plan05.path)} samples), lawnmower "
          f"{plan05.lawnmower.length:.0f} m; view {metrics.total.view_mean_deg:.1f} vs "
          f"{metrics.lawnmower.view_mean_deg:.1f} deg")


if __name__ == "__main__":
    main()
