"""Exports of a `CoveragePlan`: CSV (world frame), RFC 7946 GeoJSON (WGS 84), the COLA2 and
QGroundControl missions (`planning.missions`, `planning.qgc`), and the Table 3 report.

GeoJSON: the route as one 2D LineString and the waypoints of the vehicle files as Points,
[lon, lat] through pyproj from the grid's CRS (no `crs` member: RFC 7946 is WGS 84), depths and
altitudes as properties (`path_to_geojson`). The reports give the mission time, each vehicle
file's violations as warnings (`export_warnings`) and the QGroundControl files' upload order.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_auv.output_files import write_json, write_text
from drake_auv.terrain.geo import GeoFrame
from drake_auv.planning.missions import douglas_peucker
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.stages import next_stage, stage_bar

# The reference's Table 3 (Santorini caldera ROI, Omega = 2 m, 60 degree camera).
REFERENCE_TABLE3 = {
    "high_slope": {"length": 5864.9, "view_mean_deg": 9.3, "view_sd_deg": 4.5},
    "planar": {"length": 4973.6, "view_mean_deg": 12.3, "view_sd_deg": 6.6},
    "total": {"length": 10838.5, "view_mean_deg": 10.8, "view_sd_deg": 5.6},
    "lawnmower": {"length": 9834.2, "view_mean_deg": 23.2, "view_sd_deg": 7.1},
}


ROUTE_TOLERANCE = 0.05  # m: the route's vertices, thinned below the 6 decimals (~0.1 m) kept
ROUTE_PIECE = 2048  # samples thinned at a time: time linear in the path's length


def _waypoint_features(mission, geo: GeoFrame, surface) -> list[dict]:
    """Point features of a `VehicleMission`'s items (see `path_to_geojson`)."""
    lonlat = np.array([[it.lon, it.lat] for it in mission.items], float)
    seabed = None
    if surface is not None:
        xy = geo.from_lonlat(lonlat)
        seabed = surface.elevation(xy[:, 0], xy[:, 1])
    features = []
    for k, it in enumerate(mission.items):
        held = round(float(it.z), 3)
        if it.z_mode == "depth":
            depth, alt = held, None if seabed is None else round(float(-it.z - seabed[k]), 3)
        else:
            depth, alt = None if seabed is None else round(float(-(seabed[k] + it.z)), 3), held
        props = {"kind": "waypoint", "file": Path(mission.source).name, "seq": k + 1,
                 "item": it.kind, "heave": it.z_mode, "depth": depth, "alt": alt}
        if it.yaw is not None:
            props["yaw_deg"] = round(float(np.degrees(it.yaw)) % 360.0, 2)
        features.append({"type": "Feature", "properties": props,
                         "geometry": {"type": "Point",
                                      "coordinates": np.round(lonlat[k], 6).tolist()}})
    return features


def path_to_geojson(path: PlannedPath, geo: GeoFrame, name: str = "path", missions=(),
                    surface=None) -> dict:
    """A FeatureCollection (RFC 7946, WGS 84) of the route and the waypoints of the vehicle
    missions written with it, property names of at most 10 characters (Shapefile-safe).

    First the route: one 2D LineString [[lon, lat], ...] (degrees, 6 decimals) through the
    path's samples, those within `ROUTE_TOLERANCE` of the line thinned out (Douglas-Peucker in
    xy, `ROUTE_PIECE` samples at a time); properties `kind` "route", `name`, `samples`,
    `length_m` (3D), `depth_min`, `depth_max` (m below the sea surface). Then one Point per item of each of `missions`
    (`VehicleMission`s read back from the files, in the order flown): `kind` "waypoint",
    `file` (its file name), `seq` (1-based order in the file), `item` (waypoint, goto, section
    or park), `heave` (what the autopilot holds: "altitude" or "depth"), `depth` (m below the
    sea surface), `alt` (m above the prior seabed; the one not held needs `surface`, else null),
    `yaw_deg` (commanded heading, degrees clockwise from true north; absent where the autopilot
    chooses it). RFC 7946's third coordinate is a height above the WGS 84 ellipsoid, and the
    vehicle's vertical references are depths and altitudes, so they are properties."""
    pts = path.points
    keep = (douglas_peucker(pts[:, :2], ROUTE_TOLERANCE, ROUTE_PIECE) if len(path) > 1
            else np.zeros(2, int))
    lonlat = np.round(geo.to_lonlat(pts[keep, :2]), 6)  # RFC 7946 section 11.2: about 0.1 m
    route = {"type": "Feature",
             "properties": {"kind": "route", "name": name, "samples": len(path),
                            "length_m": round(float(path.length), 3),
                            "depth_min": round(float(-pts[:, 2].max()), 3),
                            "depth_max": round(float(-pts[:, 2].min()), 3)},
             "geometry": {"type": "LineString", "coordinates": lonlat.tolist()}}
    features = [route]
    for mission in missions:
        features += _waypoint_features(mission, geo, surface)
    return {"type": "FeatureCollection", "name": name, "features": features}


def write_geojson(path: PlannedPath, geo: GeoFrame, filename, name: str = "path", missions=(),
                  surface=None) -> None:
    write_json(filename, path_to_geojson(path, geo, name, missions, surface), indent=None,
               separators=(",", ":"))


def _ratio(a: float, b: float) -> float | None:
    """a / b, None (JSON null) when it is undefined (b zero or either not finite)."""
    return float(a / b) if np.isfinite(a) and np.isfinite(b) and b != 0 else None


def _depth_limited(path: PlannedPath, plan) -> dict:
    """Samples held at the minimum operating depth with less than Omega of altitude."""
    p = plan.parameters
    ceiling = -p.min_depth
    alt = path.points[:, 2] - plan.surface.elevation(path.points[:, 0], path.points[:, 1])
    held = (path.points[:, 2] >= ceiling - 1e-9) & (alt < p.omega - 1e-6)
    return {"samples_share": float(held.mean()),
            "length_m": float(path.segment_lengths()[held[1:]].sum()),
            "least_altitude_m": float(alt[held].min()) if held.any() else None}


def water_column_summary(plan) -> dict:
    """The minimum operating depth and how much of each path it holds shallower than Omega
    above the seabed (the coverage those parts lose shows in the metrics)."""
    out = {"min_depth_m": plan.parameters.min_depth,
           "path_depth_limited": _depth_limited(plan.path, plan)}
    if plan.lawnmower is not None:
        out["lawnmower_depth_limited"] = _depth_limited(plan.lawnmower, plan)
    return out


def _water_column_line(wc: dict) -> str:
    d = wc["path_depth_limited"]
    line = (f"Water column: minimum operating depth {wc['min_depth_m']:g} m; "
            f"{100 * d['samples_share']:.1f} % of the path's samples ({d['length_m']:.1f} m) "
            "run at that depth with less than Omega above the seabed")
    if d["least_altitude_m"] is not None:
        line += f" (down to {d['least_altitude_m']:.2f} m), so they see a smaller footprint"
    return line + "."


def _order(plan) -> dict | None:
    if plan.parameters.order is None:
        return None
    from drake_auv.planning.orders import order_report, survey_order

    return order_report(plan, survey_order(plan.parameters.order))


def _order_line(o: dict | None) -> str:
    if o is None:
        return "Survey order: none asked for (lanes one footprint apart, 100 % nominal)."
    req = ("no feature detection required" if o["required_feature_m"] is None else
           f"the order asks for {o['required_feature_m']:.2f} m "
           f"({'met' if o['meets_feature_detection'] else 'NOT met'})")
    return (f"Survey order: IHO S-44 {o['order']}, coverage target {o['coverage_target_percent']:g} % "
            f"(lanes {o['lane_spacing_m']:.2f} m apart); achieved {o['achieved_percent']:.1f} % of "
            f"the area seen by at least {o['passes_needed']} pass(es), "
            f"{o['mean_passes_per_cell']:.2f} passes per cell on average; the footprint supports "
            f"features of {o['detectable_feature_m']:.2f} m and larger (largest gap "
            f"{o['largest_gap_m']:.2f} m, sounding resolution {o['sounding_resolution_m']:.2f} m); "
            f"{req}.")


def _ratios_line(r: dict) -> str:
    """The defined ratios of path to lawnmower (undefined ones, a zero or NaN term, left out)."""
    parts = [f"{name}: {r[key]:.2f}" for key, name in (
        ("length_total_over_lawnmower", "length ratio (total / lawnmower)"),
        ("view_total_over_lawnmower", "viewing angle ratio")) if r[key] is not None]
    text = "; ".join(parts)
    return text[:1].upper() + text[1:] + "." if parts else ""


def human_duration(seconds: float) -> str:
    """'42 s', '12.5 min' or '36.6 h'."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"


def mission_time(plan, speed: float) -> dict:
    """Time to fly the path (and the lawnmower) at `speed` (m/s) along its 3D length, in still
    water: `speed_m_s`, `length_m`, `duration_s`, `duration` (human), and the lawnmower's
    `lawnmower_length_m`, `lawnmower_duration_s`, `lawnmower_duration`."""
    if not (np.isfinite(speed) and speed > 0):
        raise ValueError(f"speed (--speed) must be > 0 m/s, got {speed}")
    out = {"speed_m_s": float(speed), "length_m": float(plan.path.length),
           "duration_s": float(plan.path.length / speed)}
    out["duration"] = human_duration(out["duration_s"])
    if plan.lawnmower is not None:
        out["lawnmower_length_m"] = float(plan.lawnmower.length)
        out["lawnmower_duration_s"] = float(plan.lawnmower.length / speed)
        out["lawnmower_duration"] = human_duration(out["lawnmower_duration_s"])
    return out


def mission_time_line(t: dict) -> str:
    line = (f"Mission time: {t['duration']} for the {t['length_m'] / 1000:.2f} km path at "
            f"{t['speed_m_s']:g} m/s")
    if "lawnmower_duration" in t:
        line += (f" (the lawnmower: {t['lawnmower_length_m'] / 1000:.2f} km, "
                 f"{t['lawnmower_duration']})")
    return line + "."


def _replay_warnings(name: str, r: dict, omega: float, min_depth: float) -> list[str]:
    """The violations of one export's replay (`autopilot.replay.clearance_report`)."""
    out = []
    if r["closer_than_half_omega"]:
        cause = ("all where the minimum depth leaves no more" if not r["closer_than_reachable"]
                 else f"{r['closer_than_reachable']} of them where the minimum depth does not "
                      "force it")
        out.append(f"{name}: flown as its autopilot flies it, {r['closer_than_half_omega']} of "
                   f"{r['samples']} samples come nearer than Omega / 2 = {0.5 * omega:g} m to "
                   f"the prior seabed (least {r['min_clearance_m']:.2f} m); {cause}")
    if r["shallower_than_min_depth"]:
        out.append(f"{name}: flown as its autopilot flies it, {r['shallower_than_min_depth']} "
                   f"of {r['samples']} samples are shallower than the {min_depth:g} m minimum "
                   f"depth (shallowest {r['shallowest_depth_m']:.3f} m)")
    return out


def export_warnings(rep: dict) -> list[str]:
    """One line per violation the exports' figures in `rep` (a `report_dict`) record: COLA2
    sections beyond the deviation tolerance or unresolved, and replayed samples of either
    mission nearer than Omega / 2 to the prior seabed or above the minimum depth."""
    ex = rep.get("exports", {})
    p = rep["parameters"]
    out = []
    if "cola2" in ex:
        c, name = ex["cola2"], "mission.xml (COLA2)"
        if c["sections_over_deviation"]:
            out.append(f"{name}: {c['sections_over_deviation']} of {c['sections']} sections "
                       f"stray more than the {c['deviation_tolerance_m']:g} m deviation "
                       f"tolerance from the path (worst {c['max_deviation_m']:.2f} m)")
        if c["unresolved_sections"]:
            out.append(f"{name}: {c['unresolved_sections']} sections hold the lowest safe depth "
                       "(no target kept Omega / 2 from the seabed within the tolerance)")
        out += _replay_warnings(name, c["replay"], p["omega"], p["min_depth"])
    if "qgc" in ex:
        files = ex["qgc"]["files"]
        name = f"{files[0] if len(files) == 1 else files[0] + ' to ' + files[-1]} (ArduSub)"
        out += _replay_warnings(name, ex["qgc"]["clearance"], p["omega"], p["min_depth"])
    return out


def upload_line(rep: dict) -> str | None:
    """The QGroundControl files in upload order when the mission is split, else None."""
    q = rep.get("exports", {}).get("qgc")
    if q is None or len(q["files"]) == 1:
        return None
    order = ", then ".join(f"{f} ({n} items)" for f, n in zip(q["files"], q["items"]))
    return (f"QGroundControl: the mission is split into {len(q['files'])} files of at most "
            f"{q['max_items']} items; upload and fly them in this order: {order} (each starts "
            "at the previous one's last waypoint).")


def report_dict(plan, metrics_3d=None, speed: float = 0.5, reference_table: bool = False,
                exports: dict | None = None) -> dict:
    """Parameters, classification summary, mission time at `speed` (m/s), Table 3 metrics
    (grid and, if given, the occluded 3D ones of `planning.metrics3d`), water column, survey
    order, the `exports`' figures (see `write_outputs`) and, with `reference_table`, the
    reference's Table 3."""
    labels = plan.labels
    dx, dy = plan.bathy.spacing
    out = {
        "parameters": plan.parameter_record(),
        "grid": {"shape": list(plan.bathy.shape), "spacing_m": [dx, dy], "crs": plan.bathy.crs},
        "classification": {
            "high_slope_regions": labels.n_regions,
            "high_slope_share": float(labels.high.sum() / max(labels.valid.sum(), 1)),
            "slope_min": float(np.nanmin(labels.slope)), "slope_max": float(np.nanmax(labels.slope)),
        },
        "cells": len(plan.cells.cells),
        "contours": len(plan.contours),
        "visit_order": [f"{kind} {k}" for kind, k in plan.visit_order],
        "path_length_by_label": plan.path.length_by_label(),
        "mission_time": mission_time(plan, speed),
        "water_column": water_column_summary(plan),
        "survey_order": _order(plan),
    }
    if reference_table:
        out["reference_table3"] = REFERENCE_TABLE3
    if metrics_3d is not None:
        from drake_auv.planning.metrics3d import metrics3d_dict

        out["metrics_3d"] = metrics3d_dict(metrics_3d)
    if plan.metrics is not None:
        out["metrics"] = plan.metrics.to_dict()
        out["ratios"] = {
            "length_total_over_lawnmower": _ratio(plan.metrics.total.length,
                                                  plan.metrics.lawnmower.length),
            "view_total_over_lawnmower": _ratio(plan.metrics.total.view_mean_deg,
                                                plan.metrics.lawnmower.view_mean_deg),
        }
    if exports:
        out["exports"] = exports
    return out


def table3_markdown(metrics) -> str:
    """The Table 3 comparison as a Markdown table; a region without samples (no high-slope
    terrain, say) is left out."""
    lines = ["| path | length (m) | viewing angle (deg) | coverage | min clearance (m) |",
             "| --- | ---: | ---: | ---: | ---: |"]
    for name, m in metrics.rows():
        if m.samples == 0:
            continue
        lines.append(f"| {name} | {m.length:.1f} | {m.view_mean_deg:.1f} (sd {m.view_sd_deg:.1f}) "
                     f"| {100 * m.coverage:.1f} % | {m.min_clearance:.2f} |")
    return "\n".join(lines)


def report_markdown(plan, metrics_3d=None, speed: float = 0.5, reference_table: bool = False,
                    exports: dict | None = None) -> str:
    """A human-readable report: mission time, the exports' warnings and upload order,
    parameters, classification, Table 3 (grid, and the occluded 3D metrics if given) and, with
    `reference_table`, the reference's values."""
    return _markdown(plan, metrics_3d, report_dict(plan, metrics_3d, speed, reference_table,
                                                   exports))


def _markdown(plan, metrics_3d, rep: dict) -> str:
    p = rep["parameters"]
    lines = ["# Coverage plan report", "", mission_time_line(rep["mission_time"]), ""]
    warnings = export_warnings(rep)
    if warnings:
        lines += ["## Warnings", "", *(f"- {w}" for w in warnings), ""]
    upload = upload_line(rep)
    if upload is not None:
        lines += [upload, ""]
    lines += [f"Offset Omega = {p['omega']} m, aperture {p['aperture_deg']} deg, overlap "
              f"{p['overlap']}, slope threshold {p['slope_threshold']}, lane spacing "
              f"{p['lane_spacing']:.2f} m, sweep angle {p['sweep_angle_deg']:.1f} deg.", "",
              f"Grid {rep['grid']['shape'][1]} x {rep['grid']['shape'][0]} cells of "
              f"{rep['grid']['spacing_m'][0]:.2f} m x {rep['grid']['spacing_m'][1]:.2f} m, "
              f"CRS {rep['grid']['crs']}.", "",
              f"Classification: {rep['classification']['high_slope_regions']} high-slope "
              f"region(s) covering {100 * rep['classification']['high_slope_share']:.1f} % of "
              f"the valid area; slope {rep['classification']['slope_min']:.3f} to "
              f"{rep['classification']['slope_max']:.3f}. Planar area: {rep['cells']} "
              f"boustrophedon cells. High-slope area: {rep['contours']} contour pieces.", "",
              _water_column_line(rep["water_column"]), "", _order_line(rep["survey_order"]), ""]
    if plan.metrics is not None:
        r = rep["ratios"]
        lines += ["## Comparison with a standard lawnmower (Table 3, on the grid: cone test, no "
                  "occlusion)", "",
                  table3_markdown(plan.metrics), "", _ratios_line(r), ""]
    if metrics_3d is not None:
        from drake_auv.planning.metrics3d import table3d_markdown

        lines += ["## The same on the 3D mesh, with occlusion", "",
                  "Viewing angle of each sample's axis at its first hit on the grid's triangle "
                  "mesh; coverage: faces inside the aperture cone, in range, facing the sensor "
                  "and not occluded. On high-slope regions both sensor models: the planned one "
                  "and the reference's forward-looking sensor at one fixed tilt per region.", "",
                  table3d_markdown(metrics_3d), ""]
    if "reference_table3" in rep:
        ref = rep["reference_table3"]
        lines += ["## The reference's Table 3 (Santorini caldera ROI)", "",
                  "| path | length (m) | viewing angle (deg) |", "| --- | ---: | ---: |"]
        for key, name in (("high_slope", "High-slope region"), ("planar", "Planar region"),
                          ("total", "Total (both regions)"),
                          ("lawnmower", "Standard lawnmower path")):
            lines.append(f"| {name} | {ref[key]['length']:.1f} | "
                         f"{ref[key]['view_mean_deg']:.1f} (sd {ref[key]['view_sd_deg']:.1f}) |")
    return "\n".join(lines) + "\n"


EXPORTS = {"cola2": "mission.xml", "qgc": "mission.plan", "geojson": "path.geojson"}


def parse_exports(text: str | None) -> tuple[str, ...]:
    """'cola2,qgc,geojson' -> ('cola2', 'qgc', 'geojson'); ValueError naming an unknown one."""
    if not text:
        return ()
    names = tuple(dict.fromkeys(t.strip().lower() for t in text.split(",") if t.strip()))
    bad = [n for n in names if n not in EXPORTS]
    if bad:
        raise ValueError(f"--export: unknown format {bad[0]!r}; choose from "
                         f"{', '.join(EXPORTS)} (comma-separated)")
    return names


def check_exports(bathy, exports=None, origin_lonlat=None, max_items: int = 700,
                  ardusub_frames: str = "terrain") -> tuple[tuple[str, ...], GeoFrame | None]:
    """The exports of `write_outputs` (None: "geojson" when `bathy` is georeferenced or
    `origin_lonlat` given) and the `GeoFrame` of the exports and figures (None for a grid
    with neither), every option checked (ValueError naming the
    first bad one). Cheap, so a command checks them before it plans."""
    georeferenced = bathy.crs is not None or origin_lonlat is not None
    if exports is None:
        exports = ("geojson",) if georeferenced else ()
    for name in exports:
        if name not in EXPORTS:
            raise ValueError(f"unknown export {name!r}; choose from {', '.join(EXPORTS)}")
    if "qgc" in exports:
        from drake_auv.planning.qgc import check_options

        check_options(max_items, ardusub_frames)
    return tuple(exports), GeoFrame(bathy, origin_lonlat) if exports or georeferenced else None


def output_stages(exports: tuple[str, ...], figures: bool = True, metrics_3d=True) -> int:
    """The stages `write_outputs` counts on a progress bar: path.csv, each export, the 3D
    metrics (when computed), the reports and each figure."""
    from drake_auv.planning.figures import PLAN_VIEWS, VIEWS_3D

    return (2 + len(exports) + (metrics_3d is True)
            + (len(PLAN_VIEWS) + len(VIEWS_3D) if figures else 0))


def write_outputs(plan, outdir, figures: bool = True, progress=False,
                  exports: tuple[str, ...] | None = None, origin_lonlat=None,
                  surge_velocity: float = 0.5, tolerance_xy: float = 1.0,
                  metrics_3d=True, max_items: int = 700, ardusub_frames: str = "terrain",
                  heave_in_3d: bool = False, reference_table: bool = False,
                  current: dict | None = None) -> list[Path]:
    """Writes path.csv (world frame), report.md, report.json, the `exports` and (with
    `figures`) the PNG figures into `outdir`; returns the files written.

    Args:
        progress: a progress bar over the `output_stages`, or a caller's tqdm bar to advance
            by them (`planning.stages`: one display that ends when the last file is written).
        exports: any of "cola2" (mission.xml), "qgc" (mission.plan, or mission_1.plan, ...
            past `max_items`; report.json gains exports.qgc), "geojson" (path.geojson: the
            route and the waypoints of the vehicle files written with it; lawnmower.geojson;
            WGS 84); None: "geojson" when the grid is georeferenced (a CRS or
            `origin_lonlat`), else none.
        origin_lonlat: WGS 84 (lon, lat) of the world origin, for grids without a CRS.
        surge_velocity: mission speed, m/s (> 0; also the report's mission time);
            tolerance_xy: waypoint arrival tolerance, m.
        max_items, ardusub_frames: the QGC mission's items per file and ArduSub frames
            ("terrain" or "depth"), see `planning.qgc.write_qgc`.
        metrics_3d: add the occluded 3D metrics (`planning.metrics3d`) to the report: True
            computes them, a dict of `evaluate_plan_3d` is used as it is, False skips them.
        heave_in_3d: the COLA2 vehicle interpolates depth along sections (its heave_in_3D);
            the report's `exports.cola2` gives the sections and their replay's figures.
        reference_table: add the reference's Table 3 (the Santorini caldera) to the reports.
        current: `planning.current.current_report` of the path, added to report.json
            (`current`) and report.md.
    """
    exports, geo = check_exports(plan.bathy, exports, origin_lonlat, max_items, ardusub_frames)
    mission_time(plan, surge_velocity)  # the speed, checked before any file is written
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written, extras, missions = [], {}, []
    bar, owned = stage_bar(progress, output_stages(exports, figures, metrics_3d), "outputs")
    bar.set_postfix_str("path.csv")
    plan.path.to_csv(outdir / "path.csv")
    written.append(outdir / "path.csv")
    if "cola2" in exports:
        from drake_auv.planning.cola2 import export_cola2, read_cola2

        next_stage(bar, "mission.xml")
        extras["cola2"] = export_cola2(plan.path, plan.surface, plan.parameters.omega,
                                       plan.parameters.min_depth, geo, outdir / "mission.xml",
                                       surge_velocity, tolerance_xy, heave_in_3d)
        written.append(outdir / "mission.xml")
        missions.append(read_cola2(outdir / "mission.xml"))
    if "qgc" in exports:
        from drake_auv.planning.qgc import read_qgc_plan, write_qgc

        next_stage(bar, "mission.plan")
        files, extras["qgc"] = write_qgc(plan, geo, outdir, max_items=max_items,
                                         frames=ardusub_frames, speed=surge_velocity,
                                         acceptance_radius=tolerance_xy)
        written += files
        missions += [read_qgc_plan(f) for f in files]
    if "geojson" in exports:
        next_stage(bar, "GeoJSON")
        write_geojson(plan.path, geo, outdir / "path.geojson", "coverage path", missions,
                      plan.surface)
        written.append(outdir / "path.geojson")
        if plan.lawnmower is not None:
            write_geojson(plan.lawnmower, geo, outdir / "lawnmower.geojson", "lawnmower")
            written.append(outdir / "lawnmower.geojson")
    m3d = metrics_3d if isinstance(metrics_3d, dict) else None
    if metrics_3d is True:
        from drake_auv.planning.metrics3d import evaluate_plan_3d

        next_stage(bar, "3D metrics")
        m3d = evaluate_plan_3d(plan)
    next_stage(bar, "reports")
    rep = report_dict(plan, m3d, surge_velocity, reference_table, extras)
    markdown = _markdown(plan, m3d, rep)
    if current is not None:
        from drake_auv.vehicle.current_feasibility import current_markdown

        markdown = markdown.rstrip("\n") + "\n\n" + current_markdown(current)
        rep["current"] = current
    write_text(outdir / "report.md", markdown)
    write_json(outdir / "report.json", rep)
    written += [outdir / "report.md", outdir / "report.json"]
    next_stage(bar)
    if figures:
        from drake_auv.planning.figures import write_figures

        written += write_figures(plan, outdir, progress=bar, geo=geo)
    if owned:
        bar.close()
    return written
