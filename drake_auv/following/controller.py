"""`ProfileFollowingController`: sensor-based profile following as a Drake LeafSystem.

A thin adapter over `HorizontalFollower` / `VerticalFollower` (`following.behaviours`): at the
profiler's update period, while one of its legs flies, it feeds the new returns to the
follower's local map and stores the tracker reference it computes. A new leg starts a new
follower (empty local map, its own mode and depth or plane). The follower's state (local map,
RANSAC generator's state, yaw and turn state: an immutable `FollowerState` that each update
replaces) is abstract state; Drake's copies of it at every update are plain deep copies (a
few thousand points at most). Discrete-state groups (views in `drake_auv.signals`):
`reference` (`Reference`) with the time it was computed (`reference_time`), the last returns'
sequence and leg (`Consumed`), and `profile` (`Profile`). Between updates the reference
position is extrapolated with its velocity, so the tracker's position error does not build up
along the profile.

A `Behaviour` (`drake_auv.behaviour`). Ports: inputs `estimated_state` (`VehicleState`), `leg`
(`LegSignal`), `returns` (`SonarReturns`); outputs `reference` (`Reference`, world), `status`
(`BehaviourStatus`: the leg last fed, -1 before any; never finished, the supervisor ends its
legs on their laps or distance; progress the sequence of the last returns fed) and `profile`
(`Profile`, in the scan plane's 2D axes: horizontal x, y; vertical s, h; mode an index into
`MODES`; distances NaN while no profile is seen).
"""

from __future__ import annotations


import numpy as np
from pydrake.common.value import AbstractValue

from drake_auv.behaviour import Behaviour, trajectory_reference
from drake_auv.following.behaviours import FollowConfig, FollowerState
from drake_auv.random_streams import stream
from drake_auv.signals import BehaviourStatus, Consumed, Profile, Reference
from drake_auv.sonar.returns import SonarReturns

MODES = ("search", "follow", "turn")


def _no_profile(mode: str = "search") -> np.ndarray:
    """The `profile` value while no profile is seen: NaN distances, not valid, `mode`."""
    profile = Profile(np.full(Profile.size(), np.nan))
    profile.valid, profile.mode = 0.0, MODES.index(mode)
    return profile[:]


class ProfileFollowingController(Behaviour):
    """Drives the tracker from profiler returns.

    Args:
        legs: {leg index: `FollowConfig`} of the mission legs it flies, or one `FollowConfig`
            for leg 0 (the controller alone, its `leg` input unconnected).
        period: update period, s; use the profiler's (its returns hold the pings since its
            last update).
        seed: the run's seed; leg k's RANSAC draws from its `following` stream, child k
            (`drake_auv.random_streams`).
    """

    def __init__(self, legs: FollowConfig | dict[int, FollowConfig] = FollowConfig(),
                 period: float = 0.1, seed: int = 0):
        super().__init__({0: legs} if isinstance(legs, FollowConfig) else legs)
        if not (np.isfinite(period) and 1e-3 <= period <= 5.0):
            raise ValueError(f"ProfileFollowingController period must be in [0.001, 5] s, "
                             f"got {period}")
        if not self.legs:
            raise ValueError("ProfileFollowingController needs at least one leg")
        self.period = float(period)
        self.seed = int(seed)
        self.returns_input = self.DeclareAbstractInputPort(
            "returns", AbstractValue.Make(SonarReturns.empty(20.0)))
        self._followers = {leg: config.follower(stream(self.seed, "following", leg))
                           for leg, config in self.legs.items()}  # immutable
        self._follower_index = self.DeclareAbstractState(
            AbstractValue.Make(self._followers[min(self.legs)].initial_state()))
        self._reference = self.DeclareDiscreteState(Reference.size())
        self._reference_time = self.DeclareDiscreteState(1)
        self._consumed = self.DeclareDiscreteState(np.full(Consumed.size(), -1.0))
        self._profile = self.DeclareDiscreteState(_no_profile())
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_reference)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_reference)
        self.DeclareReferenceOutput(self._calc_reference, {
            self.discrete_state_ticket(self._reference),
            self.discrete_state_ticket(self._reference_time),
            self.discrete_state_ticket(self._consumed),
            self.input_port_ticket(self.leg_input.get_index()),
            self.input_port_ticket(self.state_input.get_index()), self.time_ticket()})
        self.DeclareStatusOutput(self._status, {self.discrete_state_ticket(self._consumed)})
        self.profile_output = self.DeclareStateOutputPort("profile", self._profile)

    def follower(self, context) -> FollowerState:
        """The follower's state (its map, turn count, ...) held in this system's own `context`
        (from a diagram's context: `GetMyContextFromRoot`), for inspection."""
        return context.get_abstract_state(self._follower_index).get_value()

    def _update_reference(self, context, state):
        leg = self.leg(context)
        follower = self._followers.get(leg)
        if follower is None:
            return  # not flying
        t = context.get_time()
        consumed = Consumed(context.get_discrete_state(self._consumed).get_value().copy())
        if consumed.leg != leg:  # a new leg: a new follower's state
            held = follower.initial_state()
        else:
            held = self.follower(context)
            if held.time is not None and t <= held.time:
                return  # the initialization and the first periodic event share t = 0
        returns = self.returns_input.Eval(context) if self.returns_input.HasValue(context) else None
        points = np.empty((0, 3))
        if returns is not None and returns.sequence != consumed.sequence:  # each batch once
            points, consumed.sequence = returns.points_nav, returns.sequence
        consumed.leg = leg
        held, out = follower.update(held, t, self.state_input.Eval(context), points)
        state.get_mutable_abstract_state(self._follower_index).set_value(held)
        profile = Profile(_no_profile(out.mode))
        if out.estimate is not None:
            est = out.estimate
            profile.distance, profile.normal_distance = est.distance, est.normal_distance
            profile.normal, profile.orientation = est.normal, est.orientation
            profile.valid = 1.0
        discrete = state.get_mutable_discrete_state()
        discrete.set_value(self._reference, out.reference)
        discrete.set_value(self._reference_time, [t])
        discrete.set_value(self._consumed, consumed[:])
        discrete.set_value(self._profile, profile[:])

    def _status(self, context) -> BehaviourStatus:
        consumed = Consumed(context.get_discrete_state(self._consumed).get_value())
        status = BehaviourStatus.zeros()
        status.leg, status.progress = consumed.leg, consumed.sequence
        return status

    def _calc_reference(self, context, output):
        leg = self.leg(context)
        consumed = Consumed(context.get_discrete_state(self._consumed).get_value())
        if consumed.leg != leg:  # before the leg's first update
            output.SetFromVector(trajectory_reference(None, 0.0, self.state_input, context))
            return
        reference = Reference(context.get_discrete_state(self._reference).get_value().copy())
        since = context.get_time() - context.get_discrete_state(self._reference_time)[0]
        reference.position += reference.velocity * since
        output.SetFromVector(reference[:])
