"""Exports of a `CoveragePlan`: GeoJSON in the bathymetry's CRS, CSV, and the Table 3 report.

GeoJSON: one 3D LineString feature per run of samples with the same label (coordinates in the
input file's map CRS, z the elevation in metres). RFC 7946 assumes WGS 84; for any other CRS
the file carries the legacy `crs` member naming it, as GDAL and QGIS read it.
"""

from __future__ import annotations

import json
from pathlib import Path as FilePath

import numpy as np

from drake_auv.planning.path import Path
from drake_auv.terrain.bathymetry import Bathymetry

# The reference's Table 3 (Santorini caldera ROI, Omega = 2 m, 60 degree camera).
REFERENCE_TABLE3 = {
    "high_slope": {"length": 5864.9, "view_mean_deg": 9.3, "view_sd_deg": 4.5},
    "planar": {"length": 4973.6, "view_mean_deg": 12.3, "view_sd_deg": 6.6},
    "total": {"length": 10838.5, "view_mean_deg": 10.8, "view_sd_deg": 5.6},
    "lawnmower": {"length": 9834.2, "view_mean_deg": 23.2, "view_sd_deg": 7.1},
}


def _crs_member(crs: str | None):
    if crs is None:
        return None
    if crs.upper().startswith("EPSG:"):
        return {"type": "name", "properties": {"name": f"urn:ogc:def:crs:EPSG::{crs[5:]}"}}
    return {"type": "name", "properties": {"name": crs}}


def path_to_geojson(path: Path, bathy: Bathymetry, name: str = "path") -> dict:
    """A FeatureCollection of the path's labelled runs, in the bathymetry's CRS."""
    xy = bathy.world_to_crs(path.points[:, :2])
    coords = np.column_stack([xy, path.points[:, 2]])
    labels = path.labels
    breaks = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [len(path)]])
    features = []
    for k, (a, b) in enumerate(zip(starts, ends)):
        # Each run starts at the previous run's last sample, so the lines join up.
        run = coords[max(a - 1, 0):b]
        if len(run) < 2:
            run = np.vstack([run, run])
        features.append({
            "type": "Feature",
            "properties": {"name": name, "label": str(labels[a]), "index": k,
                           "length_m": float(np.linalg.norm(np.diff(path.points[max(a - 1, 0):b],
                                                                    axis=0), axis=1).sum())},
            "geometry": {"type": "LineString", "coordinates": np.round(run, 3).tolist()},
        })
    collection = {"type": "FeatureCollection", "name": name, "features": features}
    crs = _crs_member(bathy.crs)
    if crs is not None and bathy.crs != "EPSG:4326":
        collection["crs"] = crs
    return collection


def write_geojson(path: Path, bathy: Bathymetry, filename, name: str = "path") -> None:
    with open(filename, "w") as f:
        json.dump(path_to_geojson(path, bathy, name), f)


def report_dict(plan) -> dict:
    """Parameters, classification summary, Table 3 metrics and the reference's Table 3."""
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
        "reference_table3": REFERENCE_TABLE3,
    }
    if plan.metrics is not None:
        out["metrics"] = plan.metrics.to_dict()
        out["ratios"] = {
            "length_total_over_lawnmower": plan.metrics.total.length / plan.metrics.lawnmower.length,
            "view_total_over_lawnmower": (plan.metrics.total.view_mean_deg
                                          / plan.metrics.lawnmower.view_mean_deg),
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


def report_markdown(plan) -> str:
    """A human-readable report: parameters, classification, Table 3, the reference's values."""
    rep = report_dict(plan)
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
             f"cells. High-slope area: {rep['contours']} contour pieces.", ""]
    if plan.metrics is not None:
        r = rep["ratios"]
        lines += ["## Comparison with a standard lawnmower (Table 3)", "",
                  table3_markdown(plan.metrics), "",
                  f"Length ratio (total / lawnmower): {r['length_total_over_lawnmower']:.2f}; "
                  f"viewing angle ratio: {r['view_total_over_lawnmower']:.2f}.", ""]
    ref = REFERENCE_TABLE3
    lines += ["## The reference's Table 3 (Santorini caldera ROI)", "",
              "| path | length (m) | viewing angle (deg) |", "| --- | ---: | ---: |"]
    for key, name in (("high_slope", "High-slope region"), ("planar", "Planar region"),
                      ("total", "Total (both regions)"), ("lawnmower", "Standard lawnmower path")):
        lines.append(f"| {name} | {ref[key]['length']:.1f} | {ref[key]['view_mean_deg']:.1f} "
                     f"(sd {ref[key]['view_sd_deg']:.1f}) |")
    return "\n".join(lines) + "\n"


def write_outputs(plan, outdir, figures: bool = True, progress: bool = False) -> list[FilePath]:
    """Writes path.csv, path.geojson, lawnmower.geojson, report.md, report.json and (with
    `figures`) the PNG figures into `outdir`; returns the files written."""
    outdir = FilePath(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    plan.path.to_csv(outdir / "path.csv")
    written.append(outdir / "path.csv")
    write_geojson(plan.path, plan.bathy, outdir / "path.geojson", "coverage path")
    write_geojson(plan.lawnmower, plan.bathy, outdir / "lawnmower.geojson", "lawnmower")
    written += [outdir / "path.geojson", outdir / "lawnmower.geojson"]
    (outdir / "report.md").write_text(report_markdown(plan))
    with open(outdir / "report.json", "w") as f:
        json.dump(report_dict(plan), f, indent=2)
    written += [outdir / "report.md", outdir / "report.json"]
    if figures:
        from drake_auv.planning.figures import write_figures

        written += write_figures(plan, outdir, progress=progress)
    return written
