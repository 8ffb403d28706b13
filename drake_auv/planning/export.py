"""Exports of a `CoveragePlan`: CSV (world frame), RFC 7946 GeoJSON (WGS 84), the COLA2 and
QGroundControl missions (`planning.missions`, `planning.qgc`), and the Table 3 report.

GeoJSON: one 2D LineString feature per path segment, [lon, lat] through pyproj from the grid's
CRS (no `crs` member: RFC 7946 is WGS 84), depths and altitudes as properties
(`path_to_geojson`).
"""

from __future__ import annotations

from pathlib import Path as FilePath

import numpy as np

from drake_auv.output_files import write_json, write_text
from drake_auv.planning.geo import GeoFrame
from drake_auv.planning.missions import ALTITUDE_LABELS
from drake_auv.planning.path import Path

# The reference's Table 3 (Santorini caldera ROI, Omega = 2 m, 60 degree camera).
REFERENCE_TABLE3 = {
    "high_slope": {"length": 5864.9, "view_mean_deg": 9.3, "view_sd_deg": 4.5},
    "planar": {"length": 4973.6, "view_mean_deg": 12.3, "view_sd_deg": 6.6},
    "total": {"length": 10838.5, "view_mean_deg": 10.8, "view_sd_deg": 5.6},
    "lawnmower": {"length": 9834.2, "view_mean_deg": 23.2, "view_sd_deg": 7.1},
}


def path_to_geojson(path: Path, geo: GeoFrame, name: str = "path", surface=None) -> dict:
    """A FeatureCollection (RFC 7946) of the path's segments in WGS 84, Shapefile-safe.

    One 2D LineString [[lon, lat], [lon, lat]] (degrees, 6 decimals) per segment between
    consecutive samples: RFC 7946's third coordinate is a height above the WGS 84 ellipsoid,
    and the path's vertical references are depths below mean sea level and altitudes above the
    seabed, so they are properties. Properties (scalars, names of at most 10 characters, as a Shapefile's DBF
    takes them), a segment taking its end sample's label like `Path.length_by_label`:
    `label`; `run` (index of the run of one label); `seq` (segment index); `heave`
    ("altitude" on lanes, "depth" elsewhere); `depth_a`, `depth_b` (m below the sea surface at
    the segment's start and end); `alt_a`, `alt_b` (m above the prior seabed, with `surface`;
    else absent); `length_m` (3D); `sens_az`, `sens_dep` (the sensor axis at the end sample:
    azimuth, degrees clockwise from true north, and depression, degrees below the horizontal;
    90 looks straight down). A single-sample path gives one zero-length segment."""
    pts = path.points
    lonlat = np.round(geo.to_lonlat(pts[:, :2]), 6)  # RFC 7946 section 11.2: about 0.1 m
    s = path.sensor_dir
    azimuth = np.degrees(np.mod(np.arctan2(s[:, 0], s[:, 1])
                                + geo.grid_north_azimuth(pts[:, :2]), 2 * np.pi))
    depression = np.degrees(np.arcsin(np.clip(-s[:, 2], -1.0, 1.0)))
    labels = path.labels.astype(str)
    a = np.arange(max(len(path) - 1, 1))
    b = np.minimum(a + 1, len(path) - 1)
    run = np.concatenate([[0], np.cumsum(labels[1:] != labels[:-1])])
    depth = np.round(-pts[:, 2], 3)
    length = np.round(np.linalg.norm(pts[b] - pts[a], axis=1), 3)
    alt = (None if surface is None else
           np.round(pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1]), 3))
    heave = np.where(np.isin(labels, ALTITUDE_LABELS), "altitude", "depth")
    features = []
    for k, (i, j) in enumerate(zip(a.tolist(), b.tolist())):
        props = {"label": labels[j], "run": int(run[j]), "seq": k, "heave": str(heave[j]),
                 "depth_a": float(depth[i]), "depth_b": float(depth[j])}
        if alt is not None:
            props.update(alt_a=float(alt[i]), alt_b=float(alt[j]))
        props.update(length_m=float(length[k]), sens_az=round(float(azimuth[j]), 2),
                     sens_dep=round(float(depression[j]), 2))
        features.append({"type": "Feature", "properties": props,
                         "geometry": {"type": "LineString",
                                      "coordinates": [lonlat[i].tolist(), lonlat[j].tolist()]}})
    return {"type": "FeatureCollection", "name": name, "features": features}


def write_geojson(path: Path, geo: GeoFrame, filename, name: str = "path", surface=None) -> None:
    write_json(filename, path_to_geojson(path, geo, name, surface), indent=None,
               separators=(",", ":"))


def _ratio(a: float, b: float) -> float | None:
    """a / b, None (JSON null) when it is undefined (b zero or either not finite)."""
    return float(a / b) if np.isfinite(a) and np.isfinite(b) and b != 0 else None


def _depth_limited(path: Path, plan) -> dict:
    """Samples held at the minimum operating depth with less than Omega of altitude."""
    p = plan.parameters
    ceiling = -p["min_depth"]
    alt = path.points[:, 2] - plan.surface.elevation(path.points[:, 0], path.points[:, 1])
    held = (path.points[:, 2] >= ceiling - 1e-9) & (alt < p["omega"] - 1e-6)
    return {"samples_share": float(held.mean()),
            "length_m": float(path.segment_lengths()[held[1:]].sum()),
            "least_altitude_m": float(alt[held].min()) if held.any() else None}


def water_column_summary(plan) -> dict:
    """The minimum operating depth and how much of each path it holds shallower than Omega
    above the seabed (the coverage those parts lose shows in the metrics)."""
    out = {"min_depth_m": plan.parameters["min_depth"],
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
    if plan.parameters.get("order") is None:
        return None
    from drake_auv.planning.orders import order_report, survey_order

    return order_report(plan, survey_order(plan.parameters["order"]))


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


def _fmt(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.2f}"


def report_dict(plan, metrics_3d=None) -> dict:
    """Parameters, classification summary, Table 3 metrics (grid and, if given, the occluded
    3D ones of `planning.metrics3d`), water column, survey order and the reference's Table 3."""
    labels = plan.labels
    dx, dy = plan.bathy.spacing
    out = {
        "parameters": plan.parameters,
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
        "water_column": water_column_summary(plan),
        "survey_order": _order(plan),
        "reference_table3": REFERENCE_TABLE3,
    }
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
    return out


def table3_markdown(metrics) -> str:
    """The Table 3 comparison as a Markdown table."""
    lines = ["| path | length (m) | viewing angle (deg) | coverage | min clearance (m) |",
             "| --- | ---: | ---: | ---: | ---: |"]
    for name, m in metrics.rows():
        lines.append(f"| {name} | {m.length:.1f} | {m.view_mean_deg:.1f} (sd {m.view_sd_deg:.1f}) "
                     f"| {100 * m.coverage:.1f} % | {m.min_clearance:.2f} |")
    return "\n".join(lines)


def report_markdown(plan, metrics_3d=None) -> str:
    """A human-readable report: parameters, classification, Table 3 (grid, and the occluded 3D
    metrics if given), the reference's values."""
    rep = report_dict(plan, metrics_3d)
    p = plan.parameters
    lines = ["# Coverage plan report", "",
             f"Offset Omega = {p['omega']} m, aperture {p['aperture_deg']} deg, overlap "
             f"{p['overlap']}, slope threshold {p['slope_threshold']}, lane spacing "
             f"{p['lane_spacing']:.2f} m, sweep angle {p['sweep_angle_deg']:.1f} deg.", "",
             f"Grid {rep['grid']['shape'][1]} x {rep['grid']['shape'][0]} cells of "
             f"{rep['grid']['spacing_m'][0]:.2f} m x {rep['grid']['spacing_m'][1]:.2f} m, "
             f"CRS {rep['grid']['crs']}.", "",
             f"Classification: {rep['classification']['high_slope_regions']} high-slope region(s) "
             f"covering {100 * rep['classification']['high_slope_share']:.1f} % of the valid area; "
             f"slope {rep['classification']['slope_min']:.3f} to "
             f"{rep['classification']['slope_max']:.3f}. Planar area: {rep['cells']} boustrophedon "
             f"cells. High-slope area: {rep['contours']} contour pieces.", "",
             _water_column_line(rep["water_column"]), "", _order_line(rep["survey_order"]), ""]
    if plan.metrics is not None:
        r = rep["ratios"]
        lines += ["## Comparison with a standard lawnmower (Table 3, on the grid: cone test, no "
                  "occlusion)", "",
                  table3_markdown(plan.metrics), "",
                  f"Length ratio (total / lawnmower): {_fmt(r['length_total_over_lawnmower'])}; "
                  f"viewing angle ratio: {_fmt(r['view_total_over_lawnmower'])}.", ""]
    if metrics_3d is not None:
        from drake_auv.planning.metrics3d import table3d_markdown

        lines += ["## The same on the 3D mesh, with occlusion", "",
                  "Viewing angle of each sample's axis at its first hit on the grid's triangle "
                  "mesh; coverage: faces inside the aperture cone, in range, facing the sensor "
                  "and not occluded. On high-slope regions both sensor models: the planned one "
                  "and the reference's forward-looking sensor at one fixed tilt per region.", "",
                  table3d_markdown(metrics_3d), ""]
    ref = REFERENCE_TABLE3
    lines += ["## The reference's Table 3 (Santorini caldera ROI)", "",
              "| path | length (m) | viewing angle (deg) |", "| --- | ---: | ---: |"]
    for key, name in (("high_slope", "High-slope region"), ("planar", "Planar region"),
                      ("total", "Total (both regions)"), ("lawnmower", "Standard lawnmower path")):
        lines.append(f"| {name} | {ref[key]['length']:.1f} | {ref[key]['view_mean_deg']:.1f} "
                     f"(sd {ref[key]['view_sd_deg']:.1f}) |")
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


def write_outputs(plan, outdir, figures: bool = True, progress: bool = False,
                  exports: tuple[str, ...] | None = None, origin_lonlat=None,
                  surge_velocity: float = 0.5, tolerance_xy: float = 1.0,
                  metrics_3d=True, max_items: int = 700, ardusub_frames: str = "terrain",
                  heave_in_3d: bool = False, current: dict | None = None) -> list[FilePath]:
    """Writes path.csv (world frame), report.md, report.json, the `exports` and (with
    `figures`) the PNG figures into `outdir`; returns the files written.

    Args:
        exports: any of "cola2" (mission.xml), "qgc" (mission.plan, or mission_1.plan, ...
            past `max_items`; report.json gains exports.qgc), "geojson" (path.geojson
            and lawnmower.geojson, WGS 84); None: "geojson" when the grid is georeferenced
            (a CRS or `origin_lonlat`), else none.
        origin_lonlat: WGS 84 (lon, lat) of the world origin, for grids without a CRS.
        surge_velocity: mission speed, m/s; tolerance_xy: waypoint arrival tolerance, m.
        max_items, ardusub_frames: the QGC mission's items per file and ArduSub frames
            ("terrain" or "depth"), see `planning.qgc.write_qgc`.
        metrics_3d: add the occluded 3D metrics (`planning.metrics3d`) to the report: True
            computes them, a dict of `evaluate_plan_3d` is used as it is, False skips them.
        heave_in_3d: the COLA2 vehicle interpolates depth along sections (its heave_in_3D);
            the report's `exports.cola2` gives the sections and their replay's figures.
        current: `planning.current.current_report` of the path, added to report.json
            (`current`) and report.md.
    """
    georeferenced = plan.bathy.crs is not None or origin_lonlat is not None
    if exports is None:
        exports = ("geojson",) if georeferenced else ()
    for name in exports:
        if name not in EXPORTS:
            raise ValueError(f"unknown export {name!r}; choose from {', '.join(EXPORTS)}")
    if "qgc" in exports:
        from drake_auv.planning.qgc import check_options

        check_options(max_items, ardusub_frames)
    geo = GeoFrame(plan.bathy, origin_lonlat) if exports else None
    outdir = FilePath(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written, extras = [], {}
    plan.path.to_csv(outdir / "path.csv")
    written.append(outdir / "path.csv")
    if "geojson" in exports:
        write_geojson(plan.path, geo, outdir / "path.geojson", "coverage path", plan.surface)
        written.append(outdir / "path.geojson")
        if plan.lawnmower is not None:
            write_geojson(plan.lawnmower, geo, outdir / "lawnmower.geojson", "lawnmower",
                          plan.surface)
            written.append(outdir / "lawnmower.geojson")
    if "cola2" in exports:
        from drake_auv.planning.cola2 import export_cola2

        extras["cola2"] = export_cola2(plan.path, plan.surface, plan.parameters["omega"],
                                       plan.parameters["min_depth"], geo, outdir / "mission.xml",
                                       surge_velocity, tolerance_xy, heave_in_3d)
        written.append(outdir / "mission.xml")
    if "qgc" in exports:
        from drake_auv.planning.qgc import write_qgc

        files, extras["qgc"] = write_qgc(plan, geo, outdir, max_items=max_items,
                                         frames=ardusub_frames, speed=surge_velocity,
                                         acceptance_radius=tolerance_xy)
        written += files
    m3d = metrics_3d if isinstance(metrics_3d, dict) else None
    if metrics_3d is True:
        from drake_auv.planning.metrics3d import evaluate_plan_3d

        m3d = evaluate_plan_3d(plan)
    markdown = report_markdown(plan, m3d)
    rep = report_dict(plan, m3d)
    if current is not None:
        from drake_auv.planning.current import current_markdown

        markdown = markdown.rstrip("\n") + "\n\n" + current_markdown(current)
        rep["current"] = current
    write_text(outdir / "report.md", markdown)
    if extras:
        rep["exports"] = extras
    write_json(outdir / "report.json", rep)
    written += [outdir / "report.md", outdir / "report.json"]
    if figures:
        from drake_auv.planning.figures import write_figures

        written += write_figures(plan, outdir, progress=progress)
    return written
