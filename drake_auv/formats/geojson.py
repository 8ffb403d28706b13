"""RFC 7946 GeoJSON (WGS 84) of a planned route and the waypoints of the vehicle files written
with it, for a GIS.

The route is one 2D LineString and each vehicle file's items are Points, [lon, lat] through
pyproj from the grid's CRS (no `crs` member: RFC 7946 is WGS 84); depths and altitudes are
properties (`path_to_geojson`). `--export geojson` writes path.geojson and lawnmower.geojson
(`write_export`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_auv.formats import Exported, ExportOptions
from drake_auv.output_files import write_json
from drake_auv.terrain.geo import GeoFrame
from drake_auv.planning.missions import douglas_peucker
from drake_auv.planning.path import PlannedPath

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


def write_export(plan, geo: GeoFrame, outdir: Path, options: ExportOptions,
                 missions: tuple) -> Exported:
    """`--export geojson`: path.geojson, the route with the waypoints of `missions` (the
    vehicle files written before it), and lawnmower.geojson when the plan has a lawnmower."""
    write_geojson(plan.path, geo, outdir / "path.geojson", "coverage path", missions,
                  plan.surface)
    files = [outdir / "path.geojson"]
    if plan.lawnmower is not None:
        write_geojson(plan.lawnmower, geo, outdir / "lawnmower.geojson", "lawnmower")
        files.append(outdir / "lawnmower.geojson")
    return Exported(files)
