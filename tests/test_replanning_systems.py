"""The OctreeMapper and the Replanner as Drake systems: all their state in the Context, each
Context its own map, the nominal plan through a port, the replanner's steps as an output."""

import copy

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_auv.mapping.mapper import OctreeMapper, OnlineMap
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mapping.scan_log import ScanBatch, ScanLog
from drake_auv.planning.path import PlannedPath
from drake_auv.replanning.replanner import Replanner
from drake_auv.signals import Reference, ReplanningStep
from drake_auv.sonar.returns import SonarReturns


def _wall_returns(sequence, x_wall=8.0):
    """A horizontal 61-beam fan from the origin hitting the wall x = x_wall."""
    a = np.linspace(-0.5, 0.5, 61)
    d = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    r = x_wall / d[:, 0]
    return SonarReturns(0.1 * sequence, np.zeros(3), a, r, d, d * r[:, None], d * r[:, None],
                        20.0, sequence)


def test_mapper_records_each_update_once_and_maps_it():
    mapper = OctreeMapper(resolution=0.5, period=0.1, multibeam_stride=1)
    context = mapper.CreateDefaultContext()
    mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_wall_returns(1)))
    simulator = Simulator(mapper, context)
    simulator.AdvanceTo(0.35)  # four updates, one new scan
    assert mapper.scan_log(context).count == 1
    online = mapper.map_output.Eval(context)
    assert online.map.num_scans == 1
    assert np.all(np.abs(online.map.occupied_points()[:, 0] - 8.0) <= 0.5)
    mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_wall_returns(2, 9.0)))
    simulator.AdvanceTo(0.55)
    again = mapper.map_output.Eval(context)
    assert again is online and again.map.num_scans == 2  # caught up, not rebuilt
    assert mapper.scan_log_output.Eval(context).count == 2


def test_the_mappers_insertion_options_reach_every_contexts_map():
    mapper = OctreeMapper(resolution=0.5, discretize=True)
    context = mapper.CreateDefaultContext()
    mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_wall_returns(1)))
    Simulator(mapper, context).AdvanceTo(0.15)
    online = mapper.map_output.Eval(context)
    assert online.map.discretize and len(online.map.occupied_points()) > 0
    assert mapper.map_output.Eval(context.Clone()).map.discretize  # a copy rebuilds it so
    plain = OctreeMapper()
    assert not plain.map_output.Eval(plain.CreateDefaultContext()).map.discretize


def test_each_context_has_its_own_map():
    mapper = OctreeMapper(resolution=0.5)
    first, second = mapper.CreateDefaultContext(), mapper.CreateDefaultContext()
    for context in (first, second):
        mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_wall_returns(1)))
    Simulator(mapper, first).AdvanceTo(0.25)
    assert len(mapper.map_output.Eval(first).map.occupied_points()) > 0
    assert mapper.scan_log(second).count == 0
    assert len(mapper.map_output.Eval(second).map.occupied_points()) == 0
    # A copy of an advanced Context rebuilds the same map from its log, sharing nothing.
    clone = first.Clone()
    copied = mapper.map_output.Eval(clone)
    assert copied is not mapper.map_output.Eval(first)
    np.testing.assert_array_equal(np.sort(copied.map.occupied_points(), axis=0),
                                  np.sort(mapper.map_output.Eval(first).map.occupied_points(),
                                          axis=0))


def test_scan_log_versions_are_immutable_and_share_their_past():
    batch = ScanBatch.make(0.0, "profiler", np.zeros(3), [[1.0, 0.0, 0.0]], [4.0], 20.0)
    empty = ScanLog()
    one = empty.append(batch)
    two = one.append(batch)
    assert copy.deepcopy(two) is two and empty.count == 0 and two.parent is one
    assert two.since(one) == [batch] and len(two.batches()) == 2
    assert one.since(two) is None  # not its past: a consumer must start again
    with pytest.raises(ValueError):
        batch.ranges[0] = 1.0
    np.testing.assert_allclose(batch.points(), [[4.0, 0.0, 0.0]])


def test_online_map_copy_rebuilds_its_own_octree():
    online = OnlineMap(0.5)
    log = ScanLog().append(ScanBatch.make(0.0, "multibeam", np.zeros(3),
                                          _wall_returns(1).directions_nav,
                                          _wall_returns(1).ranges, 20.0))
    online.catch_up(log)
    clone = copy.deepcopy(online)
    assert clone.map is not online.map and clone.version is log
    assert len(clone.map.occupied_points()) == len(online.map.occupied_points()) > 0
    online.catch_up(log.append(log.batch))
    assert clone.map.num_scans == 1 and online.map.num_scans == 2


def test_mapper_rejects_bad_parameters():
    with pytest.raises(ValueError, match="period"):
        OctreeMapper(period=0.0)
    with pytest.raises(ValueError, match="multibeam's stride"):
        OctreeMapper(multibeam_stride=0)
    with pytest.raises(ValueError, match="resolution"):
        OctreeMapper(resolution=0.0)


def _replanner_context(replanner, waypoints, state):
    context = replanner.CreateDefaultContext()
    replanner.state_input.FixValue(context, state)
    replanner.map_input.FixValue(context, AbstractValue.Make(OnlineMap(0.5)))
    replanner.nominal_input.FixValue(context, AbstractValue.Make(
        PlannedPath(waypoints, 0.0, (0.0, 1.0, 0.0))))
    return context


def test_replanner_flies_towards_the_waypoints_at_survey_speed():
    waypoints = np.stack([np.arange(1.0, 11.0), np.zeros(10), np.full(10, -5.0)], axis=1)
    replanner = Replanner(speed=0.5, period=1.0)
    state = np.zeros(12)
    state[2] = -5.0
    context = _replanner_context(replanner, waypoints, state)
    simulator = Simulator(replanner, context)
    simulator.AdvanceTo(0.5)
    ref = Reference(replanner.reference_output.Eval(context))
    # Empty map: the plan is the straight line to the waypoints, flown at 0.5 m/s along +x.
    assert ref.position == pytest.approx([0.25, 0.0, -5.0], abs=1e-6)
    assert ref.velocity == pytest.approx([0.5, 0.0, 0.0], abs=1e-6)
    assert ref.yaw == pytest.approx(0.0, abs=1e-9)
    assert replanner.section(context).indices.tolist() == [0, 1, 2, 3]
    step = ReplanningStep(replanner.step_output.Eval(context))
    assert step.planned == 1.0 and step.time == 0.0 and step.wall_time > 0
    assert step.iterations >= 1 and step.map_voxels == 0  # STOMP ran; the map is empty
    assert replanner.status_output.Eval(context).tolist() == [0.0, 0.0, 0.0]


def test_replanner_reports_the_leg_finished_after_the_last_waypoint():
    waypoints = np.array([[1.0, 0.0, -5.0], [2.0, 0.0, -5.0]])
    replanner = Replanner(speed=0.5, period=1.0)
    state = np.zeros(12)
    state[:3] = (2.0, 0.0, -5.0)
    context = _replanner_context(replanner, waypoints, state)
    Simulator(replanner, context).AdvanceTo(12.0)
    leg, finished, next_index = replanner.status_output.Eval(context)
    assert (leg, finished, next_index) == (0.0, 1.0, 2.0)


def test_replanner_does_nothing_on_legs_it_does_not_fly():
    waypoints = np.array([[5.0, 0.0, -5.0]])
    replanner = Replanner(legs=(1,))
    context = _replanner_context(replanner, waypoints, np.zeros(12))
    replanner.leg_input.FixValue(context, [0.0, 0.0])
    Simulator(replanner, context).AdvanceTo(3.0)
    assert replanner.section(context) is None
    assert replanner.status_output.Eval(context)[0] == -1.0
    replanner.leg_input.FixValue(context, [1.0, 3.0])
    Simulator(replanner, context).AdvanceTo(4.0)
    assert replanner.section(context) is not None


def test_replanner_rejects_bad_parameters():
    with pytest.raises(ValueError, match="speed"):
        Replanner(speed=0.0)
    with pytest.raises(ValueError, match="period"):
        Replanner(period=100.0)


def test_octree_is_drawn_as_one_point_cloud():
    from pydrake.geometry import Meshcat, MeshcatParams

    from drake_auv.visualization.octree import depth_colours, draw_octree

    meshcat = Meshcat(MeshcatParams(host="localhost"))
    omap = OctreeMap(0.5)
    omap.insert_returns(_wall_returns(1))
    assert draw_octree(meshcat, "/drake_auv/octree", omap) == len(omap.occupied_points()) > 0
    assert meshcat.HasPath("/drake_auv/octree")
    colours = depth_colours(np.array([-10.0, -5.0, 0.0]))
    assert colours.shape == (3, 3) and not np.array_equal(colours[0], colours[2])
