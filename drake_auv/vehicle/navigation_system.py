"""`Navigation`: true state -> estimated state with a dead-reckoning error model.

A thin adapter over `drake_auv.navigation`: the error vector is discrete state updated every
`params.period` seconds (update n draws from the run's `navigation` stream, child n, so the
same seed gives the same run); the output is the current true state plus that error. With all error
sources zero (the default) no update is declared and the output equals the input exactly.
"""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.vehicle.navigation import ERROR_SIZE, NavigationParams, estimate, update_error
from drake_auv.vehicle.model import STATE_SIZE


class Navigation(LeafSystem):
    """Input `true_state` (12); output `estimated_state` (12)."""

    def __init__(self, params: NavigationParams | None = None):
        super().__init__()
        self.params = params if params is not None else NavigationParams()
        self.true_state_input = self.DeclareVectorInputPort("true_state", STATE_SIZE)
        self._xd = self.DeclareDiscreteState(BasicVector(np.zeros(ERROR_SIZE)))
        if not self.params.exact:
            self.DeclarePeriodicDiscreteUpdateEvent(self.params.period, 0.0, self._update_error)
        self.estimated_state_output = self.DeclareVectorOutputPort(
            "estimated_state", STATE_SIZE, self._calc_estimated_state)

    def drift(self, context) -> np.ndarray:
        """The current horizontal drift (2,), m (estimate minus truth, without white noise)."""
        return context.get_discrete_state(self._xd).get_value()[:2].copy()

    def _update_error(self, context, discrete_state):
        error = context.get_discrete_state(self._xd).get_value()
        discrete_state.set_value(
            self._xd, update_error(self.params, error, self.true_state_input.Eval(context)))

    def _calc_estimated_state(self, context, output):
        true_state = self.true_state_input.Eval(context)
        if self.params.exact:
            output.SetFromVector(true_state)
            return
        output.SetFromVector(estimate(self.params, context.get_discrete_state(self._xd).get_value(),
                                      true_state))
