"""A recorded dive (`reader.open_log`) through the simulator's products: the on-line octree,
`points.ply`, the screened-Poisson surface and, given the true meshes, its scores.

The returns go, in the order they were logged, into a `ScanLog` (streamed to a temporary
file) and an `OnlineMap` caught up every `CATCH_UP` batches, so memory holds the octree and a
few batches, whatever the log's length; then the mission's own writers and scorers run on
that log (`reconstruction.products`), so a dive's `dive.mcap` replayed gives its run's
octree, `points.ply` and scores. The world frame is the log's (its odometry's frame);
`points.ply`, the surface and the meshes `world` and `target` are in the site's coordinates,
the world frame shifted by the log's metadata origin (`origin_x`, `origin_y`, 0 when the log
has none, as a vehicle's own log).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mapping.scan_log import ScanLog
from drake_auv.output_files import replacing, write_json, write_text
from drake_auv.rosio.reader import LogIndex, iter_batches

CATCH_UP = 64  # batches between the octree's catch-ups (the log's store keeps 64 in memory)


@dataclass(frozen=True)
class ReplaySite:
    """The duck-typed part of a `Site` the products read: the local frame's `origin` (2,)
    in site coordinates, and the true `world` and `target_mesh` in the local frame."""

    origin: np.ndarray
    world: trimesh.Trimesh | None = None
    target_mesh: trimesh.Trimesh | None = None

    def _shift(self, points, sign: float) -> np.ndarray:
        out = np.array(points, dtype=float)
        out[..., :2] += sign * self.origin
        return out

    def to_site(self, points) -> np.ndarray:
        return self._shift(points, 1.0)

    def to_local(self, points) -> np.ndarray:
        return self._shift(points, -1.0)

    def local_mesh(self, mesh: trimesh.Trimesh | None):
        return None if mesh is None else trimesh.Trimesh(self.to_local(mesh.vertices),
                                                         mesh.faces, process=False)


@dataclass(frozen=True)
class Replayed:
    """What `replay` built: the `scan_log` of the returns (world frame), its `online_map`,
    and the `site` (origin and meshes) the products read."""

    scan_log: ScanLog
    online_map: OnlineMap
    site: ReplaySite


def map_settings(index: LogIndex, voxel=None, stride=None, discretize=None,
                 clear=None) -> dict:
    """The octree's settings: the arguments, else the log's metadata (a dive's own), else the
    mapper's defaults (0.5 m voxels, every beam, no discretisation, no-echo beams clearing to
    the sonar's range)."""
    meta = index.metadata.get("drake_auv", {})

    def pick(value, key, cast, default):
        return cast(value if value is not None else meta.get(key, default))

    return dict(resolution_m=pick(voxel, "voxel_m", float, 0.5),
                multibeam_stride=pick(stride, "multibeam_stride", int, 1),
                discretize=pick(discretize, "discretize", lambda v: str(v) == "True", False),
                no_return_clear_m=pick(clear, "no_return_clear_m", float, np.inf))


def replay(index: LogIndex, settings: dict, world=None, target=None) -> Replayed:
    """Inserts every return of the log (`index`) into a `ScanLog` and its octree."""
    meta = index.metadata.get("drake_auv", {})
    origin = np.array([float(meta.get("origin_x", 0.0)), float(meta.get("origin_y", 0.0))])
    site = ReplaySite(origin)
    site = ReplaySite(origin, site.local_mesh(world), site.local_mesh(target))
    online = OnlineMap(settings["resolution_m"], settings["no_return_clear_m"],
                       settings["discretize"])
    log = ScanLog()
    for batch in iter_batches(index, settings["multibeam_stride"]):
        log = log.append(batch)
        if log.count % CATCH_UP == 0:
            online.catch_up(log)
    online.catch_up(log)
    return Replayed(log, online, site)


def map_summary(replayed: Replayed, settings: dict) -> dict:
    """The report's `map`: the octree's leaves and occupied voxels, the batches and returns."""
    octree = replayed.online_map.map
    return dict(**settings, leaves=int(octree.tree.getNumLeafNodes()),
                occupied_voxels=int(len(octree.occupied_points())),
                batches=replayed.scan_log.count, returns=replayed.scan_log.returns)


def write_replay_outputs(index: LogIndex, replayed: Replayed, settings: dict, outdir,
                         dpi: int = 110) -> dict:
    """Writes points.ply, the octree (`map.bt`), the surface (reconstruction.ply and .png,
    scored with a target) and report.json / report.md into `outdir`; returns the summary."""
    from drake_auv.reconstruction.products import write_points, write_products

    out = Path(outdir)
    summary = dict(log=log_summary(index), map=map_summary(replayed, settings))
    if replayed.site.target_mesh is not None:
        summary["reconstruction"] = write_products(replayed.scan_log, replayed.site, out, dpi)
        if summary["reconstruction"].get("built"):
            summary["coverage"] = dict(
                point_cloud=summary["reconstruction"]["point_cloud"]["completeness"],
                surface=summary["reconstruction"]["surface"]["completeness"],
                tolerance_m=summary["reconstruction"]["tolerance_m"])
    else:
        write_points(replayed.scan_log, replayed.site, out / "points.ply")
        summary["reconstruction"] = unscored_surface(replayed, out)
    with replacing(out / "map.bt") as temporary:
        replayed.online_map.map.write(temporary)
    write_json(out / "report.json", summary, default=float)
    write_text(out / "report.md", replay_markdown(summary))
    return summary


def unscored_surface(replayed: Replayed, out: Path) -> dict:
    """Without a target: the surface of every return (site coordinates), not scored."""
    from drake_auv.reconstruction.products import MIN_POINTS, THIN_VOXEL, dive_cloud
    from drake_auv.reconstruction.surface import open3d_error, reconstruct

    cloud = dive_cloud(replayed.scan_log)
    if len(cloud) < MIN_POINTS:
        return dict(built=False, reason=f"fewer than {MIN_POINTS} returns")
    if open3d_error() is not None:
        return dict(built=False, reason=open3d_error())
    surface = reconstruct(cloud, progress=False)
    with replacing(out / "reconstruction.ply") as temporary:
        trimesh.Trimesh(replayed.site.to_site(surface.mesh.vertices), surface.mesh.faces,
                        process=False).export(temporary)
    return dict(built=True, scored=False, thin_voxel_m=THIN_VOXEL,
                vertices=int(len(surface.mesh.vertices)), faces=int(len(surface.mesh.faces)),
                support_median_m=float(np.median(surface.support_m)))


def log_summary(index: LogIndex) -> dict:
    return dict(path=str(index.path), world_frame=index.world, base_frame=index.base,
                start_s=float(index.track.times[0] / 1e9),
                end_s=float(index.track.times[-1] / 1e9), poses=int(len(index.track.times)),
                sources={name: dict(s, max_range_m=index.max_ranges[name])
                         for name, s in index.sources.items()})


def replay_markdown(summary: dict) -> str:
    log, m = summary["log"], summary["map"]
    lines = ["# Replayed log", "",
             f"`{log['path']}`: {log['poses']} poses of `{log['base_frame']}` in "
             f"`{log['world_frame']}` from {log['start_s']:.1f} to {log['end_s']:.1f} s.", "",
             "| source | topic | type | messages | frames | max range (m) |",
             "| --- | --- | --- | --- | --- | --- |"]
    lines += [f"| {name} | `{s['topic']}` | {s['type']} | {s['count']} | "
              f"{', '.join(s['frames'])} | {s['max_range_m']:g} |"
              for name, s in log["sources"].items()]
    lines += ["", "## On-line map (OctoMap)", "",
              f"{m['batches']} sonar updates, {m['returns']} returns, {m['resolution_m']:g} m "
              f"voxels, every {m['multibeam_stride']} multibeam beam(s): {m['leaves']} leaves, "
              f"{m['occupied_voxels']} occupied voxels (`map.bt`).", ""]
    section = summary["reconstruction"]
    if "surface" in section:
        from drake_auv.reconstruction.products import products_markdown

        lines.append(products_markdown(section))
    elif section.get("built"):
        lines += ["## Reconstruction (recorded returns, screened Poisson)", "",
                  f"{section['vertices']} vertices, {section['faces']} faces "
                  f"(`reconstruction.ply`), not scored: no --target given.", ""]
    else:
        lines += ["## Reconstruction", "", f"Not built: {section['reason']}. The returns are "
                  "in `points.ply`.", ""]
    return "\n".join(lines)
