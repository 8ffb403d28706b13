"""`MissionSupervisor`: flies a mission's legs in order and ends the dive.

Every `period` s it judges the current leg (`drake_auv.mission.legs.goal_reached`: from the
estimated state and the behaviours' status, never the true world) and, when the leg is done
by its goal or its time budget, starts the next one. Its `leg` output tells the behaviours
which leg flies and since when; its `behaviour` output selects the tracker's reference in a
`PortSwitch`. After the last leg `done` is set, and `monitor` (a Simulator monitor) ends the
simulation with `EventStatus.ReachedTermination`.

Discrete-state groups: `leg` ([index, start time]), `progress` (of the current leg: see
`legs.PROGRESS_SIZE`), `outcomes` (per leg: 0 not ended, 1 goal reached, 2 timed out) and
`done` (1 after the last leg).

Ports: inputs `estimated_state` (12), `path_status` (2), `replanner_status` (3) (either may be
left unconnected when no leg needs it); outputs `leg` (2), `behaviour` (`InputPortIndex`).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, InputPortIndex, LeafSystem

from drake_auv.leg_signal import LEG_SIZE
from drake_auv.mission.legs import (PROGRESS_SIZE, Leg, advance_progress, goal_reached,
                                    start_progress)
from drake_auv.vehicle.model import STATE_SIZE

OUTCOMES = ("flying", "goal", "timed out")


class MissionSupervisor(LeafSystem):
    """Sequences `legs`.

    Args:
        legs: the mission's legs, in order (at least one).
        behaviour_ports: {behaviour name: index of the PortSwitch input it drives}.
        period: judging period, s, in (0, 5].
    """

    def __init__(self, legs: tuple[Leg, ...], behaviour_ports: dict[str, int],
                 period: float = 0.5):
        super().__init__()
        if not legs:
            raise ValueError("a mission needs at least one leg")
        missing = {leg.behaviour for leg in legs} - set(behaviour_ports)
        if missing:
            raise ValueError(f"no PortSwitch input for behaviour(s) {sorted(missing)}")
        if not (np.isfinite(period) and 0 < period <= 5.0):
            raise ValueError(f"MissionSupervisor period must be in (0, 5] s, got {period}")
        self.legs = tuple(legs)
        self.behaviour_ports = dict(behaviour_ports)
        self.state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self.path_status_input = self.DeclareVectorInputPort("path_status", 2)
        self.replanner_status_input = self.DeclareVectorInputPort("replanner_status", 3)
        self._leg = self.DeclareDiscreteState(LEG_SIZE)
        self._progress = self.DeclareDiscreteState(PROGRESS_SIZE)
        self._outcomes = self.DeclareDiscreteState(len(self.legs))
        self._done = self.DeclareDiscreteState(1)
        self.DeclareInitializationDiscreteUpdateEvent(self._start_mission)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update_leg)
        self.leg_output = self.DeclareStateOutputPort("leg", self._leg)
        self.behaviour_output = self.DeclareAbstractOutputPort(
            "behaviour", lambda: AbstractValue.Make(InputPortIndex(0)), self._calc_behaviour,
            prerequisites_of_calc={self.discrete_state_ticket(self._leg)})

    def _status(self, port, context, size: int) -> np.ndarray:
        return port.Eval(context) if port.HasValue(context) else np.full(size, -1.0)

    def _start_mission(self, context, discrete_state):
        x = self.state_input.Eval(context)
        discrete_state.set_value(self._leg, [0.0, context.get_time()])
        discrete_state.set_value(self._progress, start_progress(self.legs[0], x))

    def _update_leg(self, context, discrete_state):
        if context.get_discrete_state(self._done)[0]:
            return
        t = context.get_time()
        index, start = context.get_discrete_state(self._leg).get_value()
        index = int(index)
        leg = self.legs[index]
        x = self.state_input.Eval(context)
        progress = advance_progress(leg, context.get_discrete_state(self._progress).get_value(),
                                    x)
        outcome = 0
        if goal_reached(leg, index, t, x, progress,
                        self._status(self.path_status_input, context, 2),
                        self._status(self.replanner_status_input, context, 3)):
            outcome = 1
        elif t - start >= leg.max_duration:
            outcome = 2
        if outcome:
            outcomes = context.get_discrete_state(self._outcomes).get_value().copy()
            outcomes[index] = outcome
            discrete_state.set_value(self._outcomes, outcomes)
            if index + 1 == len(self.legs):
                discrete_state.set_value(self._done, [1.0])
            else:
                index += 1
                discrete_state.set_value(self._leg, [index, t])
                progress = start_progress(self.legs[index], x)
        discrete_state.set_value(self._progress, progress)

    def _calc_behaviour(self, context, output):
        index = int(context.get_discrete_state(self._leg)[0])
        output.set_value(InputPortIndex(self.behaviour_ports[self.legs[index].behaviour]))

    def monitor(self, root_context) -> EventStatus:
        """A Simulator monitor: ends the simulation once the last leg is done."""
        if self.GetMyContextFromRoot(root_context).get_discrete_state(self._done)[0]:
            return EventStatus.ReachedTermination(self, "mission complete")
        return EventStatus.Succeeded()

    def outcomes(self, context) -> list[str]:
        """Per leg, how it ended (`OUTCOMES`), from this system's `context`."""
        values = context.get_discrete_state(self._outcomes).get_value()
        return [OUTCOMES[int(v)] for v in values]
