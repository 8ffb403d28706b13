"""`build_mission_diagram`: one Diagram flies a whole mission, in one dive.

Like a manipulation station: free functions add and wire each part into a `DiagramBuilder`,
and `build_mission_diagram` is the one place that builds the whole mission.

    nominal_plan ──> path_reference ──┐
         │      profile_following ────┤ reference_switch ─> tracker ─> allocation ─> dynamics
         └──────────> replanner ──────┤        ^ behaviour                               │
        dvl ──> autopilot (fly) ──────┘        │                                         │
                  ^ map      ^ status    mission_supervisor <─ path/replanner status     │
             octree_mapper   └──────────────── leg ─────> behaviours, profiler head      │
                  ^                                                                      │
         multibeam, profiler <── true state (ray casting on the true world) ─────────────┤
                  ^ estimated state <── navigation <─────────────────────────────────────┘
    camera_coverage, multibeam_coverage, logs and the Meshcat visualisers listen.

The true world reaches only the sonars' ray casting and the coverage recorders; everything
that decides (supervisor, behaviours, mapper) sees the estimated state and the returns.
A mission's `faults` splice small systems (`drake_auv.mission.faults`) into this wiring: a
silence gate after a sonar, a failure between the allocation and the dynamics, a jump after
the navigation; the supervisor sees the returns, the reference and the map to detect them, and
drives the switch's fourth input, `response`, while it answers.
Behaviours that are not flying skip their periodic updates, and `PortSwitch` evaluates only
the selected reference. The path reference (transits) is always there; every other behaviour
is added by the step kind that flies it (`drake_auv.mission.steps`: follow, survey, fly,
explore, a step's own), behind the switch input of its name, its status on the supervisor's
`<name>_status`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, LogVectorOutput, PortSwitch

from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mapping.mapper import OctreeMapper
from drake_auv.mission.config import MissionSpec, SensorSpec
from drake_auv.mission.faults import NavigationJump, SonarSilence, ThrusterFailure
from drake_auv.mission.plan import MissionPlan, plan_mission
from drake_auv.mission.steps import behaviour_step
from drake_auv.mission.steps.step import LOG_PERIOD, Wiring, terrain_elevation
from drake_auv.mission.steps.survey import connect_replanner
from drake_auv.mission.site import Site
from drake_auv.mission.supervisor import MissionSupervisor
from drake_auv.ocean.system import TURBULENCE_PERIOD_S, Ocean
from drake_auv.random_streams import generator
from drake_auv.sonar.altimeter import DvlAltimeter
from drake_auv.sonar.beams import SonarMount
from drake_auv.sonar.multibeam import MultibeamSonar
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.profiler import FOLLOWING_SETUP, PencilBeamProfiler
from drake_auv.sonar.sensor import BUILT_IN, Sensor, stream_of
from drake_auv.vehicle.diagram import VehicleSystems, add_girona500
from drake_auv.vehicle.path_reference import PathReference

SUPERVISOR_PERIOD = 0.5  # s
CAMERA_SIDE = {"port": (0.0, 1.0, 0.0), "starboard": (0.0, -1.0, 0.0),
               "down": (0.0, 0.0, -1.0), "forward": (1.0, 0.0, 0.0)}


@dataclass
class MissionHandles:
    """The systems `build_mission_diagram` added, and the plan it flies."""

    plan: MissionPlan
    caster: RayCaster
    vehicle: VehicleSystems
    sonars: dict  # name -> the payload's sonars (`sonar_table`): a `Sensor` each
    mapper: OctreeMapper
    supervisor: MissionSupervisor
    camera_coverage: CoverageRecorder
    multibeam_coverage: CoverageRecorder
    logs: dict  # name -> VectorLogSink: state, estimated_state, reference, leg, response,
    # and the behaviours' (profile, replanning, exploration); `run_mission` spools them to
    # disk as the dive runs (after it, a log holds its last samples only; `MissionResult`
    # holds the whole dive)
    faults: dict  # fault name -> the system injecting it (only the mission's faults)
    behaviours: dict  # behaviour name -> its system ("path": the path reference, always)
    dvl: DvlAltimeter | None = None  # with a step that needs one (fly, explore)
    ocean: Ocean | None = None  # with a sea (`ocean:` not none): the water at the vehicle
    mcap: object = None  # with an `McapLog`: the `rosio.McapRecorder` writing into it

    @property
    def multibeam(self) -> MultibeamSonar:
        return self.sonars["multibeam"]

    @property
    def profiler(self) -> PencilBeamProfiler:
        return self.sonars["profiler"]

    @property
    def path_reference(self) -> PathReference:
        return self.behaviours["path"]

    @property
    def controller(self):
        """The profile-following controller (None without a follow step)."""
        return self.behaviours.get("follow")

    @property
    def replanner(self):
        """The replanner (None without a replanned survey)."""
        return self.behaviours.get("replan")

    @property
    def autopilot(self):
        """The autopilot pilot (None without a fly step)."""
        return self.behaviours.get("autopilot")

    @property
    def explorer(self):
        """The view planner (None without an explore step)."""
        return self.behaviours.get("explore")


def add_faults(builder: DiagramBuilder, vehicle: VehicleSystems, spec: MissionSpec):
    """The thruster failure and the navigation jump of `spec.faults`, spliced in; returns
    ({name: system}, the estimated-state port everything downstream reads)."""
    faults, estimated = {}, vehicle.navigation.estimated_state_output
    thruster = spec.faults.thruster_failure
    if thruster.start_s is not None:
        gate = faults["thruster_failure"] = builder.AddNamedSystem(
            "thruster_failure", ThrusterFailure(thruster.thruster, thruster.start_s))
        builder.Disconnect(vehicle.allocation.thrust_output, vehicle.dynamics.thrust_input)
        builder.Connect(vehicle.allocation.thrust_output, gate.command_input)
        builder.Connect(gate.thrust_output, vehicle.dynamics.thrust_input)
    jump = spec.faults.navigation_jump
    if jump.time_s is not None:
        heading = np.radians(jump.direction_deg)
        gate = faults["navigation_jump"] = builder.AddNamedSystem("navigation_jump", NavigationJump(
            jump.time_s, jump.error_m * np.array([np.cos(heading), np.sin(heading)])))
        builder.Disconnect(estimated, vehicle.tracker.state_input)
        builder.Connect(estimated, gate.estimated_input)
        builder.Connect(gate.estimated_state_output, vehicle.tracker.state_input)
        estimated = gate.estimated_state_output
    return faults, estimated


def sonar_table(spec: MissionSpec) -> dict[str, SensorSpec]:
    """{name: `SensorSpec`} of the mission's sonars, in their order as sources of the map: the
    built-in multibeam (looking to `payload.multibeam_mount`, every
    `replanner.multibeam_stride`-th beam mapped) and pencil-beam profiler (the horizontal head
    of profile following), then the `payload.sensors` configured."""
    return {"multibeam": SensorSpec("multibeam", "multibeam", spec.payload.multibeam_mount,
                                    map_stride=spec.replanner.multibeam_stride),
            "profiler": SensorSpec("profiler", "profiler", "horizontal",
                                   rate_hz=FOLLOWING_SETUP["update_rate"]),
            **{sensor.name: sensor for sensor in spec.payload.sensors}}


def make_sonar(caster: RayCaster, sensor: SensorSpec, max_range: float,
               noise: SonarNoise | None, seed: int, **options) -> Sensor:
    """The sonar system of `sensor` (its noise drawn from the stream of its name,
    `sonar.sensor.stream_of`); `options` go to its class (`axis_hits_output` of a multibeam,
    `planes` of a profiler)."""
    common = dict(max_range=max_range, mount=SonarMount.named(sensor.mount, sensor.position_m),
                  noise=noise, seed=seed, stream=stream_of(sensor.name), **options)
    if sensor.kind == "multibeam":
        return MultibeamSonar(caster, num_beams=sensor.num_beams, fan_deg=sensor.fan_deg,
                              rate=sensor.rate_hz, **common)
    setup = {key: value for key, value in FOLLOWING_SETUP.items()
             if key not in ("max_range", "update_rate")}
    return PencilBeamProfiler(caster, update_rate=sensor.rate_hz, **setup, **common)


def add_sonars(builder: DiagramBuilder, caster: RayCaster, vehicle: VehicleSystems,
               spec: MissionSpec, plan: MissionPlan, max_range: float, estimated, faults):
    """The sonars of `sonar_table(spec)` (the profiler's head tilted to the vertical plane on
    vertical-following legs), each named by its key, ray casting on the true world, placing
    their returns with the `estimated` state; a silent-sonar fault gates the built-in ones'
    returns (added to `faults`). Returns ({name: sonar}, {name: its returns port})."""
    noise = spec.sonar_noise.to_noise()
    options = {"multibeam": dict(axis_hits_output=True),
               "profiler": dict(planes=plan.profiler_planes or None)}
    silent = spec.faults.sonar_silent
    sonars, returns = {}, {}
    for name, sensor in sonar_table(spec).items():
        sonar = sonars[name] = builder.AddNamedSystem(name, make_sonar(
            caster, sensor, max_range, noise, spec.seed, **options.get(name, {})))
        builder.Connect(vehicle.dynamics.state_output, sonar.true_state_input)
        builder.Connect(estimated, sonar.estimated_state_input)
        returns[name] = sonar.returns_output
        if silent.start_s is not None and silent.sensor in (name, "both") and name in BUILT_IN:
            gate = faults[f"sonar_silent_{name}"] = builder.AddNamedSystem(
                f"{name}_silence", SonarSilence(silent.start_s, silent.duration_s, max_range))
            builder.Connect(sonar.returns_output, gate.returns_input)
            returns[name] = gate.returns_output
    return sonars, returns


def add_ocean(builder: DiagramBuilder, vehicle: VehicleSystems, spec: MissionSpec,
              site: Site, plan: MissionPlan, dvl: DvlAltimeter | None):
    """The sea of `spec.ocean` (None: still water, nothing added): the `Ocean` system at the
    vehicle's true position, feeding the dynamics' relative-velocity hydrodynamics and the
    navigation (which dead-reckons through the water when `dvl` loses the bottom). The sea's
    files are checked against the site, the dive's span (from its start to its time cap,
    `MissionPlan.time_cap`) and the nominal route first (one line). Returns the Ocean or
    None."""
    if spec.ocean is None:
        return None
    model = spec.ocean.model(generator(spec.seed, "ocean.waves"), site.crs, site.origin)
    bounds = site.world.bounds
    cap, source = plan.time_cap(spec)
    model.check((bounds[0, 0], bounds[0, 1], bounds[1, 0], bounds[1, 1]), -bounds[0, 2], cap,
                plan.nominal.points if plan.nominal is not None else None,
                f"its time cap, {cap:g} s: {source}")
    step = vehicle.dynamics.time_step  # the turbulence updated every whole number of steps
    ocean = builder.AddNamedSystem("ocean", Ocean(
        model, seed=spec.seed, period=step,
        turbulence_period=max(1, round(TURBULENCE_PERIOD_S / step)) * step))
    builder.Connect(vehicle.dynamics.state_output, ocean.state_input)
    builder.Connect(ocean.water_output, vehicle.dynamics.water_input)
    builder.Connect(ocean.water_output, vehicle.navigation.water_input)
    if dvl is not None:
        builder.Connect(dvl.bottom_lock_output, vehicle.navigation.bottom_lock_input)
    return ocean


def add_behaviours(builder: DiagramBuilder, wiring: Wiring, own: dict | None = None):
    """The nominal plan's source, the path reference (transits, surveys flown as planned), the
    behaviour of every step kind the plan flies (`MissionStep.add_behaviour`, in the
    registry's order), the reference switch and the supervisor (watching the sonars'
    returns, the reference and the map), wired: each behaviour's `estimated_state`, `leg`,
    `reference` (to the switch input of its name) and `status` (to the supervisor's
    `<name>_status`). `own`: {behaviour name: a LeafSystem of your own, not yet added} to fly
    that behaviour's legs instead of the built-in one, with the `Behaviour` ports (inputs
    `estimated_state` (12), `leg` (2) and, for "replan", if it declares them, `map` and
    `nominal`; outputs `reference` (8) and `status` (3: `[leg, finished, progress]`,
    finished > 0 ends the leg)); see `examples/custom_controller.py`. Returns (supervisor,
    switch, {behaviour name: system}); `wiring.nominal` is set."""
    own = dict(own or {})
    plan = wiring.plan
    if plan.nominal is not None:  # the off-line plan, as a signal
        source = builder.AddNamedSystem("nominal_plan",
                                        ConstantValueSource(AbstractValue.Make(plan.nominal)))
        wiring.nominal = source.get_output_port()
    names = ["path", *(name for name in plan.behaviours if name != "path"), "response"]
    switch = builder.AddNamedSystem("reference_switch", PortSwitch(8))
    ports = {name: switch.DeclareInputPort(name).get_index() for name in names}
    supervisor = builder.AddNamedSystem("mission_supervisor", MissionSupervisor(
        plan.legs, ports, SUPERVISOR_PERIOD, sensors=tuple(wiring.returns)))
    path_reference = builder.AddNamedSystem("path_reference", PathReference(
        plan.legs_of("path"), terrain=terrain_elevation(wiring.site),
        clearance=wiring.spec.replanner.params.clearance))
    if wiring.nominal is not None:
        builder.Connect(wiring.nominal, path_reference.nominal_input)
    behaviours = {"path": path_reference}
    for name in names[1:-1]:
        step = behaviour_step(name)
        if name in own:
            behaviours[name] = builder.AddSystem(own.pop(name))
            if name == "replan":
                connect_replanner(wiring, behaviours[name])
        else:
            behaviours[name] = step.add_behaviour(wiring, plan.legs_of(name))
    if own:
        raise ValueError(f"no legs for the behaviour(s) {sorted(own)} of `own`")
    for name, system in behaviours.items():
        builder.Connect(wiring.estimated, system.GetInputPort("estimated_state"))
        builder.Connect(supervisor.leg_output, system.GetInputPort("leg"))
        builder.Connect(system.GetOutputPort("reference"), switch.GetInputPort(name))
        builder.Connect(system.GetOutputPort("status"), supervisor.status_inputs[name])
    if plan.profiler_planes:
        builder.Connect(supervisor.leg_output, wiring.profiler.leg_input)
    builder.Connect(supervisor.response_reference_output, switch.GetInputPort("response"))
    for name, port in wiring.returns.items():
        builder.Connect(port, supervisor.returns_inputs[name])
    builder.Connect(switch.get_output_port(), supervisor.reference_input)
    builder.Connect(wiring.mapper.map_output, supervisor.map_input)
    builder.Connect(wiring.estimated, supervisor.state_input)
    builder.Connect(supervisor.behaviour_output, switch.get_port_selector_input_port())
    builder.Connect(switch.get_output_port(), wiring.vehicle.tracker.reference_input)
    return supervisor, switch, behaviours


def add_coverage_recorders(builder: DiagramBuilder, caster: RayCaster, vehicle: VehicleSystems,
                           spec: MissionSpec, site: Site, max_range: float,
                           multibeam: MultibeamSonar):
    """What the payload camera (2 frames/s) and `multibeam` (every ping) have seen of the
    target, on the true world. The multibeam is scored at its own ping rate, on the faces its
    beams' axes hit (its `axis_hits`): at 2 Hz and 0.3 m/s its vertical fan would sweep the
    face every 0.15 m and miss parts of 0.25 m faces it did ping."""
    mount = spec.payload.multibeam_mount
    camera = builder.AddNamedSystem("camera_coverage", CoverageRecorder(
        caster, site.target_faces, sensor="camera",
        aperture_deg=spec.payload.camera_aperture_deg, max_range=spec.payload.camera_range_m,
        axis_body=CAMERA_SIDE[mount], rate=2.0))
    recorder = builder.AddNamedSystem("multibeam_coverage", CoverageRecorder(
        caster, site.target_faces, sensor="multibeam", max_range=max_range, mount=mount,
        rate=1.0 / multibeam.period, hits_input=True))
    builder.Connect(multibeam.axis_hits_output, recorder.hits_input)
    for system in (camera, recorder):
        builder.Connect(vehicle.dynamics.state_output, system.true_state_input)
    return camera, recorder


def add_visualizers(builder: DiagramBuilder, scene, spec: MissionSpec, plan: MissionPlan,
                    vehicle: VehicleSystems, mapper: OctreeMapper,
                    supervisor: MissionSupervisor, estimated, switch, replanner=None,
                    ocean: Ocean | None = None) -> None:
    """What `scene` draws while the mission flies: the vehicle and its trail, the on-line map,
    with a sea the current at the vehicle (the `ocean`'s `water`), and in a live scene the
    leg, the replanner's section, the reference and the mission clock (`mission.live_view`).
    Each layer is named in the scene's legend."""
    from drake_auv.visualization.current import CurrentVisualizer
    from drake_auv.visualization.octree import OctreeVisualizer, octree_legend

    # a pose every 0.5 s: at the recordings' 20x playback and 32 frames/s a frame is 0.6 s
    scene.add_vehicle_visualizer(builder, vehicle.dynamics.state_output, period=0.5)
    octree_view = builder.AddNamedSystem("octree_visualizer", OctreeVisualizer(
        scene.meshcat, scene.path_of("octree"), period=10.0))
    builder.Connect(mapper.map_output, octree_view.map_input)
    scene.add_legend(octree_legend(scene.path_of("octree")))
    if ocean is not None:
        arrow = builder.AddNamedSystem("current_visualizer", CurrentVisualizer(scene, period=1.0))
        builder.Connect(vehicle.dynamics.state_output, arrow.state_input)
        builder.Connect(ocean.water_output, arrow.water_input)
    if scene.live:  # the leg, the replanner's section and the reference, for a browser
        from drake_auv.mission.live_view import add_mission_view

        cap = spec.limits.max_time_s if spec.limits.max_time_s is not None else plan.budget
        add_mission_view(builder, scene, plan.legs, supervisor.leg_output, estimated,
                         switch.get_output_port(),
                         replanner.GetOutputPort("section") if replanner is not None
                         and replanner.HasOutputPort("section") else None,
                         duration=cap if np.isfinite(cap) else None)


def build_mission_diagram(site: Site, spec: MissionSpec, plan: MissionPlan | None = None,
                          scene=None, caster: RayCaster | None = None, mcap=None):
    """The whole mission `spec` at `site` as one Diagram; returns (diagram, MissionHandles).

    Args:
        plan: the off-line part (default: `plan_mission(spec, site)`).
        scene: a `drake_auv.visualization.Scene` to draw the vehicle, its trail and the
            on-line map in while it flies (a `live` scene: also the leg, the section and the
            reference).
        caster: a `RayCaster` of `site.world` to share (default: built here).
        mcap: a `drake_auv.rosio.McapLog` the dive is written into as ROS 2 messages.
    Exported outputs: `state` (true), `estimated_state`, `map`, `leg`.
    """
    plan = plan if plan is not None else plan_mission(spec, site)
    caster = caster if caster is not None else site.clearance.caster  # built once per site
    max_range = site.max_range
    builder = DiagramBuilder()
    vehicle = add_girona500(builder, navigation=replace(spec.navigation, seed=spec.seed),
                            initial_state=plan.start_state)
    faults, estimated = add_faults(builder, vehicle, spec)
    sonars, returns = add_sonars(builder, caster, vehicle, spec, plan, max_range, estimated,
                                 faults)
    table = sonar_table(spec)
    mapper = builder.AddNamedSystem("octree_mapper", OctreeMapper(
        resolution=spec.replanner.voxel_m, multibeam_stride=table["multibeam"].map_stride,
        discretize=spec.replanner.discretize, no_return_clear_m=min(  # a step may set it
            (getattr(s, "no_return_clear_m", np.inf) for s in spec.steps), default=np.inf),
        extra={name: s.map_stride for name, s in table.items() if name not in BUILT_IN}))
    for name, port in returns.items():
        builder.Connect(port, mapper.returns_inputs[name])
    wiring = Wiring(builder, spec, plan, site, caster, vehicle, estimated, mapper, returns,
                    sonars["profiler"])
    supervisor, switch, behaviours = add_behaviours(builder, wiring)
    dvl, replanner = wiring.added.get("dvl"), behaviours.get("replan")
    ocean = add_ocean(builder, vehicle, spec, site, plan, dvl)
    camera, multibeam_coverage = add_coverage_recorders(builder, caster, vehicle, spec, site,
                                                        max_range, sonars["multibeam"])
    logs = {
        "state": LogVectorOutput(vehicle.dynamics.state_output, builder, LOG_PERIOD),
        "estimated_state": LogVectorOutput(estimated, builder, LOG_PERIOD),
        "reference": LogVectorOutput(switch.get_output_port(), builder, LOG_PERIOD),
        "leg": LogVectorOutput(supervisor.leg_output, builder, SUPERVISOR_PERIOD),
        "response": LogVectorOutput(supervisor.response_output, builder, SUPERVISOR_PERIOD),
    }
    if ocean is not None:
        logs["water"] = LogVectorOutput(ocean.water_output, builder, LOG_PERIOD)
    logs.update(wiring.logs)
    for name, log in logs.items():
        log.set_name(f"{name}_log")
    recorder = None
    if mcap is not None:
        from drake_auv.rosio.recorder import add_mcap_recorder

        recorder = add_mcap_recorder(
            builder, mcap, vehicle, estimated, switch.get_output_port(), supervisor,
            {**sonars, **({"dvl": dvl} if dvl else {})},
            {**returns, **({"dvl": dvl.returns_output} if dvl else {})},
            {"multibeam": multibeam_coverage, "camera": camera}, site, plan.nominal, mapper,
            replanner, ocean)
    builder.ExportOutput(vehicle.dynamics.state_output, "state")
    builder.ExportOutput(estimated, "estimated_state")
    builder.ExportOutput(mapper.map_output, "map")
    builder.ExportOutput(supervisor.leg_output, "leg")
    if scene is not None:
        add_visualizers(builder, scene, spec, plan, vehicle, mapper, supervisor, estimated,
                        switch, replanner, ocean)
    diagram = builder.Build()
    diagram.set_name(f"mission_{spec.name}")
    handles = MissionHandles(plan, caster, vehicle, sonars, mapper, supervisor,
                             camera, multibeam_coverage, logs, faults, behaviours, dvl, ocean,
                             recorder)
    return diagram, handles
