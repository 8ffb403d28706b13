"""`ThrusterAllocation`: desired body wrench [X, Y, Z, N] -> five thrust commands.

Minimum-norm pseudo-inverse of the surge/sway/heave/yaw rows of the thruster configuration
matrix; a command beyond a thruster's limit scales all five thrusts together, so the wrench
keeps its direction (`drake_auv.vehicle.allocate_thrust`). Stateless, direct feedthrough.
"""

from __future__ import annotations

from pydrake.systems.framework import LeafSystem

from drake_auv.vehicle.model import NUM_THRUSTERS, Girona500Params, allocate_thrust


class ThrusterAllocation(LeafSystem):
    """Input `wrench` (4: X, Y, Z N; N N m, body FLU); output `thrust` (5, N)."""

    def __init__(self, params: Girona500Params | None = None):
        super().__init__()
        params = params if params is not None else Girona500Params()
        self.allocation = params.allocation_matrix()
        self.max_thrust = params.max_thrust
        self.wrench_input = self.DeclareVectorInputPort("wrench", 4)
        self.thrust_output = self.DeclareVectorOutputPort(
            "thrust", NUM_THRUSTERS, self._calc_thrust,
            prerequisites_of_calc={self.all_input_ports_ticket()})

    def _calc_thrust(self, context, output):
        output.SetFromVector(allocate_thrust(self.allocation, self.wrench_input.Eval(context),
                                             self.max_thrust))
