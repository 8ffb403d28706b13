"""Honest 3D metrics: coverage and viewing angle on the triangle mesh of the grid, with
occlusion (`geometry.visibility`), for the plan and the lawnmower.

- Mesh: `terrain.mesh.bathymetry_to_mesh` of the planned grid (two triangles per square of
  valid cells; no-data stays a hole).
- Viewing angle of a sample: its sensor axis is ray-cast against the mesh (Embree, first hit
  within the sensor range); the angle between the axis and the hit face's inward normal.
  Mean and sd in degrees over the group's imaging samples whose axis hits one of the group's
  faces; `blind_share`: samples whose axis hits nothing in range.
- Coverage: a face is seen from a sample when its centroid lies in the aperture cone, within
  range, the face turns its front to the sensor, and the ray to it meets nothing nearer; the
  share of the group's face area seen at least once.
- Groups: high-slope (slice samples, faces over high-slope cells), planar (planar samples, the
  other valid faces), total and lawnmower (all faces), and the lawnmower's samples on the
  high-slope faces (how well a plain survey sees the walls).
- Sensor models on the high-slope regions: the planned one, and (for a plan whose slicing
  sensor looks along the normal, which is 0 deg by construction) the forward-looking sensor at
  one fixed tilt per region the reference assumes, set as `slicing.fixed_depression` of the
  region's median slope and turned to the wall, at the same positions.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import ndimage

from drake_auv.geometry.raycast import RayCaster
from drake_auv.geometry.visibility import FaceVisibility, coverage_share, merge_best
from drake_auv.planning.slicing import fixed_depression, sensor_axes
from drake_auv.terrain.mesh import bathymetry_to_mesh


@dataclass(frozen=True)
class Metrics3D:
    """Occluded metrics of one group of samples (see the module docstring)."""

    view_mean_deg: float
    view_sd_deg: float
    coverage: float
    blind_share: float
    samples: int


def _grid_cells(bathy, xy) -> tuple[np.ndarray, np.ndarray]:
    ny, nx = bathy.shape
    j = np.clip(np.rint((xy[:, 0] - bathy.origin[0]) / bathy.spacing[0]).astype(int), 0, nx - 1)
    i = np.clip(np.rint((xy[:, 1] - bathy.origin[1]) / bathy.spacing[1]).astype(int), 0, ny - 1)
    return i, j


def fixed_tilt_axes(plan, points: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Axes of the reference's forward-looking sensor at one fixed tilt per high-slope region
    (the region nearest to each sample), facing the horizontal part of `axes`."""
    labels = plan.labels
    _, (ii, jj) = ndimage.distance_transform_edt(labels.regions == 0, return_indices=True)
    i, j = _grid_cells(plan.bathy, points)
    region = labels.regions[ii[i, j], jj[i, j]]
    dep = np.zeros(labels.n_regions + 1)
    for r in range(1, labels.n_regions + 1):
        dep[r] = fixed_depression(labels.slope[labels.regions == r])
    horiz = np.column_stack([axes[:, :2], np.zeros(len(axes))])
    return sensor_axes(-horiz, dep[region])


def evaluate_plan_3d(plan) -> dict[str, Metrics3D]:
    """Occluded 3D metrics of a `CoveragePlan`'s path and lawnmower, per group (keys
    high_slope, high_slope_fixed_tilt (normal-sensor plans only), planar, total, lawnmower,
    lawnmower_high_slope)."""
    p = plan.parameters
    aperture, rng = np.radians(p["aperture_deg"]), p["sensor_range"]
    mesh = bathymetry_to_mesh(plan.bathy)
    caster = RayCaster(mesh)
    vis = FaceVisibility(caster)
    i, j = _grid_cells(plan.bathy, vis.centroids[:, :2])
    high_face = plan.labels.high[i, j]
    path = plan.path
    groups = {"high_slope": (path, path.labels == "slice", None, high_face)}
    if p.get("slice_sensor", "normal") == "normal":
        m = path.labels == "slice"
        groups["high_slope_fixed_tilt"] = (
            path, m, fixed_tilt_axes(plan, path.points[m], path.sensor_dir[m]), high_face)
    groups["planar"] = (path, path.labels == "planar", None, ~high_face)
    groups["total"] = (path, path.labels != "transit", None, None)
    if plan.lawnmower is not None:
        lawn = plan.lawnmower
        groups["lawnmower"] = (lawn, lawn.labels != "transit", None, None)
        groups["lawnmower_high_slope"] = (lawn, lawn.labels != "transit", None, high_face)
    out = {}
    for name, (pth, mask, axes, faces) in groups.items():
        pts = pth.points[mask]
        axes = pth.sensor_dir[mask] if axes is None else axes
        n = len(pts)
        if n == 0:
            out[name] = Metrics3D(float("nan"), float("nan"), 0.0, 0.0, 0)
            continue
        _, hit = caster.cast_unit(pts, axes, rng)
        ok = hit >= 0
        on = ok.copy()  # hits on the group's faces
        if faces is not None:
            on[ok] = faces[hit[ok]]
        ang = np.degrees(np.arccos(np.clip(-np.einsum("ij,ij->i", caster.face_normals[hit[on]],
                                                      axes[on]), -1.0, 1.0)))
        slots, angles, _ = vis.cameras(pts, axes, aperture, rng)
        best = merge_best(np.full(len(vis.areas), np.nan), slots, angles)
        target = np.ones(len(best), bool) if faces is None else faces
        cov = coverage_share(best[target], vis.areas[target]) if target.any() else float("nan")
        out[name] = Metrics3D(float(ang.mean()) if ang.size else float("nan"),
                              float(ang.std()) if ang.size else float("nan"), cov,
                              float(1.0 - ok.mean()), n)
    return out


ROW_NAMES = {"high_slope": "High-slope region (planned sensor)",
             "high_slope_fixed_tilt": "High-slope region (fixed-tilt sensor)",
             "planar": "Planar region", "total": "Total (both regions)",
             "lawnmower": "Standard lawnmower path",
             "lawnmower_high_slope": "Lawnmower on the high-slope faces"}


def table3d_markdown(metrics: dict[str, Metrics3D]) -> str:
    """The occluded 3D metrics as a Markdown table."""
    lines = ["| path (3D mesh, occlusion) | viewing angle (deg) | coverage | blind share |",
             "| --- | ---: | ---: | ---: |"]
    for key, m in metrics.items():
        lines.append(f"| {ROW_NAMES[key]} | {m.view_mean_deg:.1f} (sd {m.view_sd_deg:.1f}) | "
                     f"{100 * m.coverage:.1f} % | {100 * m.blind_share:.1f} % |")
    return "\n".join(lines)


def metrics3d_dict(metrics: dict[str, Metrics3D]) -> dict:
    return {k: asdict(m) for k, m in metrics.items()}
