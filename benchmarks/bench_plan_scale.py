"""`drake-auv plan` with its default options at scale: a shipped Monterey tile and a 2 km x
2 km site at 1 m (4 M cells), every output written (path.csv, GeoJSON, the grid and the
occluded 3D metrics, the reports, the figures).

Each plan runs in a fresh process (`python -m drake_auv.cli plan FILE -o DIR`): its wall time,
its CPU time (user + system: what the shared machine's load inflates least) and its peak
memory (ru_maxrss). The reference of `benchmarks/_reference.py` (the vehicle alone, 600 s
lawnmower, median of 3) is measured before, between and after the plans, and each plan's wall
time is given over the reference's (the median of the three) as well. With `--phases`, the
site's stages are timed in this process too: `plan_coverage` (the grid metrics included),
path.csv, the GeoJSON, the 3D metrics and the figures.

The site: a seeded relief (Gaussian noise on a 200 x 200 grid, Gaussian-filtered over 4 cells
and upsampled ten times by cubic splines, 13 m standard deviation: hills and hollows of some
40 m, 7 % of the cells steeper than the default slope threshold 0.5) on a 1 % and 0.5 %
regional slope, 12 to 102 m deep, written as a UTM GeoTIFF.
Targets: the tile well under a minute; the site within a minute (an unloaded 2-core machine).

    .venv/bin/python benchmarks/bench_plan_scale.py [--phases] [--site-cells 2000]
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

import numpy as np
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _reference import SIM_SECONDS, machine, vehicle_real_time_factor  # noqa: E402
from drake_auv.terrain.bathymetry import Bathymetry  # noqa: E402
from drake_auv.terrain.readers import write_geotiff  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TILE = ROOT / "drake_auv/data/monterey/MontereyBay.R_-121.815_-121.805_36.790_36.800.epsg3857.tif"
CHILD = ("import resource, sys; from drake_auv.cli import main; code = main(); "
         "r = resource.getrusage(resource.RUSAGE_SELF); "
         "print('RUSAGE', r.ru_utime + r.ru_stime, r.ru_maxrss, file=sys.stderr); sys.exit(code)")


def site(n: int = 2000, seed: int = 0) -> Bathymetry:
    """The n x n site of 1 m cells (see the module docstring), in UTM zone 10 N."""
    rng = np.random.default_rng(seed)  # the site itself, not a run's noise
    coarse = ndimage.gaussian_filter(rng.standard_normal((n // 10, n // 10)), 4.0, mode="wrap")
    relief = ndimage.zoom(coarse, 10, order=3)[:n, :n]
    yy, xx = np.mgrid[0:n, 0:n]
    z = -70.0 + 0.01 * xx + 0.005 * yy + 13.0 * relief / relief.std()
    return Bathymetry(z, (1.0, 1.0), (590000.5, 4070000.5), "EPSG:32610")


def plan_run(grid, out) -> dict:
    """One default `plan` in a fresh process: wall and CPU seconds, peak MiB, the report."""
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", CHILD, "plan", str(grid), "-o", str(out)],
                          capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"plan {grid} failed:\n{done.stderr[-2000:]}")
    cpu, rss = next(line.split()[1:] for line in done.stderr.splitlines()
                    if line.startswith("RUSAGE"))
    report = json.loads((Path(out) / "report.json").read_text())
    return {"wall": wall, "cpu": float(cpu), "peak_mib": int(rss) / 1024, "report": report}


def phases(grid) -> dict:
    """Wall and CPU seconds of each stage of a default plan of `grid`, in this process."""
    from drake_auv.formats.geojson import write_geojson
    from drake_auv.formats.registry import check_exports
    from drake_auv.planning.coverage_plan import plan_coverage
    from drake_auv.planning.figures import write_figures
    from drake_auv.planning.metrics3d import evaluate_plan_3d
    from drake_auv.terrain.readers import read_bathymetry

    out, times = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        def timed(name, fn):
            t0, c0 = time.perf_counter(), time.process_time()
            out[name] = fn()
            times[name] = (time.perf_counter() - t0, time.process_time() - c0)

        timed("plan_coverage (with the grid metrics)", lambda: plan_coverage(read_bathymetry(grid)))
        plan = out["plan_coverage (with the grid metrics)"]
        _, geo = check_exports(plan.bathy)
        timed("path.csv", lambda: plan.path.to_csv(Path(tmp) / "path.csv"))
        timed("GeoJSON (route, lawnmower)", lambda: (
            write_geojson(plan.path, geo, Path(tmp) / "p.geojson"),
            write_geojson(plan.lawnmower, geo, Path(tmp) / "l.geojson")))
        timed("3D metrics", lambda: evaluate_plan_3d(plan))
        timed("figures", lambda: write_figures(plan, tmp, geo=geo))
        print(f"  path {len(plan.path)} samples, lawnmower {len(plan.lawnmower)}, "
              f"{plan.bathy.z.size} cells")
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--site-cells", type=int, default=2000,
                        help="the site's cells along a side (1 m each; default 2000)")
    parser.add_argument("--phases", action="store_true",
                        help="also time the site's stages in this process")
    args = parser.parse_args()
    print(machine())
    refs = [vehicle_real_time_factor()]
    with tempfile.TemporaryDirectory() as tmp:
        grid = Path(tmp) / "site.tif"
        write_geotiff(site(args.site_cells), grid)
        runs = {"Monterey tile": plan_run(TILE, Path(tmp) / "tile")}
        refs.append(vehicle_real_time_factor())
        runs[f"site {args.site_cells} x {args.site_cells} at 1 m"] = plan_run(
            grid, Path(tmp) / "site")
        refs.append(vehicle_real_time_factor())
        factor = statistics.median(refs)
        print(f"reference (vehicle alone, 600 s lawnmower, before / between / after): "
              f"{', '.join(f'{r:.0f}x' for r in refs)} real time; median {factor:.0f}x, "
              f"{SIM_SECONDS / factor:.2f} s wall")
        print("| run | samples (path / lawnmower) | wall (s) | CPU (s) | peak (MiB) | "
              "wall over the reference's |")
        print("| --- | ---: | ---: | ---: | ---: | ---: |")
        for name, r in runs.items():
            m = r["report"]["metrics"]
            print(f"| {name} | {m['total']['samples']} / {m['lawnmower']['samples']} | "
                  f"{r['wall']:.1f} | {r['cpu']:.1f} | {r['peak_mib']:.0f} | "
                  f"{r['wall'] * factor / SIM_SECONDS:.1f} |")
        for name, r in runs.items():
            cov = {k: f"{100 * v['coverage']:.2f} % (se {100 * v['coverage_se']:.2f})"
                   for k, v in r["report"]["metrics_3d"].items()}
            print(f"{name}: 3D coverage {cov}")
        if args.phases:
            print(f"stages of the site, in this process (load average {os.getloadavg()[0]:.1f}):")
            for name, (wall, cpu) in phases(grid).items():
                print(f"  {name}: wall {wall:.1f} s, CPU {cpu:.1f} s")
    print(machine())


if __name__ == "__main__":
    main()
