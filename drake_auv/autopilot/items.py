"""The items of a vehicle mission file, as its reader returns them, and in the local frame.

A reader (`drake_auv.formats.cola2.read_cola2`, `drake_auv.formats.qgc.read_qgc_plan`)
returns a `VehicleMission`: the file's items in order, positions in WGS 84 as the file holds
them, every vertical reference with the mode the autopilot holds it in. `localise` turns them
into `LocalLeg`s in a site's local frame (world xy, z up) for the replay and the pilot.
Pure Python, no Drake.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AUTOPILOTS = ("cola2", "ardusub")
ITEM_KINDS = ("goto", "section", "park", "waypoint")
Z_MODES = ("depth", "altitude")
# The longest hold at an item, s: a COLA2 park or an ArduSub hold longer than an hour is not
# part of a survey, and the dive's simulation would run through it.
MAX_HOLD_S = 3600.0


@dataclass(frozen=True)
class MissionItem:
    """One item of a vehicle mission (a COLA2 maneuver, an ArduSub NAV_WAYPOINT).

    Attributes:
        kind: "goto", "section", "park" (COLA2) or "waypoint" (ArduSub AUTO).
        lat, lon: final position, WGS 84 degrees.
        z_mode: "depth" (z is a depth below the sea surface, m, positive down) or "altitude"
            (z is a height above the seabed, m).
        z: the final vertical reference in `z_mode`, m.
        start_lat, start_lon, start_depth: a COLA2 section's initial point (degrees, degrees,
            m positive down); None for other kinds.
        speed: commanded speed along the item, m/s (COLA2 surge_velocity; ArduSub: the last
            DO_CHANGE_SPEED before it); None: the autopilot's default.
        tolerance: arrival tolerance, m (COLA2 tolerance_xy, horizontal; ArduSub acceptance
            radius, 3D).
        hold_s: time held at the item's position once reached, s (COLA2 park time, ArduSub
            hold param).
        yaw: heading, rad clockwise from true north (NED), None: along the motion.
    """

    kind: str
    lat: float
    lon: float
    z_mode: str
    z: float
    start_lat: float | None = None
    start_lon: float | None = None
    start_depth: float | None = None
    speed: float | None = None
    tolerance: float = 1.0
    hold_s: float = 0.0
    yaw: float | None = None

    def __post_init__(self):
        if self.kind not in ITEM_KINDS:
            raise ValueError(f"mission item kind must be one of {ITEM_KINDS}, got {self.kind!r}")
        if self.z_mode not in Z_MODES:
            raise ValueError(f"mission item z_mode must be one of {Z_MODES}, got "
                             f"{self.z_mode!r}")
        for name in ("lat", "lon", "z", "tolerance", "hold_s"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"mission item {name} must be finite, got "
                                 f"{getattr(self, name)}")
        if not 0.0 <= self.hold_s <= MAX_HOLD_S:
            raise ValueError(f"mission item hold_s must be in [0, {MAX_HOLD_S:g}] s, got "
                             f"{self.hold_s}")


@dataclass(frozen=True)
class VehicleMission:
    """A mission file's items in order.

    Attributes:
        autopilot: "cola2" or "ardusub" (whose semantics fly it).
        items: the items, in the order flown.
        heave_in_3d: COLA2 only: the vehicle interpolates depth along a section from its
            initial to its final depth (COLA2's `heave_in_3D`); False: it holds the final
            depth (or altitude) from the section's start.
        source: the file it was read from (for messages), or "".
    """

    autopilot: str
    items: tuple[MissionItem, ...]
    heave_in_3d: bool = False
    source: str = ""

    def __post_init__(self):
        if self.autopilot not in AUTOPILOTS:
            raise ValueError(f"autopilot must be one of {AUTOPILOTS}, got {self.autopilot!r}")

    def __len__(self) -> int:
        return len(self.items)


@dataclass(frozen=True)
class LocalLeg:
    """A mission item in a site's local frame (x, y in m, z up, sea surface z = 0).

    Attributes:
        kind, z_mode, z, speed, tolerance, hold_s: as in `MissionItem`.
        end: (2,) the item's final xy, m.
        start: (2,) a section's initial xy (None: from wherever the vehicle is).
        start_z: a section's initial elevation (-start_depth), m, or None.
        yaw: heading in the local frame, rad counter-clockwise from +x, or None.
    """

    kind: str
    end: tuple
    z_mode: str
    z: float
    start: tuple | None = None
    start_z: float | None = None
    speed: float | None = None
    tolerance: float = 1.0
    hold_s: float = 0.0
    yaw: float | None = None


def leg_target_z(leg: LocalLeg, seabed_z: float) -> float:
    """The elevation the item's final vertical reference means over `seabed_z`, m."""
    return -leg.z if leg.z_mode == "depth" else seabed_z + leg.z


def localise(mission: VehicleMission, lonlat_to_local, north_azimuth=None) -> tuple[LocalLeg, ...]:
    """The mission's items as `LocalLeg`s.

    Args:
        lonlat_to_local: callable (N, 2) WGS 84 (lon, lat) -> (N, 2) local xy, m.
        north_azimuth: callable (N, 2) local xy -> (N,) azimuth of the local +y axis from true
            north, rad (clockwise), to turn NED yaws into local ones; None: grid north is true
            north.
    """
    items = mission.items
    ends = lonlat_to_local(np.array([[it.lon, it.lat] for it in items], float))
    starts = {k: it for k, it in enumerate(items) if it.start_lat is not None}
    start_xy = (lonlat_to_local(np.array([[starts[k].start_lon, starts[k].start_lat]
                                          for k in starts], float)) if starts else [])
    start_of = dict(zip(starts, start_xy))
    grid_north = (north_azimuth(ends) if north_azimuth is not None else np.zeros(len(items)))
    legs = []
    for k, it in enumerate(items):
        yaw = None if it.yaw is None else float(np.pi / 2 - (it.yaw - grid_north[k]))
        start = tuple(map(float, start_of[k])) if k in start_of else None
        legs.append(LocalLeg(it.kind, (float(ends[k, 0]), float(ends[k, 1])), it.z_mode,
                             float(it.z), start,
                             None if it.start_depth is None else -float(it.start_depth),
                             it.speed, float(it.tolerance), float(it.hold_s), yaw))
    return tuple(legs)


@dataclass(frozen=True)
class FlownMission:
    """A vehicle mission as one leg flies it.

    Attributes:
        autopilot: "cola2" or "ardusub" (`items.AUTOPILOTS`).
        legs: its items in the local frame (`items.localise`), at least one.
        heave_in_3d: COLA2's heave_in_3D (depth interpolated along sections).
        default_speed: m/s where an item gives none (ArduSub before any DO_CHANGE_SPEED).
        source: the file's name, for messages.
    """

    autopilot: str
    legs: tuple[LocalLeg, ...]
    heave_in_3d: bool = False
    default_speed: float = 0.5
    source: str = ""

    def __post_init__(self):
        if self.autopilot not in AUTOPILOTS:
            raise ValueError(f"FlownMission autopilot must be one of {AUTOPILOTS}, got "
                             f"{self.autopilot!r}")
        if not self.legs:
            raise ValueError(f"{self.source or 'the mission'} has no item to fly")
        if not (np.isfinite(self.default_speed) and self.default_speed > 0):
            raise ValueError(f"FlownMission default_speed must be > 0 m/s, got "
                             f"{self.default_speed}")

    def speed(self, leg: LocalLeg) -> float:
        return leg.speed if leg.speed is not None else self.default_speed


METRES_PER_DEGREE = 111_320.0  # of latitude, on the WGS 84 ellipsoid (within 0.6 %)


def _decimals(value: float) -> int:
    """Decimals of `value` as written (its shortest round-trip form)."""
    text = np.format_float_positional(float(value), trim="-")
    return len(text.split(".")[1]) if "." in text else 0


def position_tolerance(mission: VehicleMission) -> float:
    """How far past a site's edge (m) the file's items may lie and still be the site's: two
    units of the last decimal its latitudes and longitudes are written with, on the ground
    (each rounded by up to half a unit; twice that covers both and the re-projection), 0.22 m
    for 6 decimals, 0.22 mm for the 9 the exports write; a file with fewer than 5 is judged as
    one with 5 (2.2 m: coarser positions are no file for one site)."""
    values = [v for item in mission.items
              for v in (item.lat, item.lon, item.start_lat, item.start_lon) if v is not None]
    return 2.0 * 10.0 ** -max(5, *(_decimals(v) for v in values)) * METRES_PER_DEGREE


def item_positions(mission: VehicleMission, legs: tuple[LocalLeg, ...], seabed_z,
                   source: str) -> tuple[np.ndarray, list[str]]:
    """(n, 3) where the items put the vehicle, local frame: each item's end (an altitude over
    `seabed_z`, (len(legs),) m, the seabed's elevation under each end; NaN: not judged) and a
    COLA2 section's start; and a name for each, for messages ("<source>: item k at lon .., lat
    ..")."""
    points, names = [], []
    for k, (item, leg, seabed) in enumerate(zip(mission.items, legs, seabed_z)):
        name = f"{source}: item {k + 1} at lon {item.lon:.6f}, lat {item.lat:.6f}"
        z = leg_target_z(leg, float(seabed))
        if np.isfinite(z):
            points.append([*leg.end, z])
            names.append(name)
        if leg.start is not None and leg.start_z is not None:
            points.append([*leg.start, leg.start_z])
            names.append(f"{name} (its start at lon {item.start_lon:.6f}, lat "
                         f"{item.start_lat:.6f})")
    return np.array(points, float).reshape(-1, 3), names
