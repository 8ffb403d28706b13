"""Table 3 of the reference on the synthetic caldera-rim site: our 3D coverage path against a
standard lawnmower (Omega = 2 m, 60 degree camera, delta_s = 0.5, 0.5 m cells).

    .venv/bin/python examples/caldera_offline.py [--outdir out/caldera_offline] [--no-figures]

Prints the comparison twice: on the grid (cone test on cell centres, the planner's own metric)
and on the grid's 3D mesh with occlusion, where the high-slope region is reported for both
sensor models (the planned normal-aligned one and the reference's fixed-tilt forward-looking
one). Writes the plan's files (path CSV, COLA2 and QGroundControl missions, WGS 84 GeoJSON
with the site placed on the Santorini caldera, report, PNG figures) to --outdir.
"""

from __future__ import annotations

import argparse
import time

from drake_auv.formats.outputs import write_outputs
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.metrics3d import evaluate_plan_3d, table3d_markdown
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.report import REFERENCE_TABLE3, table3_markdown
from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT
from drake_auv.terrain.synthetic import caldera_site


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--outdir", default="out/caldera_offline", help="where to write the plan")
    parser.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    args = parser.parse_args()

    bathy = caldera_site(cell=0.5, seed=0)
    t0 = time.perf_counter()
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0, aperture_deg=60.0, overlap=0.1,
                                                   slope_threshold=0.5), progress=True)
    elapsed = time.perf_counter() - t0
    m = plan.metrics
    print(f"Caldera-rim ROI {bathy.extent[1]:.0f} m x {bathy.extent[3]:.0f} m, "
          f"{plan.labels.n_regions} high-slope region(s), {len(plan.cells.cells)} planar cells, "
          f"{len(plan.contours)} contour pieces; planned with metrics in {elapsed:.2f} s.\n")
    print("On the grid (cone test, no occlusion):\n")
    print(table3_markdown(m))
    print("\nOn the 3D mesh with occlusion:\n")
    m3d = evaluate_plan_3d(plan)
    print(table3d_markdown(m3d))
    print(f"\nlength ratio {m.total.length / m.lawnmower.length:.2f} (reference "
          f"{REFERENCE_TABLE3['total']['length'] / REFERENCE_TABLE3['lawnmower']['length']:.2f}), "
          f"viewing-angle ratio {m.total.view_mean_deg / m.lawnmower.view_mean_deg:.2f} (reference "
          f"{REFERENCE_TABLE3['total']['view_mean_deg'] / REFERENCE_TABLE3['lawnmower']['view_mean_deg']:.2f})")
    files = write_outputs(plan, args.outdir, figures=not args.no_figures, progress=True,
                          exports=("cola2", "qgc", "geojson"), origin_lonlat=CALDERA_ORIGIN_LONLAT,
                          metrics_3d=m3d, reference_table=True)
    print(f"wrote {len(files)} files to {args.outdir}")


if __name__ == "__main__":
    main()
