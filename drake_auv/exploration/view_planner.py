"""`ViewPlanner`: on-line view planning from the octree as a Drake LeafSystem (thin adapter).

Every `period` s while one of its legs flies it runs `planner.plan_view` on the mapper's map
from the estimated position: the map is read into the planning grid only where the beams
inserted since the last step passed (`frontiers.scan_rays`, from the map's `ScanLog`), the
target is kept or replaced, and a new target's STOMP path is timed at the planner's speed as
a `PiecewisePolynomial` of [x, y, z, yaw] (the yaw turns the multibeam towards the frontier
the target looks at), which the `reference` output evaluates. When no viewpoint would newly
see `min_gain_m2` for `patience` steps the leg is reported finished.

State, all in the Context: the current view (abstract, immutable, replaced at each step:
target, trajectory, the planning grid and the map version it reflects), the `progress` group
(`PROGRESS_FIELDS`) and the `last_step` group (`STEP_FIELDS`, the `step` output, for a log).

Ports: inputs `estimated_state` (12), `map` (`OnlineMap`), `leg` (2); outputs `reference`
(8, `[x, y, z, yaw, vx, vy, vz, yaw_rate]`), `status` (3: `[leg, finished, viewpoints]`, -1
before any leg) and `step` (`STEP_FIELDS`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.exploration.frontiers import LabelGrid, scan_rays
from drake_auv.exploration.planner import ExploreParameters, Target, plan_view
from drake_auv.leg_signal import LEG_SIZE, read_leg
from drake_auv.mapping.mapper import OnlineMap
from drake_auv.planning.path import Path
from drake_auv.vehicle.model import STATE_SIZE
from drake_auv.vehicle.path_reference import trajectory_reference

PROGRESS_FIELDS = ("leg", "steps", "finished", "viewpoints", "no_gain_steps")
STEP_FIELDS = ("time", "wall_time", "gain_m2", "candidates", "frontier_cells",
               "believed_coverage", "viewpoints")
YAW_RATE = np.radians(15.0)  # rad/s, the largest commanded yaw rate


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


class ViewPlanner(LeafSystem):
    """Flies the explore legs `legs` ({leg index: `ExploreParameters`}).

    Args:
        legs: the legs it flies and their parameters (default: leg 0 with `params`).
        period: planning period, s, in [0.5, 60].
        seed: seed of the random strategy and STOMP (step k of a leg uses seed + k).
    """

    def __init__(self, legs: dict[int, ExploreParameters], period: float = 5.0, seed: int = 0):
        super().__init__()
        if not legs:
            raise ValueError("ViewPlanner needs at least one leg")
        if not (np.isfinite(period) and 0.5 <= period <= 60.0):
            raise ValueError(f"ViewPlanner period must be in [0.5, 60] s, got {period}")
        self.legs = dict(legs)
        self.period, self.seed = float(period), int(seed)
        self.state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self.map_input = self.DeclareAbstractInputPort("map", AbstractValue.Make(OnlineMap(0.5)))
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)
        self._view_index = self.DeclareAbstractState(AbstractValue.Make(_View()))
        progress = np.zeros(len(PROGRESS_FIELDS))
        progress[0] = -1.0
        self._progress = self.DeclareDiscreteState(progress)
        self._last_step = self.DeclareDiscreteState(np.zeros(len(STEP_FIELDS)))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, self.period, self._update)
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", 8, self._calc_reference,
            prerequisites_of_calc={self.abstract_state_ticket(self._view_index),
                                   self.time_ticket(),
                                   self.input_port_ticket(self.state_input.get_index())})
        self.status_output = self.DeclareVectorOutputPort(
            "status", 3, self._calc_status,
            prerequisites_of_calc={self.discrete_state_ticket(self._progress)})
        self.step_output = self.DeclareStateOutputPort("step", self._last_step)

    def view(self, context) -> _View:
        """The current view in this system's `context`."""
        return context.get_abstract_state(self._view_index).get_value()

    def _update(self, context, state):
        leg, _ = read_leg(self.leg_input, context)
        if leg not in self.legs:
            return  # not flying: nothing to do
        params = self.legs[leg]
        t = context.get_time()
        progress = dict(zip(PROGRESS_FIELDS,
                            context.get_discrete_state(self._progress).get_value()))
        view = self.view(context)
        if progress["leg"] != leg:  # a new leg: nothing chosen yet
            progress = dict(leg=leg, steps=0, finished=0, viewpoints=0, no_gain_steps=0)
            view = _View()
        if progress["finished"]:
            return
        x = self.state_input.Eval(context)
        online = self.map_input.Eval(context)
        start = time.perf_counter()
        batches = (online.version.since(view.version)
                   if online.version is not None and view.grid is not None else None)
        rays = scan_rays(batches, params.cell_m) if batches is not None else None
        step = plan_view(online.map, x[:3], params, view.target,
                         seed=self.seed + int(progress["steps"]), previous=view.grid, rays=rays,
                         visited=view.visited, yaw=float(x[5]),
                         current_path=self._remaining(view.trajectory, t))
        trajectory = view.trajectory
        if step.path is not None:
            trajectory = self._timed(step.path, step.target, params, x, t)
            progress["viewpoints"] += 1
        progress["no_gain_steps"] = progress["no_gain_steps"] + 1 if step.no_gain else 0
        progress["finished"] = float(progress["no_gain_steps"] >= params.patience)
        progress["steps"] += 1
        state.get_mutable_abstract_state(self._view_index).set_value(
            _View(step.target, trajectory, step.grid, online.version, step.visited))
        state.get_mutable_discrete_state(self._progress).set_value(
            [progress[k] for k in PROGRESS_FIELDS])
        state.get_mutable_discrete_state(self._last_step).set_value(
            [t, time.perf_counter() - start, step.gain_m2, step.candidates,
             step.frontier_cells, step.believed_coverage, progress["viewpoints"]])

    @staticmethod
    def _remaining(trajectory: PiecewisePolynomial | None, t: float) -> np.ndarray | None:
        """(k, 3) the trajectory's positions from time `t` on (None without one)."""
        if trajectory is None or t >= trajectory.end_time():
            return None
        times = trajectory.get_segment_times()
        times = np.concatenate([[t], [s for s in times if s > t]])
        return trajectory.vector_values(times)[:3].T

    @staticmethod
    def _timed(path: np.ndarray, target: Target, params: ExploreParameters, x: np.ndarray,
               t: float) -> PiecewisePolynomial:
        """`path` from time `t` at the planner's speed, the yaw turning the multibeam to the
        frontier the target looks at (the target's own yaw within 1 m of it horizontally)."""
        to = target.looks_at[:2] - path[:, :2]
        heading = np.arctan2(to[:, 1], to[:, 0]) - params.sensor_azimuth
        heading = np.where(np.linalg.norm(to, axis=1) > 1.0, heading, target.yaw)
        heading[-1] = target.yaw
        heading = x[5] + np.angle(np.exp(1j * (heading - x[5])))  # nearest turn first
        sensor = np.column_stack([np.cos(heading), np.sin(heading), np.zeros(len(path))])
        return Path(path, heading, sensor).to_trajectory(params.speed, start_time=t,
                                                         yaw_rate=YAW_RATE)

    def _calc_reference(self, context, output):
        output.SetFromVector(trajectory_reference(self.view(context).trajectory,
                                                  context.get_time(), self.state_input,
                                                  context))

    def _calc_status(self, context, output):
        progress = context.get_discrete_state(self._progress).get_value()
        output.SetFromVector([progress[0], progress[2], progress[3]])


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
    last = dict(zip(STEP_FIELDS, own.get_discrete_state(planner._last_step).get_value()))
    progress = dict(zip(PROGRESS_FIELDS, own.get_discrete_state(planner._progress).get_value()))
    legs = sorted(planner.legs)
    return dict(believed_coverage=float(last["believed_coverage"]),
                viewpoints=int(last["viewpoints"]),
                strategy=planner.legs[legs[-1]].strategy,
                stopped="gain" if progress["finished"] and outcomes[int(progress["leg"])]
                == "goal" else "time")
