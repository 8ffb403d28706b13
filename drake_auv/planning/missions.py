"""Missions a vehicle runs, from a `Path`: COLA2 mission XML (GIRONA 500) here, QGroundControl
`.plan` JSON (ArduSub) in `planning.qgc`, both in WGS 84.

Waypoints: the path's samples thinned per labelled run by Douglas-Peucker in 3D (x, y and the
coordinate the vehicle holds: altitude above the seabed on terrain-following lanes, elevation
elsewhere), so every dropped sample lies within `tolerance` (m) of the waypoint polyline and
every waypoint is a path sample. A waypoint takes the label of the segment that arrives at it.
Vertical reference per waypoint: altitude above the seabed on "planar" and "lawnmower" lanes
(the DVL holds the offset over planar terrain), depth on slicing contours and transits (planned
3D lines whose altitude varies).

COLA2 mission format 2.0 (field names as cola2_lib's `Mission::loadMission` reads them, see
docs/planning.md): `<mission><version>2.0</version>` then `<mission_step>`s with one
`<maneuver type="goto|section|park">`: a goto to the first waypoint, one section per leg
(initial_latitude/longitude/depth to final_latitude/longitude/depth/altitude), a park at the
end. heave_mode 0 = depth, 1 = altitude; depths positive down, m; yaw radians clockwise from
north (NED).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from drake_auv.planning.geo import GeoFrame
from drake_auv.planning.path import Path
from drake_auv.planning.surface import TerrainSurface

ALTITUDE_LABELS = ("planar", "lawnmower")


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


def mission_waypoints(path: Path, surface: TerrainSurface, tolerance: float = 0.05,
                      altitude_labels: tuple[str, ...] = ALTITUDE_LABELS) -> Waypoints:
    """Waypoints of `path` (see the module docstring); `tolerance` in m, > 0; the vehicle holds
    altitude on the runs labelled one of `altitude_labels` (() : depth everywhere)."""
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"waypoint tolerance must be > 0 m, got {tolerance}")
    pts = path.points
    altitude = pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1])
    labels = path.labels
    use_alt = np.isin(labels.astype(str), list(altitude_labels))
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


def _text(parent, tag: str, value) -> None:
    el = ET.SubElement(parent, tag)
    if isinstance(value, bool):
        el.text = "true" if value else "false"
    elif isinstance(value, (int, np.integer)):
        el.text = str(int(value))
    else:
        el.text = f"{float(value):.9f}"  # 1e-9 deg of latitude is 0.1 mm


def cola2_mission(wp: Waypoints, geo: GeoFrame, surge_velocity: float = 0.5,
                  tolerance_xy: float = 1.0, park_time: float = 10.0) -> ET.ElementTree:
    """The COLA2 mission (version 2.0) of the waypoints: goto, sections, park.

    Args:
        surge_velocity: commanded forward speed, m/s (> 0).
        tolerance_xy: horizontal arrival tolerance, m (> 0).
        park_time: time holding the last waypoint, s (>= 0).
    """
    for name, value, ok in (("surge_velocity", surge_velocity, surge_velocity > 0),
                            ("tolerance_xy", tolerance_xy, tolerance_xy > 0),
                            ("park_time", park_time, park_time >= 0)):
        if not (np.isfinite(value) and ok):
            raise ValueError(f"{name} must be {'>= 0' if name == 'park_time' else '> 0'}, "
                             f"got {value}")
    lonlat = geo.to_lonlat(wp.points[:, :2])
    depth = -wp.points[:, 2]
    yaw = _compass_yaw(geo, wp)
    root = ET.Element("mission")
    ET.SubElement(root, "version").text = "2.0"

    def final(man, k):
        _text(man, "final_latitude", lonlat[k, 1])
        _text(man, "final_longitude", lonlat[k, 0])
        _text(man, "final_depth", depth[k])
        _text(man, "final_altitude", wp.altitude[k])
        _text(man, "heave_mode", 1 if wp.use_altitude[k] else 0)
        _text(man, "surge_velocity", surge_velocity)

    for k in range(len(wp)):
        step = ET.SubElement(root, "mission_step")
        man = ET.SubElement(step, "maneuver", type="goto" if k == 0 else "section")
        if k:
            _text(man, "initial_latitude", lonlat[k - 1, 1])
            _text(man, "initial_longitude", lonlat[k - 1, 0])
            _text(man, "initial_depth", depth[k - 1])
        final(man, k)
        _text(man, "tolerance_xy", tolerance_xy)
        _text(man, "no_altitude_goes_up", True)
    step = ET.SubElement(root, "mission_step")
    man = ET.SubElement(step, "maneuver", type="park")
    final(man, len(wp) - 1)
    _text(man, "final_yaw", yaw[-1])
    _text(man, "use_yaw", False)
    _text(man, "time", park_time)
    _text(man, "no_altitude_goes_up", True)
    ET.indent(root)
    return ET.ElementTree(root)


def write_cola2(wp: Waypoints, geo: GeoFrame, filename, **kwargs) -> None:
    """Writes `cola2_mission` to `filename` (UTF-8 XML with a declaration)."""
    cola2_mission(wp, geo, **kwargs).write(filename, encoding="utf-8", xml_declaration=True)
