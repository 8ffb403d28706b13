"""Injected faults as small systems spliced into the mission Diagram (`faults:` of a mission
file, `drake_auv.mission.config.FaultsSpec`). They change what the vehicle senses or does;
the `MissionSupervisor` must notice them from what the vehicle knows.

- `SonarSilence`: between a sonar and its consumers; from `start` for `duration` s every
  beam of every update has no return (the pings go on: time and sequence advance).
- `ThrusterFailure`: between the allocation and the dynamics; one thruster's command is zero
  from `start` s on (the allocation still counts on it).
- `NavigationJump`: between the navigation and every consumer of the estimate; from `time` s
  on the estimated position is moved by `offset` (a late position fix applied at once).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.signals import THRUSTER_NAMES, VehicleState
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.model import NUM_THRUSTERS, STATE_SIZE


def silenced(returns: SonarReturns) -> SonarReturns:
    """What a silent sonar delivers in place of `returns`: an update with no beams at all
    (same time and sequence). Not the same as beams without an echo, which a working sonar
    gives over open water."""
    return SonarReturns(returns.time, returns.origin_nav, np.zeros(0), np.zeros(0),
                        np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)),
                        returns.max_range, returns.sequence)


class SonarSilence(LeafSystem):
    """Input `returns_in`, output `returns` (`SonarReturns`): silent in [start, start +
    duration) s, the input otherwise."""

    def __init__(self, start: float, duration: float, max_range: float):
        super().__init__()
        if not (np.isfinite(start) and start >= 0 and np.isfinite(duration) and duration > 0):
            raise ValueError(f"SonarSilence needs start >= 0 s and duration > 0 s, got "
                             f"{start}, {duration}")
        self.start, self.end = float(start), float(start) + float(duration)
        model = AbstractValue.Make(SonarReturns.empty(max_range))
        self.returns_input = self.DeclareAbstractInputPort("returns_in", model)
        self.returns_output = self.DeclareAbstractOutputPort(
            "returns", lambda: AbstractValue.Make(SonarReturns.empty(max_range)),
            self._calc_returns,
            prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})

    def _calc_returns(self, context, output):
        returns = self.returns_input.Eval(context)
        silent = self.start <= returns.time < self.end and self.start <= context.get_time()
        output.set_value(silenced(returns) if silent else returns)


class ThrusterFailure(LeafSystem):
    """Input `thrust_command` (5, N), output `thrust` (5, N): thruster `thruster` (a name of
    `THRUSTER_NAMES`) zero from `start` s on."""

    def __init__(self, thruster: str, start: float):
        super().__init__()
        if thruster not in THRUSTER_NAMES:
            raise ValueError(f"thruster must be one of {THRUSTER_NAMES}, got {thruster!r}")
        self.index, self.start = THRUSTER_NAMES.index(thruster), float(start)
        self.command_input = self.DeclareVectorInputPort("thrust_command", NUM_THRUSTERS)
        self.thrust_output = self.DeclareVectorOutputPort(
            "thrust", NUM_THRUSTERS, self._calc_thrust,
            prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})

    def _calc_thrust(self, context, output):
        thrust = self.command_input.Eval(context).copy()
        if context.get_time() >= self.start:
            thrust[self.index] = 0.0
        output.SetFromVector(thrust)


class NavigationJump(LeafSystem):
    """Input `estimated_in` (12), output `estimated_state` (12): x, y moved by `offset` (2, m)
    from `time` s on."""

    def __init__(self, time: float, offset):
        super().__init__()
        self.time, self.offset = float(time), np.asarray(offset, dtype=float)
        if self.offset.shape != (2,) or not np.all(np.isfinite(self.offset)):
            raise ValueError(f"NavigationJump offset must be 2 finite numbers, got {offset}")
        self.estimated_input = self.DeclareVectorInputPort("estimated_in", STATE_SIZE)
        self.estimated_state_output = self.DeclareVectorOutputPort(
            "estimated_state", STATE_SIZE, self._calc_estimated_state,
            prerequisites_of_calc={self.all_input_ports_ticket(), self.time_ticket()})

    def _calc_estimated_state(self, context, output):
        x = self.estimated_input.Eval(context).copy()
        if context.get_time() >= self.time:
            VehicleState(x).xy += self.offset
        output.SetFromVector(x)
