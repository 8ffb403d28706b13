"""`ProfileFollowingController`: sensor-based profile following as a Drake LeafSystem.

A thin adapter over `drake_auv.perception` (`HorizontalFollower` / `VerticalFollower`): at the
profiler's update period, while one of its legs flies, it feeds the new returns to the
follower's local map and stores the tracker reference it computes. A new leg starts a new
follower (empty local map, its own mode and depth or plane). The follower (local map, RANSAC
generator, yaw and turn state) is abstract state, boxed so that Drake's copies of the state
cost nothing while it does not fly; a flying update copies it once (a few thousand points at
most). Discrete-state groups: `reference` (8) with the time
it was computed (`reference_time`), the last returns' sequence and leg (`consumed`), and
`profile` (7). Between updates the reference position is extrapolated with its velocity, so
the tracker's position error does not build up along the profile.

Ports: inputs `returns` (`SonarReturns`), `estimated_state` (12), `leg` (2); outputs
`reference` (8, world) and `profile` (7): `[distance, normal_distance, normal_a, normal_b,
orientation, valid, mode]` in the scan plane's 2D axes (horizontal: x, y; vertical: s, h), mode
0 search, 1 follow, 2 turn; distances NaN while no profile is seen.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.leg_signal import LEG_SIZE, read_leg
from drake_auv.following.behaviours import FollowConfig
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.model import STATE_SIZE
from drake_auv.vehicle.path_reference import trajectory_reference

MODES = ("search", "follow", "turn")
PROFILE_SIZE = 7


@dataclass(frozen=True)
class _Held:
    """The follower as abstract state, boxed: the box is never changed (an update copies the
    follower, advances the copy and stores a new box), so Drake's state copies of it, two at
    every periodic update whether a leg flies or not, share it for free."""

    follower: object

    def __deepcopy__(self, memo):
        return self


class ProfileFollowingController(LeafSystem):
    """Drives the tracker from profiler returns.

    Args:
        legs: {leg index: `FollowConfig`} of the mission legs it flies, or one `FollowConfig`
            for leg 0 (the controller alone, its `leg` input unconnected).
        period: update period, s; use the profiler's (its returns hold the pings since its
            last update).
        seed: seed of the estimator's RANSAC (leg k uses seed + k).
    """

    def __init__(self, legs: FollowConfig | dict[int, FollowConfig] = FollowConfig(),
                 period: float = 0.1, seed: int = 0):
        super().__init__()
        if not (np.isfinite(period) and 1e-3 <= period <= 5.0):
            raise ValueError(f"ProfileFollowingController period must be in [0.001, 5] s, "
                             f"got {period}")
        self.legs = {0: legs} if isinstance(legs, FollowConfig) else dict(legs)
        if not self.legs:
            raise ValueError("ProfileFollowingController needs at least one leg")
        self.period = float(period)
        self.seed = int(seed)
        self.returns_input = self.DeclareAbstractInputPort(
            "returns", AbstractValue.Make(SonarReturns.empty(20.0)))
        self.state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)
        first = min(self.legs)
        self._follower_index = self.DeclareAbstractState(
            AbstractValue.Make(_Held(self.legs[first].follower(self.seed + first))))
        self._reference = self.DeclareDiscreteState(8)
        self._reference_time = self.DeclareDiscreteState(1)
        self._consumed = self.DeclareDiscreteState(np.array([-1.0, -1.0]))  # sequence, leg
        initial_profile = np.full(PROFILE_SIZE, np.nan)
        initial_profile[5:] = 0.0
        self._profile = self.DeclareDiscreteState(initial_profile)
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_reference)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_reference)
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", 8, self._calc_reference,
            prerequisites_of_calc={self.discrete_state_ticket(self._reference),
                                   self.discrete_state_ticket(self._reference_time),
                                   self.discrete_state_ticket(self._consumed),
                                   self.input_port_ticket(self.leg_input.get_index()),
                                   self.input_port_ticket(self.state_input.get_index()),
                                   self.time_ticket()})
        self.profile_output = self.DeclareStateOutputPort("profile", self._profile)

    def follower(self, context):
        """The follower (its map, turn count, ...) held in this system's own `context`
        (from a diagram's context: `GetMyContextFromRoot`), for inspection."""
        return context.get_abstract_state(self._follower_index).get_value().follower

    def _update_reference(self, context, state):
        leg, _ = read_leg(self.leg_input, context)
        config = self.legs.get(leg)
        if config is None:
            return  # not flying
        t = context.get_time()
        sequence, flown = context.get_discrete_state(self._consumed).get_value()
        if flown != leg:  # a new leg: a new follower
            follower = config.follower(self.seed + leg)
        else:
            follower = self.follower(context)
            if follower.time is not None and t <= follower.time:
                return  # the initialization and the first periodic event share t = 0
            follower = copy.deepcopy(follower)
        state.get_mutable_abstract_state(self._follower_index).set_value(_Held(follower))
        returns = self.returns_input.Eval(context) if self.returns_input.HasValue(context) else None
        points = np.empty((0, 3))
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
        discrete = state.get_mutable_discrete_state()
        discrete.set_value(self._reference, out.reference)
        discrete.set_value(self._reference_time, [t])
        discrete.set_value(self._consumed, [sequence, leg])
        discrete.set_value(self._profile, profile)

    def _calc_reference(self, context, output):
        leg, _ = read_leg(self.leg_input, context)
        if context.get_discrete_state(self._consumed)[1] != leg:  # before the leg's first update
            output.SetFromVector(trajectory_reference(None, 0.0, self.state_input, context))
            return
        reference = context.get_discrete_state(self._reference).get_value().copy()
        since = context.get_time() - context.get_discrete_state(self._reference_time)[0]
        reference[:3] += reference[4:7] * since
        output.SetFromVector(reference)
