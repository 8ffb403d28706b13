"""Profile-following mission: the GIRONA 500 driven by its pencil-beam profiler.

Also `run_mission` (simulate with a progress bar and a stop condition).

    true state ──> PencilBeamProfiler ──returns──> ProfileFollowingController ──reference──┐
         ^              ^ estimated_state ─────────────────┘ ^                            v
         └── dynamics <── allocation <── tracker <───────────┼────────────────────────────┘
                                            ^ estimated_state┘
The controller replaces the path source of the tracking diagram. The profiler scans the
horizontal plane (horizontal following) or the body x-z plane (vertical following).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import VectorLogSink
from tqdm import tqdm

from drake_auv.vehicle.control import TrackingGains
from drake_auv.vehicle.diagram import VehicleSystems, add_girona500
from drake_auv.geometry.raycast import RayCaster
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.perception.behaviours import FollowingParams
from drake_auv.sonar.noise import SonarNoise
from drake_auv.perception.controller import PROFILE_SIZE, ProfileFollowingController
from drake_auv.sonar.profiler import PencilBeamProfiler
from drake_auv.vehicle.model import STATE_SIZE

# Profiler head set-up for following (our choice): a full circle at the SeaKing's coarse
# 1.8 degree step and 30 pings/s, one revolution in 6.7 s, batched at 10 Hz.
PROFILER_DEFAULTS = dict(sector_deg=(-180.0, 180.0), step_deg=1.8, ping_rate=30.0,
                         update_rate=10.0, beam_width_deg=1.5, max_range=20.0)


@dataclass
class ProfileFollowingHandles:
    """What `build_profile_following_diagram` returns beside the diagram."""

    vehicle: VehicleSystems
    profiler: PencilBeamProfiler
    controller: ProfileFollowingController
    state_log: VectorLogSink  # true state
    estimated_state_log: VectorLogSink
    reference_log: VectorLogSink
    profile_log: VectorLogSink  # the controller's `profile` output
    caster: RayCaster  # of the true world, for truth checks
    visualizer: object = None


def build_profile_following_diagram(world, initial_state, mode: str = "horizontal",
                                    params: FollowingParams | None = None,
                                    noise: SonarNoise | None = None,
                                    navigation: NavigationParams | None = None,
                                    profiler_options: dict | None = None,
                                    depth_z: float | None = None,
                                    plane_yaw: float | None = None, seed: int = 0,
                                    gains: TrackingGains | None = None,
                                    log_period: float = 0.1, scene=None, extra=None):
    """Wires vehicle, profiler and controller for profile following in `world`.

    Args:
        world: the true world (trimesh) or a `RayCaster` of it.
        initial_state: 12-state at t = 0.
        mode: "horizontal" or "vertical".
        params: following behaviours (`FollowingParams`); a zero `warmup` is replaced by the
            time the profiler head takes to scan its sector once.
        noise: profiler errors, e.g. `SonarNoise(spurious_prob=0.05)` (default: none).
        navigation: navigation error model (default: exact).
        profiler_options: overrides of `PROFILER_DEFAULTS` (keyword arguments of
            `PencilBeamProfiler`).
        depth_z, plane_yaw: see `ProfileFollowingController`.
        seed: seeds the profiler noise and the estimator's RANSAC.
        gains: tracker gains (default: `TrackingGains()`).
        log_period: s, of the state, reference and profile logs.
        scene: a `drake_auv.visualization.Scene` to draw the vehicle, its trail and the
            profiler's recent returns in.
    Returns (diagram, ProfileFollowingHandles); exported outputs `state`, `estimated_state`,
    `reference`, `profile`.
    """
    if mode not in ("horizontal", "vertical"):
        raise ValueError(f"mode must be 'horizontal' or 'vertical', got {mode!r}")
    if not (np.isfinite(log_period) and log_period > 0):
        raise ValueError(f"log_period must be > 0 s, got {log_period}")
    initial_state = np.asarray(initial_state, dtype=float)
    if initial_state.shape != (STATE_SIZE,) or not np.all(np.isfinite(initial_state)):
        raise ValueError(f"initial_state must be a finite 12-vector, got {initial_state!r}")
    options = {**PROFILER_DEFAULTS, **(profiler_options or {})}
    unknown = set(options) - set(PROFILER_DEFAULTS) - {"mount_position", "max_incidence_deg"}
    if unknown:
        raise ValueError(f"profiler_options: unknown option(s) {sorted(unknown)}; allowed: "
                         f"{sorted(PROFILER_DEFAULTS) + ['max_incidence_deg', 'mount_position']}")
    caster = world if isinstance(world, RayCaster) else RayCaster(world)
    params = params if params is not None else FollowingParams()
    if params.warmup == 0.0:  # hold still until the head has scanned its sector once
        lo, hi = options["sector_deg"]
        params = dataclasses.replace(
            params, warmup=float(hi - lo) / options["step_deg"] / options["ping_rate"])

    builder = DiagramBuilder()
    vehicle = add_girona500(builder, navigation=navigation, initial_state=initial_state,
                            gains=gains)
    profiler = builder.AddNamedSystem("profiler", PencilBeamProfiler(
        caster, scan_plane=mode, noise=noise, seed=seed, **options))
    controller = builder.AddNamedSystem("profile_following", ProfileFollowingController(
        mode, params, period=profiler.period, depth_z=depth_z, plane_yaw=plane_yaw, seed=seed))
    builder.Connect(vehicle.dynamics.state_output, profiler.true_state_input)
    builder.Connect(vehicle.navigation.estimated_state_output, profiler.estimated_state_input)
    builder.Connect(profiler.returns_output, controller.returns_input)
    builder.Connect(vehicle.navigation.estimated_state_output, controller.state_input)
    builder.Connect(controller.reference_output, vehicle.tracker.reference_input)

    logs = {}
    for name, port, size in (("state_log", vehicle.dynamics.state_output, STATE_SIZE),
                             ("estimated_state_log", vehicle.navigation.estimated_state_output,
                              STATE_SIZE),
                             ("reference_log", controller.reference_output, 8),
                             ("profile_log", controller.profile_output, PROFILE_SIZE)):
        logs[name] = builder.AddNamedSystem(name, VectorLogSink(size, log_period))
        builder.Connect(port, logs[name].get_input_port())
    builder.ExportOutput(vehicle.dynamics.state_output, "state")
    builder.ExportOutput(vehicle.navigation.estimated_state_output, "estimated_state")
    builder.ExportOutput(controller.reference_output, "reference")
    builder.ExportOutput(controller.profile_output, "profile")
    visualizer = None
    if scene is not None:
        from drake_auv.visualization.sensors import SonarVisualizer

        visualizer = scene.add_vehicle_visualizer(builder, vehicle.dynamics.state_output)
        # the head's returns of the last ~20 s (a local map's worth) as points, beams live
        returns_view = builder.AddNamedSystem("profiler_visualizer", SonarVisualizer(
            scene.meshcat, scene.path_of("profiler"), period=profiler.period, history=200,
            point_size=0.06))
        builder.Connect(profiler.returns_output, returns_view.returns_input)
    if extra is not None:
        extra(builder, vehicle)
    diagram = builder.Build()
    diagram.set_name(f"profile_following_{mode}")
    return diagram, ProfileFollowingHandles(vehicle, profiler, controller, logs["state_log"],
                                            logs["estimated_state_log"], logs["reference_log"],
                                            logs["profile_log"], caster, visualizer)


def run_mission(diagram, duration: float, stop=None, chunk: float = 1.0, progress: bool = True,
                label: str = "simulating"):
    """Simulates `diagram` for up to `duration` s in chunks of `chunk` s, with a progress bar;
    `stop(context)` returning True ends the run early (checked after every chunk). Returns
    the Simulator."""
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be > 0 s, got {duration}")
    simulator = Simulator(diagram)
    simulator.Initialize()
    context = simulator.get_context()
    steps = int(np.ceil(duration / chunk))
    for k in tqdm(range(1, steps + 1), desc=label, unit="s sim", disable=not progress,
                  unit_scale=chunk):
        simulator.AdvanceTo(min(k * chunk, duration))
        if stop is not None and stop(context):
            break
    return simulator
