"""`Navigation`: true state -> estimated state with a dead-reckoning error model.

A thin adapter over `drake_auv.vehicle.navigation`: the error vector is discrete state updated
every `params.period` seconds (update n draws from the run's `navigation` stream, child n, so
the same seed gives the same run); the output is the current true state plus that error. With
all error sources zero (the default) no update is declared and the output equals the input
exactly, current or not (an ideal navigation).
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.signals import NavigationError
from drake_auv.vehicle.model import STATE_SIZE, WATER_SIZE
from drake_auv.vehicle.navigation import ERROR_SIZE, NavigationParams, estimate, update_error


class Navigation(LeafSystem):
    """Inputs `true_state` (12), `water` (6, `signals.Water`: the water at the vehicle; not
    connected: still water) and `bottom_lock` (1: > 0.5 while the DVL tracks the bottom, as
    the `DvlAltimeter`'s; not connected: always); outputs `estimated_state` (12),
    `water_tracking` (1: 1 when the last update dead-reckoned through the water, 0 over the
    bottom) and `current_drift` (2, m: the part of the position drift the current caused
    while the DVL tracked the water, world x, y)."""

    def __init__(self, params: NavigationParams | None = None):
        super().__init__()
        self.params = params if params is not None else NavigationParams()
        self.true_state_input = self.DeclareVectorInputPort("true_state", STATE_SIZE)
        self.water_input = self.DeclareVectorInputPort("water", WATER_SIZE)
        self.bottom_lock_input = self.DeclareVectorInputPort("bottom_lock", 1)
        self._xd = self.DeclareDiscreteState(BasicVector(np.zeros(ERROR_SIZE)))
        if not self.params.exact:
            self.DeclarePeriodicDiscreteUpdateEvent(self.params.period, 0.0, self._update_error)
        error_ticket = {self.discrete_state_ticket(self._xd)}
        self.estimated_state_output = self.DeclareVectorOutputPort(
            "estimated_state", STATE_SIZE, self._calc_estimated_state,
            prerequisites_of_calc={self.input_port_ticket(self.true_state_input.get_index()),
                                   *error_ticket})
        self.water_tracking_output = self.DeclareVectorOutputPort(
            "water_tracking", 1, self._calc_water_tracking, prerequisites_of_calc=error_ticket)
        self.current_drift_output = self.DeclareVectorOutputPort(
            "current_drift", 2, self._calc_current_drift, prerequisites_of_calc=error_ticket)

    def drift(self, context) -> np.ndarray:
        """The current horizontal drift (2,), m (estimate minus truth, without white noise)."""
        return context.get_discrete_state(self._xd).get_value()[:2].copy()

    def _error(self, context):
        return NavigationError(context.get_discrete_state(self._xd).get_value())

    def _update_error(self, context, discrete_state):
        lock = (not self.bottom_lock_input.HasValue(context)
                or self.bottom_lock_input.Eval(context)[0] > 0.5)
        water = (self.water_input.Eval(context)  # read only while the DVL tracks the water
                 if not lock and self.water_input.HasValue(context) else None)
        discrete_state.set_value(self._xd, update_error(
            self.params, self._error(context)[:], self.true_state_input.Eval(context), water,
            lock))

    def _calc_estimated_state(self, context, output):
        true_state = self.true_state_input.Eval(context)
        if self.params.exact:
            output.SetFromVector(true_state)
            return
        output.SetFromVector(estimate(self.params, context.get_discrete_state(self._xd).get_value(),
                                      true_state))

    def _calc_water_tracking(self, context, output):
        output.SetAtIndex(0, self._error(context).water_tracking)

    def _calc_current_drift(self, context, output):
        output.SetFromVector(self._error(context).current_drift)
