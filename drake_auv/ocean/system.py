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
every `turbulence_period` seconds (a whole number of periods, by the same update: one event
per step) by the exact Ornstein-Uhlenbeck transition (its statistics do not depend on the
period) and drawn at the start from its stationary law. Update k takes
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
        step); `turbulence_period`: s between turbulence updates, a whole number of periods."""
        super().__init__()
        self.model, self.seed = model, int(seed)
        self.period, self.turbulence_period = float(period), float(turbulence_period)
        # the turbulence advances in the water's update, every `_every`-th one
        self._every = max(1, round(self.turbulence_period / self.period))
        if abs(self._every * self.period - self.turbulence_period) > 1e-9 * self.period:
            raise ValueError(f"turbulence_period = {turbulence_period!r} s is not a whole "
                             f"number of periods ({period!r} s); must be k * period, k >= 1")
        self._transition = model.turbulence.transition(self.turbulence_period)
        self.state_input = self.DeclareVectorInputPort("state", VehicleState.size())
        initial = (model.turbulence.initial(generator(seed, "ocean.turbulence", 0))
                   if model.turbulence.enabled else np.zeros(TURBULENCE_SIZE))
        self._turbulence = self.DeclareDiscreteState(BasicVector(initial))
        self._draws = self.DeclareDiscreteState(1)
        self._water = self.DeclareDiscreteState(Water.size())
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize_water)
        self.DeclarePeriodicDiscreteUpdateEvent(self.period, 0.0, self._update_water)
        self.water_output = self.DeclareStateOutputPort("water", self._water)

    def turbulence(self, context) -> np.ndarray:
        """The turbulence deviation (2,): speed (m/s), direction (rad)."""
        return context.get_discrete_state(self._turbulence).get_value().copy()

    def _sample(self, context, t: float) -> np.ndarray:
        """The water (6,) at time `t` at the vehicle's position now."""
        return self.model.sample(t, self.state_input.Eval(context)[:3],
                                 context.get_discrete_state(self._turbulence).get_value())[0]

    def _initialize_water(self, context, discrete_state):
        discrete_state.set_value(self._water, self._sample(context, context.get_time()))
        return EventStatus.Succeeded()

    def _update_water(self, context, discrete_state):
        """The water of the next step and, every `turbulence_period`, the turbulence's next
        deviation (the water sampled with the deviation held until now)."""
        t = context.get_time()
        discrete_state.set_value(self._water, self._sample(context, t + self.period))
        if self.model.turbulence.enabled and round(t / self.period) % self._every == 0:
            k = int(context.get_discrete_state(self._draws).GetAtIndex(0))
            decay, spread = self._transition
            discrete_state.set_value(self._turbulence, decay * context.get_discrete_state(
                self._turbulence).get_value() + spread * _normals(self.seed, k // DRAW_BLOCK)[
                    k % DRAW_BLOCK])
            discrete_state.set_value(self._draws, [k + 1])
