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

Both are pure (numpy) and own their local map; the Drake controller is a thin adapter.
Reference: `[x, y, z, yaw, vx, vy, vz, yaw_rate]` in the world frame (architecture.md).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from drake_auv.params import nested, param, validate
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

    def follower(self, seed: int):
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


@dataclass
class FollowerOutput:
    """One update: the tracker reference (8,), the estimate (None if no profile is seen) and
    the behaviour's mode ("search", "follow" or "turn")."""

    reference: np.ndarray
    estimate: ProfileEstimate | None
    mode: str


class _Follower:
    """Common part: local map, seeded RANSAC generator, rate-limited yaw reference."""

    DEFAULT_MAX_AGE = 20.0  # s

    def __init__(self, params: FollowingParams, seed: int):
        self.params = params
        self.map = LocalProfileMap(params.max_age or self.DEFAULT_MAX_AGE, params.max_points)
        self.rng = np.random.default_rng(seed)
        self.yaw_ref = None
        self.yaw_rate_ref = 0.0
        self.time = None
        self.start_time = None
        self.look = None
        self.normal = None

    def __deepcopy__(self, memo):
        # Drake copies abstract state at every update: share what is never modified in place
        # (the frozen params, the map's arrays, which every update replaces) and copy the
        # rest; the generator's state is copied so the copy draws the same numbers.
        clone = copy.copy(self)
        clone.map = copy.copy(self.map)
        clone.rng = np.random.default_rng()
        clone.rng.bit_generator.state = self.rng.bit_generator.state
        return clone

    def _begin(self, time, state, points_nav):
        state = np.asarray(state, dtype=float)
        if state.shape != (12,) or not np.all(np.isfinite(state)):
            raise ValueError(f"state must be a finite 12-vector, got shape {state.shape}")
        dt = 0.0 if self.time is None else time - self.time
        if dt < 0:
            raise ValueError(f"follower updates must go forward in time: {time} < {self.time}")
        self.time = time
        if self.start_time is None:
            self.start_time = time
        if self.yaw_ref is None:
            self.yaw_ref = float(state[5])
        self.map.add(points_nav, time)
        return state, dt

    def _search_speed(self) -> float:
        """Speed of the search behaviour: zero during the warm-up."""
        return 0.0 if self.time - self.start_time < self.params.warmup else self.params.search_speed

    def _steer_yaw(self, target, dt):
        """Moves the yaw reference towards `target` with a rate bounded by `yaw_rate` and
        changed by at most `yaw_accel` * dt, braking in time to stop on the target (a smooth
        reference the tracker can follow without overshoot); returns the reference's rate."""
        if dt <= 0:
            return self.yaw_rate_ref
        p = self.params
        error = float(wrap_angle(target - self.yaw_ref))
        braking = np.sign(error) * np.sqrt(2.0 * p.yaw_accel * abs(error))
        desired = np.clip(braking, -p.yaw_rate, p.yaw_rate)
        rate = self.yaw_rate_ref + np.clip(desired - self.yaw_rate_ref, -p.yaw_accel * dt,
                                           p.yaw_accel * dt)
        if abs(rate * dt) > abs(error) and np.sign(rate) == np.sign(error):
            rate = error / dt  # land on the target
        self.yaw_ref = float(wrap_angle(self.yaw_ref + rate * dt))
        self.yaw_rate_ref = float(rate)
        return self.yaw_rate_ref

    def _estimate(self, points):
        estimate = estimate_profile(points, self.params.estimator, self.rng, self.look, self.normal)
        if estimate is not None:
            self.normal = estimate.normal
        return estimate


class HorizontalFollower(_Follower):
    """Horizontal profile following at constant depth, facing the profile.

    Args:
        params: `FollowingParams`.
        depth_z: z of the horizontal plane to follow, m (world, z up); None holds the z of the
            first update.
        seed: seed of the RANSAC generator.
    """

    DEFAULT_MAX_AGE = 10.0  # s

    def __init__(self, params: FollowingParams = FollowingParams(), depth_z=None, seed: int = 0):
        super().__init__(params, seed)
        if depth_z is not None and not np.isfinite(depth_z):
            raise ValueError(f"HorizontalFollower depth_z must be finite, got {depth_z}")
        self.depth_z = None if depth_z is None else float(depth_z)

    def update(self, time: float, state, points_nav) -> FollowerOutput:
        """Adds the new return points (navigation frame) and computes the reference from the
        estimated `state` (12)."""
        state, dt = self._begin(time, state, points_nav)
        if self.depth_z is None:
            self.depth_z = float(state[2])
        position = state[:3]
        points = self.map.horizontal_slice(position, self.params.plane_band)
        facing = state[5] - self.params.yaw_offset
        if self.look is None:
            self.look = np.array([np.cos(facing), np.sin(facing)])
        estimate = self._estimate(points)
        reference = np.zeros(8)
        if estimate is None:
            ahead = self.yaw_ref - self.params.yaw_offset
            heading = np.array([np.cos(ahead), np.sin(ahead)])
            reference[:2] = position[:2]
            reference[4:6] = self._search_speed() * heading
            mode = "search"
            yaw_rate = self._steer_yaw(self.yaw_ref, dt)
        else:
            correction, velocity = follow_step(estimate, self.params)
            reference[:2] = position[:2] + correction
            reference[4:6] = velocity
            yaw_rate = self._steer_yaw(np.arctan2(-estimate.normal[1], -estimate.normal[0])
                                       + self.params.yaw_offset, dt)
            tangent = self.params.side * np.array([estimate.normal[1], -estimate.normal[0]])
            self.look = tangent
            mode = "follow"
        reference[2] = self.depth_z
        reference[3] = self.yaw_ref
        reference[7] = yaw_rate
        return FollowerOutput(reference, estimate, mode)


class VerticalFollower(_Follower):
    """Vertical profile following in the vertical plane along yaw `plane_yaw`.

    The plane's 2D axes are s = (cos, sin, 0) of `plane_yaw` and h = z up; the heading is
    `plane_yaw` or `plane_yaw + pi` and flips (the 180 degree turn) instead of moving backwards.

    Args:
        params: `FollowingParams` (`side` = +1: the profile on the right of the motion with s
            to the right and h up, e.g. bottom below while moving along +s).
        plane_yaw: direction of the plane, rad; None takes the yaw of the first update.
        seed: seed of the RANSAC generator.
    """

    def __init__(self, params: FollowingParams = FollowingParams(), plane_yaw=None, seed: int = 0):
        super().__init__(params, seed)
        if plane_yaw is not None and not np.isfinite(plane_yaw):
            raise ValueError(f"VerticalFollower plane_yaw must be finite, got {plane_yaw}")
        self.plane_yaw = None if plane_yaw is None else float(plane_yaw)
        self.heading_sign = None
        self.turns = 0

    def update(self, time: float, state, points_nav) -> FollowerOutput:
        """Adds the new return points (navigation frame) and computes the reference from the
        estimated `state` (12)."""
        state, dt = self._begin(time, state, points_nav)
        if self.plane_yaw is None:
            self.plane_yaw = float(state[5])
        if self.heading_sign is None:
            self.heading_sign = 1 if np.cos(state[5] - self.plane_yaw) >= 0 else -1
        e = np.array([np.cos(self.plane_yaw), np.sin(self.plane_yaw), 0.0])
        up = np.array([0.0, 0.0, 1.0])
        position = state[:3]
        points = self.map.vertical_slice(position, self.plane_yaw, self.params.plane_band)
        if self.look is None:
            self.look = np.array([float(self.heading_sign), 0.0])
        estimate = self._estimate(points)
        correction = np.zeros(2)
        velocity = np.zeros(2)
        if estimate is None:
            velocity = np.array([self.heading_sign * self._search_speed(), 0.0])
            mode = "search"
        else:
            correction, velocity = follow_step(estimate, self.params)
            speed = np.linalg.norm(velocity)
            if speed > 1e-9:
                self.look = velocity / speed
                if self.heading_sign * self.look[0] < -self.params.turn_threshold:
                    self.heading_sign = -self.heading_sign  # ceiling: turn, do not back up
                    self.turns += 1
            mode = "follow"
        target = self.plane_yaw + (0.0 if self.heading_sign > 0 else np.pi)
        if abs(wrap_angle(target - state[5])) > self.params.turn_tolerance:
            velocity = np.zeros(2)  # hold the offset while turning
            mode = "turn"
        yaw_rate = self._steer_yaw(target, dt)
        reference = np.zeros(8)
        reference[:3] = position + correction[0] * e + correction[1] * up
        reference[3] = self.yaw_ref
        reference[4:7] = velocity[0] * e + velocity[1] * up
        reference[7] = yaw_rate
        if reference[2] >= -self.params.min_depth:  # depth limit: hold below it
            reference[2] = -self.params.min_depth
            reference[6] = min(reference[6], 0.0)
        return FollowerOutput(reference, estimate, mode)
