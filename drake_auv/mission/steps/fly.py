"""The `fly` step: an exported vehicle mission (COLA2 mission XML, QGroundControl plan)
flown the way its autopilot executes it (`drake_auv.autopilot`), by the `AutopilotPilot` on
its own DVL's seabed. Its file is read and placed in the local frame off-line
(`flown_mission`); it needs no transit, its first item (a COLA2 goto, ArduSub's first
waypoint) is one."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from drake_auv.autopilot.items import (FlownMission, item_positions, localise,
                                       position_tolerance)
from drake_auv.autopilot.semantics import mission_duration
from drake_auv.formats.registry import VEHICLE_FILES
from drake_auv.mission.legs import Leg
from drake_auv.mission.spec import SPEED_MS, TIME_S, MissionFileError
from drake_auv.mission.steps.step import TIME_SLACK, MissionStep
from drake_auv.params import checks, param, validate

FLY_FORMATS = {suffix: f.autopilot for suffix, f in VEHICLE_FILES.items()}  # ".xml": "cola2"


@dataclass(frozen=True)
class FlyStep:
    """An exported vehicle mission flown the way its autopilot executes it
    (`drake_auv.autopilot`): COLA2 goto/section/park or ArduSub AUTO waypoints.

    Attributes:
        file: the mission file, relative to the mission file: COLA2 mission XML (`.xml`) or a
            QGroundControl plan (`.plan`, flown as ArduSub AUTO); the extension names the
            format.
        heave_in_3d: COLA2 only: the vehicle is configured with heave_in_3D (depth
            interpolated along each section).
        speed: m/s where the file commands none (ArduSub before its first DO_CHANGE_SPEED).
        max_time_s: cap, s (None: the file's nominal duration times `limits.time_margin`).
    """

    KIND: ClassVar[str] = "fly"
    file: Path = param(kind="path", note="a COLA2 mission (.xml) or QGroundControl plan (.plan) "
                                         "file, relative to the mission file")
    heave_in_3d: bool = param(False, kind="bool")
    speed: float = param(0.5, **SPEED_MS)
    max_time_s: float | None = param(None, **TIME_S)

    def __post_init__(self):
        validate(self)

    @property
    def autopilot(self) -> str:
        return FLY_FORMATS[self.file.suffix.lower()]


def flown_mission(step: FlyStep, site, label: str, where: str) -> FlownMission:
    """The fly step's file read and placed in the site's local frame. Raises
    MissionFileError (one line naming `where`) for a site without a CRS, a file that does not
    parse, an item outside the world or above the sea surface."""
    from drake_auv.formats.registry import read_vehicle_mission
    from drake_auv.terrain.geo import GeoFrame

    if site.prior.crs is None:
        raise MissionFileError(label, where, "the site has no CRS, so the file's WGS 84 "
                               "positions cannot be placed",
                               "a site whose prior raster or site.crs gives its CRS")
    try:
        mission = read_vehicle_mission(step.file, step.heave_in_3d)
    except (ValueError, OSError) as err:
        raise MissionFileError(label, f"{where}.file", " ".join(str(err).split()),
                               f"a valid {step.file.suffix} {step.autopilot} mission") from None
    geo = GeoFrame(site.prior)
    legs = localise(mission, geo.from_lonlat, geo.grid_north_azimuth)
    tolerance = position_tolerance(mission)
    (x0, y0), (x1, y1) = site.world.bounds[:, :2] + [[-tolerance], [tolerance]]
    for k, (item, leg) in enumerate(zip(mission.items, legs)):
        points = [leg.end] + ([leg.start] if leg.start is not None else [])
        if not all(x0 <= x <= x1 and y0 <= y <= y1 for x, y in points):
            (sx0, sy0), (sx1, sy1) = site.to_site(site.world.bounds[:, :2])
            raise MissionFileError(label, f"{where}.file", f"{step.file.name}: item {k + 1} "
                                   f"at lon {item.lon:.6f}, lat {item.lat:.6f} lies outside "
                                   "the world (a file for another site?)",
                                   f"positions in x [{sx0:.1f}, {sx1:.1f}], y [{sy0:.1f}, "
                                   f"{sy1:.1f}] m of the site's CRS {site.prior.crs}, or within "
                                   f"{tolerance:.2g} m of them (the file's precision)")
        depths = [item.z] if item.z_mode == "depth" else []
        depths += [item.start_depth] if item.start_depth is not None else []
        if any(d < 0 for d in depths):
            raise MissionFileError(label, f"{where}.file", f"{step.file.name}: item {k + 1} "
                                   f"commands depth {min(depths):g} m, above the sea surface",
                                   "depths >= 0 m (positive down)")
    from drake_auv.mission.site import check_in_water

    ends = np.array([leg.end for leg in legs], float)
    tops = site.clearance.top(ends)  # where an altitude item holds its altitude over
    tops = np.where(np.isfinite(tops), tops, site.prior.elevation_at(ends[:, 0], ends[:, 1]))
    points, names = item_positions(mission, legs, tops, step.file.name)
    check_in_water(site, points, label, f"{where}.file", names)
    return FlownMission(mission.autopilot, legs, mission.heave_in_3d, step.speed,
                        step.file.name)


def _item_position(leg, site, end: bool = True) -> np.ndarray:
    """(3,) where an item puts the vehicle: its end (or its start, else its end), at its
    depth or altitude over the prior."""
    xy = np.asarray(leg.end if end or leg.start is None else leg.start, float)
    return np.array([*xy, -leg.z if leg.z_mode == "depth" else
                     float(site.prior.elevation_at(*xy)) + leg.z])


class Fly(MissionStep):
    spec = FlyStep
    behaviour = "autopilot"
    needs_prior = True

    @classmethod
    def check(cls, reader, v, where: str) -> None:
        path = v.file  # a Path: `validate` has refused None
        if path.suffix.lower() not in FLY_FORMATS:
            reader.fail(f"{where}.file", f"{path.name}: unknown mission format "
                        f"{path.suffix or '(no extension)'!r}", ", ".join(FLY_FORMATS))
        if not path.is_file():
            reader.fail(f"{where}.file", f"{path.name} not found ({path})",
                        checks(FlyStep)["file"].allowed())
        if v.heave_in_3d and FLY_FORMATS[path.suffix.lower()] != "cola2":
            reader.fail(f"{where}.heave_in_3d", "only for COLA2 missions (.xml)",
                        "false for a .plan file")

    @classmethod
    def prepare(cls, planning, k: int, step) -> None:
        planning.prepared[k] = flown_mission(step, planning.site, planning.label,
                                             f"steps[{k}].fly")

    @classmethod
    def start(cls, planning, k: int, step) -> np.ndarray:
        start, position = np.zeros(12), _item_position(planning.prepared[k].legs[0],
                                                       planning.site, end=False)
        start[:3] = position[0], position[1], min(position[2], -0.5)
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        mission = planning.prepared[k]
        duration = step.max_time_s or (planning.margin * mission_duration(
            mission.legs, planning.position, step.speed) + TIME_SLACK)
        planning.add(Leg("survey", k, "autopilot", "finished", duration), mission)
        planning.position = _item_position(mission.legs[-1], planning.site)

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        from drake_auv.autopilot.pilot import AutopilotPilot

        pilot = wiring.builder.AddNamedSystem("autopilot", AutopilotPilot(legs))
        wiring.builder.Connect(wiring.dvl().seabed_output, pilot.seabed_input)
        return pilot


STEP = Fly
