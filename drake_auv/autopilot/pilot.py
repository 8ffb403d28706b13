"""`AutopilotPilot`: flies an exported vehicle mission with its autopilot's semantics.

A behaviour beside the path reference, profile following and the replanner, behind the same
`PortSwitch`: while one of its legs flies, it executes that leg's mission items one at a time
the way COLA2 or ArduSub AUTO does (`drake_auv.autopilot.semantics`), from the estimated state
and the seabed elevation its own DVL measures, never the true world. Every `period` s (the
autopilots' 10 Hz control rate) it checks the current item's arrival and hold, and starts the
next; the `reference` output is the tracker's reference for the current item.

Discrete-state groups: `item` (`semantics.ITEM_FIELDS`, the current item's record) and
`status` (`signals.BehaviourStatus`, -1 before its first leg; progress: the current item).

A `Behaviour` (`drake_auv.behaviour`). Ports (views in `drake_auv.signals`): inputs
`estimated_state` (`VehicleState`), `leg` (`LegSignal`), `seabed_elevation` (1, m, NaN without
bottom lock: the `DvlAltimeter`'s); outputs `reference` (`Reference`) and `status`
(`BehaviourStatus`).
"""

from __future__ import annotations

import numpy as np

from drake_auv.autopilot.items import FlownMission
from drake_auv.autopilot.semantics import (INDEX, ITEM_FIELDS, REACHED_S, SEABED_Z,
                                           item_reached, item_reference, start_record)
from drake_auv.behaviour import Behaviour, trajectory_reference
from drake_auv.signals import BehaviourStatus


class AutopilotPilot(Behaviour):
    """Flies `missions` (see the module docstring).

    Args:
        missions: {leg index: `FlownMission`}, or one `FlownMission` for leg 0.
        period: control period, s, in (0, 1].
    """

    def __init__(self, missions: FlownMission | dict[int, FlownMission], period: float = 0.1):
        super().__init__({0: missions} if isinstance(missions, FlownMission) else missions)
        if not (np.isfinite(period) and 0 < period <= 1.0):
            raise ValueError(f"AutopilotPilot period must be in (0, 1] s, got {period}")
        self.missions = self.legs
        self.period = float(period)
        self.seabed_input = self.DeclareVectorInputPort("seabed_elevation", 1)
        initial = np.full(len(ITEM_FIELDS), np.nan)
        self._item = self.DeclareDiscreteState(initial)
        status = BehaviourStatus.zeros()
        status.leg = -1.0  # before its first leg
        self._status = self.DeclareDiscreteState(status[:])
        self.DeclareInitializationDiscreteUpdateEvent(self._update_item)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update_item)
        self.DeclareReferenceOutput(self._calc_reference, {
            self.discrete_state_ticket(self._item), self.discrete_state_ticket(self._status),
            self.input_port_ticket(self.state_input.get_index()),
            self.input_port_ticket(self.seabed_input.get_index())})
        self.DeclareStatusOutput(group=self._status)

    def _seabed(self, context) -> float:
        return float(self.seabed_input.Eval(context)[0]) if self.seabed_input.HasValue(
            context) else float("nan")

    def _update_item(self, context, discrete_state):
        leg = self.leg(context)
        mission = self.missions.get(leg)
        if mission is None:
            return
        status = BehaviourStatus(context.get_discrete_state(self._status).get_value().copy())
        t, x, seabed = context.get_time(), self.state_input.Eval(context), self._seabed(context)
        if status.leg != leg:  # the leg begins: its first item
            discrete_state.set_value(self._item, start_record(
                mission.autopilot, mission.legs, 0, t, x, seabed))
            status = BehaviourStatus.zeros()
            status.leg = leg
            discrete_state.set_value(self._status, status[:])
            return
        if status.finished:
            return
        record = context.get_discrete_state(self._item).get_value().copy()
        if np.isfinite(seabed):
            record[SEABED_Z] = seabed
        item = mission.legs[int(record[INDEX])]
        if record[REACHED_S] < 0 and item_reached(mission.autopilot, item, record, x, seabed):
            record[REACHED_S] = t
        if record[REACHED_S] >= 0 and t - record[REACHED_S] >= item.hold_s - 1e-9:
            following = int(record[INDEX]) + 1
            if following == len(mission.legs):
                status.finished = 1.0
            else:
                record = start_record(mission.autopilot, mission.legs, following, t, x,
                                      record[SEABED_Z])
                status.progress = following
        discrete_state.set_value(self._item, record)
        discrete_state.set_value(self._status, status[:])

    def _calc_reference(self, context, output):
        x = self.state_input.Eval(context)
        status = BehaviourStatus(context.get_discrete_state(self._status).get_value())
        mission = self.missions.get(int(status.leg))
        if mission is None:  # before its first leg: hold the estimated pose
            output.SetFromVector(trajectory_reference(None, 0.0, self.state_input, context))
            return
        record = context.get_discrete_state(self._item).get_value()
        item = mission.legs[int(record[INDEX])]
        output.SetFromVector(item_reference(mission.autopilot, item, record, x,
                                            self._seabed(context), mission.speed(item),
                                            mission.heave_in_3d))
