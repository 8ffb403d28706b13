"""The data products of a flown mission: its point cloud, surface and their scores.

`write_products(result, outdir)` writes `points.ply` (every return of the dive as the vehicle
believed it: navigation frame, site coordinates, with sensor origin, time and source per point)
and, when Open3D is installed and the target's box holds enough returns, `reconstruction.ply`
(site coordinates, vertices coloured by their distance to the true target) and
`reconstruction.png`; it returns the report's `reconstruction` section. The scoring is done in
the local frame against the true target (`site.target_mesh`), on the returns inside the
target's bounding box grown by `CROP_MARGIN` (the navigation error moves them, and the box also
keeps a ring of seabed and, at the breakwater, the neighbouring block's face across the 0.5 m
gap, which count as error), thinned to one return per `THIN_VOXEL` cube. Needs only the
result's `scan_log` and `site`: no Drake. The returns are read from the log's file a chunk at
a time (`write_points`, `returns_in_box`): memory is bounded whatever the dive's length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path as FilePath

import numpy as np
import trimesh

from drake_auv.mapping.scan_log import ScanLog
from drake_auv.reconstruction.pointcloud import PointCloud, from_scan_log, write_ply_chunks
from drake_auv.reconstruction.scoring import score
from drake_auv.reconstruction.surface import (Reconstruction, open3d_available, open3d_error,
                                              reconstruct)

CROP_MARGIN = 1.0  # m around the target's bounding box
THIN_VOXEL = 0.1  # m, one return per cube before the normals and Poisson
MIN_POINTS = 1000  # returns in the target's box below which no surface is built
ERROR_VMAX = 1.0  # m, the top of the error colour scale


@dataclass(frozen=True, eq=False)
class MissionSurface:
    """A dive's target surface: `cloud` (thinned returns in the target's box, local frame),
    `reconstruction` (local frame), `errors` (per vertex distance to the true target, m) and
    `summary` (the report's `reconstruction` section)."""

    cloud: PointCloud
    reconstruction: Reconstruction
    errors: np.ndarray
    summary: dict


def target_cloud(result, margin: float = CROP_MARGIN, voxel: float = THIN_VOXEL) -> PointCloud:
    """The dive's returns inside the target's bounding box grown by `margin` m, one per `voxel`
    m cube; local frame (navigation)."""
    lo, hi = result.site.target_mesh.bounds
    cloud = returns_in_box(result.scan_log, lo, hi, margin)
    return cloud.thin(voxel) if len(cloud) else cloud


def returns_in_box(log, lo, hi, margin: float = 0.0) -> PointCloud:
    """The returns of `log` (a `ScanLog`) inside the box [lo - margin, hi + margin] (m, the
    log's frame), read from it a chunk of batches at a time (memory: the box's returns)."""
    parts = [from_scan_log(chunk).crop(lo, hi, margin) for chunk in log.chunks()]
    parts = [p for p in parts if len(p)] or [from_scan_log(ScanLog())]
    return PointCloud(*(np.concatenate([getattr(p, name) for p in parts])
                        for name in ("points", "origins", "times", "sources")))


def write_points(result, filename) -> int:
    """Writes every return of the dive (`result.scan_log`) to `filename` (PLY, site
    coordinates, `pointcloud.write_ply`'s format), streamed from the log's file a chunk of
    batches at a time, so memory does not grow with the dive; returns the number of points."""
    log = result.scan_log
    write_ply_chunks((from_scan_log(chunk).shifted(result.site.to_site)
                      for chunk in log.chunks()), log.returns, filename)
    return log.returns


def mission_surface(result, depth: int = 9, trim: float = 0.05, k: int = 200,
                    progress: bool = False) -> MissionSurface | None:
    """Reconstructs and scores the target from the dive's returns; None when Open3D is unusable
    or the target's box holds fewer than `MIN_POINTS` returns."""
    cloud = target_cloud(result)
    if not open3d_available() or len(cloud) < max(MIN_POINTS, k + 1):
        return None
    surface = reconstruct(cloud, depth=depth, trim=trim, k=k, progress=progress)
    summary, errors = score(result.site.target_mesh, surface.mesh, cloud.points)
    summary.update(depth=depth, trim=trim, k=k, crop_margin_m=CROP_MARGIN,
                   thin_voxel_m=THIN_VOXEL, frame="local, navigation (as the vehicle believed)")
    return MissionSurface(cloud, surface, errors, summary)


def error_colours(errors: np.ndarray, vmax: float = ERROR_VMAX) -> np.ndarray:
    """(n, 4) RGBA in [0, 1] of distances (m) on the figures' colour scale."""
    from matplotlib import colormaps

    return colormaps["inferno"](np.clip(np.asarray(errors) / vmax, 0.0, 1.0))


def write_products(result, outdir, dpi: int = 110) -> dict:
    """Writes points.ply and, when a surface was built, reconstruction.ply and
    reconstruction.png into `outdir`; returns the report's `reconstruction` section (with
    `built` False and the `reason` when none was)."""
    from drake_auv.reconstruction.figures import fig_reconstruction

    out = FilePath(outdir)
    write_points(result, out / "points.ply")
    surface = mission_surface(result)
    if surface is None:  # too few returns (whatever Open3D's state), else Open3D's reason
        if open3d_error() is not None and len(target_cloud(result)) >= MIN_POINTS:
            return dict(built=False, reason=open3d_error())
        return dict(built=False, reason=f"fewer than {MIN_POINTS} returns in the target's box "
                                        f"(+{CROP_MARGIN:g} m)")
    mesh = surface.reconstruction.mesh
    colours = (255 * error_colours(surface.errors)).astype(np.uint8)
    trimesh.Trimesh(result.site.to_site(mesh.vertices), mesh.faces, vertex_colors=colours,
                    process=False).export(out / "reconstruction.ply")
    s = surface.summary["surface"]
    fig = fig_reconstruction(
        [("reconstruction", mesh, surface.errors)], vmax=ERROR_VMAX,
        title=f"Screened Poisson surface of the target from the dive's returns: accuracy mean "
              f"{s['accuracy_mean_m']:.2f} m (p95 {s['accuracy_p95_m']:.2f} m), completeness "
              f"{100 * s['completeness']:.1f} %")
    fig.savefig(out / "reconstruction.png", dpi=dpi, bbox_inches="tight")
    return dict(built=True, **surface.summary)


def products_markdown(section: dict) -> str:
    """The report's reconstruction section as Markdown."""
    lines = ["## Reconstruction (recorded returns, screened Poisson)", ""]
    if not section.get("built"):
        return "\n".join(lines + [f"Not built: {section['reason']}. The returns are in "
                                  "`points.ply`.", ""])
    s, p = section["surface"], section["point_cloud"]
    lines += [f"The returns as the vehicle believed them (navigation frame, drift included) "
              f"inside the target's box grown by {section['crop_margin_m']:g} m (a seabed ring "
              f"and any neighbouring face there count as error), one per "
              f"{section['thin_voxel_m']:g} m cube: normals from k = {section['k']} "
              f"neighbours oriented towards the sensor, screened Poisson at depth "
              f"{section['depth']}, the lowest {100 * section['trim']:g} % of density trimmed. "
              f"Scored against the true target ({section['target_area_m2']:.0f} m^2); "
              f"completeness is the share of its area within {section['tolerance_m']:g} m.", "",
              "| | accuracy mean (m) | accuracy p95 (m) | completeness | size |",
              "| --- | --- | --- | --- | --- |",
              f"| surface | {s['accuracy_mean_m']:.3f} | {s['accuracy_p95_m']:.3f} | "
              f"{100 * s['completeness']:.1f} % | {s['vertices']} vertices |",
              f"| point cloud | {p['accuracy_mean_m']:.3f} | {p['accuracy_p95_m']:.3f} | "
              f"{100 * p['completeness']:.1f} % | {p['points']} points |", "",
              "Files: `points.ply` (every return, site coordinates), `reconstruction.ply` "
              "(coloured by error), `reconstruction.png`.", ""]
    return "\n".join(lines)


def draw_products(scene, result, outdir, max_faces: int = 30_000) -> None:
    """Adds the `reconstruction` layer (the surface of `outdir`/reconstruction.ply, coloured by
    error, at most `max_faces` faces) to a mission's Meshcat scene, when there is one."""
    from drake_auv.reconstruction.figures import decimated

    filename = FilePath(outdir) / "reconstruction.ply"
    if not filename.is_file():
        return
    mesh = trimesh.load(filename, process=False)
    rgb = np.asarray(mesh.visual.vertex_colors, dtype=float)[:, :3] / 255.0
    local = trimesh.Trimesh(result.site.to_local(mesh.vertices), mesh.faces, process=False)
    small, colours = decimated(local, rgb, max_faces)
    scene.meshcat.SetTriangleColorMesh(scene.path_of("reconstruction"),
                                       np.asfortranarray(small.vertices.T),
                                       np.asfortranarray(small.faces.T.astype(np.int32)),
                                       np.asfortranarray(colours.T))
