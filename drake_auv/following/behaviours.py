"""Behaviours of sensor-based profile following, combined into a tracker reference.

Three behaviours act on the `ProfileEstimate` of the scan plane (our choice of combination; the
reference publishes only that they are behaviour-based):

- keep offset: a position correction along the normal, (offset - distance) * normal, capped at
  `max_correction` so the tracker's position loop, not a new gain, sets the approach dynamics;
  the distance is the nearest distance blended with the range along the normal by
  `corner_weight` (0: nearest only, the safe choice for contact; 0.5 in a concave 90 degree
  corner balances the nearest and the frontal error, about 0.34 m each instead of 0 and 0.83 m);
- advance: survey speed along the profile tangent, the normal turned by -90 degrees (`side` = +1:
  the profile stays on the right of the motion in the plane's (a, b) axes, i.e. clockwise) or
  +90 degrees (`side` = -1); the speed fades linearly to zero as |distance - offset| grows to
  `slow_band`, so the vehicle re-acquires the offset before it moves on;
- face: the yaw reference, moved towards its target with bounded rate and acceleration.

`HorizontalFollower` circumnavigates at constant depth in the horizontal scan plane and faces
the profile (heading = -normal). `VerticalFollower` follows the profile in the vertical plane of
a fixed horizontal direction (bottom, wall, overhang, ceiling); the vehicle cannot pitch, so
it faces along the plane, and when advancing would mean moving backwards (the motion's
horizontal component opposes the heading by more than `turn_threshold`, which happens under a
ceiling) it turns 180 degrees in place, holding the offset, before it goes on.

Both are pure (numpy) and immutable: an update takes a `FollowerState` (the local map, the
RANSAC generator's state, the yaw and turn state) and returns the next one, so the Drake
controller, a thin adapter, holds that state in its Context and no copy shares anything mutable.
Reference: `[x, y, z, yaw, vx, vy, vz, yaw_rate]` in the world frame (architecture.md).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import numpy as np

from drake_auv.params import nested, param, validate
from drake_auv.signals import Reference, VehicleState
from drake_auv.vehicle.control import wrap_angle
from drake_auv.perception.local_map import LocalProfileMap
from drake_auv.perception.profile_estimation import (EstimatorParams, ProfileEstimate,
                                                     estimate_profile)


@dataclass(frozen=True)
class FollowingParams:
    """Behaviour parameters (SI units, radians; ranges in the fields' `param` metadata).

    offset: desired distance to the profile, m.
    speed: survey speed along the profile, m/s.
    side: +1 keeps the profile on the right of the motion, -1 on the left.
    yaw_offset: horizontal mode, heading relative to facing the profile, rad (-pi/2 turns a
        port-looking payload to the profile while the vehicle moves along it, with side -1);
        while searching the vehicle moves towards where it would face.
    max_correction: cap of the position correction along the normal, m.
    slow_band: distance error at which the advance speed has faded to zero, m.
    yaw_rate: maximum rate of the yaw reference, rad/s.
    yaw_accel: maximum change of that rate, rad/s^2.
    plane_band: half-thickness of the map slice taken around the scan plane, m.
    search_speed: speed straight ahead while no profile is seen, m/s.
    warmup: s; while no profile is seen during the first `warmup` seconds the vehicle holds
        still, so that it does not run into a profile the scanning head has not reached yet
        (set it to the time of one scan of the head).
    turn_threshold: vertical mode, turn when the motion's horizontal component is below
        -turn_threshold times the heading (a cosine, in (0, 1)).
    turn_tolerance: vertical mode, the advance waits while the yaw error exceeds this, rad.
    corner_weight: weight in [0, 1] of the range along the normal in the controlled distance.
    min_depth: the reference never rises above z = -min_depth (a wall can lead to the
        surface), m, >= 0.
    max_age, max_points: forgetting of the local map; max_age None takes the mode's default:
        10 s horizontal (1.5 head revolutions: the profile is re-scanned all the time, and a
        short memory limits the smear of navigation drift), 20 s vertical (the map must bridge
        the 180 degree turn, about 15 s, while the head's plane is turned away).
    estimator: `EstimatorParams`.
    """

    offset: float = param(2.0, low=0.0, high=20.0, low_open=True, unit="m")
    speed: float = param(0.3, low=0.05, high=1.4, unit="m/s")
    side: int = param(1, kind="choice", choices=(1, -1))
    yaw_offset: float = param(0.0, unit="rad")
    max_correction: float = param(1.0, low=0.0, low_open=True, unit="m")
    slow_band: float = param(1.0, low=0.0, low_open=True, unit="m")
    yaw_rate: float = param(np.radians(15.0), low=0.0, low_open=True, unit="rad/s")
    yaw_accel: float = param(np.radians(5.0), low=0.0, low_open=True, unit="rad/s^2")
    plane_band: float = param(0.5, low=0.0, low_open=True, unit="m")
    search_speed: float = param(0.3, low=0.0, unit="m/s")
    warmup: float = param(0.0, low=0.0, unit="s")
    turn_threshold: float = param(0.5, low=0.0, high=1.0, low_open=True, high_open=True)
    turn_tolerance: float = param(np.radians(20.0), low=0.0, high=np.pi, low_open=True,
                                  high_open=True, unit="rad")
    corner_weight: float = param(0.0, low=0.0, high=1.0)
    min_depth: float = param(1.0, low=0.0, high=100.0, unit="m")
    max_age: float | None = param(None, low=0.0, low_open=True, nullable=True, unit="s")
    max_points: int = param(4000, low=1, integer=True)
    estimator: EstimatorParams = nested(EstimatorParams)

    def __post_init__(self):
        validate(self)
        if self.estimator.window <= self.offset:
            raise ValueError(f"FollowingParams.estimator.window ({self.estimator.window} m) must "
                             f"exceed the offset ({self.offset} m)")


@dataclass(frozen=True)
class FollowConfig:
    """One profile-following leg (what `ProfileFollowingController` flies).

    Attributes:
        mode: "horizontal" (constant depth, facing the profile) or "vertical" (in the vertical
            plane along `plane_yaw`, with the 180 degree turn under ceilings).
        params: `FollowingParams`.
        depth_z: horizontal mode, z to hold, m (None: the z where the leg starts).
        plane_yaw: vertical mode, direction of the plane, rad (None: the yaw at the start).
    """

    mode: str = param("horizontal", kind="choice", choices=("horizontal", "vertical"))
    params: FollowingParams = nested(FollowingParams)
    depth_z: float | None = param(None, nullable=True, unit="m")
    plane_yaw: float | None = param(None, nullable=True, unit="rad")

    def __post_init__(self):
        validate(self)

    def follower(self, seed: int | np.random.SeedSequence):
        if self.mode == "horizontal":
            return HorizontalFollower(self.params, depth_z=self.depth_z, seed=seed)
        return VerticalFollower(self.params, plane_yaw=self.plane_yaw, seed=seed)


def follow_step(estimate: ProfileEstimate, params: FollowingParams):
    """(correction (2,), velocity (2,)) in the scan plane from the keep-offset and advance
    behaviours."""
    n = estimate.normal
    distance = ((1 - params.corner_weight) * estimate.distance
                + params.corner_weight * min(estimate.normal_distance, 2 * estimate.distance))
    error = params.offset - distance
    correction = np.clip(error, -params.max_correction, params.max_correction) * n
    tangent = params.side * np.array([n[1], -n[0]])
    fade = np.clip(1.0 - abs(error) / params.slow_band, 0.0, 1.0)
    return correction, fade * params.speed * tangent


@dataclass(frozen=True)
class FollowerOutput:
    """One update: the tracker reference (8,), the estimate (None if no profile is seen) and
    the behaviour's mode ("search", "follow" or "turn")."""

    reference: np.ndarray
    estimate: ProfileEstimate | None
    mode: str


@dataclass(frozen=True)
class FollowerState:
    """Everything a follower remembers between updates; an update returns a new one and
    never changes this one, so a Drake context's copy of it is an independent follower.

    Attributes:
        map: the `LocalProfileMap` of recent returns (an update adds to a copy of it).
        rng: the RANSAC generator's `bit_generator.state`, so a copy repeats the same draws.
        time, start_time: of the last and the first update, s (None before any).
        yaw_ref, yaw_rate_ref: the rate-limited yaw reference, rad and rad/s (None: not set).
        look: (2,) direction of the estimator's sector, scan-plane axes (None: not set).
        normal: (2,) the last estimated profile normal (None before any).
        anchor: horizontal mode, the z held, m; vertical mode, the plane's yaw, rad (None:
            taken at the first update).
        heading_sign: vertical mode, +1 facing along the plane, -1 against it (0: not set).
        turns: vertical mode, how many 180 degree turns it has made.
    """

    map: LocalProfileMap
    rng: dict
    time: float | None = None
    start_time: float | None = None
    yaw_ref: float | None = None
    yaw_rate_ref: float = 0.0
    look: np.ndarray | None = None
    normal: np.ndarray | None = None
    anchor: float | None = None
    heading_sign: int = 0
    turns: int = 0

    def __deepcopy__(self, memo):
        # Immutable (see above): Drake's copies of the state at every event can share it.
        return self


class _Follower:
    """Common part of the two followers: immutable (parameters, anchor, seed); each `update`
    takes a `FollowerState` and returns the next one with its output."""

    DEFAULT_MAX_AGE = 20.0  # s

    def __init__(self, params: FollowingParams, anchor, seed: int | np.random.SeedSequence,
                 name: str):
        if anchor is not None and not np.isfinite(anchor):
            raise ValueError(f"{type(self).__name__} {name} must be finite, got {anchor}")
        self.params = params
        self.anchor = None if anchor is None else float(anchor)
        self.seed = seed if isinstance(seed, np.random.SeedSequence) else int(seed)

    def initial_state(self) -> FollowerState:
        """The state before the first update: an empty map, the generator seeded."""
        return FollowerState(
            LocalProfileMap(self.params.max_age or self.DEFAULT_MAX_AGE, self.params.max_points),
            np.random.default_rng(self.seed).bit_generator.state, anchor=self.anchor)

    def _begin(self, state: FollowerState, time, x, points_nav):
        """Checks the estimated state `x` (12), adds the returns to a copy of the map; returns
        (x as a `VehicleState`, dt, the state with the new map, time and start time)."""
        x = np.asarray(x, dtype=float)
        if x.shape != (12,) or not np.all(np.isfinite(x)):
            raise ValueError(f"state must be a finite 12-vector, got shape {x.shape}")
        dt = 0.0 if state.time is None else time - state.time
        if dt < 0:
            raise ValueError(f"follower updates must go forward in time: {time} < {state.time}")
        local_map = copy.copy(state.map)  # its arrays are replaced, never changed in place
        local_map.add(points_nav, time)
        state = replace(state, map=local_map, time=time,
                        start_time=time if state.start_time is None else state.start_time,
                        yaw_ref=float(VehicleState(x).yaw) if state.yaw_ref is None
                        else state.yaw_ref)
        return VehicleState(x), dt, state

    def _search_speed(self, state: FollowerState) -> float:
        """Speed of the search behaviour: zero during the warm-up."""
        warming = state.time - state.start_time < self.params.warmup
        return 0.0 if warming else self.params.search_speed

    def _steer_yaw(self, state: FollowerState, target, dt) -> tuple[float, float]:
        """Moves the yaw reference towards `target` with a rate bounded by `yaw_rate` and
        changed by at most `yaw_accel` * dt, braking in time to stop on the target (a smooth
        reference the tracker can follow without overshoot); returns (yaw, rate), rad, rad/s."""
        if dt <= 0:
            return state.yaw_ref, state.yaw_rate_ref
        p = self.params
        error = float(wrap_angle(target - state.yaw_ref))
        braking = np.sign(error) * np.sqrt(2.0 * p.yaw_accel * abs(error))
        desired = np.clip(braking, -p.yaw_rate, p.yaw_rate)
        rate = state.yaw_rate_ref + np.clip(desired - state.yaw_rate_ref, -p.yaw_accel * dt,
                                            p.yaw_accel * dt)
        if abs(rate * dt) > abs(error) and np.sign(rate) == np.sign(error):
            rate = error / dt  # land on the target
        return float(wrap_angle(state.yaw_ref + rate * dt)), float(rate)

    def _estimate(self, state: FollowerState, points, look):
        """The profile estimate (or None) and the generator's state after its draws."""
        rng = np.random.default_rng()
        rng.bit_generator.state = state.rng
        estimate = estimate_profile(points, self.params.estimator, rng, look, state.normal)
        return estimate, rng.bit_generator.state


class HorizontalFollower(_Follower):
    """Horizontal profile following at constant depth, facing the profile.

    Args:
        params: `FollowingParams`.
        depth_z: z of the horizontal plane to follow, m (world, z up); None holds the z of the
            first update.
        seed: seed of the RANSAC generator (an int or a `numpy.random.SeedSequence`).
    """

    DEFAULT_MAX_AGE = 10.0  # s

    def __init__(self, params: FollowingParams = FollowingParams(), depth_z=None,
                 seed: int | np.random.SeedSequence = 0):
        super().__init__(params, depth_z, seed, "depth_z")

    def update(self, state: FollowerState, time: float, x,
               points_nav) -> tuple[FollowerState, FollowerOutput]:
        """Adds the new return points (navigation frame) to the map and computes the reference
        from the estimated state `x` (12); returns the new state and the output."""
        x, dt, state = self._begin(state, time, x, points_nav)
        p = self.params
        depth_z = float(x.z) if state.anchor is None else state.anchor
        position = x.position
        points = state.map.horizontal_slice(position, p.plane_band)
        facing = x.yaw - p.yaw_offset
        look = np.array([np.cos(facing), np.sin(facing)]) if state.look is None else state.look
        estimate, rng = self._estimate(state, points, look)
        reference = Reference.zeros()
        if estimate is None:
            ahead = state.yaw_ref - p.yaw_offset
            reference.x, reference.y = position[:2]
            reference.vx, reference.vy = (self._search_speed(state)
                                          * np.array([np.cos(ahead), np.sin(ahead)]))
            mode, normal = "search", state.normal
            yaw, yaw_rate = self._steer_yaw(state, state.yaw_ref, dt)
        else:
            correction, velocity = follow_step(estimate, p)
            reference.x, reference.y = position[:2] + correction
            reference.vx, reference.vy = velocity
            normal = estimate.normal
            yaw, yaw_rate = self._steer_yaw(state, np.arctan2(-normal[1], -normal[0])
                                            + p.yaw_offset, dt)
            look = p.side * np.array([normal[1], -normal[0]])
            mode = "follow"
        reference.z, reference.yaw, reference.yaw_rate = depth_z, yaw, yaw_rate
        state = replace(state, rng=rng, yaw_ref=yaw, yaw_rate_ref=yaw_rate, look=look,
                        normal=normal, anchor=depth_z)
        return state, FollowerOutput(reference[:], estimate, mode)


class VerticalFollower(_Follower):
    """Vertical profile following in the vertical plane along yaw `plane_yaw`.

    The plane's 2D axes are s = (cos, sin, 0) of `plane_yaw` and h = z up; the heading is
    `plane_yaw` or `plane_yaw + pi` and flips (the 180 degree turn) instead of moving backwards.

    Args:
        params: `FollowingParams` (`side` = +1: the profile on the right of the motion with s
            to the right and h up, e.g. bottom below while moving along +s).
        plane_yaw: direction of the plane, rad; None takes the yaw of the first update.
        seed: seed of the RANSAC generator (an int or a `numpy.random.SeedSequence`).
    """

    def __init__(self, params: FollowingParams = FollowingParams(), plane_yaw=None,
                 seed: int | np.random.SeedSequence = 0):
        super().__init__(params, plane_yaw, seed, "plane_yaw")

    def update(self, state: FollowerState, time: float, x,
               points_nav) -> tuple[FollowerState, FollowerOutput]:
        """Adds the new return points (navigation frame) to the map and computes the reference
        from the estimated state `x` (12); returns the new state and the output."""
        x, dt, state = self._begin(state, time, x, points_nav)
        p = self.params
        plane_yaw = float(x.yaw) if state.anchor is None else state.anchor
        sign = state.heading_sign or (1 if np.cos(x.yaw - plane_yaw) >= 0 else -1)
        turns = state.turns
        e = np.array([np.cos(plane_yaw), np.sin(plane_yaw), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        position = x.position
        points = state.map.vertical_slice(position, plane_yaw, p.plane_band)
        look = np.array([float(sign), 0.0]) if state.look is None else state.look
        estimate, rng = self._estimate(state, points, look)
        correction = np.zeros(2)
        velocity = np.zeros(2)
        normal = state.normal
        if estimate is None:
            velocity = np.array([sign * self._search_speed(state), 0.0])
            mode = "search"
        else:
            normal = estimate.normal
            correction, velocity = follow_step(estimate, p)
            speed = np.linalg.norm(velocity)
            if speed > 1e-9:
                look = velocity / speed
                if sign * look[0] < -p.turn_threshold:
                    sign, turns = -sign, turns + 1  # ceiling: turn, do not back up
            mode = "follow"
        target = plane_yaw + (0.0 if sign > 0 else np.pi)
        if abs(wrap_angle(target - x.yaw)) > p.turn_tolerance:
            velocity = np.zeros(2)  # hold the offset while turning
            mode = "turn"
        yaw, yaw_rate = self._steer_yaw(state, target, dt)
        reference = Reference.zeros()
        reference.position = position + correction[0] * e + correction[1] * up
        reference.velocity = velocity[0] * e + velocity[1] * up
        reference.yaw, reference.yaw_rate = yaw, yaw_rate
        if reference.z >= -p.min_depth:  # depth limit: hold below it
            reference.z = -p.min_depth
            reference.vz = min(reference.vz, 0.0)
        state = replace(state, rng=rng, yaw_ref=yaw, yaw_rate_ref=yaw_rate, look=look,
                        normal=normal, anchor=plane_yaw, heading_sign=sign, turns=turns)
        return state, FollowerOutput(reference[:], estimate, mode)
