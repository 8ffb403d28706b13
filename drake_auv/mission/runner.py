"""Running a mission: load its site, plan, build the one Diagram, fly it, collect the results.

`run_mission(spec)` simulates until the `MissionSupervisor`'s monitor ends the dive (every leg
done) or the time cap (`limits.max_time_s`, default the sum of the legs' budgets). The monitor
also updates the progress display (`dive_share`: the legs flown, not the time budget) and
moves the logs' samples to disk every `LOG_SPOOL_S` (`mission.log_spool`: their memory does
not grow with the dive). `MissionResult` holds what
the report needs, read from the logs and the systems' Contexts after the run; true distances
come from the exact point-to-mesh distance, on the true world, and the clearance is signed
(`geometry.clearance`: negative inside the world or out of the water).
"""

from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass

import numpy as np
from pydrake.systems.analysis import Simulator, SimulatorStatus
from pydrake.systems.framework import EventStatus

from drake_auv.behaviour import Behaviour
from drake_auv.geometry.distance import mesh_distance
from drake_auv.mapping.scan_log import ScanLog
from drake_auv.mission.config import MissionSpec
from drake_auv.mission.diagram import MissionHandles, build_mission_diagram
from drake_auv.mission.log_spool import LogSpool
from drake_auv.mission.plan import MissionPlan, check_against_site, plan_mission
from drake_auv.mission.site import Site, load_site
from drake_auv.mission.supervisor import responses_from_log
from drake_auv.progress import RunProgress
from drake_auv.signals import (LegSignal, Profile, ReplanningStep, VehicleState, Water,
                               annotate_graphviz)

VEHICLE_RADIUS = 1.0  # m, a sphere around the GIRONA 500's hulls for the contact check
LOG_SPOOL_S = 300.0  # s of simulated time between moves of the logs' samples to disk


@dataclass
class Phase:
    """A contiguous part of the dive: consecutive legs of the same phase name."""

    name: str
    start_s: float
    end_s: float
    legs: list[int]


@dataclass(frozen=True, kw_only=True)
class DiveLog:
    """The dive's samples, one row per logged step (n), local frame.

    Attributes:
        times: (n,) s.
        state, estimated: (n, 12) the true state and navigation's (columns
            `signals.VehicleState`).
        reference: (n, 8) the tracker's reference (columns `signals.Reference`).
        profile: (n, 7) the profile-following controller's `profile` output (columns
            `signals.Profile`; NaN rows without a controller).
        water: (n, 6) the water at the vehicle (columns `signals.Water`, world frame; zeros in
            still water).
        leg_at: (n,) index of the leg flying at each sample.
        distance: (n,) true distance to the target, m.
        clearance: (n,) signed clearance to anything, m (`geometry.clearance`: negative
            inside the world or above the sea surface).
    """

    times: np.ndarray
    state: np.ndarray
    estimated: np.ndarray
    reference: np.ndarray
    profile: np.ndarray
    water: np.ndarray
    leg_at: np.ndarray
    distance: np.ndarray
    clearance: np.ndarray

    @property
    def duration_s(self) -> float:
        """Simulated time from the first sample to the last, s."""
        return float(self.times[-1] - self.times[0])


@dataclass(frozen=True, kw_only=True)
class DiveOutcome:
    """How the dive went, leg by leg.

    Attributes:
        phases: the legs grouped by phase, on one time axis.
        outcomes: per leg ("goal", "timed out", "flying" when the time cap stopped it).
        completed: whether the supervisor ended the dive (False: the time cap did).
        responses: the supervisor's answers to faults ({response, cause, start_s, end_s}).
    """

    phases: list[Phase]
    outcomes: list[str]
    completed: bool
    responses: list[dict]


@dataclass(frozen=True, kw_only=True)
class CoverageRecord:
    """The target's coverage at the end of the dive, per target face (T).

    Attributes:
        camera_best, multibeam_best: (T,) best viewing angle, rad, NaN unseen.
        areas: (T,) area, m^2.
    """

    camera_best: np.ndarray
    multibeam_best: np.ndarray
    areas: np.ndarray


@dataclass(frozen=True, kw_only=True)
class MappingRecord:
    """What the on-line mapping built.

    Attributes:
        scan_log: the returns recorded by the mapper; online_map: its final octree.
        replanning: (k, 7) replanning steps (columns `signals.ReplanningStep`), planned ones
            only.
    """

    scan_log: ScanLog
    online_map: object
    replanning: np.ndarray


@dataclass(frozen=True, kw_only=True)
class OceanRecord:
    """The ocean's effects on the dive.

    Attributes:
        thrust_saturation: (5,) share of the dive each thruster's command was at its limit.
        current_drift: (2,) m, the navigation drift the current caused while the DVL tracked
            the water (world x, y).
    """

    thrust_saturation: np.ndarray
    current_drift: np.ndarray


@dataclass(frozen=True, kw_only=True)
class RunRecord:
    """The simulation itself, for timing and inspection.

    Attributes:
        wall_s: wall time of the simulation, s.
        diagram_dot: the Diagram's Graphviz text, each vector port labelled with its fields.
        diagram, handles, context: the simulated Diagram, its `MissionHandles` and the root
            Context at the end.
    """

    wall_s: float
    diagram_dot: str
    diagram: object
    handles: MissionHandles
    context: object


@dataclass(frozen=True, kw_only=True)
class MissionResult:
    """A flown mission (local frame; `site.to_site` gives the site's coordinates), built by
    keyword from the logs and the systems' Contexts after the run, its parts grouped by
    concern.

    Attributes:
        spec, site, plan: what was flown, where, and its off-line part.
        log: the samples (`DiveLog`: times, states, reference, distance, clearance, ...).
        dive: the legs' course (`DiveOutcome`: phases, outcomes, completed, responses).
        coverage: the target's (`CoverageRecord`: best angles and areas per face).
        mapping: the mapper's (`MappingRecord`: scan log, octree, replanning steps).
        ocean: the current's effects (`OceanRecord`: thrust saturation, navigation drift).
        run: the simulation's (`RunRecord`: wall time, Diagram, handles, final Context).
    """

    spec: MissionSpec
    site: Site
    plan: MissionPlan
    log: DiveLog
    dive: DiveOutcome
    coverage: CoverageRecord
    mapping: MappingRecord
    ocean: OceanRecord
    run: RunRecord


def _phases(leg_log, legs, end: float) -> tuple[list[Phase], np.ndarray, np.ndarray]:
    """Phases from the supervisor's `leg` log; also the (index, start) of every leg begun."""
    leg = LegSignal(leg_log.data().T)
    index, start = leg.index.astype(int), leg.start_s
    first = np.flatnonzero(np.r_[True, np.diff(index) != 0])
    begun, starts = index[first], start[first]
    phases: list[Phase] = []
    for k, (leg, t0) in enumerate(zip(begun, starts)):
        t1 = starts[k + 1] if k + 1 < len(starts) else end
        name = legs[leg].phase
        if phases and phases[-1].name == name:
            phases[-1].end_s = float(t1)
            phases[-1].legs.append(int(leg))
        else:
            phases.append(Phase(name, float(t0), float(t1), [int(leg)]))
    return phases, begun, starts


def dive_share(handles: MissionHandles, root_context, cap: float) -> float:
    """How much of the dive is done, in [0, 1]: the mission's own share
    (`MissionSupervisor.flown_share`, with the flying behaviour's share of its leg) or the
    share of the time cap `cap` (s) elapsed, whichever is larger: the cap ends it at the
    latest."""
    supervisor = handles.supervisor
    context = supervisor.GetMyContextFromRoot(root_context)
    leg = supervisor.flying(context)
    own = None
    if leg is not None:
        behaviour = handles.behaviours[leg.behaviour]
        if isinstance(behaviour, Behaviour):  # a step's own LeafSystem may be another kind
            own = behaviour.share(behaviour.GetMyContextFromRoot(root_context))
    return max(supervisor.flown_share(context, own), root_context.get_time() / cap)


def run_mission(spec: MissionSpec, site: Site | None = None, scene=None,
                progress: bool | RunProgress = True, plan: MissionPlan | None = None,
                realtime_rate: float = 0.0, probe=None, mcap=None) -> MissionResult:
    """Flies `spec` in one dive, at `site` (default `load_site(spec.site, spec.seed)`) with
    `plan` (default `plan_mission(spec, site)`), paced at `realtime_rate` times real time
    (0: as fast as possible; pacing changes no result); `probe(root_context)`, when given, is
    called at every simulator step (a benchmark's sampling of memory and wall time); `mcap`:
    an `rosio.McapLog` the dive is written into (closed, into place, when the dive ends;
    aborted, no file left, when building or flying it fails).

    `progress`: a `RunProgress` in its `setup` phase (this call's last step of it is the
    Diagram's build; it then runs the `dive` phase, ended at 100 % when the dive ends, and the
    `results` phase, reading the dive back), or whether to show one of its own."""
    own = not isinstance(progress, RunProgress)
    display = RunProgress(("setup", "dive", "results"), enabled=progress) if own else progress
    if own:
        display.start("setup", total=1 + (site is None) + (plan is None),
                      note="site" if site is None else "plan" if plan is None else "Diagram")
    with mcap if mcap is not None else contextlib.nullcontext():
        if site is None:
            with display.step("site"):
                site = load_site(spec.site, spec.seed, label=spec.name)
        check_against_site(spec, site)
        if plan is None:
            with display.step("plan"):
                plan = plan_mission(spec, site)
        with display.step("Diagram"):
            diagram, handles = build_mission_diagram(site, spec, plan, scene=scene, mcap=mcap)
            simulator = Simulator(diagram)
        simulator.set_target_realtime_rate(realtime_rate)
        context = simulator.get_context()
        cap, _ = plan.time_cap(spec)
        supervisor = handles.supervisor
        spool = LogSpool(handles.logs, LOG_SPOOL_S)
        display.start("dive", note=f"mission {spec.name}")

        def monitor(root_context) -> EventStatus:
            if display.due():
                display.update(dive_share(handles, root_context, cap),
                               note=f"mission {spec.name}, t = {root_context.get_time():.0f} s")
            spool.spool(root_context)
            if probe is not None:
                probe(root_context)
            return supervisor.monitor(root_context)

        simulator.set_monitor(monitor)
        try:
            wall = time.perf_counter()
            status = simulator.AdvanceTo(cap)
            wall = time.perf_counter() - wall
            display.finish(note=f"mission {spec.name}, t = {context.get_time():.0f} s")
            completed = (status.reason()
                         == SimulatorStatus.ReturnReason.kReachedTerminationCondition)
            display.start("results", total=COLLECT_STEPS + 1, note="logs")
            with display.step("logs"):
                logs = {name: spool.read(name, context) for name in handles.logs}
        finally:
            spool.close()
    result = _collect(spec, site, plan, diagram, handles, context, completed, wall, logs,
                      display)
    display.finish(note=f"{len(result.log.times)} samples")
    if own:
        display.close()
    return result


COLLECT_STEPS = 3  # the display's steps of `_collect`


def _collect(spec, site, plan, diagram, handles: MissionHandles, context, completed: bool,
             wall: float, logs: dict, progress: RunProgress) -> MissionResult:
    """`logs`: each of `handles.logs`' samples over the whole dive (`LogSpool.read`);
    `progress`: the display, `COLLECT_STEPS` steps of its phase."""
    times = logs["state"].sample_times()
    state = logs["state"].data().T.copy()
    estimated = logs["estimated_state"].data().T.copy()
    end = float(context.get_time())
    phases, begun, starts = _phases(logs["leg"], plan.legs, end)
    leg_at = begun[np.maximum(np.searchsorted(starts, times, side="right") - 1, 0)]
    position = VehicleState(state).position
    with progress.step("distance to the target"):
        distance = mesh_distance(site.target_mesh, position)
    with progress.step("clearance"):
        clearance = site.clearance.signed(position)
    with progress.step("the systems' state"):
        replanning = np.zeros((0, ReplanningStep.size()))
        if "replanning" in logs:
            table = logs["replanning"].data().T
            steps = ReplanningStep(table)
            # one row per step: the log samples the last step at every period
            replanning = table[np.r_[True, np.diff(steps.time) != 0] & (steps.planned > 0)]
        mapper_context = handles.mapper.GetMyContextFromRoot(context)
        profile = np.full((len(times), Profile.size()), np.nan)
        if "profile" in logs:
            profile = logs["profile"].data().T[:len(times)]
        water = np.zeros((len(times), Water.size()))
        if "water" in logs:
            water = logs["water"].data().T[:len(times)].copy()
        vehicle = handles.vehicle
        saturation = vehicle.dynamics.thrust_saturation_output.Eval(
            vehicle.dynamics.GetMyContextFromRoot(context)).copy()
        current_drift = vehicle.navigation.current_drift_output.Eval(
            vehicle.navigation.GetMyContextFromRoot(context)).copy()
        supervisor, camera, multibeam = (handles.supervisor, handles.camera_coverage,
                                         handles.multibeam_coverage)
        return MissionResult(
            spec=spec, site=site, plan=plan,
            log=DiveLog(times=times, state=state, estimated=estimated,
                        reference=logs["reference"].data().T[:len(times)].copy(),
                        profile=profile, water=water, leg_at=leg_at, distance=distance,
                        clearance=clearance),
            dive=DiveOutcome(
                phases=phases,
                outcomes=supervisor.outcomes(supervisor.GetMyContextFromRoot(context)),
                completed=completed, responses=responses_from_log(logs["response"])),
            coverage=CoverageRecord(
                camera_best=camera.best_angles(camera.GetMyContextFromRoot(context)),
                multibeam_best=multibeam.best_angles(multibeam.GetMyContextFromRoot(context)),
                areas=np.asarray(site.world.area_faces)[site.target_faces]),
            mapping=MappingRecord(scan_log=handles.mapper.scan_log(mapper_context),
                                  online_map=handles.mapper.map_output.Eval(mapper_context),
                                  replanning=replanning),
            ocean=OceanRecord(thrust_saturation=saturation, current_drift=current_drift),
            run=RunRecord(wall_s=wall,
                          diagram_dot=annotate_graphviz(diagram, diagram.GetGraphvizString()),
                          diagram=diagram, handles=handles, context=context))
