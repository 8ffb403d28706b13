"""`Girona500Dynamics`: the 6-DOF Fossen model of the GIRONA 500 as a discrete-time LeafSystem.

The plant is stepped with fixed-step RK4 at `time_step` (s) by a periodic discrete update,
which keeps a 600 s mission far faster than real time (the model itself is in
`drake_auv.vehicle.Girona500Model`, in Fossen's relative-velocity form for moving water).
Discrete state: the 12-state of docs/architecture.md, the five actual thrusts (first-order
lag behind the `thrust` input), the water's acceleration at the last step (the model
extrapolates it over the next) and the time each thruster's command has spent at its limit.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.framework import LeafSystem

from drake_auv.signals import VehicleState
from drake_auv.vehicle.model import (NUM_THRUSTERS, STATE_SIZE, WATER_SIZE, Girona500Model,
                                     Girona500Params)

# A command within this fraction of the thrust limit counts as at the limit (the allocation
# scales a saturated command so that its largest thrust is the limit, up to rounding).
AT_LIMIT = 1.0 - 1e-9


class Girona500Dynamics(LeafSystem):
    """Inputs `thrust` (5, N) and `water` (6: world-frame water velocity at the vehicle, m/s,
    then its acceleration, m/s^2; not connected: still water); outputs `state` (12), `pose`
    (RigidTransform X_WB) and `thrust_saturation` (5: the share of the simulated time each
    thruster's command has been at its limit, 0 .. 1)."""

    def __init__(self, params: Girona500Params | None = None, time_step: float = 0.05,
                 initial_state=None):
        super().__init__()
        if not (np.isfinite(time_step) and 1e-4 <= time_step <= 0.2):
            raise ValueError(f"time_step must be in [1e-4, 0.2] s, got {time_step}")
        self.model = Girona500Model(params)
        self.params = self.model.params
        self.time_step = float(time_step)
        initial = np.zeros(STATE_SIZE) if initial_state is None else _checked_state(initial_state)
        self.thrust_input = self.DeclareVectorInputPort("thrust", NUM_THRUSTERS)
        self.water_input = self.DeclareVectorInputPort("water", WATER_SIZE)
        # Four discrete-state groups: the 12-state, the thrusters' lagged forces (N), the
        # water's acceleration at the last step (m/s^2; NaN before any water), and the time
        # each thruster's command has been at its limit with the time stepped (s).
        self._state = self.DeclareDiscreteState(initial)
        self._thrust = self.DeclareDiscreteState(NUM_THRUSTERS)
        self._water = self.DeclareDiscreteState(np.full(3, np.nan))
        self._saturation = self.DeclareDiscreteState(NUM_THRUSTERS + 1)
        self.DeclarePeriodicDiscreteUpdateEvent(self.time_step, 0.0, self._update_state)
        self.state_output = self.DeclareStateOutputPort("state", self._state)
        self.pose_output = self.DeclareAbstractOutputPort(
            "pose", lambda: AbstractValue.Make(RigidTransform()), self._calc_pose,
            prerequisites_of_calc={self.discrete_state_ticket(self._state)})
        self.thrust_saturation_output = self.DeclareVectorOutputPort(
            "thrust_saturation", NUM_THRUSTERS, self._calc_thrust_saturation,
            prerequisites_of_calc={self.discrete_state_ticket(self._saturation)})

    def set_state(self, context, state) -> None:
        """Sets the 12-state (thrusts to zero, no water history) in this system's context."""
        context.SetDiscreteState(self._state, _checked_state(state))
        context.SetDiscreteState(self._thrust, np.zeros(NUM_THRUSTERS))
        context.SetDiscreteState(self._water, np.full(3, np.nan))
        context.SetDiscreteState(self._saturation,
                                 np.zeros(context.get_discrete_state(self._saturation).size()))

    def _update_state(self, context, discrete_state):
        x = np.concatenate([context.get_discrete_state(self._state).get_value(),
                            context.get_discrete_state(self._thrust).get_value()])
        command = self.thrust_input.Eval(context)
        water = previous = None
        if self.water_input.HasValue(context):
            water = self.water_input.Eval(context)  # `signals.Water`
            previous = context.get_discrete_state(self._water).get_value()
            previous = None if math.isnan(previous[0]) else previous
            discrete_state.set_value(self._water, water[3:])  # its acceleration
        x = self.model.step(x, command, self.time_step, water, previous)
        discrete_state.set_value(self._state, x[:STATE_SIZE])
        discrete_state.set_value(self._thrust, x[STATE_SIZE:])
        saturation = context.get_discrete_state(self._saturation).get_value().copy()
        saturation[:NUM_THRUSTERS] += self.time_step * (
            np.abs(command) >= AT_LIMIT * self.model.max_thrust)
        saturation[NUM_THRUSTERS] += self.time_step
        discrete_state.set_value(self._saturation, saturation)

    def _calc_pose(self, context, output):
        x = VehicleState(context.get_discrete_state(self._state).get_value())
        output.set_value(RigidTransform(RollPitchYaw(x.attitude), x.position))

    def _calc_thrust_saturation(self, context, output):
        saturation = context.get_discrete_state(self._saturation).get_value()
        elapsed = saturation[NUM_THRUSTERS]
        output.SetFromVector(saturation[:NUM_THRUSTERS] / elapsed if elapsed > 0
                             else np.zeros(NUM_THRUSTERS))


def _checked_state(state) -> np.ndarray:
    state = np.asarray(state, dtype=float)
    if state.shape != (STATE_SIZE,) or not np.all(np.isfinite(state)):
        raise ValueError(f"initial_state must be {STATE_SIZE} finite numbers "
                         f"[x, y, z, roll, pitch, yaw, u, v, w, p, q, r], got {state}")
    return state
