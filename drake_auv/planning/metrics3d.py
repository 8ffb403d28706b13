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
  share of the group's face area seen at least once. Tested from the faces' side: every face
  of a mesh of at most `EXACT_FACES` (a grid of 200 000 cells: exact), else a fixed uniform
  sample of `SAMPLED_FACES` of the high-slope faces and of the other faces each, the share
  then a stratified estimate with its standard error `coverage_se` (about 0.03 percentage
  points at 99 % coverage).
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
from drake_auv.geometry.visibility import FaceVisibility
from drake_auv.planning.slicing import fixed_depression, sensor_axes
from drake_auv.terrain.mesh import bathymetry_to_mesh


EXACT_FACES = 400_000  # a mesh of at most this many faces (200 000 cells) has every face tested
SAMPLED_FACES = 100_000  # else this many of each stratum (high-slope, other) with more
SAMPLE_SEED = 0  # the faces sampled: the same for every plan of a grid (not a run's noise)


@dataclass(frozen=True)
class Metrics3D:
    """Occluded metrics of one group of samples (see the module docstring); `coverage_se`:
    the standard error of `coverage` from sampling the faces, 0 where every face counts."""

    view_mean_deg: float
    view_sd_deg: float
    coverage: float
    blind_share: float
    samples: int
    coverage_se: float = 0.0


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


def sampled_faces(strata: np.ndarray, max_faces: int = SAMPLED_FACES,
                  exact_faces: int = EXACT_FACES) -> np.ndarray:
    """(F,) bool: the faces whose coverage is tested: all of them when there are at most
    `exact_faces`, else every face of a stratum (`strata`, an integer label per face) of at
    most `max_faces` faces and `max_faces` of a larger one, drawn uniformly without
    replacement (seed `SAMPLE_SEED`)."""
    if len(strata) <= exact_faces:
        return np.ones(len(strata), dtype=bool)
    rng = np.random.default_rng(SAMPLE_SEED)
    out = np.zeros(len(strata), dtype=bool)
    for k in np.unique(strata):
        members = np.flatnonzero(strata == k)
        out[members if len(members) <= max_faces
            else rng.choice(members, max_faces, replace=False)] = True
    return out


def stratified_coverage(seen, areas, strata, sampled, target) -> tuple[float, float]:
    """Seen share of the area of the `target` faces and its standard error: per stratum the
    ratio estimate over its `sampled` faces, weighted by the stratum's whole target area (exact,
    error 0, where a stratum's faces are all sampled)."""
    total = float(areas[target].sum())
    cov, var = 0.0, 0.0
    for k in np.unique(strata[target]):
        in_k = target & (strata == k)
        m = in_k & sampled
        a, hit = areas[m], seen[m].astype(float)
        c = float((a * hit).sum() / a.sum())
        w = float(areas[in_k].sum()) / total
        cov += w * c
        n, big_n = len(a), int(in_k.sum())
        if n < big_n and n > 1:  # ratio estimator, finite-population corrected
            var += w * w * (1 - n / big_n) * float((a * (hit - c)) @ (a * (hit - c))) / (
                n * (n - 1) * a.mean() ** 2)
    return cov, float(np.sqrt(var))


def evaluate_plan_3d(plan, max_faces: int = SAMPLED_FACES,
                     exact_faces: int = EXACT_FACES) -> dict[str, Metrics3D]:
    """Occluded 3D metrics of a `CoveragePlan`'s path and lawnmower, per group (keys
    high_slope, high_slope_fixed_tilt (normal-sensor plans only), planar, total, lawnmower,
    lawnmower_high_slope).

    Each set of poses (the path's samples of one label, the fixed-tilt slices, the lawnmower)
    is ray-cast once and a group merges its sets. Viewing angles use every sample; coverage
    tests every face of a mesh of at most `exact_faces`, else `max_faces` of the high-slope
    and of the other faces each (`sampled_faces`), the figure then a stratified estimate with
    its standard error (`coverage_se`)."""
    p = plan.parameters
    aperture, rng = np.radians(p.aperture_deg), p.sensor_range
    mesh = bathymetry_to_mesh(plan.bathy)
    caster = RayCaster(mesh)
    vis = FaceVisibility(caster)
    i, j = _grid_cells(plan.bathy, vis.centroids[:, :2])
    high_face = plan.labels.high[i, j]
    strata = high_face.astype(np.int8)
    sampled = sampled_faces(strata, max_faces, exact_faces)
    path, lawn = plan.path, plan.lawnmower
    names, code = path.label_codes()
    poses = {lab: (path.points[code == k], path.sensor_dir[code == k], None)
             for k, lab in enumerate(names) if lab != "transit"}
    imaging = list(poses)
    groups = {"high_slope": (["slice"], high_face)}
    if p.slice_sensor == "normal":
        m = path.labels == "slice"
        poses["fixed_tilt"] = (path.points[m], fixed_tilt_axes(plan, path.points[m],
                                                               path.sensor_dir[m]), high_face)
        groups["high_slope_fixed_tilt"] = (["fixed_tilt"], high_face)
    groups["planar"] = (["planar"], ~high_face)
    groups["total"] = (imaging, None)
    if lawn is not None:
        m = lawn.labels != "transit"
        poses["lawnmower"] = (lawn.points[m], lawn.sensor_dir[m], None)
        groups["lawnmower"] = (["lawnmower"], None)
        groups["lawnmower_high_slope"] = (["lawnmower"], high_face)
    hits, seen = {}, {}
    for name, (pts, axes, faces) in poses.items():
        _, hits[name] = caster.cast_unit(pts, axes, rng) if len(pts) else (None, np.zeros(0, int))
        tested = sampled if faces is None else sampled & faces
        seen[name] = np.zeros(len(sampled), dtype=bool)
        seen[name][tested] = vis.seen_by(pts, axes, aperture, rng, np.flatnonzero(tested))
    out = {}
    for name, (sets, faces) in groups.items():
        sets = [s for s in sets if s in poses]
        hit = np.concatenate([hits[s] for s in sets]) if sets else np.zeros(0, int)
        axes = np.concatenate([poses[s][1] for s in sets]) if sets else np.zeros((0, 3))
        n = len(hit)
        if n == 0:
            out[name] = Metrics3D(float("nan"), float("nan"), 0.0, 0.0, 0)
            continue
        ok = hit >= 0
        on = ok.copy()  # hits on the group's faces
        if faces is not None:
            on[ok] = faces[hit[ok]]
        ang = np.degrees(np.arccos(np.clip(-np.einsum("ij,ij->i", caster.face_normals[hit[on]],
                                                      axes[on]), -1.0, 1.0)))
        target = np.ones(len(sampled), bool) if faces is None else faces
        seen_g = np.logical_or.reduce([seen[s] for s in sets])
        cov, se = (stratified_coverage(seen_g, vis.areas, strata, sampled, target)
                   if target.any() else (float("nan"), 0.0))
        out[name] = Metrics3D(float(ang.mean()) if ang.size else float("nan"),
                              float(ang.std()) if ang.size else float("nan"), cov,
                              float(1.0 - ok.mean()), n, se)
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
        se = f" (se {100 * m.coverage_se:.2f})" if m.coverage_se > 0 else ""
        lines.append(f"| {ROW_NAMES[key]} | {m.view_mean_deg:.1f} (sd {m.view_sd_deg:.1f}) | "
                     f"{100 * m.coverage:.1f} %{se} | {100 * m.blind_share:.1f} % |")
    return "\n".join(lines)


def metrics3d_dict(metrics: dict[str, Metrics3D]) -> dict:
    return {k: asdict(m) for k, m in metrics.items()}
