"""`McapRecorder`: a mission's signals written as ROS 2 messages into an MCAP log as it flies.

Every `tick` (0.1 s, the state logs' period) a periodic unrestricted update (the mapper's
kind, at its times, so both see the same sonar updates) writes `/tf` (`map` -> `base_link`,
the navigation estimate, and `map` -> `base_link_truth`), the two `nav_msgs/Odometry`, the
tracked reference (`geometry_msgs/PoseStamped`), the thrusts (`std_msgs/Float64MultiArray`,
N) and each sonar update not yet written (`sensor_msgs/PointCloud2` in the sensor's frame,
the multibeam also as `sensor_msgs/LaserScan`); each new replanned section
(`nav_msgs/Path`); every `mission_period` the leg and the safety response (`std_msgs/Int32`:
the leg's index, the response's `mission.safety.RESPONSES` index); every `coverage_period`
the coverage shares (`std_msgs/Float64`); every `map_period` the on-line map's occupied
voxels (`visualization_msgs/MarkerArray`). The first tick writes `/tf_static` (`base_link`
-> each sensor), the plan (`nav_msgs/Path`) and the world and target meshes.

A sonar's returns are placed with the estimated pose at their update (the update at t is seen
at the next tick, as the mapper sees it): the Context keeps the last few ticks' estimated
states (`poses`) to express the beams in the sensor frame with exactly the pose that placed
them, and the cloud is stamped with that tick, whose `/tf` carried the pose. The `McapLog`
is an output device, like an LCM interface: the system writes to it and keeps its own
bookkeeping (which sonar updates and section it has written, the recent poses) in the
Context. Frames and fields: `drake_auv.rosio.messages`.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.rosio import messages as m
from drake_auv.rosio.writer import McapLog, MessageBlock
from drake_auv.signals import (THRUSTER_NAMES, LegSignal, Reference, Response, VehicleState,
                               Water)
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.control import rotation_world_body

TOPICS = dict(
    tf="/tf", tf_static="/tf_static", odometry="/odometry/navigation",
    odometry_truth="/odometry/truth", reference="/reference", plan="/plan",
    section="/plan/section", leg="/mission/leg", response="/mission/response",
    thrust="/thrust", current="/ocean/current", world="/world", map="/octomap/occupied")


def points_topic(sensor: str) -> str:
    return f"/sonar/{sensor}/points"


def scan_topic(sensor: str) -> str:
    return f"/sonar/{sensor}/scan"


def coverage_topic(sensor: str) -> str:
    return f"/coverage/{sensor}"


MAX_PATH_POSES = 20_000  # a plan longer than this is written every k-th pose


class McapRecorder(LeafSystem):
    """Writes the mission's signals into `log` (module doc).

    Args:
        log: the `McapLog` written to (closed by its owner).
        sonars: {name: (SonarMount, update period s, max range m)}: an input
            `{name}_returns` each; the periods must be multiples of `tick`. Their max ranges
            go into the log's metadata (`sensors`: `{name}_max_range_m`).
        laser_scans: the sonars also written as `LaserScan` (equiangular fans).
        coverage: names of the `coverage_{name}` inputs (1: the seen share of the target).
        world, target: trimesh meshes drawn once in `map` (None: not drawn).
        plan: (n, 3) the nominal path, m (None: none).
        section_input: declare `section` ((k, 3) the replanner's current section).
        map_input: declare `map` (an `OnlineMap`), its occupied voxels written every
            `map_period` s.
        water_input: declare `water` (6, `signals.Water`): the current at the vehicle, written
            every tick as [east, north, up] m/s (`std_msgs/Float64MultiArray`).
        mission_period: s between the leg and response messages (the supervisor's).
    Inputs: `state`, `estimated_state` (12, `signals.VehicleState`), `reference` (8), `leg`
    (2), `response` (10), `thrust` (5, N), and the optional ones above.
    """

    def __init__(self, log: McapLog, sonars: dict, laser_scans=("multibeam",), coverage=(),
                 world=None, target=None, plan=None, section_input: bool = False,
                 map_input: bool = False, water_input: bool = False, tick: float = 0.1, coverage_period: float = 1.0,
                 map_period: float = 10.0, mission_period: float = 0.5):
        super().__init__()
        self.log, self.tick = log, float(tick)
        self.sonars = dict(sonars)
        self.laser_scans = tuple(s for s in laser_scans if s in self.sonars)
        self._every = {"coverage": self._ticks(coverage_period, "coverage_period"),
                       "map": self._ticks(map_period, "map_period"),
                       "mission": self._ticks(mission_period, "mission_period")}
        depth = 1 + max([self._ticks(p, f"{name}'s period") for name, (_, p, _)
                         in self.sonars.items()], default=1)
        self.world, self.target = world, target
        self.plan = None if plan is None else np.asarray(plan, dtype=float).reshape(-1, 3)
        # the vehicle's messages of each tick, serialised once and filled in
        # (`messages.CdrTemplate`, `writer.MessageBlock`); built when the inputs are declared
        self._clouds = {name: m.CloudWriter(name) for name in self.sonars}
        self._scans = {name: m.ScanWriter(name, self.sonars[name][1])
                       for name in self.laser_scans}
        log.add_metadata("sensors", {f"{name}_max_range_m": repr(float(r))
                                     for name, (_, _, r) in self.sonars.items()})
        self.state_input = self.DeclareVectorInputPort("state", VehicleState.size())
        self.estimated_state_input = self.DeclareVectorInputPort("estimated_state",
                                                                 VehicleState.size())
        self.reference_input = self.DeclareVectorInputPort("reference", Reference.size())
        self.leg_input = self.DeclareVectorInputPort("leg", LegSignal.size())
        self.response_input = self.DeclareVectorInputPort("response", Response.size())
        self.thrust_input = self.DeclareVectorInputPort("thrust", len(THRUSTER_NAMES))
        model = AbstractValue.Make(SonarReturns.empty(20.0))
        self.returns_inputs = {name: self.DeclareAbstractInputPort(f"{name}_returns",
                                                                   model.Clone())
                               for name in self.sonars}
        self.coverage_inputs = {name: self.DeclareVectorInputPort(f"coverage_{name}", 1)
                                for name in coverage}
        self.section_input = (self.DeclareAbstractInputPort(
            "section", AbstractValue.Make(np.zeros((0, 3)))) if section_input else None)
        self.map_input = (self.DeclareAbstractInputPort("map", AbstractValue.Make(OnlineMap(
            0.5))) if map_input else None)
        self.water_input = (self.DeclareVectorInputPort("water", Water.size()) if water_input
                            else None)
        self._vehicle = MessageBlock(log, [
            (TOPICS["tf"], m.tf_template(m.MAP, (m.BASE, m.TRUTH))),
            (TOPICS["odometry"], m.odometry_template(m.BASE)),
            (TOPICS["odometry_truth"], m.odometry_template(m.TRUTH)),
            (TOPICS["reference"], m.pose_template(m.MAP)),
            (TOPICS["thrust"], m.array_template(THRUSTER_NAMES)),
            *([(TOPICS["current"], m.array_template(("east_mps", "north_mps", "up_mps")))]
              if water_input else [])])
        # The estimated state at the last `depth` ticks: rows [time, 12 state], NaN: none yet.
        self._poses = self.DeclareDiscreteState(np.full(depth * 13, np.nan))
        self._sequences = self.DeclareDiscreteState(np.zeros(max(len(self.sonars), 1)))
        # [ticks written, rows of the last section written, its sum]
        self._progress = self.DeclareDiscreteState(np.array([0.0, 0.0, 0.0]))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.tick, 0.0, self._update_log)

    def _ticks(self, period: float, name: str) -> int:
        k = round(period / self.tick)
        if not (math.isfinite(period) and k >= 1 and abs(k * self.tick - period) < 1e-9):
            raise ValueError(f"McapRecorder {name} must be a multiple of its tick "
                             f"{self.tick:g} s, got {period}")
        return k

    def _update_log(self, context, state):
        t = context.get_time()
        progress = context.get_discrete_state(self._progress).get_value().copy()
        tick = int(progress[0])
        if tick == 0:
            self._write_static(t)
        estimated = self.estimated_state_input.Eval(context)
        before = context.get_discrete_state(self._poses).get_value().reshape(-1, 13)
        poses = np.empty_like(before)
        poses[0, 0], poses[0, 1:], poses[1:] = t, estimated, before[:-1]
        self._write_vehicle(context, t, tick, estimated)
        sequences = context.get_discrete_state(self._sequences).get_value().copy()
        written = False
        for k, (name, port) in enumerate(self.returns_inputs.items()):
            returns = port.Eval(context)
            if returns.sequence != sequences[k] and len(returns):
                self._write_returns(name, returns, poses, t)
                sequences[k], written = returns.sequence, True
        if self.section_input is not None:
            section = np.asarray(self.section_input.Eval(context), dtype=float)
            key = (len(section), float(section.sum()) if len(section) else 0.0)
            if len(section) and key != (progress[1], progress[2]):
                self.log.write(TOPICS["section"], "nav_msgs/msg/Path",
                               m.path(t, m.MAP, section), t)
                progress[1:] = key
        if tick % self._every["coverage"] == 0:
            for name, port in self.coverage_inputs.items():
                self._write_scalar(coverage_topic(name), "std_msgs/msg/Float64",
                                   float(port.Eval(context)[0]), t)
        if self.map_input is not None and tick % self._every["map"] == 0:
            octree = self.map_input.Eval(context).map
            self.log.write_cdr(TOPICS["map"], "visualization_msgs/msg/MarkerArray",
                               m.marker_array_cdr([m.marker(
                                   t, "octomap", m.CUBE_LIST, octree.resolution,
                                   (0.2, 0.6, 1.0, 0.8))], [octree.occupied_points()]), t)
        progress[0] = tick + 1
        state.get_mutable_discrete_state(self._poses).set_value(poses.reshape(-1))
        if written:
            state.get_mutable_discrete_state(self._sequences).set_value(sequences)
        state.get_mutable_discrete_state(self._progress).set_value(progress)

    def _write_static(self, t: float) -> None:
        self.log.write(TOPICS["tf_static"], "tf2_msgs/msg/TFMessage", m.tf_message(
            m.transform(t, m.BASE, name, mount.position, mount.rotation)
            for name, (mount, _, _) in self.sonars.items()), t)
        if self.plan is not None and len(self.plan):
            stride = max(1, -(-len(self.plan) // MAX_PATH_POSES))
            self.log.write(TOPICS["plan"], "nav_msgs/msg/Path",
                           m.path(t, m.MAP, self.plan[::stride]), t)
        meshes = [(ns, mesh, rgba) for ns, mesh, rgba in (
            ("world", self.world, (0.55, 0.5, 0.42, 1.0)),
            ("target", self.target, (0.9, 0.6, 0.2, 1.0))) if mesh is not None]
        if meshes:
            self.log.write_cdr(TOPICS["world"], "visualization_msgs/msg/MarkerArray",
                               m.marker_array_cdr(
                                   [m.marker(t, ns, m.TRIANGLE_LIST, 1.0, rgba, k)
                                    for k, (ns, _, rgba) in enumerate(meshes)],
                                   [m.mesh_corners(mesh.vertices, mesh.faces)
                                    for _, mesh, _ in meshes]), t)

    def _write_vehicle(self, context, t: float, tick: int, estimated) -> None:
        navigation, truth = VehicleState(estimated), VehicleState(self.state_input.Eval(context))
        # Python floats (numpy's scalars pack slower)
        pose = (*navigation.position.tolist(), *m.quaternion_rpy(*navigation.attitude.tolist()))
        pose_truth = (*truth.position.tolist(), *m.quaternion_rpy(*truth.attitude.tolist()))
        reference = Reference(self.reference_input.Eval(context))
        floats = [*pose, *pose_truth,
                  *pose, *navigation.linear_velocity.tolist(),
                  *navigation.angular_velocity.tolist(),
                  *pose_truth, *truth.linear_velocity.tolist(), *truth.angular_velocity.tolist(),
                  *reference.position.tolist(), *m.quaternion_rpy(0.0, 0.0, float(reference.yaw)),
                  *self.thrust_input.Eval(context).tolist()]
        if self.water_input is not None:
            floats += Water(self.water_input.Eval(context)).velocity.tolist()
        self._vehicle.write(floats, t)
        if tick % self._every["mission"] == 0:
            self._write_scalar(TOPICS["leg"], "std_msgs/msg/Int32",
                               int(LegSignal(self.leg_input.Eval(context)).index), t)
            self._write_scalar(TOPICS["response"], "std_msgs/msg/Int32",
                               int(Response(self.response_input.Eval(context)).mode), t)

    def _write_scalar(self, topic: str, typename: str, value, t: float) -> None:
        self.log.write_cdr(topic, typename, m.scalar_cdr(typename, value), t)

    def _write_returns(self, name: str, returns: SonarReturns, poses: np.ndarray,
                       now: float) -> None:
        """One sonar update in its frame, with the estimated pose that placed it: the recent
        tick whose pose puts the sensor at the returns' origin, that of their update time
        when several do (the DVL places its last measurement at the current pose: its cloud
        is stamped with that tick). Logged at `now`, the tick that received it (as a
        recorder's receive time): in log order, the updates reach a replay in the order the
        mapper recorded them."""
        mount = self.sonars[name][0]
        times = poses[:, 0].tolist()
        rows = sorted((k for k, time in enumerate(times) if time == time),  # NaN: no tick yet
                      key=lambda k: abs(times[k] - returns.time))  # on time first
        origin_nav = returns.origin_nav
        for k in rows:
            row = poses[k]
            rotation = rotation_world_body(*row[4:7])
            origin = row[1:4] + rotation @ mount.position
            if np.abs(origin - origin_nav).max() < 1e-9:
                break
        else:
            raise ValueError(f"McapRecorder: {name} returns at {returns.time:.3f} s were not "
                             f"placed at any of the last {len(rows)} ticks' estimated poses")
        t = float(row[0])
        beams = np.asarray(returns.directions_nav) @ (rotation @ mount.rotation)
        self.log.write_cdr(points_topic(name), "sensor_msgs/msg/PointCloud2",
                           self._clouds[name].cdr(t, returns.ranges, beams), now)
        if name in self._scans:
            self.log.write_cdr(scan_topic(name), "sensor_msgs/msg/LaserScan", self._scans[
                name].cdr(t, returns.angles, returns.ranges, returns.max_range), now)


def add_mcap_recorder(builder, log: McapLog, vehicle, estimated, reference, supervisor,
                      sonars: dict, returns: dict, coverage: dict, site, plan=None,
                      mapper=None, replanner=None, ocean=None) -> McapRecorder:
    """Adds an `McapRecorder` writing into `log` and wires it: `vehicle` (`VehicleSystems`),
    the `estimated` state and `reference` ports, the `supervisor`, `sonars` ({name: a
    `sonar.sensor.Sensor`, for its mount, period and range}) with their `returns` ports,
    `coverage` ({name: a `CoverageRecorder`}), the `site`'s world and target, the nominal
    `plan` (a `PlannedPath`), the `mapper`, the `replanner` and the `ocean` when there are."""
    recorder = builder.AddNamedSystem("mcap_recorder", McapRecorder(
        log, {name: (sonar.mount, sonar.period, sonar.max_range)
              for name, sonar in sonars.items()},
        coverage=tuple(coverage), world=site.world, target=site.target_mesh,
        plan=None if plan is None else plan.points, section_input=replanner is not None,
        map_input=mapper is not None, water_input=ocean is not None))
    builder.Connect(vehicle.dynamics.state_output, recorder.state_input)
    builder.Connect(estimated, recorder.estimated_state_input)
    builder.Connect(reference, recorder.reference_input)
    builder.Connect(supervisor.leg_output, recorder.leg_input)
    builder.Connect(supervisor.response_output, recorder.response_input)
    builder.Connect(vehicle.allocation.thrust_output, recorder.thrust_input)
    for name, port in returns.items():
        builder.Connect(port, recorder.returns_inputs[name])
    for name, system in coverage.items():
        builder.Connect(system.coverage_output, recorder.coverage_inputs[name])
    if mapper is not None:
        builder.Connect(mapper.map_output, recorder.map_input)
    if replanner is not None:
        builder.Connect(replanner.section_output, recorder.section_input)
    if ocean is not None:
        builder.Connect(ocean.water_output, recorder.water_input)
    return recorder
