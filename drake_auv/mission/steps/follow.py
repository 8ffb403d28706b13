"""The `follow` step: sensor-based profile following with the pencil-beam profiler
(`drake_auv.following`), flown by the `ProfileFollowingController`.

Its legs: a transit to where following begins, then following, ended by the supervisor on
the estimated state (horizontal: `loops` laps around the structure's charted centre;
vertical: `distance_m` along the plane and/or shallower than `end_depth_m`). Where it begins,
unless the file says: on the line from the vehicle's previous position to the structure's
charted centre, `offset` + 4 m outside the structure's cross-section at the step's depth on
the prior map (within the profiler's range of it). The centre is the target's footprint as
the operator charts it, i.e. on the prior map (shifted by its error).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from drake_auv.following.behaviours import EstimatorParams, FollowConfig, FollowingParams
from drake_auv.mission.legs import Leg
from drake_auv.mission.spec import ANGLE_DEG, DEPTH_M, TIME_S, MissionFileError
from drake_auv.mission.steps.step import (LOG_PERIOD, SENSOR_AZIMUTH, TIME_SLACK,
                                          TRANSIT_SPEED, MissionStep, charted_centre)
from drake_auv.params import like, param, validate

APPROACH_MARGIN = 4.0  # m beyond offset + cross-section where following starts


@dataclass(frozen=True)
class FollowStep:
    """Sensor-based profile following with the pencil-beam profiler.

    Attributes:
        mode: "horizontal" (around the structure at a constant depth) or "vertical" (in a
            vertical plane, over and under the profile).
        offset: distance to keep from the profile, m.
        depth: depth where following starts (horizontal: and holds), m (None: the depth of
            the vehicle when the step starts).
        loops: horizontal: laps around the structure.
        distance_m: vertical: end after this horizontal distance along the plane, m.
        end_depth_m: vertical: end once shallower than this (with `distance_m`: both), m.
        heading_deg: vertical: yaw of the plane, deg (None: the vehicle's heading).
        start: (x, y) in site coordinates where following begins, m (None: by the runner).
        speed: speed along the profile, m/s.
        corner_weight: weight of the range along the normal in the controlled distance (see
            `FollowingParams`), in [0, 1].
        min_depth_m: the following never rises above this depth, m.
        max_time_s: cap on the step's simulated time, s.
    """

    KIND: ClassVar[str] = "follow"
    mode: str = param(kind="choice", choices=("horizontal", "vertical"))
    offset: float = like(FollowingParams, "offset", required=True)
    depth: float | None = param(None, **DEPTH_M)
    loops: float = param(1.0, low=0.0, high=100.0, low_open=True)
    distance_m: float | None = param(None, low=0.0, high=10000.0, low_open=True, unit="m",
                                     nullable=True)
    end_depth_m: float | None = param(None, **DEPTH_M)
    heading_deg: float | None = param(None, **ANGLE_DEG, nullable=True)
    start: tuple | None = param(None, kind="vector", names=("x", "y"), unit="m, site coordinates",
                                nullable=True)
    speed: float = like(FollowingParams, "speed")
    corner_weight: float = like(FollowingParams, "corner_weight")
    min_depth_m: float = like(FollowingParams, "min_depth")
    max_time_s: float | None = param(None, **TIME_S)

    def __post_init__(self):
        validate(self)


def approach_point(site, depth: float, offset: float, previous: np.ndarray) -> np.ndarray:
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


def _deepest(site, lo, hi) -> float:
    """Depth of the prior's deepest cell with its centre in the local box [lo, hi] (x, y),
    m; the whole prior's when the box holds none."""
    gx, gy = np.meshgrid(site.prior.x, site.prior.y)
    inside = (gx >= lo[0]) & (gx <= hi[0]) & (gy >= lo[1]) & (gy <= hi[1]) & site.prior.valid
    z = site.prior.z[inside] if inside.any() else site.prior.z[site.prior.valid]
    return float(-z.min())


class Follow(MissionStep):
    spec = FollowStep
    behaviour = "follow"
    needs_prior = True

    @classmethod
    def check(cls, reader, v, where: str) -> None:
        ends = ("distance_m", "end_depth_m")
        if v.mode == "vertical" and all(getattr(v, k) is None for k in ends):
            reader.fail(where, "a vertical follow needs an end",
                        "distance_m and/or end_depth_m")
        if v.mode == "horizontal":
            for key in ends:
                if getattr(v, key) is not None:
                    reader.fail(f"{where}.{key}", "only for mode vertical",
                                "null for a horizontal follow (it ends after `loops` laps)")

    @classmethod
    def check_site(cls, site, step, where: str, label: str) -> None:
        from drake_auv.mission.site import check_inside

        if step.start is not None:
            check_inside(site, step.start, f"{where}.start", label)
        if step.depth is not None:
            if step.start is not None:
                x, y = site.to_local(step.start)
                seabed = -float(site.prior.elevation_at(x, y))
                place = f"at ({step.start[0]:g}, {step.start[1]:g})"
            else:
                target_lo, target_hi = site.target_mesh.bounds[:, :2]
                seabed = _deepest(site, target_lo - step.offset, target_hi + step.offset)
                place = "under the structure"
            if step.depth >= seabed:
                raise MissionFileError(label, f"{where}.depth",
                                       f"{step.depth:g} m is below the seabed "
                                       f"({seabed:.1f} m {place})",
                                       f"(0, {seabed:.1f}) m")

    @classmethod
    def start(cls, planning, index: int, step) -> np.ndarray:
        start = planning.default_start(step.depth)
        if step.start is not None:
            start[:2] = planning.site.to_local(np.asarray(step.start[:2], dtype=float))
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        site, margin, position = planning.site, planning.margin, planning.position
        azimuth = SENSOR_AZIMUTH.get(planning.spec.payload.multibeam_mount)
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
        from drake_auv.mission.site import check_in_water

        check_in_water(site, (*xy, z), planning.label, f"steps[{k}].follow",
                       f"where following begins, at ({xy[0]:.1f}, {xy[1]:.1f}) local")
        planning.add_transit(k, (*xy, z), facing + yaw_offset, TRANSIT_SPEED)
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
        index = planning.add(leg, config)
        if step.mode == "vertical":
            planning.profiler_planes[index] = "vertical"
        planning.position = np.array([*xy, z])  # where the next transit is planned from

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        from drake_auv.following.controller import ProfileFollowingController

        controller = wiring.builder.AddNamedSystem("profile_following",
                                                   ProfileFollowingController(
                                                       legs, period=wiring.profiler.period,
                                                       seed=wiring.spec.seed))
        wiring.builder.Connect(wiring.returns["profiler"], controller.returns_input)
        wiring.log("profile", controller.profile_output, LOG_PERIOD)
        return controller


STEP = Follow
