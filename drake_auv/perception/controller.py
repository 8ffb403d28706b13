"""`ProfileFollowingController`: sensor-based profile following as a Drake LeafSystem.

A thin adapter over `drake_auv.perception` (`HorizontalFollower` / `VerticalFollower`): at the
profiler's update period it feeds the new returns to the follower's local map and stores the
tracker reference it computes. The follower (local map, RANSAC generator, yaw and turn state)
is abstract state; it holds a few thousand points at most, so the copies Drake makes of it
are cheap. Between updates the reference position is extrapolated with its velocity, so the
tracker's position error does not build up along the profile.

Ports: inputs `returns` (abstract `SonarReturns`), `estimated_state` (12); outputs
`reference` (8, world) and `profile` (7): `[distance, normal_distance, normal_a, normal_b,
orientation, valid, mode]` in the scan plane's 2D axes (horizontal: x, y; vertical: s, h), mode
0 search, 1 follow, 2 turn; distances NaN while no profile is seen.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.perception.behaviours import FollowingParams, HorizontalFollower, VerticalFollower
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.model import STATE_SIZE

MODES = ("search", "follow", "turn")
PROFILE_SIZE = 7


class ProfileFollowingController(LeafSystem):
    """Drives the tracker from profiler returns.

    Args:
        mode: "horizontal" (constant depth, facing the profile) or "vertical" (in the vertical
            plane along `plane_yaw`, with the 180 degree turn under ceilings).
        params: `FollowingParams`.
        period: update period, s; use the profiler's (its returns hold the pings since its
            last update).
        depth_z: horizontal mode, z to hold (None: the initial z).
        plane_yaw: vertical mode, direction of the plane (None: the initial yaw).
        seed: seed of the estimator's RANSAC.
    """

    def __init__(self, mode: str = "horizontal", params: FollowingParams | None = None,
                 period: float = 0.1, depth_z: float | None = None,
                 plane_yaw: float | None = None, seed: int = 0):
        super().__init__()
        if mode not in ("horizontal", "vertical"):
            raise ValueError(f"ProfileFollowingController mode must be 'horizontal' or "
                             f"'vertical', got {mode!r}")
        if not (np.isfinite(period) and 1e-3 <= period <= 5.0):
            raise ValueError(f"ProfileFollowingController period must be in [0.001, 5] s, got {period}")
        self.mode = mode
        self.params = params if params is not None else FollowingParams()
        self.period = float(period)
        if mode == "horizontal":
            follower = HorizontalFollower(self.params, depth_z=depth_z, seed=seed)
        else:
            follower = VerticalFollower(self.params, plane_yaw=plane_yaw, seed=seed)
        self.returns_input = self.DeclareAbstractInputPort(
            "returns", AbstractValue.Make(SonarReturns.empty(20.0)))
        self.state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self._follower_index = self.DeclareAbstractState(AbstractValue.Make(follower))
        # reference (8), time of the update, sequence number of the last returns used, profile (7)
        initial = np.zeros(8 + 2 + PROFILE_SIZE)
        initial[9] = -1
        self._xd = self.DeclareDiscreteState(BasicVector(initial))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_reference)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_reference)
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", 8, self._calc_reference,
            prerequisites_of_calc={self.xd_ticket(), self.time_ticket()})
        self.profile_output = self.DeclareVectorOutputPort(
            "profile", PROFILE_SIZE, self._calc_profile, prerequisites_of_calc={self.xd_ticket()})

    def follower(self, context):
        """The follower (its map, turn count, ...) held in this system's own `context`
        (from a diagram's context: `GetMyContextFromRoot`), for inspection."""
        return context.get_abstract_state(self._follower_index).get_value()

    def _update_reference(self, context, state):
        t = context.get_time()
        x = context.get_discrete_state(self._xd).get_value()
        follower = state.get_mutable_abstract_state(self._follower_index).get_mutable_value()
        if follower.time is not None and t <= follower.time:
            return  # the initialization and the first periodic event share t = 0
        returns = self.returns_input.Eval(context) if self.returns_input.HasValue(context) else None
        points, sequence = np.empty((0, 3)), x[9]
        if returns is not None and returns.sequence != sequence:  # each batch once
            points, sequence = returns.points_nav, returns.sequence
        out = follower.update(t, self.state_input.Eval(context), points)
        profile = np.full(PROFILE_SIZE, np.nan)
        profile[5] = 0.0
        if out.estimate is not None:
            est = out.estimate
            profile[:5] = (est.distance, est.normal_distance, est.normal[0], est.normal[1],
                           est.orientation)
            profile[5] = 1.0
        profile[6] = MODES.index(out.mode)
        state.get_mutable_discrete_state(self._xd).set_value(
            np.concatenate([out.reference, [t, sequence], profile]))

    def _calc_reference(self, context, output):
        x = context.get_discrete_state(self._xd).get_value()
        reference = x[:8].copy()
        reference[:3] += reference[4:7] * (context.get_time() - x[8])
        output.SetFromVector(reference)

    def _calc_profile(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._xd).get_value()[10:])
