"""All together at the boulder site: the reference's combined experiment (Section 5.5.4).

Three phases on the `boulder` scenario, each its own Diagram (its own dive), all recorded into
one Meshcat scene one after the other:

1. **plan**: off-line 3D coverage plan on the site's prior map (shifted by a seeded error, as a
   GPS-referenced chart would be): boustrophedon lanes at Omega over the planar seabed and the
   boulder's top, the high-slope flanks sliced into `slice_count` contours `slice_spacing`
   apart (the reference's deliberately redundant two contours 2 m apart at Omega = 10 m).
2. **profile**: horizontal profile following around the boulder with the pencil-beam profiler
   (one closed loop at `follow_depth`, `follow_offset` from the true surface). The vehicle faces
   the structure, so the payload camera and multibeam look forward in this dive.
3. **replan**: the nominal plan flown with realtime replanning against the on-line octree map,
   under the prior-map error and seeded navigation drift; payload camera and multibeam look to
   port, and the yaw turns them to the mapped structure along the contours.

Coverage is measured on the true mesh (the boulder's faces above the seabed) by
`CoverageRecorder`s; true distances come from the exact point-to-mesh distance.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from pydrake.systems.analysis import Simulator
from tqdm import tqdm

from drake_auv.diagrams.profile_following import build_profile_following_diagram
from drake_auv.diagrams.replanning import build_replanning_diagram
from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.raycast import RayCaster
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.perception import EstimatorParams, FollowingParams
from drake_auv.planning.coverage_plan import CoveragePlan, plan_coverage
from drake_auv.replanning.section import ReplanningParameters
from drake_auv.scenarios import Scenario, get_scenario
from drake_auv.coverage.recorder import CoverageRecorder

VEHICLE_RADIUS = 1.0  # m, a sphere around the GIRONA 500's hulls for the contact check
FOLLOW_RADIUS = 16.0  # m, from the boulder's centre: where profile following starts, and the
# radius of the circle that sizes its time budget (the boulder is about 20 m x 15 m)


@dataclass(frozen=True)
class MissionConfig:
    """Parameters of the boulder mission (SI units; angles in degrees where named so).

    Attributes:
        seed: seeds the prior-map error, navigation drift, sonar noise and STOMP.
        prior_error_m: horizontal error of the prior map, m, in [0, 5].
        omega: offset of the off-line plan and of the replanner, m.
        slice_count, slice_spacing: slicing contours per high-slope region and their spacing, m.
        speed: survey speed, m/s.
        follow_depth, follow_offset, follow_loops: horizontal profile following (phase 2).
        camera_range: distance up to which the payload camera resolves the surface, m.
        heading_bias_deg, dvl_scale_error, random_walk: navigation drift (see
            `NavigationParams`); the seed is `seed`.
        time_margin: each phase may last this many times its nominal duration.
        replan_time: cap on the replanning phase's simulated time, s (None: the whole plan);
            for quick runs and tests.
        clearance: the replanner's obstacle margin, m.
    """

    seed: int = 0
    prior_error_m: float = 3.0
    omega: float = 10.0
    slice_count: int = 2
    slice_spacing: float = 2.0
    speed: float = 0.5
    follow_depth: float = 34.0
    follow_offset: float = 3.0
    follow_loops: float = 1.0
    camera_range: float = 12.0
    heading_bias_deg: float = 1.0
    dvl_scale_error: float = 0.01
    random_walk: float = 0.02
    time_margin: float = 1.4
    replan_time: float | None = None
    clearance: float = 4.0

    def __post_init__(self):
        if not (isinstance(self.seed, (int, np.integer)) and self.seed >= 0):
            raise ValueError(f"MissionConfig.seed must be an int >= 0, got {self.seed!r}")
        ranges = {"prior_error_m": (0.0, 5.0), "omega": (1.0, 50.0), "slice_spacing": (0.1, 20.0),
                  "speed": (0.05, 1.4), "follow_depth": (29.0, 39.0),
                  "follow_offset": (1.5, 10.0), "follow_loops": (0.1, 5.0),
                  "camera_range": (0.5, 50.0), "time_margin": (1.0, 5.0),
                  "clearance": (1.0, 20.0)}
        for name, (low, high) in ranges.items():
            value = getattr(self, name)
            if not (np.isfinite(value) and low <= value <= high):
                raise ValueError(f"MissionConfig.{name} must be in [{low:g}, {high:g}], "
                                 f"got {value!r}")
        if self.replan_time is not None and not (np.isfinite(self.replan_time)
                                                 and self.replan_time > 0):
            raise ValueError(f"MissionConfig.replan_time must be > 0 s or None, got "
                             f"{self.replan_time!r}")
        if not (int(self.slice_count) == self.slice_count and 1 <= self.slice_count <= 20):
            raise ValueError(f"MissionConfig.slice_count must be a whole number in [1, 20], "
                             f"got {self.slice_count!r}")

    def navigation(self) -> NavigationParams:
        return NavigationParams(heading_bias=np.radians(self.heading_bias_deg),
                                scale_error=self.dvl_scale_error,
                                random_walk=self.random_walk, seed=int(self.seed))


@dataclass
class PhaseResult:
    """One simulated phase, from the logs (true state unless named otherwise).

    Attributes:
        times: (n,) s; xyz: (n, 3) true positions, m; estimated_xyz: (n, 3) navigation's.
        distance: (n,) true distance to the structure (target faces), m.
        clearance: (n,) true distance to anything in the world, m.
        camera_best, multibeam_best: (T,) best viewing angle per target face, rad, NaN unseen.
        replan_wall: (k,) wall time of each replanning step, s (empty without a replanner).
        wall: wall time of the simulation, s.
        octree_map: the on-line `OctreeMap` at the end (None without a mapper).
    """

    name: str
    times: np.ndarray
    xyz: np.ndarray
    estimated_xyz: np.ndarray
    distance: np.ndarray
    clearance: np.ndarray
    camera_best: np.ndarray
    multibeam_best: np.ndarray
    wall: float
    replan_wall: np.ndarray = field(default_factory=lambda: np.zeros(0))
    octree_map: object = None

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0])

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.xyz, axis=0), axis=1).sum())


@dataclass
class MissionResult:
    """The plan and the simulated phases (profile following, then replanning)."""

    config: MissionConfig
    scenario: Scenario
    plan: CoveragePlan
    phases: list[PhaseResult]
    areas: np.ndarray  # (T,) area of each target face, m^2


class _MissionClock:
    """One progress bar over the simulated-time budgets of every phase."""

    def __init__(self, total: float, progress: bool):
        self.bar = tqdm(total=round(total), unit="s sim", desc="mission", disable=not progress)

    def advance(self, simulator: Simulator, end: float, stop, label: str, chunk: float = 5.0):
        """Advances `simulator` to `end` in chunks, stopping early when `stop()` is true; the
        bar then skips the rest of this phase's budget."""
        self.bar.set_description(label)
        context = simulator.get_context()
        while context.get_time() < end - 1e-9:
            before = context.get_time()
            simulator.AdvanceTo(min(before + chunk, end))
            self.bar.update(round(context.get_time()) - round(before))
            if stop():
                break
        self.bar.update(round(end) - round(context.get_time()))

    def close(self):
        self.bar.close()


def follow_budget(config: MissionConfig) -> float:
    """Longest simulated time of the profile-following phase, s: `follow_loops` turns of a
    `FOLLOW_RADIUS` circle at the survey speed, times the margin."""
    return config.time_margin * 2.0 * np.pi * FOLLOW_RADIUS * config.follow_loops / config.speed


def replan_budget(config: MissionConfig, plan: CoveragePlan) -> float:
    """Longest simulated time of the replanning phase, s: the nominal plan's duration times
    the margin, capped by `replan_time`."""
    budget = config.time_margin * plan.path.times(config.speed)[-1]
    return budget if config.replan_time is None else min(budget, config.replan_time)


def plan_phase(scenario: Scenario, config: MissionConfig) -> CoveragePlan:
    """The off-line plan on the prior map (shifted by `prior_error_m`, seeded)."""
    prior = scenario.prior_map(error_m=config.prior_error_m, seed=config.seed)
    return plan_coverage(prior, omega=config.omega, slice_spacing=config.slice_spacing,
                         slice_count=config.slice_count,
                         sensor_range=scenario.params["max_range"])


def _structure_distances(scenario: Scenario, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return (mesh_distance(target_mesh(scenario), xyz), mesh_distance(scenario.world, xyz))


def target_mesh(scenario: Scenario):
    """The structure to inspect (the scenario's target faces) as its own mesh."""
    return scenario.world.submesh([np.flatnonzero(scenario.target_faces)], append=True)


def _log_xyz(log_sink, context) -> tuple[np.ndarray, np.ndarray]:
    log = log_sink.FindLog(context)
    return log.sample_times(), log.data()[:3].T.copy()


def _fly(name: str, scenario: Scenario, simulator: Simulator, budget: float, stop,
         clock: _MissionClock, state_log, estimated_log, camera: CoverageRecorder,
         multibeam: CoverageRecorder) -> PhaseResult:
    """Simulates one phase until `stop()` or `budget` s and collects its `PhaseResult`."""
    context = simulator.get_context()
    wall = time.perf_counter()
    simulator.Initialize()
    clock.advance(simulator, budget, stop, name)
    wall = time.perf_counter() - wall
    t, xyz = _log_xyz(state_log, context)
    _, estimated = _log_xyz(estimated_log, context)
    distance, clearance = _structure_distances(scenario, xyz)
    camera_best, multibeam_best = (r.best_angles(r.GetMyContextFromRoot(context))
                                   for r in (camera, multibeam))
    return PhaseResult(name, t, xyz, estimated, distance, clearance, camera_best,
                       multibeam_best, wall)


def profile_phase(scenario: Scenario, caster: RayCaster, config: MissionConfig,
                  clock: _MissionClock, scene=None) -> PhaseResult:
    """Horizontal profile following: one closed loop around the boulder."""
    world = scenario.world
    centre = np.asarray(world.triangles_center[scenario.target_faces]).mean(axis=0)
    params = FollowingParams(offset=config.follow_offset, speed=config.speed,
                             estimator=EstimatorParams(window=config.follow_offset + 3.0))
    start = np.zeros(12)
    start[:3] = (centre[0] - FOLLOW_RADIUS, centre[1], -config.follow_depth)  # off its -x side
    recorders = {}

    def add_recorders(builder, vehicle):
        recorders["camera"] = builder.AddNamedSystem("camera_coverage", CoverageRecorder(
            caster, scenario.target_faces, sensor="camera", max_range=config.camera_range,
            axis_body=(1.0, 0.0, 0.0)))
        recorders["multibeam"] = builder.AddNamedSystem("multibeam_coverage", CoverageRecorder(
            caster, scenario.target_faces, sensor="multibeam",
            max_range=scenario.params["max_range"], mount="vertical"))
        for recorder in recorders.values():
            builder.Connect(vehicle.dynamics.state_output, recorder.true_state_input)

    diagram, handles = build_profile_following_diagram(
        caster, start, "horizontal", params, navigation=config.navigation(), seed=config.seed, scene=scene, extra=add_recorders)
    simulator = Simulator(diagram)
    context = simulator.get_context()
    budget = follow_budget(config)

    def closed() -> bool:
        x = handles.state_log.FindLog(context).data()
        if x.shape[1] < 2:
            return False
        angle = np.unwrap(np.arctan2(x[1] - centre[1], x[0] - centre[0]))
        return abs(angle[-1] - angle[0]) >= 2.0 * np.pi * config.follow_loops

    return _fly("profile", scenario, simulator, budget, closed, clock, handles.state_log,
                handles.estimated_state_log, recorders["camera"], recorders["multibeam"])


def replan_phase(scenario: Scenario, caster: RayCaster, plan: CoveragePlan,
                 config: MissionConfig, clock: _MissionClock, scene=None) -> PhaseResult:
    """The nominal plan flown with realtime replanning against the on-line octree map."""
    nominal = plan.path
    start = np.zeros(12)
    start[:3] = nominal.points[0]
    start[5] = nominal.heading[0]
    params = ReplanningParameters(omega=config.omega, clearance=config.clearance,
                                  offset_metric="3d")
    diagram, handles = build_replanning_diagram(
        caster, nominal, start, replanning=True, params=params, speed=config.speed,
        navigation=config.navigation(), max_range=scenario.params["max_range"],
        multibeam_mount="port", seed=config.seed, scene=scene,
        target_faces=scenario.target_faces, camera_range=config.camera_range)
    simulator = Simulator(diagram)
    budget = replan_budget(config, plan)
    log = handles.replanner.log

    def done() -> bool:
        return bool(log) and log[-1].plan is None

    phase = _fly("replan", scenario, simulator, budget, done, clock, handles.state_log,
                 handles.estimated_log, handles.camera_coverage, handles.multibeam_coverage)
    phase.replan_wall = np.array([s.wall_time for s in log if s.plan is not None])
    phase.octree_map = handles.mapper.octree_map
    return phase


def run_mission(config: MissionConfig = MissionConfig(), scene=None,
                progress: bool = True) -> MissionResult:
    """Plans, then simulates profile following and the replanned nominal plan."""
    scenario = get_scenario("boulder")
    caster = RayCaster(scenario.world)
    plan = plan_phase(scenario, config)
    clock = _MissionClock(follow_budget(config) + replan_budget(config, plan), progress)
    if scene is not None:
        scene.add_mesh("world", scenario.world, rgba=(0.55, 0.5, 0.42, 1.0))
        scene.add_path("nominal_path", plan.path)
    profile = profile_phase(scenario, caster, config, clock, scene)
    if scene is not None:
        scene.time_offset = profile.times[-1]
    replan = replan_phase(scenario, caster, plan, config, clock, scene)
    clock.close()
    areas = np.asarray(scenario.world.area_faces)[scenario.target_faces]
    return MissionResult(config, scenario, plan, [profile, replan], areas)


def write_recording(result: MissionResult, scene, filename):
    """Adds the end-of-mission layers (occupied voxels of the on-line map, the boulder
    coloured by its best multibeam viewing angle) and writes the standalone HTML."""
    from drake_auv.visualization.octree import draw_octree
    from drake_auv.visualization.sensors import draw_coverage

    world, target = result.scenario.world, result.scenario.target_faces
    best = np.full(len(world.faces), np.nan)
    best[target] = np.fmin.reduce([p.multibeam_best for p in result.phases])
    draw_coverage(scene.meshcat, scene.path_of("coverage"), world, best, target)
    draw_octree(scene.meshcat, scene.path_of("octree"), result.phases[-1].octree_map)
    return scene.write_html(filename)
