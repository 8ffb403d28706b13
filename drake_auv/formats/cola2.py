"""COLA2 mission XML (GIRONA 500) from a `PlannedPath`, with sections chosen to hold under COLA2's
execution semantics, and its reader.

COLA2 flies a section toward its final point holding the section's FINAL depth (heave_mode 0)
or final altitude above the seabed (heave_mode 1) from the section's start; only a vehicle
configured with `heave_in_3D` interpolates the depth along a depth-mode section
(`autopilot.cola2` models it, docs/planning.md says where it was read). So the waypoints of a
path are not enough: `cola2_sections` splits the path greedily into sections whose held target,
replayed with `autopilot.cola2.held_band` (the change from the previous z included), keeps
0.5 Omega from the prior seabed (`TerrainSurface.safe_elevation_at`; where the minimum depth
leaves less, the section holds the minimum depth) and stays at or below the minimum depth, and
whose held positions stay within `deviation` (m, 3D) of every path sample they replace; where
none can, the shortest section holds the lowest safe depth. A section is depth mode where any
of its samples is held at the minimum depth or lies off the lanes (contours, transits), else
altitude mode (the DVL holds the offset over planar terrain). No section is shorter than
tolerance_xy: COLA2 ends a section once within it of the final point.

COLA2 mission format 2.0 (field names as cola2_lib's mission loader reads them):
`<mission><version>2.0</version>` then `<mission_step>`s with one `<maneuver
type="goto|section|park">`: a goto to the path's first sample, the sections, a park at the end.
heave_mode 0 = depth, 1 = altitude (2 = altitude where the DVL has it, else depth); depths
positive down, m; yaw radians clockwise from true north (NED).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.autopilot.cola2 import DEFAULT_SURGE, HEAVE_SPEED, held_band, replay_cola2
from drake_auv.autopilot.items import MAX_HOLD_S, MissionItem, VehicleMission, localise
from drake_auv.autopilot.replay import clearance_report, clearance_warnings
from drake_auv.formats import Exported, ExportOptions
from drake_auv.output_files import replacing
from drake_auv.terrain.geo import GeoFrame
from drake_auv.planning.missions import ALTITUDE_LABELS
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.surface import TerrainSurface


_EPS = 1e-9
DEVIATION_SHARE = 0.1  # default deviation tolerance, a share of Omega


@dataclass(frozen=True)
class Cola2Sections:
    """A COLA2 mission's geometry, world frame (z up, m).

    Attributes:
        points: (K+1, 3) the first sample (the goto's point) then each section's final point,
            z the elevation the vehicle holds there.
        index: (K+1,) the path sample each point stands for.
        altitude_mode: (K,) True where a section holds altitude (heave_mode 1), else depth.
        altitude: (K+1,) height of each point above the seabed below it, m.
        heading: (K+1,) yaw of the body x axis at each point, rad (world, from +x).
        deviation: (K,) largest 3D distance from a replaced path sample to the held position
            at its projection on the section, m.
        unresolved: sections where no target met the clearance (the lowest safe depth used).
        heave_in_3d: written for vehicles configured with COLA2's heave_in_3D.
    """

    points: np.ndarray
    index: np.ndarray
    altitude_mode: np.ndarray
    altitude: np.ndarray
    heading: np.ndarray
    deviation: np.ndarray
    unresolved: int = 0
    heave_in_3d: bool = False

    def __len__(self) -> int:
        return len(self.altitude_mode)


class _Splitter:
    """The greedy section search on one path (see the module docstring)."""

    def __init__(self, path, surface, omega, min_depth, deviation, tolerance_xy, speed,
                 heave_in_3d, heave_speed, spacing):
        self.surface, self.omega, self.ceiling = surface, float(omega), -float(min_depth)
        self.p = path.points
        self.xy = self.p[:, :2]
        self.alt = self.p[:, 2] - surface.elevation(self.p[:, 0], self.p[:, 1])
        held = self.p[:, 2] >= self.ceiling - 1e-6
        depth = held | ~np.isin(path.labels.astype(str), ALTITUDE_LABELS)
        self.depth_count = np.concatenate([[0], np.cumsum(depth)])
        self.deviation, self.tol = float(deviation), float(tolerance_xy)
        self.band_kw = dict(heave_in_3d=heave_in_3d, spacing=spacing, speed=speed,
                            heave_speed=heave_speed)
        self._need_lattice(self.omega)

    def _need_lattice(self, omega):
        """Lowest safe elevation on a square lattice of spacing h over the path's extent,
        for a radius grown by h / sqrt(2): a point is at least that far from its nearest node,
        so the node's value bounds the point's from above (conservative)."""
        h = omega / 8.0
        lo = self.xy.min(axis=0) - 2 * h
        n = np.ceil((self.xy.max(axis=0) + 2 * h - lo) / h).astype(int) + 1
        gx, gy = np.meshgrid(lo[0] + h * np.arange(n[0]), lo[1] + h * np.arange(n[1]))
        z = self.surface.safe_elevation_at(gx.ravel(), gy.ravel(), 0.5 * omega + h / np.sqrt(2))
        self.lattice = (lo, h, np.minimum(z, self.ceiling).reshape(gx.shape))

    def need(self, xy):
        """Lowest elevation the held z may take at xy (from the lattice): 0.5 Omega off the
        surface, or the minimum depth where that is above it."""
        lo, h, grid = self.lattice
        j = np.clip(np.rint((xy[:, 0] - lo[0]) / h).astype(int), 0, grid.shape[1] - 1)
        i = np.clip(np.rint((xy[:, 1] - lo[1]) / h).astype(int), 0, grid.shape[0] - 1)
        return grid[i, j]

    def first_reach(self, a):
        """Smallest b > a with the xy chord a->b at least tolerance_xy long, or None."""
        n, width = len(self.p), 64
        while True:
            d = np.hypot(*(self.xy[a + 1:a + 1 + width] - self.xy[a]).T)
            hit = np.flatnonzero(d >= self.tol)
            if hit.size:
                return a + 1 + int(hit[0])
            if a + 1 + width >= n:
                return None
            width *= 4

    def evaluate(self, a, b, z0, altitude, target, limit=np.inf):
        """(safe, deviation, end z) of the section a->b holding `target` (altitude above the
        seabed, or elevation) with the vehicle starting at elevation z0; a deviation over
        `limit` returns at once (unsafe)."""
        seg = self.xy[b] - self.xy[a]
        v = self.xy[a:b + 1] - self.xy[a]
        t = np.clip(v @ seg / max(float(seg @ seg), 1e-18), 0.0, 1.0)
        proj = self.xy[a] + t[:, None] * seg
        if altitude:
            z_held = self.surface.elevation(proj[:, 0], proj[:, 1]) + target
        elif self.band_kw["heave_in_3d"]:
            z_held = z0 + t * (target - z0)
        else:
            z_held = np.full(len(t), target)
        dev = float(np.max(np.hypot(np.hypot(*(v - t[:, None] * seg).T),
                                    z_held - self.p[a:b + 1, 2])))
        if dev > limit:
            return False, dev, np.nan
        xy, z_f, z_c = held_band(self.xy[a], self.xy[b], altitude, target, z0,
                                 self.surface.elevation, start_z=z0, **self.band_kw)
        safe = bool(np.all(np.minimum(z_f, z_c) >= self.need(xy) - _EPS)
                    and np.all(np.maximum(z_f, z_c) <= self.ceiling + _EPS))
        return safe, dev, float(z_c[-1])

    def natural(self, a, b, z0):
        """The section a->b at the path's own target: (ok, altitude_mode, deviation, end z);
        not ok when shorter than tolerance_xy (a path that doubles back)."""
        if np.hypot(*(self.xy[b] - self.xy[a])) < self.tol:
            return False, False, np.inf, np.nan
        altitude = self.depth_count[b + 1] == self.depth_count[a + 1]
        target = self.alt[b] if altitude else self.p[b, 2]
        safe, dev, z_end = self.evaluate(a, b, z0, altitude, target, self.deviation)
        return safe and dev <= self.deviation, altitude, dev, z_end

    def lifted(self, a, b, z0):
        """The section a->b in depth mode at the lowest safe elevation at or above the path's:
        (safe, deviation, end z)."""
        n = max(int(np.ceil(np.hypot(*(self.xy[b] - self.xy[a])) / self.band_kw["spacing"])), 1)
        chord = self.xy[a] + np.linspace(0, 1, n + 1)[:, None] * (self.xy[b] - self.xy[a])
        target = min(max(self.p[b, 2], float(self.need(chord).max()) + 1e-3), self.ceiling)
        safe, dev, z_end = self.evaluate(a, b, z0, False, target)
        return safe, dev, z_end

    def section_from(self, a, z0, guess=1):
        """The longest acceptable section from sample a (galloping, then bisection):
        (b, altitude_mode, deviation, end z, resolved) or None when the path ends within
        tolerance_xy of sample a. The gallop's first step is `guess` samples (the previous
        section's length: lanes repeat)."""
        b_min = self.first_reach(a)
        if b_min is None:
            return None
        n = len(self.p)
        ok, altitude, dev, z_end = self.natural(a, b_min, z0)
        if not ok:
            safe, dev, z_end = self.lifted(a, b_min, z0)
            return b_min, False, dev, z_end, safe
        good, bad, step = (b_min, altitude, dev, z_end), None, max(int(guess), 1)
        while good[0] < n - 1:
            cand = min(b_min + step, n - 1)
            res = self.natural(a, cand, z0)
            if not res[0]:
                bad = cand
                break
            good, step = (cand, *res[1:]), step * 2
        if bad is not None:
            lo_b, hi_b = good[0], bad
            while hi_b - lo_b > 1:
                mid = (lo_b + hi_b) // 2
                res = self.natural(a, mid, z0)
                if res[0]:
                    good, lo_b = (mid, *res[1:]), mid
                else:
                    hi_b = mid
        return (*good, True)

    def end_at_last(self, a, z0):
        """The section from a to the path's last sample (the tail shorter than tolerance_xy
        joins the section before it)."""
        b = len(self.p) - 1
        ok, altitude, dev, z_end = self.natural(a, b, z0)
        if ok:
            return b, altitude, dev, z_end, True
        safe, dev, z_end = self.lifted(a, b, z0)
        return b, False, dev, z_end, safe


def cola2_sections(path: PlannedPath, surface: TerrainSurface, omega: float, min_depth: float, *,
                   deviation: float | None = None, tolerance_xy: float = 1.0,
                   surge_velocity: float = DEFAULT_SURGE, heave_in_3d: bool = False,
                   heave_speed: float = HEAVE_SPEED, spacing: float = 1.0) -> Cola2Sections:
    """Sections of `path` that hold under COLA2's semantics (see the module docstring).

    Args:
        omega: the plan's offset, m (> 0): every held target keeps 0.5 omega from `surface`.
        min_depth: minimum operating depth, m (>= 0).
        deviation: largest 3D distance from a path sample to the held position, m (> 0;
            default 0.1 omega).
        tolerance_xy: COLA2's arrival tolerance, m (> 0): the shortest section.
        surge_velocity, heave_speed: m/s, the replay's transition model (`autopilot.cola2`).
        heave_in_3d: the vehicle interpolates depth along depth-mode sections.
        spacing: largest distance between checked samples along a section, m.
    """
    deviation = DEVIATION_SHARE * omega if deviation is None else deviation
    for name, value in (("omega", omega), ("deviation", deviation),
                        ("tolerance_xy", tolerance_xy), ("surge_velocity", surge_velocity),
                        ("heave_speed", heave_speed), ("spacing", spacing)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"COLA2 sections: {name} must be > 0, got {value}")
    if len(path) < 2:
        raise ValueError(f"COLA2 sections need a path of at least 2 samples, got {len(path)}")
    sp = _Splitter(path, surface, omega, min_depth, deviation, tolerance_xy, surge_velocity,
                   heave_in_3d, heave_speed, spacing)
    index, modes, devs, ends, resolved = [0], [], [], [float(path.points[0, 2])], []
    a = 0
    while a < len(path) - 1:
        res = sp.section_from(a, ends[-1], index[-1] - index[-2] if len(index) > 1 else 1)
        if res is None:
            if not modes:
                raise ValueError(f"the path lies within tolerance_xy = {tolerance_xy} m of its "
                                 "first sample: no COLA2 section can be made")
            for lst in (index, ends):
                lst.pop()
            for lst in (modes, devs, resolved):
                lst.pop()
            res = sp.end_at_last(index[-1], ends[-1])
        b, altitude, dev, z_end, ok = res
        index.append(b)
        modes.append(altitude)
        devs.append(dev)
        ends.append(z_end)
        resolved.append(ok)
        a = b
    idx = np.array(index)
    pts = path.points[idx].copy()
    pts[:, 2] = ends
    alt = pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1])
    return Cola2Sections(pts, idx, np.array(modes, bool), alt, path.heading[idx],
                         np.array(devs), int(len(resolved) - sum(resolved)), bool(heave_in_3d))


def _text(parent, tag: str, value) -> None:
    el = ET.SubElement(parent, tag)
    if isinstance(value, bool):
        el.text = "true" if value else "false"
    elif isinstance(value, (int, np.integer)):
        el.text = str(int(value))
    else:
        el.text = f"{float(value):.9f}"  # 1e-9 deg of latitude is 0.1 mm


def cola2_mission(sections: Cola2Sections, geo: GeoFrame, surge_velocity: float = DEFAULT_SURGE,
                  tolerance_xy: float = 1.0, park_time: float = 10.0) -> ET.ElementTree:
    """The COLA2 mission (version 2.0) of the sections: goto, sections, park.

    Args:
        surge_velocity: commanded forward speed, m/s (> 0).
        tolerance_xy: horizontal arrival tolerance, m (> 0).
        park_time: time holding the last point, s (>= 0).
    """
    for name, value, ok in (("surge_velocity", surge_velocity, surge_velocity > 0),
                            ("tolerance_xy", tolerance_xy, tolerance_xy > 0),
                            ("park_time", park_time, park_time >= 0)):
        if not (np.isfinite(value) and ok):
            raise ValueError(f"{name} must be {'>= 0' if name == 'park_time' else '> 0'}, "
                             f"got {value}")
    pts = sections.points
    lonlat = geo.to_lonlat(pts[:, :2])
    depth = -pts[:, 2]
    # The goto and the park hold the mode of the first and last section.
    mode = np.concatenate([sections.altitude_mode[:1], sections.altitude_mode,
                           sections.altitude_mode[-1:]])
    root = ET.Element("mission")
    ET.SubElement(root, "version").text = "2.0"

    def final(man, k, altitude):
        _text(man, "final_latitude", lonlat[k, 1])
        _text(man, "final_longitude", lonlat[k, 0])
        _text(man, "final_depth", depth[k])
        _text(man, "final_altitude", sections.altitude[k])
        _text(man, "heave_mode", 1 if altitude else 0)
        _text(man, "surge_velocity", surge_velocity)

    for k in range(len(pts)):
        step = ET.SubElement(root, "mission_step")
        man = ET.SubElement(step, "maneuver", type="goto" if k == 0 else "section")
        if k:
            _text(man, "initial_latitude", lonlat[k - 1, 1])
            _text(man, "initial_longitude", lonlat[k - 1, 0])
            _text(man, "initial_depth", depth[k - 1])
        final(man, k, bool(mode[k]))
        _text(man, "tolerance_xy", tolerance_xy)
        _text(man, "no_altitude_goes_up", True)
    step = ET.SubElement(root, "mission_step")
    man = ET.SubElement(step, "maneuver", type="park")
    final(man, len(pts) - 1, bool(mode[-1]))
    _text(man, "final_yaw", geo.compass_yaw(pts[-1:, :2], sections.heading[-1:])[0])
    _text(man, "use_yaw", False)
    _text(man, "time", park_time)
    _text(man, "no_altitude_goes_up", True)
    ET.indent(root)
    return ET.ElementTree(root)


def write_cola2(sections: Cola2Sections, geo: GeoFrame, filename, **kwargs) -> None:
    """Writes `cola2_mission` to `filename` (UTF-8 XML with a declaration)."""
    with replacing(filename) as temporary:
        cola2_mission(sections, geo, **kwargs).write(temporary, encoding="utf-8",
                                                     xml_declaration=True)


# -- reading -------------------------------------------------------------------------------------
_FINAL = ("final_latitude", "final_longitude", "final_depth", "final_altitude", "heave_mode",
          "surge_velocity")
REQUIRED = {
    "goto": _FINAL + ("tolerance_xy", "no_altitude_goes_up"),
    "section": ("initial_latitude", "initial_longitude", "initial_depth") + _FINAL
    + ("tolerance_xy", "no_altitude_goes_up"),
    "park": _FINAL + ("final_yaw", "use_yaw", "time", "no_altitude_goes_up"),
}
_BOOLS = ("no_altitude_goes_up", "use_yaw")
HEAVE_MODES = {0: "depth", 1: "altitude", 2: "altitude"}  # 2: altitude where the DVL has it


def _fields(name: str, k: int, kind: str, man) -> dict:
    """The maneuver's required fields, parsed and range-checked; ValueError naming the field."""
    out = {}
    for tag in REQUIRED[kind]:
        el = man.find(tag)
        where = f"{name}: mission_step {k}: {kind} field {tag!r}"
        if el is None or not (el.text or "").strip():
            raise ValueError(f"{where} is missing")
        text = el.text.strip()
        if tag in _BOOLS:
            if text.lower() not in ("true", "false"):
                raise ValueError(f"{where} must be 'true' or 'false', got {text!r}")
            out[tag] = text.lower() == "true"
            continue
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"{where} must be a number, got {text!r}") from None
        if not np.isfinite(value):
            raise ValueError(f"{where} must be finite, got {text!r}")
        if tag.endswith("latitude") and not -90 <= value <= 90:
            raise ValueError(f"{where} must be in [-90, 90] degrees, got {value}")
        if tag.endswith("longitude") and not -180 <= value <= 180:
            raise ValueError(f"{where} must be in [-180, 180] degrees, got {value}")
        if tag == "heave_mode" and value not in HEAVE_MODES:
            raise ValueError(f"{where} must be 0 (depth), 1 (altitude) or 2 (both), got {text}")
        if tag in ("surge_velocity", "tolerance_xy", "time") and value < 0:
            raise ValueError(f"{where} must be >= 0, got {value}")
        if tag == "time" and value > MAX_HOLD_S:
            raise ValueError(f"{where} must be in [0, {MAX_HOLD_S:g}] s, got {value}")
        out[tag] = value
    return out


def read_cola2(path) -> VehicleMission:
    """Reads a COLA2 mission file (format 2.0) into a `VehicleMission`.

    Checks what cola2_lib's loader needs: an XML `<mission>` with `<version>` 2.0, every
    `<mission_step>` holding one `<maneuver>` of type goto, section or park with its fields
    (numbers; latitudes in [-90, 90], longitudes in [-180, 180]; heave_mode 0, 1 or 2).
    Raises FileNotFoundError / ValueError in one line naming the file, the step (from 1) and
    the field.
    """
    name = str(path)
    if not Path(path).is_file():
        raise FileNotFoundError(f"{name}: no such COLA2 mission file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise ValueError(f"{name}: not a COLA2 mission: not XML ({err})") from None
    except OSError as err:
        raise ValueError(f"{name}: cannot read: {err.strerror or err}") from None
    if root.tag != "mission":
        raise ValueError(f"{name}: not a COLA2 mission: root element <{root.tag}>, expected "
                         "<mission>")
    version = root.find("version")
    if version is None or (version.text or "").strip() not in ("2.0", "2"):
        got = "missing" if version is None else repr((version.text or "").strip())
        raise ValueError(f"{name}: COLA2 mission <version> must be 2.0, got {got}")
    items = []
    for k, step in enumerate(root.findall("mission_step"), start=1):
        mans = step.findall("maneuver")
        if len(mans) != 1:
            raise ValueError(f"{name}: mission_step {k}: expected one <maneuver>, got "
                             f"{len(mans)}")
        kind = mans[0].get("type")
        if kind not in REQUIRED:
            raise ValueError(f"{name}: mission_step {k}: unknown maneuver type {kind!r}; "
                             f"choose from {', '.join(REQUIRED)}")
        f = _fields(name, k, kind, mans[0])
        z_mode = HEAVE_MODES[int(f["heave_mode"])]
        items.append(MissionItem(
            kind, f["final_latitude"], f["final_longitude"], z_mode,
            f["final_altitude"] if z_mode == "altitude" else f["final_depth"],
            start_lat=f.get("initial_latitude"), start_lon=f.get("initial_longitude"),
            start_depth=f.get("initial_depth"), speed=f["surge_velocity"] or None,
            tolerance=f.get("tolerance_xy", 1.0), hold_s=f.get("time", 0.0),
            yaw=f["final_yaw"] if f.get("use_yaw") else None))
    if not items:
        raise ValueError(f"{name}: COLA2 mission has no <mission_step>")
    return VehicleMission("cola2", tuple(items), source=name)


def export_cola2(path: PlannedPath, surface: TerrainSurface, omega: float, min_depth: float,
                 geo: GeoFrame, filename, surge_velocity: float = DEFAULT_SURGE,
                 tolerance_xy: float = 1.0, heave_in_3d: bool = False) -> dict:
    """Writes the COLA2 mission of `path` to `filename`, reads it back (`read_cola2`), replays
    it as COLA2 flies it from its first point (`autopilot.cola2`) and returns the figures for
    the report: sections, altitude-mode sections, the largest deviation from the path, the
    sections over the deviation tolerance (depth changing faster than it holds without
    heave_in_3d) or unresolved, and the replay's `clearance_report`."""
    from drake_auv.autopilot.cola2 import replay_cola2
    from drake_auv.autopilot.replay import clearance_report
    from drake_auv.autopilot.items import localise

    sections = cola2_sections(path, surface, omega, min_depth, tolerance_xy=tolerance_xy,
                              surge_velocity=surge_velocity, heave_in_3d=heave_in_3d)
    write_cola2(sections, geo, filename, surge_velocity=surge_velocity,
                tolerance_xy=tolerance_xy)
    legs = localise(read_cola2(filename), geo.from_lonlat, geo.grid_north_azimuth)
    positions, _ = replay_cola2(legs, surface.elevation, sections.points[0],
                                heave_in_3d=heave_in_3d)
    over = int((sections.deviation > DEVIATION_SHARE * omega + 1e-9).sum())
    return {"sections": len(sections), "altitude_sections": int(sections.altitude_mode.sum()),
            "heave_in_3d": bool(heave_in_3d), "deviation_tolerance_m": DEVIATION_SHARE * omega,
            "max_deviation_m": float(sections.deviation.max()),
            "sections_over_deviation": over,
            "unresolved_sections": sections.unresolved,
            "replay": clearance_report(positions, surface, omega, min_depth)}


def write_export(plan, geo: GeoFrame, outdir: Path, options: ExportOptions,
                 missions: tuple) -> Exported:
    """`--export cola2`: mission.xml (`export_cola2`), its figures and the mission read back."""
    filename = outdir / "mission.xml"
    figures = export_cola2(plan.path, plan.surface, plan.parameters.omega,
                           plan.parameters.min_depth, geo, filename, options.surge_velocity,
                           options.tolerance_xy, options.heave_in_3d)
    return Exported([filename], figures, (read_cola2(filename),))


def report_warnings(figures: dict, parameters: dict) -> list[str]:
    """One line per violation `export_cola2`'s `figures` record: sections beyond the deviation
    tolerance or unresolved, and replayed samples nearer than Omega / 2 to the prior seabed or
    above the minimum depth."""
    c, name, out = figures, "mission.xml (COLA2)", []
    if c["sections_over_deviation"]:
        out.append(f"{name}: {c['sections_over_deviation']} of {c['sections']} sections "
                   f"stray more than the {c['deviation_tolerance_m']:g} m deviation "
                   f"tolerance from the path (worst {c['max_deviation_m']:.2f} m)")
    if c["unresolved_sections"]:
        out.append(f"{name}: {c['unresolved_sections']} sections hold the lowest safe depth "
                   "(no target kept Omega / 2 from the seabed within the tolerance)")
    return out + clearance_warnings(name, c["replay"], parameters["omega"],
                                    parameters["min_depth"])
