"""The realtime replanning mission: vehicle, sonars, octree mapper and replanner, wired.

    multibeam ─┐                       ┌──────────── estimated_state ──────────┐
    profiler ──┴─> octree_mapper ─map─> replanner ─reference─> tracker ─> ... dynamics
         ^ true_state, estimated_state                                           │
         └───────────────────────────────────────────────────────────────────────┘

With `replanning=False` the tracker flies the nominal path as planned (a `TrajectorySource`
of it at the survey speed) while the sonars and the mapper run unchanged, so the two runs
differ only in who drives the tracker. True state, estimated state and reference are logged;
two `CoverageRecorder`s measure, on the true world, what the side-looking payload camera and
multibeam have seen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource, VectorLogSink

from drake_auv.vehicle.diagram import VehicleSystems, add_girona500
from drake_auv.geometry.raycast import RayCaster
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.planning.path import Path
from drake_auv.replanning.section import ReplanningParameters
from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.sonar.multibeam import MultibeamSonar
from drake_auv.mapping.mapper import OctreeMapper
from drake_auv.sonar.profiler import PencilBeamProfiler
from drake_auv.replanning.replanner import Replanner
from drake_auv.vehicle.model import STATE_SIZE
from drake_auv.visualization.octree import OctreeVisualizer


@dataclass
class ReplanningHandles:
    """What `build_replanning_diagram` returns beside the diagram."""

    vehicle: VehicleSystems
    multibeam: MultibeamSonar
    profiler: PencilBeamProfiler
    mapper: OctreeMapper
    replanner: Replanner | None  # None when replanning is off
    source: TrajectorySource | None  # the nominal path's source when replanning is off
    camera_coverage: CoverageRecorder | None  # side-looking camera on the true world
    multibeam_coverage: CoverageRecorder | None  # the payload multibeam's fan, true world
    state_log: VectorLogSink  # true state
    estimated_log: VectorLogSink
    reference_log: VectorLogSink
    visualizer: object = None


def build_replanning_diagram(world, nominal: Path, start_state, replanning: bool = True,
                             params: ReplanningParameters | None = None, speed: float = 0.3,
                             navigation: NavigationParams | None = None,
                             resolution: float = 0.5, max_range: float = 20.0,
                             multibeam_mount: str = "port", multibeam_stride: int = 2,
                             heading_offset: float = 0.0, replanning_period: float = 1.0,
                             log_period: float = 0.1, seed: int = 0, scene=None,
                             coverage: bool = True, target_faces=None,
                             camera_range: float = 8.0):
    """Builds the mission Diagram; returns (diagram, ReplanningHandles).

    Args:
        world: the true world (trimesh or a shared `RayCaster`).
        nominal: the nominal path, planned on the prior map (its first sample should be the
            start position: the nominal-only run flies it from there).
        start_state: (12,) initial true state.
        replanning: True: the `Replanner` drives the tracker; False: the nominal path does.
        params: `ReplanningParameters` (R, K, Omega, STOMP).
        speed: survey speed, m/s.
        navigation: navigation error model (default exact).
        resolution: octree voxel edge, m.
        max_range: range of both sonars, m.
        multibeam_mount: "port", "starboard", "down" or "forward" (the payload multibeam).
        multibeam_stride: the mapper inserts every n-th multibeam beam.
        heading_offset: yaw relative to the direction of motion along the replanned path where
            no structure is mapped near (the yaw turns a side-looking multibeam to the
            mapped structure where it is), rad.
        replanning_period: s.
        log_period: period of the state/reference logs, s.
        seed: seed of the sonars' noise and STOMP.
        scene: an optional `drake_auv.visualization.scene.Scene` to draw the vehicle and the
            octree map (redrawn every 5 s) in.
        coverage: add the coverage recorders (off for timing the mission without them).
        target_faces: (F,) bool mask of the world's faces whose coverage is recorded.
        camera_range: range of the payload camera (60 degrees, looking to the multibeam's
            side), m: the water visibility.
    """
    if not (np.isfinite(log_period) and log_period > 0):
        raise ValueError(f"log_period must be > 0 s, got {log_period}")
    caster = world if isinstance(world, RayCaster) else RayCaster(world)
    builder = DiagramBuilder()
    vehicle = add_girona500(builder, navigation=navigation,
                            initial_state=np.asarray(start_state, dtype=float))
    true_state = vehicle.dynamics.state_output
    estimated = vehicle.navigation.estimated_state_output
    multibeam = builder.AddNamedSystem("multibeam", MultibeamSonar(
        caster, max_range=max_range, mount=multibeam_mount, seed=seed))
    profiler = builder.AddNamedSystem("profiler", PencilBeamProfiler(
        caster, scan_plane="horizontal", max_range=max_range, seed=seed + 1))
    mapper = builder.AddNamedSystem("octree_mapper", OctreeMapper(
        resolution=resolution, multibeam_stride=multibeam_stride))
    for sonar in (multibeam, profiler):
        builder.Connect(true_state, sonar.true_state_input)
        builder.Connect(estimated, sonar.estimated_state_input)
    builder.Connect(multibeam.returns_output, mapper.multibeam_input)
    builder.Connect(profiler.returns_output, mapper.profiler_input)
    replanner = source = None
    if replanning:
        replanner = builder.AddNamedSystem("replanner", Replanner(
            nominal, params, speed=speed, period=replanning_period,
            sensor_azimuth={"port": np.pi / 2, "starboard": -np.pi / 2}.get(multibeam_mount),
            heading_offset=heading_offset, seed=seed))
        builder.Connect(estimated, replanner.state_input)
        builder.Connect(mapper.map_output, replanner.map_input)
        reference = replanner.reference_output
    else:
        source = builder.AddNamedSystem("nominal_reference",
                                        TrajectorySource(nominal.to_trajectory(speed), 1))
        reference = source.get_output_port()
    builder.Connect(reference, vehicle.tracker.reference_input)
    camera_coverage = multibeam_coverage = None
    if coverage:
        side = {"port": (0.0, 1.0, 0.0), "starboard": (0.0, -1.0, 0.0),
                "down": (0.0, 0.0, -1.0), "forward": (1.0, 0.0, 0.0)}[multibeam_mount]
        camera_coverage = builder.AddNamedSystem("camera_coverage", CoverageRecorder(
            caster, target_faces, sensor="camera", aperture_deg=60.0, max_range=camera_range,
            axis_body=side, rate=2.0))
        multibeam_coverage = builder.AddNamedSystem("multibeam_coverage", CoverageRecorder(
            caster, target_faces, sensor="multibeam", max_range=max_range,
            mount=multibeam_mount, rate=2.0))
        for recorder in (camera_coverage, multibeam_coverage):
            builder.Connect(true_state, recorder.true_state_input)
    state_log = builder.AddNamedSystem("state_log", VectorLogSink(STATE_SIZE, log_period))
    builder.Connect(true_state, state_log.get_input_port())
    estimated_log = builder.AddNamedSystem("estimated_log", VectorLogSink(STATE_SIZE, log_period))
    builder.Connect(estimated, estimated_log.get_input_port())
    reference_log = builder.AddNamedSystem("reference_log", VectorLogSink(8, log_period))
    builder.Connect(reference, reference_log.get_input_port())
    builder.ExportOutput(true_state, "state")
    builder.ExportOutput(estimated, "estimated_state")
    builder.ExportOutput(mapper.map_output, "map")
    visualizer = None
    if scene is not None:
        visualizer = scene.add_vehicle_visualizer(builder, true_state)
        octree_visualizer = builder.AddNamedSystem("octree_visualizer", OctreeVisualizer(
            scene.meshcat, scene.path_of("octree"), period=5.0))
        builder.Connect(mapper.map_output, octree_visualizer.map_input)
    handles = ReplanningHandles(vehicle, multibeam, profiler, mapper, replanner, source,
                                camera_coverage, multibeam_coverage, state_log, estimated_log,
                                reference_log, visualizer)
    diagram = builder.Build()
    diagram.set_name("replanning" if replanning else "nominal_only")
    return diagram, handles
