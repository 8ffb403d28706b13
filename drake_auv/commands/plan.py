"""`drake-auv plan`: plan a 3D coverage path on a bathymetric map and compare it with a lawnmower.

    drake-auv plan map.tif -o out/                         whole grid, Omega = 2 m
    drake-auv plan map.tif --roi 500,200,600,450 --omega 2 --aperture 60 -o out/
    drake-auv plan map.tif --export cola2,qgc,geojson -o out/   missions a vehicle runs
    drake-auv plan caldera -o out/                         the synthetic caldera-rim site

Writes path.csv (world frame), report.md and report.json (mission time, the comparison with a
lawnmower, each vehicle file's violations), PNG figures (in the grid's CRS) and the --export
formats (default geojson when the grid is georeferenced): mission.xml (COLA2), mission.plan
(QGroundControl, ArduSub; mission_1.plan, ... past --max-items, uploaded in that order),
path.geojson (the route and the vehicle files' waypoints) and lawnmower.geojson (WGS 84) into
the output folder. Prints the comparison, the mission time, the upload order of split QGC files
and one warning line per violation of a vehicle file.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from drake_auv.commands import check_plan_options, option_range, whole_number
from drake_auv.params import checks, defaults
from drake_auv.planning.parameters import CoverageParameters


def _order(text: str) -> str:
    """An IHO S-44 order's name in any case (`planning.orders.ORDERS` keys are lower case)."""
    return text.strip().lower()


# The options that set `CoverageParameters`: (option, field, help with {allowed} and {default}
# filled in from the field, argparse keywords).
PARAMETER_OPTIONS = (
    ("--omega", "omega", "offset to the terrain, {allowed} (default {default:g})",
     {"type": float}),
    ("--slope-threshold", "slope_threshold", "delta_s, slope above which terrain is "
     "high-slope, {allowed} (default {default:g})", {"type": float}),
    ("--aperture", "aperture_deg", "sensor aperture, {allowed} (default {default:g})",
     {"type": float}),
    ("--overlap", "overlap", "overlap of neighbouring lanes, {allowed} (default {default:g})",
     {"type": float}),
    ("--sweep-angle", "sweep_angle_deg", "lane direction, degrees from +x (default: fewest "
     "lanes)", {"type": float}),
    ("--slice-spacing", "slice_spacing", "vertical spacing of the slicing planes, {allowed} "
     "(default: footprint)", {"type": float}),
    ("--slice-count", "slice_count", "slicing planes per high-slope region, centred on it, "
     "{allowed} (default: as many as cover it)", {"type": whole_number}),
    ("--slice-sensor", "slice_sensor", "on high-slope regions look along the inward normal "
     "(default) or with one fixed tilt per region",
     {"choices": checks(CoverageParameters)["slice_sensor"].choices}),
    ("--order", "order", "IHO S-44 ed. 6 survey order: exclusive (200 %% coverage), special, "
     "1a (100 %%), 1b, 2 (5 %%); sets the lane spacing", {"type": _order}),
    ("--min-area", "min_area", "smallest high-slope region kept, {allowed} (default 100 m^2, at "
     "least 4 cells; it does not grow with the ROI)", {"type": float}),
    ("--min-depth", "min_depth", "minimum operating depth, {allowed}: no sample above it, "
     "shallower cells are no-go (default {default:g})", {"type": float}))
OPTIONS = {field: option for option, field, _, _ in PARAMETER_OPTIONS}  # by field


def _lonlat(text: str) -> tuple[float, float]:
    try:
        lon, lat = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--origin-lonlat: expected 'LON,LAT' in degrees, got {text!r}") from None
    return lon, lat


def add_parser(subparsers) -> None:
    from drake_auv.formats.registry import export_help

    parser = subparsers.add_parser("plan", help="plan a 3D coverage path on a bathymetric map",
                                   description=__doc__.split("\n")[0])
    parser.add_argument("bathymetry",
                        help="GeoTIFF, ESRI ASCII (.asc), XYZ grid, netCDF/GMT (.nc, .grd), BAG, "
                             ".npz (z, spacing, origin), or 'caldera' for the synthetic site")
    parser.add_argument("--roi", help="region of interest in map coordinates: "
                                      "'xmin,ymin,xmax,ymax' or a polygon 'x1,y1;x2,y2;x3,y3;...' "
                                      "(write --roi=-123,... when it starts with a minus sign)")
    parser.add_argument("--roi-file", help="region of interest as polygons (holes allowed) in a "
                                           "GeoJSON, Shapefile or GeoPackage, any CRS")
    parser.add_argument("--no-go", action="append", default=[], metavar="FILE",
                        help="no-go zones (polygons: GeoJSON, Shapefile, GeoPackage, any CRS); "
                             "nothing comes within Omega of them; repeatable")
    for option, field, text, kwargs in PARAMETER_OPTIONS:
        default = defaults(CoverageParameters)[field]
        allowed = option_range(checks(CoverageParameters)[field])
        if "choices" not in kwargs:
            kwargs = {**kwargs, "metavar": option.lstrip("-").upper().replace("-", "_")}
        parser.add_argument(option, dest=field, default=default, **kwargs, help=text.format(
            allowed=f"in {allowed}" if allowed[:1] in "[(" else allowed, default=default))
    parser.add_argument("--export", default=None, help=export_help())
    parser.add_argument("--origin-lonlat", default=None,
                        help="WGS 84 'LON,LAT' of the world origin, for grids without a CRS "
                             "(the caldera site defaults to the Santorini caldera)")
    parser.add_argument("--heave-in-3d", action="store_true",
                        help="COLA2 vehicle configured with heave_in_3D (depth interpolated "
                             "along each section): write the sections it flies that way")
    parser.add_argument("--speed", type=float, default=0.5,
                        help="mission surge speed, m/s, in [0.05, 1.4] (default 0.5)")
    parser.add_argument("--max-items", type=whole_number, default=700,
                        help="QGC/ArduSub: mission items a board stores per file, home and "
                             "DO_CHANGE_SPEED included, >= 4; longer missions are split into "
                             "mission_1.plan, mission_2.plan, ... (default 700)")
    parser.add_argument("--ardusub-frames", choices=("terrain", "depth"), default="terrain",
                        help="QGC/ArduSub: terrain = frame 10 (altitude, needs a downward "
                             "rangefinder and ArduSub 4.5+) on lanes, depth = frame 3 "
                             "everywhere from the prior map (default terrain)")
    parser.add_argument("--current", default=None, metavar="SPEED,TOWARDS_DEG",
                        help="a mean current (m/s, degrees clockwise from north it flows "
                             "towards): the report gains the ground speed and thrust per lane "
                             "and contour against the vehicle's limits, warnings and the "
                             "duration at ground speed")
    parser.add_argument("--tide", type=float, default=None, metavar="AMPLITUDE",
                        help="with --current: a tide flooding and ebbing along its axis, up to "
                             "AMPLITUDE m/s; the worst case is reported too")
    parser.add_argument("--align-with-current", action="store_true",
                        help="with --current: lanes along the current (sets the sweep angle)")
    parser.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    parser.add_argument("--reference-table", action="store_true",
                        help="add the reference's Table 3 (the Santorini caldera ROI) to the "
                             "reports, to compare with `plan caldera`")
    parser.add_argument("--no-3d-metrics", action="store_true",
                        help="skip the occluded 3D metrics on the grid's mesh (seconds on large "
                             "grids)")
    parser.add_argument("-o", "--out", "--outdir", dest="out", required=True,
                        help="output folder (--outdir is its older spelling)")
    parser.set_defaults(func=run, batch_process=True)  # when run as the program


def run(args) -> int:
    import numpy as np

    from drake_auv.commands.outputs import MiB, output_folder

    output_folder(args.out, "-o", 20 * MiB)  # path.csv, reports, figures, exports
    check_plan_options([(option, getattr(args, field), field) for field, option in OPTIONS.items()]
                       + [("--speed", args.speed, "speed")])
    from drake_auv.planning.coverage_plan import plan_coverage
    from drake_auv.formats import ExportOptions
    from drake_auv.formats.outputs import write_outputs
    from drake_auv.formats.registry import (check_exports, export_notes, export_warnings,
                                            parse_exports)
    from drake_auv.planning.metrics import PlanMetrics
    from drake_auv.planning.report import mission_time_line, table3_markdown
    from drake_auv.progress import PLAN_PHASES, RunProgress
    from drake_auv.terrain.roi import parse_roi

    exports = parse_exports(args.export) if args.export is not None else None
    current = None
    if args.current is not None:
        from drake_auv.vehicle.current_feasibility import aligned_sweep_angle, parse_current

        current = parse_current(args.current, args.tide)
        if args.align_with_current and args.sweep_angle_deg is not None:
            raise ValueError("give --sweep-angle or --align-with-current, not both")
        if args.align_with_current:
            args.sweep_angle_deg = aligned_sweep_angle(current)
    elif args.tide is not None or args.align_with_current:
        raise ValueError("--tide and --align-with-current need --current SPEED,TOWARDS_DEG")
    origin = _lonlat(args.origin_lonlat) if args.origin_lonlat is not None else None
    if args.bathymetry == "caldera" and not Path("caldera").exists():
        from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT
        from drake_auv.terrain.synthetic import caldera_site

        bathy = caldera_site()
        origin = CALDERA_ORIGIN_LONLAT if origin is None else origin
    else:
        from drake_auv.terrain.readers import read_bathymetry

        bathy = read_bathymetry(args.bathymetry)
        if origin is not None and bathy.crs is not None:
            raise ValueError(f"--origin-lonlat: {args.bathymetry} is georeferenced ({bathy.crs}"
                             "), which places it; the option is for grids without a CRS")
        no_data = int(np.isnan(bathy.z).sum())
        if no_data:  # stated, never silent
            print(f"{args.bathymetry}: {no_data} of {bathy.z.size} cells are no-data (its nodata "
                  "value, mask or NaN): no-go for coverage")
    exports, _ = check_exports(bathy, exports, origin, ExportOptions(
        max_items=args.max_items, ardusub_frames=args.ardusub_frames))  # before planning
    if args.roi and args.roi_file:
        raise ValueError("give --roi or --roi-file, not both")
    roi = parse_roi(args.roi) if args.roi else None
    no_go = None
    if args.roi_file or args.no_go:
        import shapely

        from drake_auv.terrain.zones import read_zones

        if args.roi_file:
            roi = read_zones(args.roi_file, bathy, "region of interest")
        if args.no_go:
            no_go = shapely.union_all([read_zones(f, bathy) for f in args.no_go])
    with RunProgress(PLAN_PHASES) as progress:  # one display, to the last file
        params = CoverageParameters(**{field: getattr(args, field) for field in OPTIONS})
        plan = plan_coverage(bathy, params, roi=roi, no_go=no_go, compute_metrics=False,
                             progress=progress)  # the grid metrics beside the outputs
        flow = None
        if current is not None:
            from drake_auv.vehicle.current_feasibility import current_report

            flow = current_report(plan.path, current, args.speed)
        files = write_outputs(plan, args.out, figures=not args.no_figures, progress=progress,
                              exports=exports, origin_lonlat=origin, surge_velocity=args.speed,
                              metrics_3d=not args.no_3d_metrics, max_items=args.max_items,
                              ardusub_frames=args.ardusub_frames, heave_in_3d=args.heave_in_3d,
                              reference_table=args.reference_table, current=flow,
                              grid_metrics=True)
    report = json.loads((Path(args.out) / "report.json").read_text())
    print(table3_markdown(PlanMetrics.from_dict(report["metrics"])))
    print(mission_time_line(report["mission_time"]))
    if flow is not None:
        from drake_auv.vehicle.current_feasibility import summary_lines

        print("\n".join(summary_lines(flow, plan.parameters.sweep_angle_deg)))
    for note in export_notes(report):
        print(note)
    for warning in export_warnings(report):
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {len(files)} files to {args.out}")
    return 0
