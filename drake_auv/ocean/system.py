"""`Ocean`: the water at the vehicle, a thin LeafSystem over `drake_auv.ocean.model`.

Input `state` (the true 12-vector `VehicleState`); output `water` (6, `signals.Water`): the
world-frame water velocity (m/s) and acceleration (m/s^2) at the vehicle's position, for the
dynamics' relative-velocity hydrodynamics. The turbulence deviation (2: speed m/s, direction
rad) is the discrete-state group `turbulence`, advanced every `period` seconds by the exact
Ornstein-Uhlenbeck transition (its statistics do not depend on `period`) and drawn at the
start from its stationary law; the generator it draws from is abstract state (each Context
holds its own copy), the run's `ocean.turbulence` stream.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.turbulence import TURBULENCE_SIZE
from drake_auv.random_streams import generator
from drake_auv.signals import VehicleState, Water

OCEAN_PERIOD_S = 0.1  # the turbulence's update period, s


class Ocean(LeafSystem):
    """Input `state` (12); output `water` (6)."""

    def __init__(self, model: OceanModel, seed=0, period: float = OCEAN_PERIOD_S):
        """`seed`: the run's seed (the turbulence draws from its `ocean.turbulence` stream,
        `drake_auv.random_streams`); `period`: s between turbulence updates."""
        super().__init__()
        self.model, self.period = model, float(period)
        self.state_input = self.DeclareVectorInputPort("state", VehicleState.size())
        rng = generator(seed, "ocean.turbulence")
        initial = (model.turbulence.initial(rng) if model.turbulence.enabled
                   else np.zeros(TURBULENCE_SIZE))
        self._turbulence = self.DeclareDiscreteState(BasicVector(initial))
        self._rng = self.DeclareAbstractState(AbstractValue.Make(rng))
        if model.turbulence.enabled:
            self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0,
                                                        self._update_turbulence)
        self.water_output = self.DeclareVectorOutputPort(
            "water", Water.size(), self._calc_water, prerequisites_of_calc={
                self.time_ticket(), self.input_port_ticket(self.state_input.get_index()),
                self.discrete_state_ticket(self._turbulence)})

    def turbulence(self, context) -> np.ndarray:
        """The turbulence deviation (2,): speed (m/s), direction (rad)."""
        return context.get_discrete_state(self._turbulence).get_value().copy()

    def _update_turbulence(self, context, state):
        rng = state.get_mutable_abstract_state(self._rng).get_mutable_value()
        deviation = context.get_discrete_state(self._turbulence).get_value()
        state.get_mutable_discrete_state(self._turbulence).set_value(
            self.model.turbulence.step(deviation, self.period, rng))

    def _calc_water(self, context, output):
        position = VehicleState(self.state_input.Eval(context)).position
        velocity, acceleration = self.model.water(
            context.get_time(), position[None, :],
            context.get_discrete_state(self._turbulence).get_value())
        water = Water(output.get_mutable_value())
        water.velocity, water.acceleration = velocity[0], acceleration[0]
