"""The `hover` step: station keeping at a point of interest for a while.

    - hover: {at: [x, y, z] | start, heading_deg: 90, duration_s: 120}

`at` is a point in site coordinates (m, z up), reached by a transit, or `start`: where the
vehicle is when the step begins (no transit). The `StationKeeper` (`station_keeper()`)
holds that pose (the
heading: `heading_deg` from +x, or the one the vehicle has when the hover begins) against
whatever moves the vehicle, and reports its leg finished `duration_s` after the leg began.
Its status's progress is the share of `duration_s` elapsed.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import ClassVar

import numpy as np

from drake_auv.mission.legs import Leg
from drake_auv.mission.spec import ANGLE_DEG
from drake_auv.mission.steps.step import TIME_SLACK, TRANSIT_SPEED, MissionStep
from drake_auv.params import param, validate
from drake_auv.signals import BehaviourStatus, Reference, VehicleState


@dataclass(frozen=True)
class HoverStep:
    """Station keeping at a point of interest.

    Attributes:
        at: (x, y, z) in site coordinates, m, or "start" (where the step begins).
        heading_deg: the heading held, deg from +x (None: the vehicle's when it arrives).
        duration_s: how long the pose is held, s.
    """

    KIND: ClassVar[str] = "hover"
    at: tuple | str = param("start", kind="vector", names=("x", "y", "z"), choices=("start",),
                            unit="m, site coordinates")
    heading_deg: float | None = param(None, **ANGLE_DEG, nullable=True)
    duration_s: float = param(60.0, low=0.0, high=86400.0, low_open=True, unit="s")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class HoverLeg:
    """A hover leg: the point (3,), local frame (None: where the leg begins), the yaw
    (rad, None: the vehicle's when the leg begins) and the duration, s."""

    point: tuple | None
    yaw: float | None
    duration: float


def held_pose(leg: int, params: HoverLeg, t: float, x: np.ndarray) -> np.ndarray:
    """The `held` record `[leg, start_s, x, y, z, yaw]` of a hover leg beginning at `t` s
    with the vehicle at the estimated state `x` (12)."""
    state = VehicleState(x)
    point = state.position if params.point is None else params.point
    yaw = state.yaw if params.yaw is None else params.yaw
    return np.array([leg, t, *point, yaw], dtype=float)


def hover_status(held: np.ndarray, t: float, duration: float) -> BehaviourStatus:
    """The status at `t` s of the hover `held` (leg -1: none yet) lasting `duration` s."""
    status = BehaviourStatus.zeros()
    status.leg = held[0]
    if held[0] >= 0:
        share = (t - held[1]) / duration
        status.finished, status.progress = float(share >= 1.0), min(share, 1.0)
    return status


@cache
def station_keeper():
    """The `StationKeeper` class (a `Behaviour`; built on first use, so planning a mission
    loads no Drake)."""
    from drake_auv.behaviour import Behaviour

    class StationKeeper(Behaviour):
        """Holds the pose of each of its `legs` ({leg index: `HoverLeg`}) for its duration.

        Discrete state `held` (`[leg, start_s, x, y, z, yaw]`, leg -1 before any): the pose
        of the leg flying, set at its first update (every `period` s). Ports: the
        `Behaviour`'s (`reference`: the held pose, zero rates; before its first leg, the
        estimated pose; `status` progress: the share of the duration elapsed).
        """

        progress_is_share = True

        def __init__(self, legs: dict[int, HoverLeg], period: float = 0.1):
            super().__init__(legs)
            if not (np.isfinite(period) and 0 < period <= 5.0):
                raise ValueError(f"StationKeeper period must be in (0, 5] s, got {period}")
            self._held = self.DeclareDiscreteState(np.r_[-1.0, np.zeros(5)])
            self.DeclareInitializationDiscreteUpdateEvent(self._update_held)
            self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update_held)
            self.DeclareReferenceOutput(self._calc_reference, {
                self.discrete_state_ticket(self._held),
                self.input_port_ticket(self.state_input.get_index())})
            self.DeclareStatusOutput(lambda context: hover_status(
                context.get_discrete_state(self._held).get_value(), context.get_time(),
                self._duration(context)), {self.discrete_state_ticket(self._held),
                                           self.time_ticket()})

        def _duration(self, context) -> float:
            leg = int(context.get_discrete_state(self._held)[0])
            return self.legs[leg].duration if leg in self.legs else 1.0

        def _update_held(self, context, discrete_state):
            leg = self.leg(context)
            params = self.legs.get(leg)
            if params is None or context.get_discrete_state(self._held)[0] == leg:
                return  # not ours, or already held
            discrete_state.set_value(self._held, held_pose(
                leg, params, context.get_time(), self.state_input.Eval(context)))

        def _calc_reference(self, context, output):
            held = context.get_discrete_state(self._held).get_value()
            reference = Reference.zeros()
            if held[0] < 0:
                state = VehicleState(self.state_input.Eval(context))
                reference.position, reference.yaw = state.position, state.yaw
            else:
                reference.position, reference.yaw = held[2:5], held[5]
            output.SetFromVector(reference[:])

    return StationKeeper


class Hover(MissionStep):
    spec = HoverStep
    behaviour = "hover"

    @classmethod
    def start(cls, planning, index: int, step) -> np.ndarray:
        start = planning.default_start(None)
        if step.at != "start":
            start[:3] = planning.site.to_local(np.asarray(step.at, dtype=float))
        if step.heading_deg is not None:
            start[5] = np.radians(step.heading_deg)
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        yaw = None if step.heading_deg is None else float(np.radians(step.heading_deg))
        point = None
        if step.at != "start":
            from drake_auv.mission.site import check_in_water

            point = tuple(planning.site.to_local(np.asarray(step.at, dtype=float)))
            check_in_water(planning.site, point, planning.label, f"steps[{k}].hover.at",
                           "the point held")
            planning.add_transit(k, point, yaw, TRANSIT_SPEED)
        planning.add(Leg("hover", k, "hover", "finished",
                         planning.margin * step.duration_s + TIME_SLACK),
                     HoverLeg(point, yaw, step.duration_s))

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        return wiring.builder.AddNamedSystem("station_keeper", station_keeper()(legs))


STEP = Hover
