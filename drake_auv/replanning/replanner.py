"""`Replanner`: the realtime replanning loop of the reference as a Drake LeafSystem.

At each replanning step (every `period` s while one of its legs flies) it takes the estimated
position, marks the nominal waypoints the previous plan has flown past as visited, collects
the next section (waypoints within R, at most K), optimises it with STOMP against the current
octree map, warm-started from the last plan (`drake_auv.replanning.section.replan_section`;
`optimizer` "none" flies the section's initial trajectory unoptimised) and times it at the
survey speed as a `PiecewisePolynomial` of [x, y, z, yaw], which the `reference` output
evaluates. The plan also carries the offsets at its tube's nodes, which the next step reuses
where the map left them as they were (`SectionPlan.tube`). After the last waypoint it holds
the end of the last plan and reports the leg finished.

The nominal plan is an input (`nominal`, a `PlannedPath` from a source system), the map another
(`map`, the mapper's `OnlineMap`). State, all in the Context: the plan and its trajectory
(abstract, replaced at every step, never modified), the progress (`progress` group:
`signals.ReplannerProgress`) and the record of the last step (`last_step` group:
`signals.ReplanningStep`), which the `step` output exposes for a `LogVectorOutput`.

A `Behaviour` (`drake_auv.behaviour`). Ports (views in `drake_auv.signals`): inputs
`estimated_state` (`VehicleState`), `leg` (`LegSignal`), `map` (`OnlineMap`), `nominal`
(`PlannedPath`); outputs `reference` (`Reference`, world), `status` (`BehaviourStatus`, the leg last
flown, -1 before any; finished once every waypoint is visited; progress the next waypoint), `step`
(`ReplanningStep`) and `section` ((N, 3) the last optimised section's trajectory, navigation
frame, m; (0, 3) before any: for a viewer).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.behaviour import Behaviour
from drake_auv.mapping.mapper import OnlineMap
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.polyline import arc_length, motion_heading
from drake_auv.random_streams import stream
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import OPTIMIZERS, SectionPlan, replan_section
from drake_auv.signals import BehaviourStatus, ReplannerProgress, ReplanningStep, VehicleState


@dataclass(frozen=True)
class _Plan:
    """The current section and its timed trajectory (None before the first step of a leg): a
    step stores a new one. Drake's copies of it at each step (once a second) are plain deep
    copies of a few dozen points and segments, and of the section's tube nodes (a few
    thousand codes and distances: the tube's, not the dive's)."""

    plan: SectionPlan | None = None
    trajectory: PiecewisePolynomial | None = None


def _placeholder_path() -> PlannedPath:
    return PlannedPath(np.zeros((1, 3)), 0.0, (0.0, 0.0, -1.0))


class Replanner(Behaviour):
    """Replans the next section of the `nominal` input's waypoints against the on-line map.

    Args:
        params: `ReplanningParameters` (R, K, Omega, clearance, STOMP's rollouts/iterations).
        speed: survey speed along the plans, m/s, > 0.
        period: replanning period, s, in [0.05, 30].
        sensor_azimuth: azimuth of the payload sensor's axis in the body frame, rad (pi/2: a
            port-looking sensor); the yaw turns it to the nearest mapped structure of the
            section's depth band. None: the yaw follows the direction of motion.
        heading_offset: yaw relative to the direction of motion where no structure is mapped
            within 2 Omega (or always, with `sensor_azimuth` None), rad.
        yaw_rate: largest commanded yaw rate, rad/s, > 0.
        seed: the run's seed; step i of leg k draws STOMP's rollouts from its `replanner`
            stream, child (k, i) (`drake_auv.random_streams`).
        offset_labels: labels of the nominal samples that follow a wall at Omega (slicing
            contours); the others (lanes, transits) keep only clearance and depth.
        legs: the mission legs this replanner flies (default: leg 0, so it runs unsupervised).
        optimizer: "stomp" (each section optimised against the map) or "none" (each
            section's initial trajectory, through the nominal waypoints, flown as it is).
        current: the forecast current, `f(t, positions) -> (n, 3)` world m/s
            (`drake_auv.ocean.forecast.forecast`), which each step's cost knows when
            `params.current_aware` (`ReplanningCost`); None: still water.
    """

    def __init__(self, params: ReplanningParameters | None = None, speed: float = 0.3,
                 period: float = 1.0, sensor_azimuth: float | None = np.pi / 2,
                 heading_offset: float = 0.0, yaw_rate: float = np.radians(15.0),
                 seed: int = 0, offset_labels=("slice",), legs=(0,), optimizer: str = "stomp",
                 current=None):
        super().__init__(dict.fromkeys(int(leg) for leg in legs))
        if optimizer not in OPTIMIZERS:
            raise ValueError(f"optimizer must be one of {OPTIMIZERS}, got {optimizer!r}")
        self.optimizer = optimizer
        if not (np.isfinite(speed) and speed > 0):
            raise ValueError(f"speed must be > 0 m/s, got {speed}")
        if not (np.isfinite(period) and 0.05 <= period <= 30.0):
            raise ValueError(f"Replanner period must be in [0.05, 30] s, got {period}")
        if not (np.isfinite(yaw_rate) and yaw_rate > 0):
            raise ValueError(f"yaw_rate must be > 0 rad/s, got {yaw_rate}")
        self.params = params if params is not None else ReplanningParameters()
        self.speed, self.period = float(speed), float(period)
        self.sensor_azimuth = None if sensor_azimuth is None else float(sensor_azimuth)
        self.heading_offset, self.yaw_rate = float(heading_offset), float(yaw_rate)
        self.seed = int(seed)
        self.offset_labels = tuple(offset_labels)
        self.current = current if self.params.current_aware else None
        self.map_input = self.DeclareAbstractInputPort("map", AbstractValue.Make(OnlineMap(0.5)))
        self.nominal_input = self.DeclareAbstractInputPort(
            "nominal", AbstractValue.Make(_placeholder_path()))
        self._plan_index = self.DeclareTrajectoryState(_Plan())
        progress = ReplannerProgress.zeros()
        progress.leg = -1.0  # none flown yet
        self._progress = self.DeclareDiscreteState(progress[:])
        self._last_step = self.DeclareDiscreteState(ReplanningStep.size())
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_plan)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, self.period, self._update_plan)
        self.DeclareReferenceOutput()
        self.DeclareStatusOutput(self._status, {self.discrete_state_ticket(self._progress)})
        self.step_output = self.DeclareStateOutputPort("step", self._last_step)
        self.section_output = self.DeclareAbstractOutputPort(
            "section", lambda: AbstractValue.Make(np.zeros((0, 3))), self._calc_section,
            prerequisites_of_calc={self.abstract_state_ticket(self._plan_index)})

    def section(self, context) -> SectionPlan | None:
        """The section planned at the last step in this system's `context`."""
        return context.get_abstract_state(self._plan_index).get_value().plan

    def _update_plan(self, context, state):
        leg = self.leg(context)
        if leg not in self.legs:
            return  # not flying: nothing to do
        t = context.get_time()
        progress = ReplannerProgress(context.get_discrete_state(self._progress).get_value())
        next_index, steps, finished = progress.next_index, progress.steps, progress.finished
        current = context.get_abstract_state(self._plan_index).get_value()
        if progress.leg != leg:  # a new leg: from the first waypoint, nothing planned yet
            next_index, steps, finished, current = 0, 0, 0.0, _Plan()
        if finished:
            return
        x = self.state_input.Eval(context)
        position = VehicleState(x).position
        if current.plan is not None:
            samples = current.trajectory.vector_values(current.trajectory.get_segment_times())
            arc = arc_length(samples[:3].T)
            at = np.interp(t, current.trajectory.get_segment_times(), arc)
            next_index = current.plan.next_index(at)
        nominal = self.nominal_input.Eval(context)
        keep_offset = np.isin(nominal.labels, self.offset_labels)
        online = self.map_input.Eval(context) if self.map_input.HasValue(context) else None
        start = time.perf_counter()
        plan = replan_section(position, nominal.points, int(next_index),
                              online.map if online is not None else np.zeros((0, 3)),
                              self.params,
                              seed=stream(self.seed, "replanner", int(leg), int(steps)),
                              keep_offset=keep_offset,
                              optimizer=self.optimizer,
                              previous=None if current.plan is None else current.plan.trajectory,
                              tube=None if current.plan is None else current.plan.tube,
                              current=None if self.current is None
                              else lambda p: self.current(t, p), speed=self.speed)
        wall = time.perf_counter() - start
        if plan is None:  # every waypoint visited: hold the end of the last plan
            finished, next_index = 1.0, len(nominal.points)
            new = current
        else:  # the section starts at the first waypoint not passed
            next_index = int(plan.indices[0])
            new = _Plan(plan, self._timed(plan, x, t))
        state.get_mutable_abstract_state(self._plan_index).set_value(new)
        progress = ReplannerProgress.zeros()
        progress.leg, progress.next_index, progress.steps, progress.finished = (
            leg, next_index, steps + 1, finished)
        state.get_mutable_discrete_state(self._progress).set_value(progress[:])
        step = ReplanningStep.zeros()
        step.time, step.wall_time, step.next_index, step.planned = (
            t, wall, next_index, float(plan is not None))
        if plan is not None:
            step.query_time, step.iterations, step.map_voxels = (
                plan.query_time, plan.iterations, plan.map_voxels)
        state.get_mutable_discrete_state(self._last_step).set_value(step[:])

    def _timed(self, plan: SectionPlan, x: np.ndarray, t: float) -> PiecewisePolynomial:
        """The section's trajectory from time `t` at the survey speed, with its yaw: facing the
        mapped structure with the payload sensor where it is seen, along the motion elsewhere."""
        pts = plan.trajectory
        yaw = VehicleState(x).yaw
        heading = motion_heading(pts, fallback=yaw) + self.heading_offset
        if self.sensor_azimuth is not None:
            facing = plan.facing - self.sensor_azimuth
            heading = np.where(np.isfinite(facing), facing, heading)
        heading = yaw + np.angle(np.exp(1j * (heading - yaw)))  # nearest turn first
        path = PlannedPath(pts, heading, np.column_stack([np.cos(heading), np.sin(heading),
                                                   np.zeros(len(pts))]))
        trajectory = path.to_trajectory(self.speed, yaw_rate=self.yaw_rate)
        trajectory.shiftRight(t)
        return trajectory

    def _calc_section(self, context, output):
        plan = self.section(context)
        output.set_value(np.zeros((0, 3)) if plan is None else plan.trajectory)

    def share(self, context) -> float:
        """The share of the nominal waypoints passed (the status's next waypoint over their
        number)."""
        passed = BehaviourStatus(self.status_output.Eval(context)).progress
        return float(passed / max(len(self.nominal_input.Eval(context).points), 1))

    def _status(self, context) -> BehaviourStatus:
        progress = ReplannerProgress(context.get_discrete_state(self._progress).get_value())
        status = BehaviourStatus.zeros()
        status.leg, status.finished, status.progress = (progress.leg, progress.finished,
                                                        progress.next_index)
        return status
