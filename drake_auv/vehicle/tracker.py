"""`TrajectoryTracker`: follows the 8-vector reference in position and heading.

A discrete controller at `period` (s) over `drake_auv.control.TrackingController`; its wrench
is held between updates (zero-order hold) in the discrete state, followed by the position
integral.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

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
        self._xd = self.DeclareDiscreteState(BasicVector(np.zeros(7)))  # wrench (4), integral (3)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update_wrench)
        self.wrench_output = self.DeclareVectorOutputPort(
            "wrench", 4, self._calc_wrench, prerequisites_of_calc={self.xd_ticket()})

    def _update_wrench(self, context, discrete_state):
        x = context.get_discrete_state(self._xd).get_value()
        wrench, integral = self.controller.wrench(self.reference_input.Eval(context),
                                                  self.state_input.Eval(context), x[4:7],
                                                  self.period)
        discrete_state.set_value(self._xd, np.concatenate([wrench, integral]))

    def _calc_wrench(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._xd).get_value()[:4])
