"""From a mission file to what the Diagram flies: the off-line plan and the legs.

`plan_mission` runs the `plan` step off-line on the site's prior map (the coverage planner, or
the offset contour of the structure at one depth), then turns every simulated step into legs
(`drake_auv.mission.legs`): a transit to where the step begins, then the step's behaviour,
each with the parameters its LeafSystem needs and a time budget. A `fly` step reads its
exported file and places its items in the local frame (`flown_mission`); it needs no transit,
its first item (a COLA2 goto, ArduSub's first waypoint) is one. Pure: no Drake is loaded (the
legs' parameters are plain data classes), so a mission plans where pydrake is missing.

Where a follow step begins, unless the file says: on the line from the vehicle's previous
position to the structure's charted centre, `offset` + 4 m outside the structure's cross-
section at the step's depth on the prior map (within the profiler's range of it). The centre is
the target's footprint as the operator charts it, i.e. on the prior map (shifted by its error).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from drake_auv.autopilot.items import FlownMission, localise
from drake_auv.autopilot.semantics import mission_duration
from drake_auv.following.behaviours import EstimatorParams, FollowConfig, FollowingParams
from drake_auv.mission.legs import Leg
from drake_auv.mission.site import Site
from drake_auv.mission.spec import (ExploreStep, FlyStep, FollowStep, MissionFileError,
                                    MissionSpec, PlanStep, SurveyStep)
from drake_auv.planning.path import Path
from drake_auv.planning.surface import TerrainSurface
from drake_auv.vehicle.path_leg import PathLeg

TIME_SLACK = 120.0  # s a leg may last beyond `limits.time_margin` times its nominal duration
TRANSIT_SPEED = 0.5  # m/s
APPROACH_MARGIN = 4.0  # m beyond offset + cross-section where following starts
SENSOR_AZIMUTH = {"port": np.pi / 2, "starboard": -np.pi / 2}  # payload axis in the body frame


@dataclass
class MissionPlan:
    """The off-line part of a mission.

    Attributes:
        nominal: the nominal path of the survey (None without a plan step).
        coverage: the `CoveragePlan` when the plan step used the coverage planner.
        omega: the plan's offset, m (None without a plan step).
        method: the plan step's method ("coverage" or "contour"; the replanner's offset metric
            follows it).
        legs: every leg in order; path_legs, follow_legs, replan_legs, autopilot_legs: the
            parameters of the legs each behaviour flies, by leg index (autopilot_legs: the
            exported missions the fly steps fly); profiler_planes: legs whose profiler scans
            the vertical plane.
        survey_speed: m/s along the nominal path (the plan step's).
        start_state: (12,) where the vehicle starts (local frame).
        budget: sum of the legs' time budgets, s.
    """

    nominal: Path | None
    coverage: object
    omega: float | None
    method: str
    legs: tuple[Leg, ...]
    path_legs: dict[int, PathLeg]
    follow_legs: dict[int, FollowConfig]
    replan_legs: tuple[int, ...]
    profiler_planes: dict[int, str]
    survey_speed: float
    start_state: np.ndarray
    budget: float
    autopilot_legs: dict[int, FlownMission] = field(default_factory=dict)
    explore_legs: dict = field(default_factory=dict)  # leg -> ExploreParameters


def _plan_step(step: PlanStep, site: Site):
    """(nominal path, coverage plan or None) of the plan step."""
    if step.method == "contour":
        from drake_auv.planning.contour import nominal_contour

        path = nominal_contour(
            site.prior, step.depth, step.omega, step.end_width_m,
            end_heading=np.radians(step.end_heading_deg or 0.0),
            **({} if step.end_overrun_m is None else {"overrun": step.end_overrun_m}))
        return path, None
    from drake_auv.planning.coverage_plan import plan_coverage

    kwargs = dict(omega=step.omega, aperture_deg=step.aperture_deg, overlap=step.overlap,
                  slope_threshold=step.slope_threshold, slice_spacing=step.slice_spacing,
                  slice_count=step.slice_count, sensor_range=site.max_range)
    if step.min_area_m2 is not None:
        kwargs["min_area"] = step.min_area_m2
    plan = plan_coverage(site.prior, **kwargs)
    return plan.path, plan


def flown_mission(step: FlyStep, site: Site, label: str, where: str) -> FlownMission:
    """The fly step's file read and placed in the site's local frame. Raises
    MissionFileError (one line naming `where`) for a site without a CRS, a file that does not
    parse, an item outside the world or above the sea surface."""
    from drake_auv.autopilot.files import read_vehicle_mission
    from drake_auv.planning.geo import GeoFrame

    if site.prior.crs is None:
        raise MissionFileError(label, where, "the site has no CRS, so the file's WGS 84 "
                               "positions cannot be placed",
                               "a site whose prior raster or site.crs gives its CRS")
    try:
        mission = read_vehicle_mission(step.file, step.autopilot, step.heave_in_3d)
    except (ValueError, OSError) as err:
        raise MissionFileError(label, f"{where}.file", " ".join(str(err).split()),
                               f"a valid {step.file.suffix} {step.autopilot} mission") from None
    geo = GeoFrame(site.prior)
    legs = localise(mission, geo.from_lonlat, geo.grid_north_azimuth)
    (x0, y0), (x1, y1) = site.world.bounds[:, :2]
    for k, (item, leg) in enumerate(zip(mission.items, legs)):
        points = [leg.end] + ([leg.start] if leg.start is not None else [])
        if not all(x0 <= x <= x1 and y0 <= y <= y1 for x, y in points):
            (sx0, sy0), (sx1, sy1) = site.to_site(site.world.bounds[:, :2])
            raise MissionFileError(label, f"{where}.file", f"{step.file.name}: item {k + 1} "
                                   f"at lon {item.lon:.6f}, lat {item.lat:.6f} lies outside "
                                   "the world (a file for another site?)",
                                   f"positions in x [{sx0:.1f}, {sx1:.1f}], y [{sy0:.1f}, "
                                   f"{sy1:.1f}] m of the site's CRS {site.prior.crs}")
        depths = [item.z] if item.z_mode == "depth" else []
        depths += [item.start_depth] if item.start_depth is not None else []
        if any(d < 0 for d in depths):
            raise MissionFileError(label, f"{where}.file", f"{step.file.name}: item {k + 1} "
                                   f"commands depth {min(depths):g} m, above the sea surface",
                                   "depths >= 0 m (positive down)")
    return FlownMission(mission.autopilot, legs, mission.heave_in_3d, step.speed,
                        step.file.name)


def _first_position(mission: FlownMission, site: Site) -> np.ndarray:
    """(3,) where the fly step's first item puts the vehicle (altitude over the prior)."""
    leg = mission.legs[0]
    xy = np.asarray(leg.start if leg.start is not None else leg.end, float)
    z = -leg.z if leg.z_mode == "depth" else float(site.prior.elevation_at(*xy)) + leg.z
    return np.array([xy[0], xy[1], min(z, -0.5)])


def charted_centre(site: Site) -> np.ndarray:
    """(2,) the structure's centre on the operator's chart: the target footprint's centre,
    moved by the prior map's error (the chart and the prior map agree)."""
    lo, hi = site.target_mesh.bounds
    return 0.5 * (lo[:2] + hi[:2]) + site.prior_shift


def approach_point(site: Site, depth: float, offset: float, previous: np.ndarray) -> np.ndarray:
    """(2,) where horizontal following at `depth` begins, coming from `previous` (2,)."""
    centre = charted_centre(site)
    prior = site.prior
    gx, gy = np.meshgrid(prior.x, prior.y)
    solid = np.nan_to_num(prior.z, nan=-np.inf) > -depth
    radius = 0.0
    if solid.any():
        radius = float(np.hypot(gx[solid] - centre[0], gy[solid] - centre[1]).max())
    towards = np.asarray(previous, dtype=float)[:2] - centre
    norm = np.linalg.norm(towards)
    direction = towards / norm if norm > 1e-6 else np.array([-1.0, 0.0])
    return centre + (radius + offset + APPROACH_MARGIN) * direction


def plan_mission(spec: MissionSpec, site: Site) -> MissionPlan:
    """Plans the mission `spec` at `site` (see the module docstring)."""
    nominal = coverage = omega = None
    method, survey_speed = "coverage", 0.5
    margin = spec.limits.time_margin
    azimuth = SENSOR_AZIMUTH.get(spec.payload.multibeam_mount)
    for step in spec.steps:
        if isinstance(step, PlanStep):
            nominal, coverage = _plan_step(step, site)
            method = step.method
            omega = step.omega
            survey_speed = step.speed
    label = spec.source.name if spec.source is not None else spec.name
    flown = {k: flown_mission(step, site, label, f"steps[{k}].fly")
             for k, step in enumerate(spec.steps) if isinstance(step, FlyStep)}
    start = site.start_state
    if start is None:  # at the beginning of the first simulated step
        start = np.zeros(12)
        first = next(s for s in spec.steps if not isinstance(s, PlanStep))
        if isinstance(first, FlyStep):
            start[:3] = _first_position(flown[spec.steps.index(first)], site)
        elif isinstance(first, SurveyStep):
            start[:3], start[5] = nominal.points[0], nominal.heading[0]
        elif isinstance(first, ExploreStep):
            start[:3] = explore_start(first, site)
        else:
            xy = (site.to_local(np.asarray(first.start[:2], dtype=float))
                  if first.start is not None else charted_centre(site) + [-30.0, 0.0])
            start[:3] = (xy[0], xy[1], -(first.depth or 5.0))
    legs, path_legs, follow_legs, replan_legs, planes, autopilot_legs = [], {}, {}, [], {}, {}
    explore_legs = {}
    position, yaw = np.asarray(start[:3], float), float(start[5])
    budget = 0.0

    def add(leg: Leg) -> int:
        nonlocal budget
        legs.append(leg)
        budget += leg.max_duration
        return len(legs) - 1

    def add_transit(step_index: int, target, end_yaw, speed: float,
                    handover: float | None = None) -> None:
        nonlocal position, yaw
        target = np.asarray(target, dtype=float)
        duration = margin * np.linalg.norm(target - position) / speed + TIME_SLACK
        index = add(Leg("transit", step_index, "path", "arrive", duration,
                        target=tuple(target), tolerance=1.5, handover=handover))
        path_legs[index] = PathLeg("goto", tuple(target), end_yaw, speed)
        position, yaw = target, yaw if end_yaw is None else end_yaw

    for k, step in enumerate(spec.steps):
        if isinstance(step, FollowStep):
            z = -step.depth if step.depth is not None else float(position[2])
            if step.start is not None:
                xy = site.to_local(np.asarray(step.start[:2], dtype=float))
            elif step.mode == "horizontal":
                xy = approach_point(site, step.depth, step.offset, position[:2])
            else:
                xy = position[:2]
            centre = charted_centre(site)
            facing = (float(np.arctan2(*(centre - xy)[::-1])) if step.mode == "horizontal"
                      else np.radians(step.heading_deg or 0.0))
            side, yaw_offset = 1, 0.0
            if step.mode == "horizontal" and azimuth is not None:
                # fly along the wall with the payload facing it: the wall on the payload's side
                side, yaw_offset = (-1 if azimuth > 0 else 1), -azimuth
            add_transit(k, (*xy, z), facing + yaw_offset, TRANSIT_SPEED)
            params = FollowingParams(offset=step.offset, speed=step.speed, side=side,
                                     yaw_offset=yaw_offset, corner_weight=step.corner_weight,
                                     min_depth=step.min_depth_m,
                                     estimator=EstimatorParams(window=step.offset + 3.0))
            params = replace(params, warmup=360.0 / 1.8 / 30.0)  # one turn of the profiler head
            if step.mode == "horizontal":
                radius = np.linalg.norm(xy - centre)
                nominal_time = 2 * np.pi * radius * step.loops / step.speed
                leg = Leg("follow", k, "follow", "loops", step.max_time_s or
                          margin * nominal_time + TIME_SLACK, centre=tuple(centre),
                          loops=step.loops)
                config = FollowConfig("horizontal", params, depth_z=z)
            else:
                plane = np.radians(step.heading_deg or 0.0)
                distance = step.distance_m or 0.0
                leg = Leg("follow", k, "follow", "distance", step.max_time_s or
                          margin * 3.0 * max(distance, 10.0) / step.speed + TIME_SLACK,
                          direction=(np.cos(plane), np.sin(plane)), distance=step.distance_m,
                          end_depth=step.end_depth_m)
                config = FollowConfig("vertical", params, plane_yaw=plane)
            index = add(leg)
            follow_legs[index] = config
            if step.mode == "vertical":
                planes[index] = "vertical"
            position = np.array([*xy, z])  # where the next transit is planned from
        elif isinstance(step, SurveyStep):
            # Before a replanned survey the transit hands over within R of the plan's first
            # sample (placed on the shifted prior map, it may lie near the real structure):
            # the replanner flies the rest against the on-line map.
            add_transit(k, nominal.points[0], float(nominal.heading[0]), TRANSIT_SPEED,
                        handover=spec.replanner.params.radius if step.replanning else None)
            duration = step.max_time_s or (margin * nominal.times(survey_speed)[-1]
                                           + TIME_SLACK)
            if step.replanning:
                index = add(Leg("survey", k, "replan", "finished", duration))
                replan_legs.append(index)
            else:
                index = add(Leg("survey", k, "path", "finished", duration))
                path_legs[index] = PathLeg("nominal", speed=survey_speed)
            position = nominal.points[-1]
        elif isinstance(step, FlyStep):
            mission = flown[k]
            duration = step.max_time_s or (margin * mission_duration(
                mission.legs, position, step.speed) + TIME_SLACK)
            index = add(Leg("survey", k, "autopilot", "finished", duration))
            autopilot_legs[index] = mission
            last = mission.legs[-1]
            position = np.array([*last.end, -last.z if last.z_mode == "depth" else
                                 float(site.prior.elevation_at(*last.end)) + last.z])
        elif isinstance(step, ExploreStep):
            params = explore_parameters(step, site, spec, label, f"steps[{k}].explore")
            index = add(Leg("explore", k, "explore", "finished", step.max_time_s))
            explore_legs[index] = params
            position = 0.5 * (np.asarray(params.region[:3]) + params.region[3:])
    if not legs:
        raise ValueError(f"mission {spec.name!r} has no simulated step (follow or survey)")
    return MissionPlan(nominal, coverage, omega, method, tuple(legs), path_legs,
                       follow_legs, tuple(replan_legs), planes, survey_speed,
                       np.asarray(start, float), budget, autopilot_legs, explore_legs)


def explore_region(step: ExploreStep, site: Site) -> np.ndarray:
    """(6,) the step's region in the local frame."""
    region = np.asarray(step.region, dtype=float)
    return np.concatenate([site.to_local(region[:3]), site.to_local(region[3:])])


def explore_start(step: ExploreStep, site: Site) -> np.ndarray:
    """(3,) where an explore step begins when the site gives no start: Omega plus the
    clearance west (-x) of the region, at its mid-height (below z = -2 m)."""
    region = explore_region(step, site)
    return np.array([region[0] - step.omega - step.clearance_m,
                     0.5 * (region[1] + region[4]), min(0.5 * (region[2] + region[5]), -2.0)])


def explore_parameters(step: ExploreStep, site: Site, spec: MissionSpec, label: str,
                       where: str):
    """The step's `ExploreParameters` (local frame). Raises MissionFileError (one line
    naming `where`) for a region that holds no part of the world, or whose water the
    vehicle cannot reach (every point of it below the seabed or inside the structure: a
    vertical ray up from it meets the world)."""
    from drake_auv.exploration.planner import ExploreParameters
    from drake_auv.geometry.raycast import RayCaster

    region = explore_region(step, site)
    axes = [np.linspace(region[k] + 0.25, region[k + 3] - 0.25,
                        int(np.clip((region[k + 3] - region[k]) / 1.0, 2, 24)))
            for k in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    points = points[points[:, 2] < -1.0]
    up = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    blocked = (RayCaster(site.world).cast(points, up, 1e4).faces >= 0) if len(points) else []
    if np.all(blocked):
        raise MissionFileError(label, f"{where}.region", f"{list(step.region)} holds no water "
                               "the vehicle can reach (all of it below the seabed or inside "
                               "the structure)", "a box that holds open water below z = -1 m")
    (sx0, sy0, sz0), (sx1, sy1, sz1) = site.to_site(site.world.bounds)
    triangles = site.world.vertices[site.world.faces]
    lo, hi = triangles.min(axis=1), triangles.max(axis=1)
    if not np.any(np.all((hi >= region[:3]) & (lo <= region[3:]), axis=1)):
        raise MissionFileError(label, f"{where}.region", f"{list(step.region)} holds no part "
                               "of the world", f"a box meeting the world, which spans x "
                               f"[{sx0:.1f}, {sx1:.1f}], y [{sy0:.1f}, {sy1:.1f}], z "
                               f"[{sz0:.1f}, {sz1:.1f}] m")
    return ExploreParameters(
        region=tuple(region), omega=step.omega, clearance=step.clearance_m,
        strategy=step.strategy, min_gain_m2=step.min_gain_m2, max_range=site.max_range,
        mount=spec.payload.multibeam_mount)


def terrain_elevation(site: Site):
    """The prior map's elevation as a callable (x, y) -> z, for transits."""
    return TerrainSurface(site.prior).elevation
