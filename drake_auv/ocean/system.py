"""`Ocean`: the water at the vehicle, a thin LeafSystem over `drake_auv.ocean.model`.

Input `state` (the true 12-vector `VehicleState`); output `water` (6, `signals.Water`): the
world-frame water velocity (m/s) and acceleration (m/s^2) at the vehicle, for the dynamics'
relative-velocity hydrodynamics and the navigation's water tracking.

The water is the discrete-state group `water`, sampled once per `period` (the dynamics' own
step): the update at time t stores the water at t + period at the vehicle's position at t, so
the dynamics' step at t + period reads the water of its own time, computed once whoever reads
it (the dynamics, the navigation, the log). The vehicle moves a few centimetres in a step; that
is the position's lag. An initialization event samples t = 0.

The turbulence deviation (2: speed m/s, direction rad) is the group `turbulence`, advanced
every `turbulence_period` seconds by the exact Ornstein-Uhlenbeck transition (its statistics
do not depend on the period) and drawn at the start from its stationary law. Update k takes
its normal draws from the run's `ocean.turbulence` stream (`drake_auv.random_streams`),
child k // 1024: a draw depends on (seed, k) alone, k is the group `draws`, and no generator
lives in the Context.
"""

from __future__ import annotations

import functools

import numpy as np
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem

from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.turbulence import TURBULENCE_SIZE
from drake_auv.random_streams import generator
from drake_auv.signals import VehicleState, Water

OCEAN_PERIOD_S = 0.05  # s, the water's sampling period (the dynamics' step by default)
TURBULENCE_PERIOD_S = 0.1  # s, the turbulence's update period
DRAW_BLOCK = 1024  # turbulence updates per child stream


@functools.lru_cache(maxsize=4)  # a dive reads its blocks in order
def _normals(seed: int, block: int) -> np.ndarray:
    """The standard normal draws (DRAW_BLOCK, 2) of turbulence updates block * DRAW_BLOCK ...:
    a pure function of its arguments (the blocks in use cached, so a dive draws each once)."""
    return generator(seed, "ocean.turbulence", block + 1).standard_normal(
        (DRAW_BLOCK, TURBULENCE_SIZE))


class Ocean(LeafSystem):
    """Input `state` (12); output `water` (6)."""

    def __init__(self, model: OceanModel, seed: int = 0, period: float = OCEAN_PERIOD_S,
                 turbulence_period: float = TURBULENCE_PERIOD_S):
        """`seed`: the run's seed; `period`: s between samples of the water (the dynamics'
        step); `turbulence_period`: s between turbulence updates."""
        super().__init__()
        self.model, self.seed = model, int(seed)
        self.period, self.turbulence_period = float(period), float(turbulence_period)
        self.state_input = self.DeclareVectorInputPort("state", VehicleState.size())
        initial = (model.turbulence.initial(generator(seed, "ocean.turbulence", 0))
                   if model.turbulence.enabled else np.zeros(TURBULENCE_SIZE))
        self._turbulence = self.DeclareDiscreteState(BasicVector(initial))
        self._draws = self.DeclareDiscreteState(1)
        self._water = self.DeclareDiscreteState(Water.size())
        if model.turbulence.enabled:
            self.DeclarePeriodicDiscreteUpdateEvent(self.turbulence_period, 0.0,
                                                    self._update_turbulence)
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize_water)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update_water)
        self.water_output = self.DeclareStateOutputPort("water", self._water)

    def turbulence(self, context) -> np.ndarray:
        """The turbulence deviation (2,): speed (m/s), direction (rad)."""
        return context.get_discrete_state(self._turbulence).get_value().copy()

    def _sample(self, context, t: float) -> np.ndarray:
        """The water (6,) at time `t` at the vehicle's position now."""
        position = VehicleState(self.state_input.Eval(context)).position
        velocity, acceleration = self.model.water(
            t, position[None, :], context.get_discrete_state(self._turbulence).get_value())
        return np.concatenate([velocity[0], acceleration[0]])

    def _initialize_water(self, context, discrete_state):
        discrete_state.set_value(self._water, self._sample(context, context.get_time()))
        return EventStatus.Succeeded()

    def _update_water(self, context, discrete_state):
        discrete_state.set_value(self._water,
                                 self._sample(context, context.get_time() + self.period))

    def _update_turbulence(self, context, discrete_state):
        k = int(context.get_discrete_state(self._draws).GetAtIndex(0))
        deviation = context.get_discrete_state(self._turbulence).get_value()
        discrete_state.set_value(self._turbulence, self.model.turbulence.advance(
            deviation, self.turbulence_period, _normals(self.seed, k // DRAW_BLOCK)[
                k % DRAW_BLOCK]))
        discrete_state.set_value(self._draws, [k + 1])
