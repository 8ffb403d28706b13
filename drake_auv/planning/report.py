"""The report of a `CoveragePlan`: report.json's dict (`report_dict`) and report.md
(`report_markdown`): parameters, classification, mission time, water column, survey order,
the Table 3 metrics and the exports' figures, warnings and notes (`drake_auv.formats` gives
them; this module knows no file format).
"""

from __future__ import annotations

import numpy as np

from drake_auv.planning.path import PlannedPath

# The reference's Table 3 (Santorini caldera ROI, Omega = 2 m, 60 degree camera).
REFERENCE_TABLE3 = {
    "high_slope": {"length": 5864.9, "view_mean_deg": 9.3, "view_sd_deg": 4.5},
    "planar": {"length": 4973.6, "view_mean_deg": 12.3, "view_sd_deg": 6.6},
    "total": {"length": 10838.5, "view_mean_deg": 10.8, "view_sd_deg": 5.6},
    "lawnmower": {"length": 9834.2, "view_mean_deg": 23.2, "view_sd_deg": 7.1},
}


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


def report_dict(plan, metrics_3d=None, speed: float = 0.5, reference_table: bool = False,
                exports: dict | None = None) -> dict:
    """Parameters, classification summary, mission time at `speed` (m/s), Table 3 metrics
    (grid and, if given, the occluded 3D ones of `planning.metrics3d`), water column, survey
    order, the `exports`' figures (`formats.outputs.write_outputs`) and, with
    `reference_table`, the reference's Table 3."""
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


def report_markdown(plan, rep: dict, metrics_3d=None, warnings=(), notes=()) -> str:
    """A human-readable report of `rep` (a `report_dict` of `plan`): mission time, the
    exports' `warnings` and `notes` (the QGroundControl upload order), parameters,
    classification, Table 3 (grid, and the occluded 3D metrics if given) and the reference's
    values when `rep` has them."""
    p = rep["parameters"]
    lines = ["# Coverage plan report", "", mission_time_line(rep["mission_time"]), ""]
    if warnings:
        lines += ["## Warnings", "", *(f"- {w}" for w in warnings), ""]
    for note in notes:
        lines += [note, ""]
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
