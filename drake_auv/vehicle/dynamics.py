"""`Girona500Dynamics`: the 6-DOF Fossen model of the GIRONA 500 as a discrete-time LeafSystem.

The plant is stepped with fixed-step RK4 at `time_step` (s) by a periodic discrete update,
which keeps a 600 s mission far faster than real time (the model itself is in
`drake_auv.vehicle.Girona500Model`). Discrete state: the 12-state of docs/architecture.md
followed by the five actual thrusts (first-order lag behind the `thrust` input).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.systems.framework import LeafSystem

from drake_auv.signals import VehicleState
from drake_auv.vehicle.model import NUM_THRUSTERS, STATE_SIZE, Girona500Model, Girona500Params


class Girona500Dynamics(LeafSystem):
    """Input `thrust` (5, N); outputs `state` (12) and `pose` (RigidTransform X_WB)."""

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
        # Two discrete-state groups: the 12-state, and the thrusters' lagged forces (N).
        self._state = self.DeclareDiscreteState(initial)
        self._thrust = self.DeclareDiscreteState(NUM_THRUSTERS)
        self.DeclarePeriodicDiscreteUpdateEvent(self.time_step, 0.0, self._update_state)
        self.state_output = self.DeclareStateOutputPort("state", self._state)
        self.pose_output = self.DeclareAbstractOutputPort(
            "pose", lambda: AbstractValue.Make(RigidTransform()), self._calc_pose,
            prerequisites_of_calc={self.discrete_state_ticket(self._state)})

    def set_state(self, context, state) -> None:
        """Sets the 12-state (thrusts to zero) in this system's context."""
        context.SetDiscreteState(self._state, _checked_state(state))
        context.SetDiscreteState(self._thrust, np.zeros(NUM_THRUSTERS))

    def _update_state(self, context, discrete_state):
        x = np.concatenate([context.get_discrete_state(self._state).get_value(),
                            context.get_discrete_state(self._thrust).get_value()])
        x = self.model.step(x, self.thrust_input.Eval(context), self.time_step)
        discrete_state.set_value(self._state, x[:STATE_SIZE])
        discrete_state.set_value(self._thrust, x[STATE_SIZE:])

    def _calc_pose(self, context, output):
        x = VehicleState(context.get_discrete_state(self._state).get_value())
        output.set_value(RigidTransform(RollPitchYaw(x.attitude), x.position))


def _checked_state(state) -> np.ndarray:
    state = np.asarray(state, dtype=float)
    if state.shape != (STATE_SIZE,) or not np.all(np.isfinite(state)):
        raise ValueError(f"initial_state must be {STATE_SIZE} finite numbers "
                         f"[x, y, z, roll, pitch, yaw, u, v, w, p, q, r], got {state}")
    return state
