"""QGroundControl `.plan` missions for ArduSub (WGS 84), within a board's mission budget, and
their reader.

Plan file (QGroundControl's JSON keys: PlanMasterController, MissionController,
SimpleMissionItem): `fileType: "Plan"`, mission version 2, firmwareType 3 (ArduPilot),
vehicleType 12 (submarine), `mission.items` of `SimpleItem`s: first a MAV_CMD_DO_CHANGE_SPEED
(178, params [1 = ground speed, speed m/s, -1 = throttle unchanged, 0, ...]) so the speed
reaches the vehicle (`cruiseSpeed` is only QGC's time estimate), then one MAV_CMD_NAV_WAYPOINT
(16) per waypoint, params [hold s, acceptance radius m, pass radius, yaw deg from north or
null, lat, lon, alt]. Each waypoint says its altitude the way QGC's editor shows it:
`AltitudeMode` (QGroundControlQmlGlobal::AltMode: 1 relative = frame 3, 4 terrain frame =
frame 10), `Altitude` (param 7) and `AMSLAltAboveTerrain` (the elevation of the waypoint, m,
home being at the sea surface). `globalPlanAltitudeMode` is the items' own mode, or 0 (mixed)
when both frames occur. No-go zones are geofence exclusion polygons, rings open (QGC closes
them).

ArduSub frames (`--ardusub-frames`): "terrain" flies the lanes in frame 10
(MAV_FRAME_GLOBAL_TERRAIN_ALT, altitude above the seabed from the downward rangefinder) and
contours and transits in frame 3 (MAV_FRAME_GLOBAL_RELATIVE_ALT, negative = depth); "depth"
uses frame 3 everywhere, the depths taken from the prior map.

Budget: ArduPilot boards hold a few hundred mission items, home included; `max_items` counts
every item a board stores (home, DO_CHANGE_SPEED, waypoints). Waypoints come from
`missions.mission_waypoints` (Douglas-Peucker per labelled run); its tolerance is the smallest
that fits the budget, found by bisection, and never more than the cross-track error the lane
overlap admits (`admitted_cross_track`). The legs are then replayed as ArduSub flies them
(`autopilot.ardusub`) and path samples put back where a leg comes nearer than Omega / 2 to the
prior seabed or above the minimum depth. A mission still over budget is split into
mission_1.plan, mission_2.plan, ..., each starting at the previous one's last waypoint.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.autopilot.ardusub import replay_ardusub
from drake_auv.autopilot.items import MAX_HOLD_S, LocalLeg, MissionItem, VehicleMission
from drake_auv.autopilot.replay import clearance_report, clearance_warnings
from drake_auv.formats import Exported, ExportOptions
from drake_auv.output_files import open_replacing
from drake_auv.terrain.geo import GeoFrame
from drake_auv.planning.metrics import evaluate_path, surface_area_weights
from drake_auv.planning.missions import ALTITUDE_LABELS, Waypoints, mission_waypoints
from drake_auv.planning.path import PlannedPath

MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_DO_CHANGE_SPEED = 178
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_TERRAIN_ALT = 10
MAV_AUTOPILOT_ARDUPILOTMEGA = 3
MAV_TYPE_SUBMARINE = 12
ALT_MODE_MIXED, ALT_MODE_RELATIVE, ALT_MODE_TERRAIN_FRAME = 0, 1, 4  # QGC's AltMode
ARDUSUB_FRAMES = ("terrain", "depth")
DEFAULT_MAX_ITEMS = 700
WPNAV_RADIUS_DEFAULT = 2.0  # m, ArduSub's WPNAV_RADIUS default, used for a 0 acceptance radius
_BISECTION_STEPS = 12


def admitted_cross_track(plan) -> float:
    """The largest distance (m) a flown leg may stray from the `CoveragePlan`'s path without
    opening a gap between neighbouring lanes.

    Lanes are `lane_spacing` apart under a footprint F = 2 Omega tan(a / 2); a lane shifted
    sideways by e and raised by h loses e + h tan(a / 2) of its overlap share (F - spacing) / 2.
    Over all 3D errors of length d that loss is at most d / cos(a / 2), so d may reach
    (F - spacing) cos(a / 2) / 2 (with overlap o and no survey order: o Omega sin(a / 2)).
    """
    half = np.radians(plan.parameters.aperture_deg) / 2.0
    footprint = 2.0 * plan.parameters.omega * np.tan(half)
    return float(max(footprint - plan.lane_spacing, 0.0) * np.cos(half) / 2.0)


def _waypoint_legs(wp: Waypoints) -> tuple[LocalLeg, ...]:
    """The waypoints as ArduSub legs in the local frame (frame 10 where they hold altitude)."""
    return tuple(LocalLeg("waypoint", (float(p[0]), float(p[1])),
                          "altitude" if a else "depth", float(h if a else -p[2]))
                 for p, a, h in zip(wp.points, wp.use_altitude, wp.altitude))


def _replay(wp: Waypoints, surface, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """ArduSub's flight through the waypoints from the first one (the descent from the surface
    is left to the pilot)."""
    return replay_ardusub(_waypoint_legs(wp), surface.elevation, wp.points[0], spacing)


def _subset(full: Waypoints, idx: np.ndarray) -> Waypoints:
    return Waypoints(full.index[idx], full.points[idx], full.altitude[idx], full.heading[idx],
                     full.labels[idx], full.use_altitude[idx])


def _make_safe(full: Waypoints, idx: np.ndarray, surface, omega: float, min_depth: float,
               spacing: float) -> np.ndarray:
    """`idx` (sorted path-sample indices) with path samples added back, Douglas-Peucker's
    split point of each leg that, flown as ArduSub flies it, comes nearer than omega / 2 to the
    seabed or shallower than `min_depth`; until no leg does or the bad legs join neighbouring
    samples."""
    held = np.column_stack([full.points[:, :2],
                            np.where(full.use_altitude, full.altitude, full.points[:, 2])])
    while True:
        pos, item = _replay(_subset(full, idx), surface, spacing)
        near = surface.distance(pos, upper_bound=0.5 * omega)[0] < 0.5 * omega
        bad = np.unique(item[near | (-pos[:, 2] < min_depth - 1e-6)])
        bad = bad[(bad > 0) & (idx[bad] - idx[np.maximum(bad - 1, 0)] > 1)]
        if not bad.size:
            return idx
        new = [idx[j - 1] + _farthest(held[idx[j - 1]:idx[j] + 1]) for j in bad]
        idx = np.union1d(idx, new)


def _farthest(points: np.ndarray) -> int:
    """Index of the interior sample farthest from the chord of `points` (Douglas-Peucker's
    split point)."""
    v = points[1:-1] - points[0]
    seg = points[-1] - points[0]
    seg2 = float(seg @ seg)
    t = np.clip(v @ seg / seg2, 0.0, 1.0) if seg2 > 1e-18 else np.zeros(len(v))
    return 1 + int(np.argmax(np.linalg.norm(v - t[:, None] * seg, axis=1)))


def _items(n_waypoints: int) -> int:
    """Items a board stores for one file: home, DO_CHANGE_SPEED, the waypoints."""
    return n_waypoints + 2


def _flown_path(path: PlannedPath, wp: Waypoints, surface, spacing: float) -> PlannedPath:
    """The replayed flight as a `PlannedPath`, each sample taking the sensor axis, heading and label of
    the path sample at the same fraction of its leg."""
    pos, item = _replay(wp, surface, spacing)
    a = wp.index[np.maximum(item - 1, 0)]
    b = wp.index[item]
    leg_start = np.searchsorted(item, item, side="left")
    leg_len = np.bincount(item)[item]
    frac = (np.arange(len(item)) - leg_start + 1) / leg_len
    src = np.rint(a + np.where(item > 0, frac, 1.0) * (b - a)).astype(int)
    return PlannedPath(pos, path.heading[src], path.sensor_dir[src], path.labels[src])


def _coverage(path: PlannedPath, plan) -> float:
    """Coverage of the valid cells, as `metrics.evaluate_plan` computes the total's."""
    p, s = plan.parameters, plan.surface
    m = evaluate_path(path, s, p.aperture_deg, p.sensor_range, p.omega,
                      {"total": (np.ones(len(path), dtype=bool), s.valid)},
                      surface_area_weights(s))
    return m["total"].coverage


@dataclass(frozen=True)
class QGCMission:
    """An ArduSub mission within a board's budget.

    Attributes:
        waypoints: all the waypoints, in order.
        parts: waypoint index ranges (start, stop) of each file; consecutive parts share a
            waypoint (the next file starts where the previous ended).
        tolerance: Douglas-Peucker tolerance used, m.
        admitted: cross-track error the coverage admits, m (`admitted_cross_track`).
        added: path samples put back for the legs' safety.
        frames: "terrain" or "depth".
    """

    waypoints: Waypoints
    parts: tuple[tuple[int, int], ...]
    tolerance: float
    admitted: float
    added: int
    frames: str

    def part(self, k: int) -> Waypoints:
        a, b = self.parts[k]
        return _subset(self.waypoints, np.arange(a, b))


def check_options(max_items, frames: str) -> None:
    """ValueError naming the option when `max_items` or `frames` is out of range."""
    if isinstance(max_items, bool) or not isinstance(max_items, (int, np.integer)) or max_items < 4:
        raise ValueError(f"--max-items must be an integer >= 4 (home, DO_CHANGE_SPEED and two "
                         f"waypoints), got {max_items!r}")
    if frames not in ARDUSUB_FRAMES:
        raise ValueError(f"--ardusub-frames must be one of {', '.join(ARDUSUB_FRAMES)}, got "
                         f"{frames!r}")


def budget_mission(plan, max_items: int = DEFAULT_MAX_ITEMS,
                   frames: str = "terrain") -> QGCMission:
    """The waypoints of `plan.path` for ArduSub within `max_items` per file (module docstring).

    Args:
        max_items: mission items a board stores per file, home and DO_CHANGE_SPEED included,
            >= 4.
        frames: "terrain" (frame 10 on lanes) or "depth" (frame 3 everywhere).
    """
    check_options(max_items, frames)
    p, surface, path = plan.parameters, plan.surface, plan.path
    labels = ALTITUDE_LABELS if frames == "terrain" else ()
    omega, min_depth = p.omega, p.min_depth
    pts = path.points
    altitude = pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1])
    # Lane samples held at the minimum depth (less than Omega above the seabed) are flown in
    # frame 3: following the seabed there would take the vehicle above that depth.
    ceiling = (pts[:, 2] >= -min_depth - 1e-9) & (altitude < omega - 1e-6)
    path = PlannedPath(pts, path.heading, path.sensor_dir,
                np.where(ceiling, "depth limited", path.labels).astype(object))
    full = Waypoints(np.arange(len(path)), pts, altitude, path.heading, path.labels,
                     np.isin(path.labels.astype(str), list(labels)))
    admitted = max(admitted_cross_track(plan), 1e-6)

    def safe(tol):
        idx = mission_waypoints(path, surface, tol, labels).index
        return _make_safe(full, idx, surface, omega, min_depth, 1.0)

    tol, idx = admitted, safe(admitted)
    if _items(len(idx)) <= max_items:  # the smallest tolerance that still fits
        lo, hi = np.log(admitted) - np.log(1e3), np.log(admitted)
        for _ in range(_BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            cand = safe(float(np.exp(mid)))
            if _items(len(cand)) <= max_items:
                hi, tol, idx = mid, float(np.exp(mid)), cand
            else:
                lo = mid
    base = len(mission_waypoints(path, surface, tol, labels))
    per = max_items - 2
    starts = list(range(0, max(len(idx) - 1, 1), per - 1))
    parts = tuple((a, min(a + per, len(idx))) for a in starts)
    return QGCMission(_subset(full, idx), parts, tol, float(admitted), len(idx) - base, frames)


def _open_ring(ring: np.ndarray) -> np.ndarray:
    ring = np.asarray(ring, float)
    return ring[:-1] if len(ring) > 1 and np.allclose(ring[0], ring[-1]) else ring


def qgc_plan(wp: Waypoints, geo: GeoFrame, speed: float = 0.5, acceptance_radius: float = 1.0,
             no_go_lonlat: list[np.ndarray] | None = None) -> dict:
    """The QGroundControl plan of the waypoints for ArduSub (see the module docstring).

    Args:
        speed: mission speed, m/s (> 0), sent as DO_CHANGE_SPEED and QGC's estimate.
        acceptance_radius: waypoint acceptance radius, m (> 0).
        no_go_lonlat: exterior rings (K, 2) of no-go zones in WGS 84 (lon, lat), closed or
            open, for the geofence's exclusion polygons.
    """
    for name, value in (("speed", speed), ("acceptance_radius", acceptance_radius)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be > 0, got {value}")
    lonlat = geo.to_lonlat(wp.points[:, :2])
    yaw_deg = np.degrees(geo.compass_yaw(wp.points[:, :2], wp.heading))
    items = [{"type": "SimpleItem", "command": MAV_CMD_DO_CHANGE_SPEED, "frame": MAV_FRAME_MISSION,
              "params": [1, float(speed), -1, 0, 0, 0, 0], "autoContinue": True, "doJumpId": 1}]
    for k in range(len(wp)):
        alt = bool(wp.use_altitude[k])
        value = round(float(wp.altitude[k] if alt else wp.points[k, 2]), 3)
        # Lanes keep the heading along the motion (yaw left to the autopilot); contours face
        # the wall, so their yaw is commanded.
        yaw = None if alt else round(float(yaw_deg[k]), 3)
        items.append({
            "type": "SimpleItem", "command": MAV_CMD_NAV_WAYPOINT,
            "frame": MAV_FRAME_GLOBAL_TERRAIN_ALT if alt else MAV_FRAME_GLOBAL_RELATIVE_ALT,
            "params": [0, float(acceptance_radius), 0, yaw, round(float(lonlat[k, 1]), 9),
                       round(float(lonlat[k, 0]), 9), value],
            "AltitudeMode": ALT_MODE_TERRAIN_FRAME if alt else ALT_MODE_RELATIVE,
            "Altitude": value, "AMSLAltAboveTerrain": round(float(wp.points[k, 2]), 3),
            "autoContinue": True, "doJumpId": k + 2,
        })
    modes = {i["AltitudeMode"] for i in items[1:]}
    fence = [{"inclusion": False, "version": 1,
              "polygon": [[round(float(lat), 9), round(float(lon), 9)]
                          for lon, lat in _open_ring(ring)]}
             for ring in (no_go_lonlat or [])]
    return {
        "fileType": "Plan", "version": 1, "groundStation": "drake_auv",
        "mission": {"version": 2, "firmwareType": MAV_AUTOPILOT_ARDUPILOTMEGA,
                    "vehicleType": MAV_TYPE_SUBMARINE, "cruiseSpeed": float(speed),
                    "hoverSpeed": float(speed),
                    "globalPlanAltitudeMode": modes.pop() if len(modes) == 1 else ALT_MODE_MIXED,
                    "plannedHomePosition": [round(float(lonlat[0, 1]), 9),
                                            round(float(lonlat[0, 0]), 9), 0.0],
                    "items": items},
        "geoFence": {"version": 2, "circles": [], "polygons": fence},
        "rallyPoints": {"version": 2, "points": []},
    }


def write_qgc(plan, geo: GeoFrame, outdir, max_items: int = DEFAULT_MAX_ITEMS,
              frames: str = "terrain", speed: float = 0.5,
              acceptance_radius: float = 1.0) -> tuple[list[Path], dict]:
    """Writes the plan's ArduSub mission into `outdir`: mission.plan, or mission_1.plan,
    mission_2.plan, ... when it needs more than `max_items` items per file.

    Returns the files and a summary for report.json: items (per file, home included), files,
    tolerance_m, cross_track_admitted_m, waypoints_added_for_safety, coverage_before,
    coverage_after (the plan's total coverage, and the same computed on the flight the
    replay gives), clearance (`clearance_report` of that flight)."""
    mission = budget_mission(plan, max_items, frames)
    zones = [geo.to_lonlat(ring) for ring in plan.no_go_rings]
    outdir = Path(outdir)
    n = len(mission.parts)
    files = [outdir / ("mission.plan" if n == 1 else f"mission_{k + 1}.plan") for k in range(n)]
    counts = []
    for k, name in enumerate(files):
        part = mission.part(k)
        with open_replacing(name) as f:
            json.dump(qgc_plan(part, geo, speed, acceptance_radius, zones), f, indent=1,
                      allow_nan=False)  # a NaN in an autopilot's file is a bug: refused
        counts.append(_items(len(part)))
    p = plan.parameters
    flown = _flown_path(plan.path, mission.waypoints, plan.surface, p.sample_spacing)
    before = (plan.metrics.total.coverage if plan.metrics is not None
              else _coverage(plan.path, plan))
    pos, _ = _replay(mission.waypoints, plan.surface, 1.0)
    summary = {"ardusub_frames": frames, "max_items": int(max_items), "items": counts,
               "files": [f.name for f in files], "tolerance_m": mission.tolerance,
               "cross_track_admitted_m": mission.admitted,
               "waypoints_added_for_safety": mission.added,
               "coverage_before": float(before), "coverage_after": float(_coverage(flown, plan)),
               "clearance": clearance_report(pos, plan.surface, p.omega, p.min_depth)}
    return files, summary


def write_export(plan, geo: GeoFrame, outdir: Path, options: ExportOptions,
                 missions: tuple) -> Exported:
    """`--export qgc`: mission.plan or mission_1.plan, ... (`write_qgc`), their summary and
    the missions read back."""
    files, summary = write_qgc(plan, geo, outdir, max_items=options.max_items,
                               frames=options.ardusub_frames, speed=options.surge_velocity,
                               acceptance_radius=options.tolerance_xy)
    return Exported(files, summary, tuple(read_qgc_plan(f) for f in files))


def check_export(options: ExportOptions) -> None:
    """`check_options` of the export's options."""
    check_options(options.max_items, options.ardusub_frames)


def report_warnings(figures: dict, parameters: dict) -> list[str]:
    """One line per violation `write_qgc`'s summary records: replayed samples nearer than
    Omega / 2 to the prior seabed or above the minimum depth."""
    files = figures["files"]
    name = f"{files[0] if len(files) == 1 else files[0] + ' to ' + files[-1]} (ArduSub)"
    return clearance_warnings(name, figures["clearance"], parameters["omega"],
                              parameters["min_depth"])


def report_note(figures: dict) -> str | None:
    """The files in upload order when the mission is split, else None."""
    if len(figures["files"]) == 1:
        return None
    order = ", then ".join(f"{f} ({n} items)" for f, n in zip(figures["files"],
                                                              figures["items"]))
    return (f"QGroundControl: the mission is split into {len(figures['files'])} files of at "
            f"most {figures['max_items']} items; upload and fly them in this order: {order} "
            "(each starts at the previous one's last waypoint).")

def _fail(source, where: str, what: str):
    raise ValueError(f"{source}: {where}: {what}")


def _number(source, where: str, value, name: str, lo=-np.inf, hi=np.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        _fail(source, where, f"{name} must be a number in [{lo}, {hi}], got {value!r}")
    return float(value)


def read_qgc_plan(filename) -> VehicleMission:
    """The ArduSub mission a QGroundControl plan holds: its NAV_WAYPOINTs as kind "waypoint"
    items (frame 3: depth = -alt; frame 10: altitude = alt), each with the speed of the last
    DO_CHANGE_SPEED before it, its acceptance radius as tolerance (0: ArduSub's WPNAV_RADIUS
    default, 2 m), its hold time and yaw. Anything else is a one-line ValueError naming the
    file and the item."""
    source = str(filename)
    try:
        text = Path(filename).read_text()
    except FileNotFoundError:
        raise FileNotFoundError(f"{source}: no such QGroundControl plan file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"{source}: cannot read the plan ({e})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise ValueError(f"{source}: not JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        _fail(source, "fileType", "must be \"Plan\" (a QGroundControl plan)")
    mission = doc.get("mission")
    if not isinstance(mission, dict) or not isinstance(mission.get("items"), list):
        _fail(source, "mission.items", "missing or not a list")
    if mission.get("firmwareType") != MAV_AUTOPILOT_ARDUPILOTMEGA:
        _fail(source, "mission.firmwareType",
              f"must be {MAV_AUTOPILOT_ARDUPILOTMEGA} (ArduPilot), got "
              f"{mission.get('firmwareType')!r}")
    speed, out = None, []
    for k, item in enumerate(mission["items"]):
        where = f"mission item {k}"
        if not isinstance(item, dict) or item.get("type") != "SimpleItem":
            _fail(source, where, "must be a SimpleItem (complex items are not read)")
        params = item.get("params")
        if not isinstance(params, list) or len(params) != 7:
            _fail(source, where, "params must be a list of 7 values")
        command = item.get("command")
        if command == MAV_CMD_DO_CHANGE_SPEED:
            v = _number(source, where, params[1], "DO_CHANGE_SPEED speed (param 2, m/s)", -1, 10)
            speed = v if v > 0 else speed  # -1 or 0: unchanged
            continue
        if command != MAV_CMD_NAV_WAYPOINT:
            _fail(source, where, f"command {command!r} is not read (only 16 NAV_WAYPOINT and "
                                 "178 DO_CHANGE_SPEED)")
        frame = item.get("frame")
        if frame not in (MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_TERRAIN_ALT):
            _fail(source, where, f"frame must be 3 (relative, depth) or 10 (terrain), got "
                                 f"{frame!r}")
        hold = _number(source, where, params[0], "hold (param 1, s)", 0, MAX_HOLD_S)
        radius = _number(source, where, params[1], "acceptance radius (param 2, m)", 0)
        yaw = None if params[3] is None else _number(source, where, params[3],
                                                     "yaw (param 4, deg)", -360, 360)
        lat = _number(source, where, params[4], "latitude (param 5)", -90, 90)
        lon = _number(source, where, params[5], "longitude (param 6)", -180, 180)
        if frame == MAV_FRAME_GLOBAL_TERRAIN_ALT:
            z_mode, z = "altitude", _number(source, where, params[6],
                                            "frame-10 altitude above the seabed (param 7, m)", 0)
        else:
            z_mode, z = "depth", -_number(source, where, params[6],
                                          "frame-3 altitude (param 7, m, below the surface)",
                                          hi=0)
        out.append(MissionItem("waypoint", lat, lon, z_mode, z, speed=speed,
                               tolerance=radius if radius > 0 else WPNAV_RADIUS_DEFAULT,
                               hold_s=hold, yaw=None if yaw is None else float(np.radians(yaw))))
    if not out:
        _fail(source, "mission.items", "holds no NAV_WAYPOINT")
    return VehicleMission("ardusub", tuple(out), source=source)
