"""`ViewPlanner`: on-line view planning from the octree as a Drake LeafSystem (thin adapter).

Every `period` s while one of its legs flies it runs `planner.plan_view` on the mapper's map
from the estimated position: the map is read into the planning grid only where the beams
inserted since the last step passed (`frontiers.scan_rays`, from the map's `ScanLog`), the
target is kept or replaced, and a new target's STOMP path is timed at the planner's speed as
a `PiecewisePolynomial` of [x, y, z, yaw] (the yaw turns the multibeam towards the frontier
the target looks at), which the `reference` output evaluates. When no viewpoint would newly
see `min_gain_m2` for `patience` steps (a turn in place counting half) the leg is reported
finished.

State, all in the Context: the current view (abstract, immutable, replaced at each step:
target, trajectory, the planning grid and the map version it reflects), the `progress` group
(`signals.ExplorerProgress`) and the `last_step` group (`ExplorerStep`, the `step` output, for
a log).

The seabed guard: with the DVL's `seabed_elevation` connected, the reference never goes below
the measured seabed (or flat top) under the vehicle plus `GUARD` clearances, between two
planning steps as well: a flat top seen only at grazing incidence is free water in the octree
until the DVL's beams map it (boulder seed 2 descended onto the top to 0.19 m without it).

A `Behaviour` (`drake_auv.behaviour`). Ports: inputs `estimated_state` (`VehicleState`), `leg`
(`LegSignal`), `map` (`OnlineMap`), `seabed_elevation` (1, m, navigation frame, NaN without
bottom lock; may be unconnected); outputs `reference` (`Reference`), `status`
(`BehaviourStatus`, -1 before any leg; progress: the viewpoints reached) and `step`
(`ExplorerStep`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.exploration.frontiers import LabelGrid, multibeam_returns, scan_rays
from drake_auv.exploration.planner import ExploreParameters, Target, plan_view
from drake_auv.behaviour import Behaviour, trajectory_reference
from drake_auv.random_streams import stream
from drake_auv.mapping.mapper import OnlineMap
from drake_auv.planning.path import PlannedPath
from drake_auv.signals import (BehaviourStatus, ExplorerProgress, ExplorerStep, Reference,
                               VehicleState)

YAW_RATE = np.radians(15.0)  # rad/s, the largest commanded yaw rate
GUARD = 0.75  # clearances the reference keeps above the DVL's seabed


@dataclass(frozen=True)
class _View:
    """The current target and its timed path, the planning grid and the map version (the
    `ScanLog`) it reflects, the targets reached. Immutable: Drake's state copies may share
    it."""

    target: Target | None = None
    trajectory: PiecewisePolynomial | None = None
    grid: LabelGrid | None = None
    version: object = None
    visited: np.ndarray | None = None

    def __deepcopy__(self, memo):
        return self


class ViewPlanner(Behaviour):
    """Flies the explore legs `legs` ({leg index: `ExploreParameters`}).

    Args:
        legs: the legs it flies and their parameters (default: leg 0 with `params`).
        period: planning period, s, in [0.5, 60].
        seed: the run's seed; step i of leg k draws from its `exploration` stream, child
            (k, i) (`drake_auv.random_streams`).
    """

    def __init__(self, legs: dict[int, ExploreParameters], period: float = 5.0, seed: int = 0):
        if not legs:
            raise ValueError("ViewPlanner needs at least one leg")
        super().__init__(legs)
        if not (np.isfinite(period) and 0.5 <= period <= 60.0):
            raise ValueError(f"ViewPlanner period must be in [0.5, 60] s, got {period}")
        self.period, self.seed = float(period), int(seed)
        self.map_input = self.DeclareAbstractInputPort("map", AbstractValue.Make(OnlineMap(0.5)))
        self.seabed_input = self.DeclareVectorInputPort("seabed_elevation", 1)
        self._view_index = self.DeclareTrajectoryState(_View())
        progress = ExplorerProgress.zeros()
        progress.leg = -1.0
        self._progress = self.DeclareDiscreteState(progress[:])
        self._last_step = self.DeclareDiscreteState(ExplorerStep.size())
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, self.period, self._update)
        self.DeclareReferenceOutput(self._calc_reference, {
            self.abstract_state_ticket(self._view_index), self.time_ticket(),
            self.input_port_ticket(self.state_input.get_index()),
            self.input_port_ticket(self.leg_input.get_index()),
            self.input_port_ticket(self.seabed_input.get_index())})
        self.DeclareStatusOutput(self._status, {self.discrete_state_ticket(self._progress)})
        self.step_output = self.DeclareStateOutputPort("step", self._last_step)

    def view(self, context) -> _View:
        """The current view in this system's `context`."""
        return context.get_abstract_state(self._view_index).get_value()

    def progress(self, context) -> ExplorerProgress:
        """The `progress` group in this system's `context` (a copy)."""
        return ExplorerProgress(context.get_discrete_state(self._progress).get_value().copy())

    def last_step(self, context) -> ExplorerStep:
        """The last planning step's record in this system's `context` (a copy)."""
        return ExplorerStep(context.get_discrete_state(self._last_step).get_value().copy())

    def _update(self, context, state):
        leg = self.leg(context)
        if leg not in self.legs:
            return  # not flying: nothing to do
        params = self.legs[leg]
        t = context.get_time()
        progress = self.progress(context)
        view = self.view(context)
        if progress.leg != leg:  # a new leg: nothing chosen yet
            progress = ExplorerProgress.zeros()
            progress.leg = leg
            view = _View()
        if progress.finished:
            return
        x = VehicleState(self.state_input.Eval(context))
        online = self.map_input.Eval(context)
        start = time.perf_counter()
        batches = (online.version.since(view.version)
                   if online.version is not None and view.grid is not None else None)
        rays = scan_rays(batches, params.cell_m) if batches is not None else None
        returns = multibeam_returns(batches) if batches is not None else None
        step = plan_view(online.map, x.position, params, view.target,
                         seed=stream(self.seed, "exploration", int(leg), int(progress.steps)),
                         previous=view.grid, rays=rays,
                         visited=view.visited, yaw=float(x.yaw),
                         current_path=self._remaining(view.trajectory, t), returns=returns)
        trajectory = view.trajectory
        if step.path is not None:
            trajectory = self._timed(step.path, step.target, params, x, t)
            progress.viewpoints += 1
        progress.no_gain_steps = (progress.no_gain_steps + (0.5 if step.turning else 1.0)
                                  if step.no_gain else 0)
        progress.finished = float(progress.no_gain_steps >= params.patience)
        progress.steps += 1
        state.get_mutable_abstract_state(self._view_index).set_value(
            _View(step.target, trajectory, step.grid, online.version, step.visited))
        state.get_mutable_discrete_state(self._progress).set_value(progress[:])
        record = ExplorerStep.zeros()
        record.time, record.wall_time = t, time.perf_counter() - start
        record.gain_m2, record.candidates = step.gain_m2, step.candidates
        record.frontier_cells = step.frontier_cells
        record.believed_coverage = step.believed_coverage
        record.viewpoints = progress.viewpoints
        state.get_mutable_discrete_state(self._last_step).set_value(record[:])

    @staticmethod
    def _remaining(trajectory: PiecewisePolynomial | None, t: float) -> np.ndarray | None:
        """(k, 3) the trajectory's positions from time `t` on (None without one)."""
        if trajectory is None or t >= trajectory.end_time():
            return None
        times = trajectory.get_segment_times()
        times = np.concatenate([[t], [s for s in times if s > t]])
        return trajectory.vector_values(times)[:3].T

    @staticmethod
    def _timed(path: np.ndarray, target: Target, params: ExploreParameters, x: VehicleState,
               t: float) -> PiecewisePolynomial:
        """`path` from time `t` at the planner's speed, the yaw turning the multibeam to the
        frontier the target looks at (the target's own yaw within 1 m of it horizontally)."""
        to = target.looks_at[:2] - path[:, :2]
        heading = np.arctan2(to[:, 1], to[:, 0]) - params.sensor_azimuth
        heading = np.where(np.linalg.norm(to, axis=1) > 1.0, heading, target.yaw)
        heading[-1] = target.yaw
        heading = x.yaw + np.angle(np.exp(1j * (heading - x.yaw)))  # nearest turn first
        sensor = np.column_stack([np.cos(heading), np.sin(heading), np.zeros(len(path))])
        trajectory = PlannedPath(path, heading, sensor).to_trajectory(params.speed, yaw_rate=YAW_RATE)
        trajectory.shiftRight(t)
        return trajectory

    def _calc_reference(self, context, output):
        reference = Reference(trajectory_reference(self.view(context).trajectory,
                                                   context.get_time(), self.state_input,
                                                   context))
        leg = self.leg(context)
        if leg in self.legs and self.seabed_input.HasValue(context):
            floor = (self.seabed_input.Eval(context)[0]
                     + GUARD * self.legs[leg].clearance)
            if np.isfinite(floor) and reference.z < floor:  # the seabed guard
                reference.z, reference.vz = floor, max(reference.vz, 0.0)
        output.SetFromVector(reference[:])

    def _status(self, context) -> BehaviourStatus:
        progress, status = self.progress(context), BehaviourStatus.zeros()
        status.leg, status.finished, status.progress = (progress.leg, progress.finished,
                                                        progress.viewpoints)
        return status


def exploration_summary(handles, context, outcomes: list[str]) -> dict | None:
    """The report's `exploration` section from a flown mission's `MissionHandles`, root
    `context` and per-leg `outcomes`: the last step's `believed_coverage` (share of the
    map's surface the planner believes is covered), the `viewpoints` chosen, the
    `strategy` and why it `stopped` ("gain": nothing more worth seeing; "time": the leg's
    time ran out); None without an explore leg."""
    planner = handles.explorer
    if planner is None:
        return None
    own = planner.GetMyContextFromRoot(context)
    last, progress = planner.last_step(own), planner.progress(own)
    legs = sorted(planner.legs)
    return dict(believed_coverage=float(last.believed_coverage),
                viewpoints=int(last.viewpoints),
                strategy=planner.legs[legs[-1]].strategy,
                stopped="gain" if progress.finished and outcomes[int(progress.leg)]
                == "goal" else "time")
