"""Timing of the off-line planner on the 100 m x 250 m caldera ROI.

Measures (median of --runs runs, after one warm-up):
- the full plan, classification to combined path, 0.5 m cells (and with the lawnmower);
- the metrics of both paths (Table 3), 0.5 m cells;
- the full plan at 0.25 m cells (4x the cells), and its ratio to the 0.5 m time;
- survey scale: 1 km x 1 km and 2 km x 2 km at 1 m cells (1 M and 4 M cells) with
  four steep mounds of 30-60 m radius, Omega = 2 m, the plan without the baseline, each in a
  fresh process for its peak memory (ru_maxrss), one run each; with the time of a reference
  numpy pass over the same grid (np.gradient, hypot, a threshold, a sum) and the ratio, since
  the shared machine's speed varies.
Targets: plan <= 0.25 s, metrics <= 1 s, 0.25 m cells <= 5x the 0.5 m time; survey scale:
2 km x 2 km <= 5 s wall and <= 1 GiB peak, 4 M / 1 M cells <= 4x (linear).

    .venv/bin/python benchmarks/bench_planner.py [--runs 7] [--survey-only]
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
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


def survey_grid(n: int):
    """An n x n grid of 1 m cells, a gentle tilt and four seeded steep mounds (30-60 m radius,
    40 m high: slopes up to about 1.7 / (radius / 60))."""
    from drake_auv.terrain.bathymetry import Bathymetry

    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:n, 0:n].astype(float)
    z = -60.0 + 0.01 * xx
    for _ in range(4):
        cx, cy, r = rng.uniform(0.2 * n, 0.8 * n), rng.uniform(0.2 * n, 0.8 * n), rng.uniform(30, 60)
        z += 40.0 * np.exp(-(np.hypot(xx - cx, yy - cy) / r) ** 2)
    return Bathymetry(z, (1.0, 1.0))


def survey_run(n: int) -> dict:
    """One survey-scale plan in this process: wall and CPU time, peak RSS, reference pass."""
    bathy = survey_grid(n)
    t0 = time.perf_counter()
    gy, gx = np.gradient(bathy.z, 1.0, 1.0)
    s = np.hypot(gx, gy)
    ref = float(((s > 0.5) * s).sum())
    ref_wall = time.perf_counter() - t0
    del gx, gy, s
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    t0, c0 = time.perf_counter(), time.process_time()
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0), baseline=False,
                         compute_metrics=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return {"n": n, "wall": wall, "cpu": cpu, "ref_wall": ref_wall, "ref": ref,
            "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
            "before_mib": rss0, "regions": plan.labels.n_regions, "samples": len(plan.path)}


def survey_scale() -> None:
    rows = []
    for n in (1000, 2000):
        out = subprocess.run([sys.executable, __file__, "--survey-run", str(n)], check=True,
                             capture_output=True, text=True).stdout
        rows.append(json.loads(out.strip().splitlines()[-1]))
    for r in rows:
        print(f"survey {r['n'] / 1000:g} km x {r['n'] / 1000:g} km, 1 m cells ({r['n'] ** 2 / 1e6:g} M): "
              f"{r['wall']:.2f} / {r['cpu']:.2f} s wall / CPU, peak {r['peak_mib']:.0f} MiB "
              f"({r['before_mib']:.0f} before planning), {r['regions']} high-slope regions, "
              f"{r['samples']} samples; reference numpy pass {r['ref_wall']:.3f} s, plan = "
              f"{r['wall'] / r['ref_wall']:.0f}x it")
    a, b = rows
    print(f"survey scaling 4 M / 1 M cells: {b['cpu'] / a['cpu']:.2f}x CPU (linear: 4x; targets: "
          f"2 km <= 5 s, <= 1024 MiB)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="timed runs per figure (default 7)")
    parser.add_argument("--survey-only", action="store_true", help="only the survey-scale runs")
    parser.add_argument("--survey-run", type=int, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.survey_run is not None:
        print(json.dumps(survey_run(args.survey_run)))
        return
    if args.survey_only:
        survey_scale()
        return
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
    survey_scale()


if __name__ == "__main__":
    main()
