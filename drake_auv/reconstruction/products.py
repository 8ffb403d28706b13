"""The data products of a flown mission: its point cloud, surface and their scores.

`write_products(log, site, outdir)` writes `points.ply` (every return of the dive's `ScanLog`
as the vehicle believed it: navigation frame, site coordinates, with sensor origin, time and
source per point) and, when Open3D is installed and the target's box (grown by `CROP_MARGIN`)
holds enough returns, `reconstruction.ply` (site coordinates, vertices coloured by their
distance to the true world) and `reconstruction.png`; it returns the report's
`reconstruction` section. The surface is built from EVERY return of the dive, thinned to one
per `THIN_VOXEL` cube, with the support trim on (no face farther than a few local spacings
from a return), and scored over the whole mesh in the local frame: every vertex's distance
to the true world (`site.world`: a vertex on the seabed is right, one on a surface no return
supports is not), and the share of the target's area (`site.target_mesh`), all of it and the
part the returns saw, within 0.5 m of the surface. Needs only the log and the site (a `Site`,
or the part of one a `rosio.replay.ReplaySite` holds): no Drake. The returns are read from
the log's file a chunk at a time (`write_points`, `dive_cloud`): memory holds the thinned
cloud, whatever the dive's length.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from drake_auv.mapping.scan_log import ScanLog
from drake_auv.output_files import replacing
from drake_auv.progress import RunProgress, phase_display
from drake_auv.reconstruction.pointcloud import PointCloud, from_scan_log, write_ply_chunks
from drake_auv.reconstruction.scoring import score
from drake_auv.reconstruction.surface import (OUTLIERS, STAGES, SUPPORT, Reconstruction,
                                              open3d_available, open3d_error, reconstruct)

CROP_MARGIN = 1.0  # m around the target's bounding box: its returns decide whether to build
THIN_VOXEL = 0.1  # m, one return per cube before the normals and Poisson
MIN_POINTS = 1000  # returns in the target's box below which no surface is built
SUPPORT_LABEL = "distance of the surface to the nearest return (m)"
# what `mission_surface` does, in order: the display's steps of a reconstruction (and its
# files, one more)
SURFACE_STAGES = ("the returns", *STAGES, "scores")


@dataclass(frozen=True, eq=False)
class MissionSurface:
    """A dive's surface: `cloud` (every return, thinned, local frame), `reconstruction` (local
    frame), `errors` (per vertex distance to the true world, m) and `summary` (the report's
    `reconstruction` section)."""

    cloud: PointCloud
    reconstruction: Reconstruction
    errors: np.ndarray
    summary: dict


def dive_cloud(log: ScanLog, voxel: float = THIN_VOXEL) -> PointCloud:
    """Every return of the dive's `log`, one per `voxel` m cube; local frame (navigation).
    Read from the log a chunk of batches at a time, each chunk thinned before the next is
    read."""
    parts = [from_scan_log(chunk).thin(voxel) for chunk in log.chunks()]
    parts = [p for p in parts if len(p)]
    if not parts:
        return from_scan_log(ScanLog(sources=log.sources))
    cloud = PointCloud(*(np.concatenate([getattr(p, name) for p in parts])
                         for name in ("points", "origins", "times", "sources")), log.sources)
    return cloud.thin(voxel) if len(parts) > 1 else cloud


def target_returns(site, cloud: PointCloud) -> int:
    """The returns of `cloud` in the box of `site`'s target grown by `CROP_MARGIN`: whether to
    build."""
    lo, hi = site.target_mesh.bounds
    return len(cloud.crop(lo, hi, CROP_MARGIN))


def write_points(log: ScanLog, site, filename) -> int:
    """Writes every return of the dive's `log` to `filename` (PLY, `site`'s coordinates,
    `pointcloud.write_ply`'s format), streamed from the log's file a chunk of batches at a
    time, so memory does not grow with the dive; returns the number of points."""
    write_ply_chunks((from_scan_log(chunk).shifted(site.to_site)
                      for chunk in log.chunks()), log.returns, filename, log.sources)
    return log.returns


def mission_surface(log: ScanLog, site, depth: int = 9, trim: float = 0.05, k: int = 200,
                    support: float = SUPPORT,
                    progress: bool | RunProgress = False) -> MissionSurface | None:
    """Reconstructs the returns of the dive's `log` and scores the whole surface against
    `site`'s `target_mesh` and `world` (local frame); None when Open3D is unusable or the
    target's box (grown by `CROP_MARGIN`) holds fewer than `MIN_POINTS` returns.
    `progress`: show the progress over the `SURFACE_STAGES`, or a caller's `RunProgress` to
    advance by one per stage (none when nothing is built)."""
    with phase_display(progress, "reconstruct", len(SURFACE_STAGES),
                       f"reconstruction: {SURFACE_STAGES[0]}") as display:
        cloud = dive_cloud(log)
        if not open3d_available() or target_returns(site, cloud) < max(MIN_POINTS, k + 1):
            return None
        display.advance(1)
        surface = reconstruct(cloud, depth=depth, trim=trim, k=k, support=support,
                              progress=display)
        display.update(display.done, f"reconstruction: {SURFACE_STAGES[-1]}")
        summary, errors = score(site.target_mesh, surface.mesh, cloud.points, world=site.world)
        display.advance(1)
    summary.update(depth=depth, trim=trim, k=k, support=support, outliers=OUTLIERS,
                   thin_voxel_m=THIN_VOXEL,
                   support_median_m=float(np.median(surface.support_m)),
                   frame="local, navigation (as the vehicle believed)")
    return MissionSurface(cloud, surface, errors, summary)


def error_colours(errors: np.ndarray, vmax: float) -> np.ndarray:
    """(n, 4) RGBA in [0, 1] of distances (m) on a colour scale from 0 to `vmax` (m), the
    figures' (`figures.colour_scale`)."""
    from matplotlib import colormaps

    return colormaps["inferno"](np.clip(np.asarray(errors) / vmax, 0.0, 1.0))


def write_products(log: ScanLog, site, outdir, dpi: int = 110, surface: bool = True,
                   progress: RunProgress | None = None) -> dict:
    """Writes points.ply (the returns of the dive's `log`) and, when a surface was built,
    reconstruction.ply and reconstruction.png (`site`'s coordinates) into `outdir`; returns
    the report's `reconstruction` section (with `built` False and the `reason` when none
    was). `surface` False: points.ply alone.
    `progress`: the run's display, one step for the points and (with `surface`)
    `len(SURFACE_STAGES) + 1` for the reconstruction."""
    progress = progress if progress is not None else RunProgress.off()
    out = Path(outdir)
    with progress.step("points.ply"):
        write_points(log, site, out / "points.ply")
    if not surface:
        return dict(built=False, reason="switched off (outputs.reconstruction: false, "
                                        "--no-reconstruction)")
    begun = progress.done
    section = _write_surface(log, site, out, dpi, progress)
    progress.update(begun + len(SURFACE_STAGES) + 1)  # the files too (or nothing built)
    return section


def _write_surface(log: ScanLog, site, out: Path, dpi: int, progress: RunProgress) -> dict:
    """The reconstruction part of `write_products`, shown on the run's `progress`."""
    from drake_auv.reconstruction.figures import colour_scale, fig_reconstruction

    surface = mission_surface(log, site, progress=progress)
    progress.update(progress.done, "reconstruction: its files (.ply, .png)")
    if surface is None:  # too few returns (whatever Open3D's state), else Open3D's reason
        if open3d_error() is not None and target_returns(site, dive_cloud(log)) >= MIN_POINTS:
            return dict(built=False, reason=open3d_error())
        return dict(built=False, reason=f"fewer than {MIN_POINTS} returns in the target's box "
                                        f"(+{CROP_MARGIN:g} m)")
    mesh = surface.reconstruction.mesh
    colours = (255 * error_colours(surface.errors, colour_scale(surface.errors))).astype(np.uint8)
    with replacing(out / "reconstruction.ply") as temporary:
        trimesh.Trimesh(site.to_site(mesh.vertices), mesh.faces, vertex_colors=colours,
                        process=False).export(temporary)
    s = surface.summary["surface"]
    fig = fig_reconstruction(
        [("to the true world", mesh, surface.errors),
         ("to the returns", mesh, surface.reconstruction.support_m, SUPPORT_LABEL)],
        title=f"Screened Poisson surface of the dive's returns, support-trimmed: accuracy "
              f"median {s['accuracy_median_m']:.2f} m (p95 {s['accuracy_p95_m']:.2f} m) over "
              f"the whole mesh; {100 * s['completeness_seen']:.1f} % of the seen target")
    with replacing(out / "reconstruction.png") as temporary:
        fig.savefig(temporary, dpi=dpi, bbox_inches="tight")
    return dict(built=True, **surface.summary)


def products_markdown(section: dict) -> str:
    """The report's reconstruction section as Markdown."""
    lines = ["## Reconstruction (recorded returns, screened Poisson)", ""]
    if not section.get("built"):
        return "\n".join(lines + [f"Not built: {section['reason']}. The returns are in "
                                  "`points.ply`.", ""])
    s, p = section["surface"], section["point_cloud"]
    lines += [f"Every return of the dive as the vehicle believed it (navigation frame, drift "
              f"included), one per {section['thin_voxel_m']:g} m cube: normals from k = "
              f"{section['k']} neighbours oriented towards the sensor (returns whose neighbours "
              f"lie over {section.get('outliers', OUTLIERS):g} x farther than usual dropped "
              f"first), screened Poisson at "
              f"depth {section['depth']}, the lowest {100 * section['trim']:g} % of density "
              f"trimmed, then every face farther than {section['support']:g} local spacings "
              f"from a return (support trim; median distance of the kept vertices to a "
              f"return {section['support_median_m']:.3f} m). Accuracy: every vertex's "
              f"distance to the true world (the whole mesh, not only the target's box). "
              f"Completeness: the share of the true target's area "
              f"({section['target_area_m2']:.0f} m^2; {section['seen_area_m2']:.0f} m^2 of it "
              f"within {section['tolerance_m']:g} m of a return, 'seen') within "
              f"{section['tolerance_m']:g} m of the surface.", "",
              "| | accuracy median (m) | mean (m) | p95 (m) | completeness | of the seen "
              "target | size |",
              "| --- | --- | --- | --- | --- | --- | --- |",
              f"| surface | {s['accuracy_median_m']:.3f} | {s['accuracy_mean_m']:.3f} | "
              f"{s['accuracy_p95_m']:.3f} | {100 * s['completeness']:.1f} % | "
              f"{100 * s['completeness_seen']:.1f} % | {s['vertices']} vertices |",
              f"| point cloud | {p['accuracy_median_m']:.3f} | {p['accuracy_mean_m']:.3f} | "
              f"{p['accuracy_p95_m']:.3f} | {100 * p['completeness']:.1f} % | | "
              f"{p['points']} points |", "",
              "Files: `points.ply` (every return, site coordinates), `reconstruction.ply` "
              "(coloured by distance to the true world), `reconstruction.png` (coloured by "
              "distance to the true world and to the returns).", ""]
    return "\n".join(lines)

