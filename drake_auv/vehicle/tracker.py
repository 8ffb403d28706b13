"""`TrajectoryTracker`: follows the 8-vector reference in position and heading.

A discrete controller at `period` (s) over `drake_auv.vehicle.control.TrackingController`;
two discrete-state groups: the wrench, held between updates (zero-order hold) and output as
it is, and the position error integral.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import LeafSystem

from drake_auv.vehicle.control import TrackingController, TrackingGains
from drake_auv.vehicle.model import STATE_SIZE, Girona500Params


class TrajectoryTracker(LeafSystem):
    """Inputs `reference` (8, world) and `state` (12, estimated); output `wrench` (4, body)."""

    def __init__(self, params: Girona500Params | None = None, gains: TrackingGains | None = None,
                 period: float = 0.05):
        super().__init__()
        if not (np.isfinite(period) and 1e-3 <= period <= 1.0):
            raise ValueError(f"tracker period must be in [0.001, 1] s, got {period}")
        self.controller = TrackingController(params, gains)
        self.period = float(period)
        self.reference_input = self.DeclareVectorInputPort("reference", 8)
        self.state_input = self.DeclareVectorInputPort("state", STATE_SIZE)
        self._wrench = self.DeclareDiscreteState(4)
        self._integral = self.DeclareDiscreteState(3)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update_wrench)
        self.wrench_output = self.DeclareStateOutputPort("wrench", self._wrench)

    def _update_wrench(self, context, discrete_state):
        wrench, integral = self.controller.wrench(
            self.reference_input.Eval(context), self.state_input.Eval(context),
            context.get_discrete_state(self._integral).get_value(), self.period)
        discrete_state.set_value(self._wrench, wrench)
        discrete_state.set_value(self._integral, integral)
