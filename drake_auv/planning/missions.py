"""Missions a vehicle runs, from a `Path`: QGroundControl `.plan` JSON (ArduSub) in WGS 84 (the
COLA2 mission XML is `planning.cola2`: its sections follow COLA2's semantics, not waypoints).

Waypoints: the path's samples thinned per labelled run by Douglas-Peucker in 3D (x, y and the
coordinate the vehicle holds: altitude above the seabed on terrain-following lanes, elevation
elsewhere), so every dropped sample lies within `tolerance` (m) of the waypoint polyline and
every waypoint is a path sample. A waypoint takes the label of the segment that arrives at it.
Vertical reference per waypoint: altitude above the seabed on "planar" and "lawnmower" lanes
(the DVL holds the offset over planar terrain), depth on slicing contours and transits (planned
3D lines whose altitude varies).

QGroundControl plan: `fileType: "Plan"`, `mission.items` of `SimpleItem`s with command 16
(MAV_CMD_NAV_WAYPOINT), params [hold s, acceptance radius m, pass radius, yaw deg, lat, lon,
alt]; ArduSub's two altitude frames: 10 (MAV_FRAME_GLOBAL_TERRAIN_ALT, positive altitude above
the seabed) on lanes, 3 (MAV_FRAME_GLOBAL_RELATIVE_ALT, home at the surface, negative altitude =
depth) on contours and transits. No-go zones go to the geofence as exclusion polygons.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from drake_auv.planning.geo import GeoFrame
from drake_auv.planning.path import Path
from drake_auv.planning.surface import TerrainSurface

ALTITUDE_LABELS = ("planar", "lawnmower")
MAV_CMD_NAV_WAYPOINT = 16
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_TERRAIN_ALT = 10
MAV_AUTOPILOT_ARDUPILOTMEGA = 3
MAV_TYPE_SUBMARINE = 12


def douglas_peucker(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices of the samples of a polyline (any dimension) kept by Douglas-Peucker: every
    dropped sample lies within `tolerance` of the kept polyline; the ends are kept."""
    points = np.asarray(points, float)
    n = len(points)
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = True
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        v = points[a + 1:b] - points[a]
        seg = points[b] - points[a]
        seg2 = float(seg @ seg)
        t = np.clip(v @ seg / seg2, 0.0, 1.0) if seg2 > 1e-18 else np.zeros(len(v))
        d = np.linalg.norm(v - t[:, None] * seg, axis=1)
        k = int(np.argmax(d))
        if d[k] > tolerance:
            i = a + 1 + k
            keep[i] = True
            stack += [(a, i), (i, b)]
    return np.flatnonzero(keep)


@dataclass(frozen=True)
class Waypoints:
    """Mission waypoints taken from a path (world frame, z up, m).

    Attributes:
        index: (K,) index of each waypoint's sample in the path.
        points: (K, 3) positions.
        altitude: (K,) height above the seabed below, m.
        heading: (K,) yaw of the body x axis, rad (world frame, from +x counter-clockwise).
        labels: (K,) label of the segment arriving at each waypoint (the first: its own).
        use_altitude: (K,) True where the vehicle holds altitude (lanes), else depth.
    """

    index: np.ndarray
    points: np.ndarray
    altitude: np.ndarray
    heading: np.ndarray
    labels: np.ndarray
    use_altitude: np.ndarray

    def __len__(self) -> int:
        return len(self.index)


def mission_waypoints(path: Path, surface: TerrainSurface, tolerance: float = 0.05) -> Waypoints:
    """Waypoints of `path` (see the module docstring); `tolerance` in m, > 0."""
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"waypoint tolerance must be > 0 m, got {tolerance}")
    pts = path.points
    altitude = pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1])
    labels = path.labels
    use_alt = np.isin(labels.astype(str), ALTITUDE_LABELS)
    breaks = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [len(path)]])
    kept = [np.array([0])]
    for a, b in zip(starts, ends):
        lo = max(a - 1, 0)  # a run's segments start at the previous run's last sample
        held = np.column_stack([pts[lo:b, :2], np.where(use_alt[a], altitude[lo:b],
                                                        pts[lo:b, 2])])
        kept.append(lo + douglas_peucker(held, tolerance))
    idx = np.unique(np.concatenate(kept))
    return Waypoints(idx, pts[idx], altitude[idx], path.heading[idx], labels[idx], use_alt[idx])


def _compass_yaw(geo: GeoFrame, wp: Waypoints) -> np.ndarray:
    """(K,) headings as NED yaw: radians clockwise from true north, in [0, 2 pi)."""
    grid = np.pi / 2 - wp.heading  # clockwise from world +y
    return np.mod(grid + geo.grid_north_azimuth(wp.points[:, :2]), 2 * np.pi)


def qgc_plan(wp: Waypoints, geo: GeoFrame, speed: float = 0.5, acceptance_radius: float = 1.0,
             no_go_lonlat: list[np.ndarray] | None = None) -> dict:
    """The QGroundControl plan of the waypoints for ArduSub (see the module docstring).

    Args:
        speed: cruise and hover speed, m/s.
        acceptance_radius: waypoint acceptance radius, m.
        no_go_lonlat: exterior rings (K, 2) of no-go zones in WGS 84 (lon, lat), for the
            geofence's exclusion polygons.
    """
    lonlat = geo.to_lonlat(wp.points[:, :2])
    yaw_deg = np.degrees(_compass_yaw(geo, wp))
    items = []
    for k in range(len(wp)):
        alt = wp.use_altitude[k]
        # Lanes keep the heading along the motion (yaw left to the autopilot); contours face
        # the wall, so their yaw is commanded.
        yaw = None if alt else round(float(yaw_deg[k]), 3)
        items.append({
            "type": "SimpleItem", "command": MAV_CMD_NAV_WAYPOINT,
            "frame": MAV_FRAME_GLOBAL_TERRAIN_ALT if alt else MAV_FRAME_GLOBAL_RELATIVE_ALT,
            "params": [0, float(acceptance_radius), 0, yaw, round(float(lonlat[k, 1]), 9),
                       round(float(lonlat[k, 0]), 9),
                       round(float(wp.altitude[k] if alt else wp.points[k, 2]), 3)],
            "autoContinue": True, "doJumpId": k + 1,
        })
    fence = [{"inclusion": False, "version": 1,
              "polygon": [[round(float(lat), 9), round(float(lon), 9)] for lon, lat in ring]}
             for ring in (no_go_lonlat or [])]
    return {
        "fileType": "Plan", "version": 1, "groundStation": "drake_auv",
        "mission": {"version": 2, "firmwareType": MAV_AUTOPILOT_ARDUPILOTMEGA,
                    "vehicleType": MAV_TYPE_SUBMARINE, "cruiseSpeed": float(speed),
                    "hoverSpeed": float(speed), "globalPlanAltitudeMode": 1,
                    "plannedHomePosition": [round(float(lonlat[0, 1]), 9),
                                            round(float(lonlat[0, 0]), 9), 0.0],
                    "items": items},
        "geoFence": {"version": 2, "circles": [], "polygons": fence},
        "rallyPoints": {"version": 2, "points": []},
    }


def write_qgc(wp: Waypoints, geo: GeoFrame, filename, **kwargs) -> None:
    """Writes `qgc_plan` to `filename` as JSON."""
    with open(filename, "w") as f:
        json.dump(qgc_plan(wp, geo, **kwargs), f, indent=1)
