"""The behaviour contract: what every system that drives the tracker for a mission leg is.

A mission is a sequence of legs (a transit, a profile-following run, a survey), numbered from
0. The `MissionSupervisor` outputs `leg` (`signals.LegSignal`: index, start_s); a behaviour
(the path reference, the profile-following controller, the replanner, the autopilot pilot, the
view planner, a step's own) is a `Behaviour`: given the legs it serves (its leg table, leg
index -> that leg's parameters), it does its work only while one of them is flying, starting
afresh when a new one begins. A behaviour whose `leg` input is left unconnected serves leg 0
from t = 0, so it runs on its own in a test or an example.

Ports every behaviour has (views in `drake_auv.signals`): inputs `estimated_state`
(`VehicleState`) and `leg` (`LegSignal`); outputs `reference` (`Reference`, world) and
`status` (`BehaviourStatus`: `[leg, finished, progress]`, the leg it last flew, -1 before any;
finished 0/1; progress its own measure of how far it got, named in its docstring). The
supervisor ends a leg its behaviour reports finished by one rule
(`drake_auv.mission.legs.leg_finished`). Further
inputs (a map, the nominal plan, a sensor's returns) are the behaviour's own, by name.

A behaviour that flies a timed path holds it in abstract state (`DeclareTrajectoryState`: a
`TrajectoryHolder`, or any immutable value with a `trajectory` attribute) and its `reference`
is that trajectory's value and rate (`trajectory_reference`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.signals import BehaviourStatus, LegSignal, Reference, VehicleState

LEG_SIZE = LegSignal.size()


def read_leg(port, context) -> tuple[int, float]:
    """(index, start time in s) from a `leg` input port; (0, 0.0) when it is unconnected."""
    if not port.HasValue(context):
        return 0, 0.0
    leg = LegSignal(port.Eval(context))
    return int(leg.index), float(leg.start_s)


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
class TrajectoryHolder:
    """The path being flown, timed (None before the first leg). A new leg stores a new one and
    the trajectory is never modified once stored (`shiftRight` comes before), so Drake's state
    copies, two at every update, may share it: a real copy of a plan's trajectory costs
    2.3 us a segment (12 ms for 5000 segments, every 0.1 s)."""

    trajectory: PiecewisePolynomial | None = None

    def __deepcopy__(self, memo):
        return self


class Behaviour(LeafSystem):
    """Base of the behaviours (see the module docstring).

    Args:
        legs: the leg table, {leg index: that leg's parameters} (None where the behaviour
            takes none).
    """

    def __init__(self, legs: dict):
        super().__init__()
        self.legs = dict(legs)
        self.state_input = self.DeclareVectorInputPort("estimated_state", VehicleState.size())
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)

    def leg(self, context) -> int:
        """The index of the leg flying (0 with the `leg` input unconnected)."""
        return read_leg(self.leg_input, context)[0]

    progress_is_share = False  # True: the status's progress is the share of the leg done

    def share(self, context) -> float | None:
        """The share of its current leg done, in [0, 1], from this system's `context`, for a
        progress display (`MissionSupervisor.flown_share`): its status's progress when that is
        a share (`progress_is_share`), else None (it cannot tell)."""
        if not self.progress_is_share:
            return None
        return float(BehaviourStatus(self.status_output.Eval(context)).progress)

    def DeclareTrajectoryState(self, initial=None):
        """Declares the abstract state holding the timed path (`initial`: a value with a
        `trajectory` attribute, default an empty `TrajectoryHolder`); returns its index."""
        self._trajectory_index = self.DeclareAbstractState(AbstractValue.Make(
            initial if initial is not None else TrajectoryHolder()))
        return self._trajectory_index

    def held(self, context):
        """The value held by `DeclareTrajectoryState` in this system's `context`."""
        return context.get_abstract_state(self._trajectory_index).get_value()

    def DeclareReferenceOutput(self, calc=None, prerequisites=None):
        """Declares the `reference` output (`Reference`); `calc` defaults to the held
        trajectory's reference (prerequisites: the held value, time, the estimated state)."""
        if calc is None:
            calc = self._calc_trajectory_reference
            prerequisites = {self.abstract_state_ticket(self._trajectory_index),
                             self.time_ticket(),
                             self.input_port_ticket(self.state_input.get_index())}
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", Reference.size(), calc, prerequisites_of_calc=prerequisites)
        return self.reference_output

    def DeclareStatusOutput(self, calc=None, prerequisites=None, group=None):
        """Declares the `status` output (`BehaviourStatus`): the discrete-state `group` that
        holds it, or `calc(context) -> BehaviourStatus` with its `prerequisites`."""
        if group is not None:
            self.status_output = self.DeclareStateOutputPort("status", group)
        else:
            self.status_output = self.DeclareVectorOutputPort(
                "status", BehaviourStatus.size(),
                lambda context, output: output.SetFromVector(calc(context)[:]),
                prerequisites_of_calc=prerequisites)
        return self.status_output

    def _calc_trajectory_reference(self, context, output):
        output.SetFromVector(trajectory_reference(self.held(context).trajectory,
                                                  context.get_time(), self.state_input,
                                                  context))
