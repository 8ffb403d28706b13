"""`Replanner`: the realtime replanning loop of the reference as a Drake LeafSystem.

At each replanning step (every `period` s, and at initialisation) it takes the estimated
position, marks the nominal waypoints the previous plan has flown past as visited, collects
the next section (waypoints within R, at most K), optimises it with STOMP against the current
octree map (`drake_auv.replanning.section.replan_section`) and times it at the survey speed.
Between steps it outputs the reference along that plan; after the last waypoint it holds the
end of the last plan.

The plan is abstract state (a few dozen points: cheap to copy). `log` keeps, per step, the
time, the wall-clock and CPU time of the step (map query plus STOMP, s) and the optimised
section, for the mission's report; it is a diagnostic written by the update, not state.

Ports: inputs `estimated_state` (12), `map` (abstract `OctreeMapHandle`); output
`reference` (8, world: `[x, y, z, yaw, vx, vy, vz, yaw_rate]`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.mapping.octree_map import OctreeMapHandle
from drake_auv.planning.path import Path
from drake_auv.planning.polyline import motion_heading
from drake_auv.replanning.section import ReplanningParameters, SectionPlan, replan_section
from drake_auv.vehicle.model import STATE_SIZE


@dataclass(frozen=True)
class _ReplannerState:
    next_index: int = 0
    step: int = 0
    plan: SectionPlan | None = None
    start_time: float = 0.0
    times: np.ndarray | None = None  # (N,) sample times of the plan, s
    samples: np.ndarray | None = None  # (4, N) x, y, z, unwrapped yaw

    def __deepcopy__(self, memo):
        # Immutable: each update stores a new object. Drake copies the abstract state at every
        # unrestricted update of the diagram (10 Hz sonars), so copies must be free.
        return self


@dataclass(frozen=True)
class ReplanningStep:
    """One entry of `Replanner.log`."""

    time: float
    wall_time: float  # s, the whole step: map query plus section and STOMP
    query_time: float  # s (wall), of which the map query (occupied voxels in the section's box)
    cpu_time: float  # s, the step's CPU time on its thread (what load on the machine hides)
    next_index: int
    plan: SectionPlan | None


class Replanner(LeafSystem):
    """Replans the next section of `waypoints` against the on-line map every `period` s.

    Args:
        waypoints: (n, 3) nominal waypoints in the navigation frame (e.g. a `Path`'s points,
            planned off-line on the prior map), or a `Path`.
        offset_labels: with a `Path`, the labels of the samples that follow a wall at Omega
            (default: "slice"); the other samples (lanes, transits) keep only clearance and
            depth. With an array every waypoint keeps the offset.
        params: `ReplanningParameters` (R, K, Omega, clearance, STOMP's rollouts/iterations).
        speed: survey speed along the plans, m/s, > 0.
        period: replanning period, s, in [0.05, 30].
        sensor_azimuth: azimuth of the payload sensor's axis in the body frame, rad (pi/2: a
            port-looking sensor); the yaw turns it to the nearest mapped structure of the
            section's depth band. None: the yaw follows the direction of motion.
        heading_offset: yaw relative to the direction of motion where no structure is mapped
            within 2 Omega (or always, with `sensor_azimuth` None), rad.
        yaw_rate: largest commanded yaw rate, rad/s, > 0.
        seed: seed of STOMP's rollouts (step k uses seed + k).
    """

    def __init__(self, waypoints, params: ReplanningParameters | None = None,
                 speed: float = 0.3, period: float = 1.0,
                 sensor_azimuth: float | None = np.pi / 2, heading_offset: float = 0.0,
                 yaw_rate: float = np.radians(15.0), seed: int = 0,
                 offset_labels=("slice",)):
        super().__init__()
        points = waypoints.points if isinstance(waypoints, Path) else waypoints
        points = np.asarray(points, dtype=float)
        self.keep_offset = (np.isin(waypoints.labels, list(offset_labels))
                            if isinstance(waypoints, Path) else None)
        if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
            raise ValueError(f"waypoints must have shape (n >= 1, 3), got {points.shape}")
        if not np.all(np.isfinite(points)):
            raise ValueError("waypoints must be finite (no NaN or inf)")
        if not (np.isfinite(speed) and speed > 0):
            raise ValueError(f"speed must be > 0 m/s, got {speed}")
        if not (np.isfinite(period) and 0.05 <= period <= 30.0):
            raise ValueError(f"Replanner period must be in [0.05, 30] s, got {period}")
        if not (np.isfinite(yaw_rate) and yaw_rate > 0):
            raise ValueError(f"yaw_rate must be > 0 rad/s, got {yaw_rate}")
        self.waypoints = points
        self.params = params if params is not None else ReplanningParameters()
        self.speed, self.period = float(speed), float(period)
        self.sensor_azimuth = None if sensor_azimuth is None else float(sensor_azimuth)
        self.heading_offset, self.yaw_rate = float(heading_offset), float(yaw_rate)
        self.seed = int(seed)
        self.log: list[ReplanningStep] = []
        self.state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self.map_input = self.DeclareAbstractInputPort(
            "map", AbstractValue.Make(OctreeMapHandle(None)))
        self._state_index = self.DeclareAbstractState(AbstractValue.Make(_ReplannerState()))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update_plan)
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, self.period, self._update_plan)
        self.reference_output = self.DeclareVectorOutputPort(
            "reference", 8, self._calc_reference,
            prerequisites_of_calc={self.abstract_state_ticket(self._state_index)})

    def plan_state(self, context) -> _ReplannerState:
        """The current plan held in `context` (next waypoint, section, timing)."""
        return context.get_abstract_state(self._state_index).get_value()

    def _update_plan(self, context, state):
        t = context.get_time()
        current = self.plan_state(context)
        x = self.state_input.Eval(context)
        next_index = current.next_index
        if current.plan is not None:
            arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(
                np.diff(current.samples[:3].T, axis=0), axis=1))])
            travelled = np.interp(t - current.start_time, current.times, arc)
            next_index = current.plan.next_index(travelled)
        handle = self.map_input.Eval(context) if self.map_input.HasValue(context) else None
        start, start_cpu = time.perf_counter(), time.thread_time()
        occupied = handle.map if handle is not None else np.zeros((0, 3))
        plan = replan_section(x[:3], self.waypoints, next_index, occupied, self.params,
                              seed=self.seed + current.step, keep_offset=self.keep_offset)
        wall, cpu = time.perf_counter() - start, time.thread_time() - start_cpu
        query = plan.query_time if plan is not None else 0.0
        self.log.append(ReplanningStep(t, wall, query, cpu, next_index, plan))
        if plan is None:  # every waypoint visited: hold the end of the last plan
            new = _ReplannerState(next_index, current.step + 1, None, current.start_time,
                                  current.times, current.samples)
            if current.samples is None:  # nothing was ever planned: hold the vehicle
                hold = np.append(x[:3], x[5])[:, None]
                new = _ReplannerState(next_index, current.step + 1, None, t,
                                      np.array([0.0]), hold)
        else:
            pts = plan.trajectory
            heading = motion_heading(pts, fallback=x[5]) + self.heading_offset
            if self.sensor_azimuth is not None:
                facing = plan.facing - self.sensor_azimuth
                heading = np.where(np.isfinite(facing), facing, heading)
            heading = x[5] + np.angle(np.exp(1j * (heading - x[5])))  # nearest turn first
            path = Path(pts, heading, np.column_stack([np.cos(heading), np.sin(heading),
                                                       np.zeros(len(pts))]))
            times = path.times(self.speed, self.yaw_rate)
            samples = np.vstack([pts.T, np.unwrap(heading)])
            new = _ReplannerState(next_index, current.step + 1, plan, t, times, samples)
        state.get_mutable_abstract_state(self._state_index).set_value(new)

    def _calc_reference(self, context, output):
        current = self.plan_state(context)
        if current.samples is None:  # before initialisation: hold the vehicle where it is
            x = self.state_input.Eval(context)
            output.SetFromVector(np.concatenate([x[:3], [x[5]], np.zeros(4)]))
            return
        tau = context.get_time() - current.start_time
        times, samples = current.times, current.samples
        if len(times) < 2 or tau >= times[-1]:
            output.SetFromVector(np.concatenate([samples[:, -1], np.zeros(4)]))
            return
        tau = max(tau, 0.0)
        i = min(int(np.searchsorted(times, tau, side="right")) - 1, len(times) - 2)
        rate = (samples[:, i + 1] - samples[:, i]) / (times[i + 1] - times[i])
        value = samples[:, i] + rate * (tau - times[i])
        output.SetFromVector(np.concatenate([value, rate]))
