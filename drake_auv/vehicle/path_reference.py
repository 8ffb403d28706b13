"""`PathReference`: the tracker's reference along a timed path, started when its leg begins.

Two kinds of legs: `goto` (a transit from wherever the vehicle is when the leg begins to a
target pose, above the terrain and below the surface: `drake_auv.planning.transit`) and
`nominal` (the `nominal` input's path, the off-line plan, flown at the survey speed after a
transit to its first sample). At the first update of a leg (every `period` s) the transit and
the plan become one `PiecewisePolynomial` of [x, y, z, yaw] (`PlannedPath.chain_trajectory`: each
piece's first-order hold, shifted after the one before and concatenated in time), shifted to
the leg's start (`shiftRight`) and held in abstract state (its leg and end time in the
discrete `flown` group, `signals.FlownLeg`); the `reference` output is Drake's value and first
derivative of it (past its end: its end value, zero rates).

A `Behaviour` (`drake_auv.behaviour`). Ports: inputs `estimated_state` (12), `leg` (2),
`nominal` (`PlannedPath`, only for `nominal` legs); outputs `reference` (8, world) and `status`
(`BehaviourStatus`: the leg of the path held, -1 before any; finished once its end time has
passed; progress the share of its duration flown, 0 to 1).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue

from drake_auv.behaviour import Behaviour, TrajectoryHolder
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.transit import transit
from drake_auv.signals import BehaviourStatus, FlownLeg, VehicleState
from drake_auv.vehicle.path_leg import PathLeg


class PathReference(Behaviour):
    """Flies `goto` and `nominal` legs.

    Args:
        legs: {leg index: `PathLeg`}, or one `PathLeg` for leg 0 (`leg` input unconnected).
        terrain: callable (x, y) -> terrain elevation, m: the prior map, which transits keep
            `clearance` above (None: no terrain).
        clearance: m. min_depth: least depth of every transit sample, m.
        period: how often a new leg is looked for, s.
        yaw_rate: largest yaw rate of the timing, rad/s.
    """

    progress_is_share = True

    def __init__(self, legs: PathLeg | dict[int, PathLeg], terrain=None, clearance: float = 3.0,
                 min_depth: float = 1.0, period: float = 0.1,
                 yaw_rate: float = np.radians(15.0)):
        super().__init__({0: legs} if isinstance(legs, PathLeg) else legs)
        if not (np.isfinite(period) and 0 < period <= 5.0):
            raise ValueError(f"PathReference period must be in (0, 5] s, got {period}")
        self.terrain, self.clearance, self.min_depth = terrain, float(clearance), float(min_depth)
        self.yaw_rate = float(yaw_rate)
        self.nominal_input = self.DeclareAbstractInputPort(
            "nominal", AbstractValue.Make(PlannedPath(np.zeros((1, 3)), 0.0, (0.0, 0.0, -1.0))))
        self._timed_index = self.DeclareTrajectoryState()
        flown = FlownLeg.zeros()
        flown.leg = -1.0  # none yet
        self._flown = self.DeclareDiscreteState(flown[:])
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_path)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update_path)
        self.DeclareReferenceOutput()
        self.DeclareStatusOutput(self._status, prerequisites={
            self.discrete_state_ticket(self._flown), self.abstract_state_ticket(self._timed_index),
            self.time_ticket()})

    def paths_for(self, leg: PathLeg, x: np.ndarray, nominal: PlannedPath | None) -> list[PlannedPath]:
        """The paths `leg` flies in order from the estimated state `x` (12): the transit, and
        for a nominal leg the plan after it."""
        end = np.asarray(leg.target if leg.kind == "goto" else nominal.points[0], dtype=float)
        end_yaw = leg.yaw if leg.kind == "goto" else float(nominal.heading[0])
        state = VehicleState(x)
        path = transit(state.position, end, float(state.yaw), end_yaw, self.terrain,
                       self.clearance, self.min_depth)
        return [path] if leg.kind == "goto" else [path, nominal]

    def _update_path(self, context, state):
        leg = self.leg(context)
        spec = self.legs.get(leg)
        flown = FlownLeg(context.get_discrete_state(self._flown).get_value())
        if spec is None or flown.leg == leg:
            return  # not ours, or already timed
        nominal = self.nominal_input.Eval(context) if spec.kind == "nominal" else None
        trajectory = PlannedPath.chain_trajectory(
            self.paths_for(spec, self.state_input.Eval(context), nominal), spec.speed,
            self.yaw_rate)
        trajectory.shiftRight(context.get_time())
        state.get_mutable_abstract_state(self._timed_index).set_value(
            TrajectoryHolder(trajectory))
        flown = FlownLeg.zeros()
        flown.leg, flown.end_s = leg, trajectory.end_time()
        state.get_mutable_discrete_state(self._flown).set_value(flown[:])

    def _status(self, context) -> BehaviourStatus:
        flown = FlownLeg(context.get_discrete_state(self._flown).get_value())
        end, status, t = flown.end_s, BehaviourStatus.zeros(), context.get_time()
        status.leg = flown.leg
        trajectory = self.held(context).trajectory
        if trajectory is not None:
            start = trajectory.start_time()
            status.finished = float(t >= end)
            status.progress = 1.0 if end <= start else float(np.clip((t - start) / (end - start),
                                                                     0.0, 1.0))
        return status
