"""Take the mission Diagram apart: fly the survey with your own LeafSystem.

The boulder mission without its profile-following step (the off-line plan, one transit, then
the survey), built with the project's builders (`drake_auv.mission.diagram`: add_girona500,
add_sonars, the OctreeMapper, add_behaviours, add_coverage_recorders) twice on the same site,
plan and seed: once with the built-in STOMP `Replanner` on the survey leg, once with
`ConstantAltitudeFollower` below in its place, a LeafSystem that flies the nominal path's
track at a constant altitude above the prior map (the chart the operator holds) and ignores
the on-line map. Both are flown to the supervisor's end (or `--max-time`) and compared:

    behaviour | multibeam | camera | min clearance | survey altitude | duration | outcome

Run:
    MPLBACKEND=Agg .venv/bin/python examples/custom_controller.py [--altitude 10]
        [--max-time 300] [--markdown FILE]
`--max-time` caps each dive's simulated time (s; default: the legs' budgets, the whole
survey, about 30 min simulated); `--markdown` also writes the table to FILE. The table of a
run is in docs/architecture.md ("Swapping a behaviour").
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.primitives import LogVectorOutput

from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.visibility import coverage_share
from drake_auv.geometry.raycast import RayCaster
from drake_auv.behaviour import LEG_SIZE, read_leg
from drake_auv.mapping.mapper import OctreeMapper
from drake_auv.mission.config import FollowStep, load_mission
from drake_auv.mission.diagram import (SUPERVISOR_PERIOD, add_behaviours,
                                       add_coverage_recorders, add_sonars)
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.steps.step import Wiring, terrain_elevation
from drake_auv.mission.site import load_site
from drake_auv.signals import BehaviourStatus, LegSignal, Reference, VehicleState
from drake_auv.vehicle.diagram import add_girona500

SPACING = 0.5  # m between the follower's samples along the track


class ConstantAltitudeFollower(LeafSystem):
    """Flies `path`'s horizontal track at `speed` m/s, `altitude` m above `terrain` (a callable
    (x, y) -> seabed elevation, m), with the path's headings, on the mission legs `legs`.

    Stateless: the reference is a function of the time since the leg began (the supervisor's
    `leg` input says when). Ports, those of the `Replanner` it replaces, laid out by
    `drake_auv.signals`: inputs `estimated_state` (`VehicleState`, unused: an open-loop
    reference) and `leg` (`LegSignal`); outputs `reference` (`Reference`, world) and `status`
    (`BehaviourStatus`, leg -1 off its legs; progress: the next sample of the track).
    """

    def __init__(self, path, terrain, altitude: float, speed: float, legs):
        super().__init__()
        if not (np.isfinite(altitude) and altitude > 0):
            raise ValueError(f"altitude must be > 0 m, got {altitude}")
        if not (np.isfinite(speed) and speed > 0):
            raise ValueError(f"speed must be > 0 m/s, got {speed}")
        track = path.resample(SPACING)
        xy = track.points[:, :2]
        z = np.minimum(terrain(xy[:, 0], xy[:, 1]) + altitude, -1.0)  # 1 m below the surface
        self.points = np.column_stack([xy, z])
        self.heading = track.unwrapped_heading()
        self.arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(self.points, axis=0), axis=1))]
        self.speed, self.legs = float(speed), frozenset(int(leg) for leg in legs)
        self.DeclareVectorInputPort("estimated_state", VehicleState.size())
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)
        self.DeclareVectorOutputPort("reference", Reference.size(), self._calc_reference)
        self.DeclareVectorOutputPort("status", BehaviourStatus.size(), self._calc_status)

    def _along(self, context) -> tuple[int, float]:
        """(leg, metres flown along the track; -1 before the leg)."""
        leg, start = read_leg(self.leg_input, context)
        return leg, (self.speed * (context.get_time() - start) if leg in self.legs else -1.0)

    def _calc_reference(self, context, output):
        _, s = self._along(context)
        s = float(np.clip(s, 0.0, self.arc[-1]))
        k = int(np.clip(np.searchsorted(self.arc, s, side="right") - 1, 0, len(self.arc) - 2))
        ds = self.arc[k + 1] - self.arc[k]
        w = (s - self.arc[k]) / ds if ds > 0 else 0.0
        reference = Reference.zeros()
        reference.position = (1 - w) * self.points[k] + w * self.points[k + 1]
        reference.yaw = (1 - w) * self.heading[k] + w * self.heading[k + 1]
        if 0.0 < s < self.arc[-1] and ds > 0:  # moving
            reference.velocity = self.speed / ds * (self.points[k + 1] - self.points[k])
            reference.yaw_rate = self.speed / ds * (self.heading[k + 1] - self.heading[k])
        output.SetFromVector(reference[:])

    def _calc_status(self, context, output):
        leg, s = self._along(context)
        status = BehaviourStatus.zeros()
        status.leg = leg if s >= 0 else -1.0
        if s >= 0:
            status.finished = float(s >= self.arc[-1])
            status.progress = float(np.searchsorted(self.arc, s))
        output.SetFromVector(status[:])


def build(site, spec, plan, caster, follower=None):
    """The mission Diagram from the builders (`follower`: the survey's behaviour instead of the
    built-in replanner); returns (diagram, supervisor, multibeam and camera coverage, logs)."""
    builder = DiagramBuilder()
    navigation = dataclasses.replace(spec.navigation, seed=spec.seed)
    vehicle = add_girona500(builder, navigation=navigation,
                            initial_state=plan.start_state)
    estimated = vehicle.navigation.estimated_state_output
    sonars, returns = add_sonars(builder, caster, vehicle, spec, plan, site.max_range,
                                 estimated, faults={})
    mapper = builder.AddNamedSystem("octree_mapper",
                                    OctreeMapper(resolution=spec.replanner.voxel_m))
    for name, port in returns.items():
        builder.Connect(port, mapper.returns_inputs[name])
    wiring = Wiring(builder, spec, plan, site, caster, vehicle, estimated, mapper, returns,
                    sonars["profiler"])
    supervisor, *_ = add_behaviours(builder, wiring,
                                    own=None if follower is None else {"replan": follower})
    camera, multibeam_coverage = add_coverage_recorders(
        builder, caster, vehicle, spec, site, site.max_range, sonars["multibeam"])
    logs = (LogVectorOutput(vehicle.dynamics.state_output, builder, 0.1),
            LogVectorOutput(supervisor.leg_output, builder, SUPERVISOR_PERIOD))
    return builder.Build(), supervisor, multibeam_coverage, camera, logs


def fly(site, spec, plan, caster, follower=None, max_time: float | None = None) -> dict:
    """Flies one Diagram to the supervisor's end (or `max_time` s); the table's row
    (coverage shares, true minimum clearance m, the survey's mean altitude above the prior map
    m, its duration s and outcome)."""
    diagram, supervisor, multibeam, camera, logs = build(site, spec, plan, caster, follower)
    simulator = Simulator(diagram)
    simulator.set_monitor(supervisor.monitor)
    simulator.AdvanceTo(max_time if max_time is not None else plan.budget)
    context = simulator.get_context()
    state_log, leg_log = (log.FindLog(context) for log in logs)
    survey = next(iter(plan.legs_of("replan")))
    legs = LegSignal(leg_log.data().T)
    started = legs.start_s[legs.index == survey]
    outcome = supervisor.outcomes(supervisor.GetMyContextFromRoot(context))[survey]
    times, state = state_log.sample_times(), VehicleState(state_log.data().T)
    flying = (times >= started[0]) if len(started) else np.zeros(len(times), bool)
    terrain = terrain_elevation(site)
    altitude = state.z[flying] - terrain(state.x[flying], state.y[flying])
    areas = np.asarray(site.world.area_faces)[site.target_faces]
    best = {name: recorder.best_angles(recorder.GetMyContextFromRoot(context))
            for name, recorder in (("multibeam", multibeam), ("camera", camera))}
    return dict(
        multibeam=coverage_share(best["multibeam"], areas),
        camera=coverage_share(best["camera"], areas),
        clearance=float(mesh_distance(site.world, state.position).min()),
        altitude=float(altitude.mean()) if flying.any() else float("nan"),
        survey_s=float(context.get_time() - started[0]) if len(started) else 0.0,
        outcome=outcome)


def table(rows: dict) -> str:
    """The comparison as a Markdown table: coverage is the union over the whole dive (the
    transit is the same in both), clearance the true minimum, altitude the survey's mean
    height above the prior map."""
    lines = ["| survey behaviour | multibeam coverage | camera coverage | min clearance (true) "
             "| survey altitude (mean, prior map) | survey duration | survey outcome |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, r in rows.items():
        lines.append(f"| {name} | {100 * r['multibeam']:.1f} % | {100 * r['camera']:.1f} % | "
                     f"{r['clearance']:.2f} m | {r['altitude']:.1f} m | {r['survey_s']:.0f} s | "
                     f"{r['outcome']} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--altitude", type=float, default=10.0,
                        help="the follower's altitude above the prior map, m (default 10: "
                             "the plan's Omega)")
    parser.add_argument("--max-time", type=float, default=None,
                        help="cap on each dive's simulated time, s (default: the legs' budgets)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--markdown", default=None, help="also write the table to this file")
    args = parser.parse_args(argv)
    if args.max_time is not None and not (np.isfinite(args.max_time) and args.max_time > 0):
        raise SystemExit(f"--max-time must be > 0 s, got {args.max_time}")
    # still water: this Diagram adds no Ocean, so its replanner must not plan for the sea
    spec = load_mission("boulder", seed=args.seed, overrides=["ocean=none"])
    spec = dataclasses.replace(spec, steps=tuple(step for step in spec.steps
                                                 if not isinstance(step, FollowStep)))
    site = load_site(spec.site, spec.seed, label=spec.name)
    plan = plan_mission(spec, site)
    caster = RayCaster(site.world)
    follower = ConstantAltitudeFollower(plan.nominal, terrain_elevation(site), args.altitude,
                                        plan.survey_speed, tuple(plan.legs_of("replan")))
    follower.set_name("constant_altitude")
    rows = {"built-in: STOMP replanner": fly(site, spec, plan, caster, None, args.max_time),
            f"yours: constant altitude {args.altitude:g} m":
                fly(site, spec, plan, caster, follower, args.max_time)}
    text = table(rows)
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as file:
            file.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
