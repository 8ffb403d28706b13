"""`PathReference`: the tracker's reference along a timed path, started when its leg begins.

Two kinds of legs: `goto` (a transit from wherever the vehicle is when the leg begins to a
target pose, above the terrain and below the surface: `drake_auv.planning.transit`) and
`nominal` (the `nominal` input's path, the off-line plan, flown at the survey speed after a
transit to its first sample). At the first update of a leg (every `period` s) the transit and
the plan become one `PiecewisePolynomial` of [x, y, z, yaw] (`Path.chain_trajectory`: each
piece's first-order hold, shifted after the one before and concatenated in time), shifted to
the leg's start (`shiftRight`) and held in abstract state; the `reference` output is Drake's
value and first derivative of it (past its end: its end value, zero rates).

Ports: inputs `estimated_state` (12), `leg` (2), `nominal` (`Path`, only for `nominal` legs);
outputs `reference` (8, world) and `status` (2: `[leg, end_time]` of the path held, -1 before
any, so a supervisor can tell when it has been flown).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.leg_signal import LEG_SIZE, read_leg
from drake_auv.planning.path import Path
from drake_auv.planning.transit import transit
from drake_auv.signals import Reference, VehicleState
from drake_auv.vehicle.path_leg import PathLeg


def trajectory_reference(trajectory: PiecewisePolynomial | None, t: float, state_input,
                         context) -> np.ndarray:
    """The reference (`signals.Reference`) of a timed [x, y, z, yaw] `trajectory` at `t` s:
    its value and first derivative (Drake's; past the end, the end value, which `value` holds,
    and zero rates), and with no trajectory the estimated pose from `state_input` held (zero
    rates)."""
    reference = Reference.zeros()
    if trajectory is None:
        state = VehicleState(state_input.Eval(context))
        reference.position, reference.yaw = state.position, state.yaw
        return reference[:]
    reference.pose = trajectory.value(t)[:, 0]
    if t < trajectory.end_time():
        reference.rates = trajectory.EvalDerivative(t, 1)[:, 0]
    return reference[:]


@dataclass(frozen=True)
class _Timed:
    """The path being flown, timed (None before the first leg). A new leg stores a new one and
    the trajectory is never modified once stored (`shiftRight` comes before), so Drake's state
    copies, two at every update, may share it: a real copy of a plan's trajectory costs
    2.3 us a segment (12 ms for 5000 segments, every 0.1 s)."""

    trajectory: PiecewisePolynomial | None = None

    def __deepcopy__(self, memo):
        return self


class PathReference(LeafSystem):
    """Flies `goto` and `nominal` legs.

    Args:
        legs: {leg index: `PathLeg`}, or one `PathLeg` for leg 0 (`leg` input unconnected).
        terrain: callable (x, y) -> terrain elevation, m: the prior map, which transits keep
            `clearance` above (None: no terrain).
        clearance: m. min_depth: least depth of every transit sample, m.
        period: how often a new leg is looked for, s.
        yaw_rate: largest yaw rate of the timing, rad/s.
    """

    def __init__(self, legs: PathLeg | dict[int, PathLeg], terrain=None, clearance: float = 3.0,
                 min_depth: float = 1.0, period: float = 0.1,
                 yaw_rate: float = np.radians(15.0)):
        super().__init__()
        if not (np.isfinite(period) and 0 < period <= 5.0):
            raise ValueError(f"PathReference period must be in (0, 5] s, got {period}")
        self.legs = {0: legs} if isinstance(legs, PathLeg) else dict(legs)
        self.terrain, self.clearance, self.min_depth = terrain, float(clearance), float(min_depth)
        self.yaw_rate = float(yaw_rate)
        self.state_input = self.DeclareVectorInputPort("estimated_state", VehicleState.size())
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)
        self.nominal_input = self.DeclareAbstractInputPort(
            "nominal", AbstractValue.Make(Path(np.zeros((1, 3)), 0.0, (0.0, 0.0, -1.0))))
        self._timed_index = self.DeclareAbstractState(AbstractValue.Make(_Timed()))
        self._flown = self.DeclareDiscreteState(np.array([-1.0, 0.0]))  # leg, end time
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_path)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update_path)
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", Reference.size(), self._calc_reference,
            prerequisites_of_calc={self.abstract_state_ticket(self._timed_index),
                                   self.input_port_ticket(self.state_input.get_index()),
                                   self.time_ticket()})
        self.status_output = self.DeclareStateOutputPort("status", self._flown)

    def paths_for(self, leg: PathLeg, x: np.ndarray, nominal: Path | None) -> list[Path]:
        """The paths `leg` flies in order from the estimated state `x` (12): the transit, and
        for a nominal leg the plan after it."""
        end = np.asarray(leg.target if leg.kind == "goto" else nominal.points[0], dtype=float)
        end_yaw = leg.yaw if leg.kind == "goto" else float(nominal.heading[0])
        state = VehicleState(x)
        path = transit(state.position, end, float(state.yaw), end_yaw, self.terrain,
                       self.clearance, self.min_depth)
        return [path] if leg.kind == "goto" else [path, nominal]

    def _update_path(self, context, state):
        leg, _ = read_leg(self.leg_input, context)
        spec = self.legs.get(leg)
        if spec is None or context.get_discrete_state(self._flown)[0] == leg:
            return  # not ours, or already timed
        nominal = self.nominal_input.Eval(context) if spec.kind == "nominal" else None
        trajectory = Path.chain_trajectory(
            self.paths_for(spec, self.state_input.Eval(context), nominal), spec.speed,
            self.yaw_rate)
        trajectory.shiftRight(context.get_time())
        state.get_mutable_abstract_state(self._timed_index).set_value(_Timed(trajectory))
        state.get_mutable_discrete_state(self._flown).set_value([leg, trajectory.end_time()])

    def _calc_reference(self, context, output):
        output.SetFromVector(trajectory_reference(
            context.get_abstract_state(self._timed_index).get_value().trajectory,
            context.get_time(), self.state_input, context))
