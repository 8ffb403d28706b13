"""The GIRONA 500 in a Diagram: dynamics, navigation, tracker and allocation, wired.

`add_girona500` adds the vehicle to any mission diagram and leaves the tracker's `reference`
input free for the mission (a trajectory source, the profile-following controller or the
replanner). `build_tracking_diagram` is the simplest mission: a path flown at constant speed.

    reference ──> tracker ──> allocation ──> dynamics ──┬──> state (true)
                     ^                                  v
                     └──────── estimated_state <── navigation
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import (ConstantVectorSource, LogVectorOutput, TrajectorySource,
                                        VectorLogSink)

from drake_auv.vehicle.control import TrackingGains
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.planning.path import PlannedPath
from drake_auv.vehicle.dynamics import Girona500Dynamics
from drake_auv.vehicle.navigation_system import Navigation
from drake_auv.vehicle.thrusters import ThrusterAllocation
from drake_auv.vehicle.tracker import TrajectoryTracker
from drake_auv.vehicle.model import Girona500Params, STATE_SIZE


@dataclass
class VehicleSystems:
    """The systems `add_girona500` added; ports: `dynamics.state_output` (true state),
    `navigation.estimated_state_output`, `tracker.reference_input` (to connect)."""

    dynamics: Girona500Dynamics
    navigation: Navigation
    tracker: TrajectoryTracker
    allocation: ThrusterAllocation


def add_girona500(builder: DiagramBuilder, params: Girona500Params | None = None,
                  navigation: NavigationParams | None = None, initial_state=None,
                  gains: TrackingGains | None = None, time_step: float = 0.05,
                  control_period: float = 0.05, prefix: str = "") -> VehicleSystems:
    """Adds and wires the vehicle; systems are named `<prefix>dynamics`, `navigation`, ...

    Args:
        params: vehicle parameters (default: `models/girona500.yaml` values).
        navigation: navigation error model (default: exact navigation).
        initial_state: 12-state at t = 0 (default: at rest at the origin).
        gains: tracking gains; time_step: plant RK4 step, s; control_period: tracker period, s.
    """
    params = params if params is not None else Girona500Params()
    dynamics = builder.AddNamedSystem(f"{prefix}dynamics",
                                      Girona500Dynamics(params, time_step, initial_state))
    nav = builder.AddNamedSystem(f"{prefix}navigation", Navigation(navigation))
    tracker = builder.AddNamedSystem(f"{prefix}tracker",
                                     TrajectoryTracker(params, gains, control_period))
    allocation = builder.AddNamedSystem(f"{prefix}allocation", ThrusterAllocation(params))
    builder.Connect(dynamics.state_output, nav.true_state_input)
    builder.Connect(nav.estimated_state_output, tracker.state_input)
    builder.Connect(tracker.wrench_output, allocation.wrench_input)
    builder.Connect(allocation.thrust_output, dynamics.thrust_input)
    return VehicleSystems(dynamics, nav, tracker, allocation)


@dataclass
class TrackingHandles:
    """What `build_tracking_diagram` returns beside the diagram."""

    vehicle: VehicleSystems
    source: TrajectorySource
    trajectory: object  # the PiecewisePolynomial of [x, y, z, yaw]
    state_log: VectorLogSink  # true state
    reference_log: VectorLogSink
    end_time: float  # s, when the reference reaches the end of the path
    visualizer: object = None


def build_tracking_diagram(path: PlannedPath, speed: float = 0.5, params: Girona500Params | None = None,
                           navigation: NavigationParams | None = None, initial_state=None,
                           gains: TrackingGains | None = None, time_step: float = 0.05,
                           log_period: float = 0.1, scene=None, current=None):
    """A Diagram that flies `path` at `speed` (m/s): source -> tracker -> allocation -> dynamics.

    The vehicle starts at rest on the first sample with the first heading unless
    `initial_state` is given. True state and reference are logged every `log_period` s.
    `current` (3, m/s, world frame): a uniform steady current (a source named `water` feeds
    the dynamics and the navigation); None: still water.
    With a `drake_auv.visualization.Scene`, the vehicle and its trail are drawn there.
    Exported outputs: `state` (true) and `estimated_state`. Returns (diagram, TrackingHandles).
    """
    if not (np.isfinite(log_period) and log_period > 0):
        raise ValueError(f"log_period must be > 0 s, got {log_period}")
    trajectory = path.to_trajectory(speed)
    if initial_state is None:
        initial_state = np.zeros(STATE_SIZE)
        initial_state[:3] = path.points[0]
        initial_state[5] = path.unwrapped_heading()[0]
    builder = DiagramBuilder()
    vehicle = add_girona500(builder, params, navigation, initial_state, gains, time_step)
    if current is not None:
        current = np.asarray(current, dtype=float)
        if current.shape != (3,) or not np.all(np.isfinite(current)):
            raise ValueError(f"current must be 3 finite numbers (world x, y, z, m/s), got "
                             f"{current}")
        water = builder.AddNamedSystem("water", ConstantVectorSource(
            np.concatenate([current, np.zeros(3)])))
        builder.Connect(water.get_output_port(), vehicle.dynamics.water_input)
        builder.Connect(water.get_output_port(), vehicle.navigation.water_input)
    source = builder.AddNamedSystem("reference", TrajectorySource(trajectory, 1))
    builder.Connect(source.get_output_port(), vehicle.tracker.reference_input)
    state_log = LogVectorOutput(vehicle.dynamics.state_output, builder, log_period)
    state_log.set_name("state_log")
    reference_log = LogVectorOutput(source.get_output_port(), builder, log_period)
    reference_log.set_name("reference_log")
    builder.ExportOutput(vehicle.dynamics.state_output, "state")
    builder.ExportOutput(vehicle.navigation.estimated_state_output, "estimated_state")
    visualizer = None
    if scene is not None:
        visualizer = scene.add_vehicle_visualizer(builder, vehicle.dynamics.state_output)
    diagram = builder.Build()
    diagram.set_name("tracking")
    handles = TrackingHandles(vehicle, source, trajectory, state_log, reference_log,
                              float(trajectory.end_time()), visualizer)
    return diagram, handles
