"""OctreeMapper and Replanner as Drake systems, alone and in the breakwater diagram."""

import copy
import sys
from pathlib import Path as FilePath

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_auv.diagrams.replanning import build_replanning_diagram
from drake_auv.mapping.octree_map import OctreeMap, OctreeMapHandle
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.returns import SonarReturns
from drake_auv.mapping.mapper import OctreeMapper
from drake_auv.replanning.replanner import Replanner

sys.path.insert(0, str(FilePath(__file__).resolve().parents[1] / "examples"))
from breakwater_replanning import nominal_contour  # noqa: E402


def _wall_returns(sequence, x_wall=8.0):
    """A horizontal 61-beam fan from the origin hitting the wall x = x_wall."""
    a = np.linspace(-0.5, 0.5, 61)
    d = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    r = x_wall / d[:, 0]
    return SonarReturns(0.1 * sequence, np.zeros(3), a, r, d, d * r[:, None], d * r[:, None],
                        20.0, sequence)


def test_mapper_inserts_each_update_once_and_shares_the_map():
    mapper = OctreeMapper(resolution=0.5, period=0.1, multibeam_stride=1)
    context = mapper.CreateDefaultContext()
    mapper.multibeam_input.FixValue(context, AbstractValue.Make(_wall_returns(1)))
    simulator = Simulator(mapper, context)
    simulator.AdvanceTo(0.35)  # four updates, one new scan
    omap = mapper.octree_map
    assert omap.num_scans == 1
    handle = mapper.map_output.Eval(context)
    assert handle.map is omap and copy.deepcopy(handle).map is omap
    assert np.all(np.abs(omap.occupied_points()[:, 0] - 8.0) <= 0.5)
    mapper.multibeam_input.FixValue(context, AbstractValue.Make(_wall_returns(2)))
    simulator.AdvanceTo(0.55)
    assert omap.num_scans == 2


def test_mapper_rejects_bad_parameters():
    with pytest.raises(ValueError, match="period"):
        OctreeMapper(period=0.0)
    with pytest.raises(ValueError, match="multibeam_stride"):
        OctreeMapper(multibeam_stride=0)


def test_replanner_flies_towards_the_waypoints_at_survey_speed():
    waypoints = np.stack([np.arange(1.0, 11.0), np.zeros(10), np.full(10, -5.0)], axis=1)
    replanner = Replanner(waypoints, speed=0.5, period=1.0)
    context = replanner.CreateDefaultContext()
    state = np.zeros(12)
    state[2] = -5.0
    replanner.state_input.FixValue(context, state)
    replanner.map_input.FixValue(context, AbstractValue.Make(OctreeMapHandle(OctreeMap(0.5))))
    simulator = Simulator(replanner, context)
    simulator.AdvanceTo(0.5)
    ref = replanner.reference_output.Eval(context)
    # Empty map: the plan is the straight line to the waypoints, flown at 0.5 m/s along +x.
    assert ref[:3] == pytest.approx([0.25, 0.0, -5.0], abs=1e-6)
    assert ref[4:7] == pytest.approx([0.5, 0.0, 0.0], abs=1e-6)
    assert ref[3] == pytest.approx(0.0, abs=1e-9)
    assert len(replanner.log) == 1 and replanner.log[0].plan.indices.tolist() == [0, 1, 2, 3]


def test_replanner_rejects_bad_parameters():
    with pytest.raises(ValueError, match="waypoints"):
        Replanner(np.zeros((0, 3)))
    with pytest.raises(ValueError, match="speed"):
        Replanner(np.zeros((2, 3)), speed=0.0)
    with pytest.raises(ValueError, match="period"):
        Replanner(np.zeros((2, 3)), period=100.0)


def test_breakwater_replanning_keeps_the_offset_without_contact():
    scenario = get_scenario("breakwater")
    p = scenario.params
    prior = scenario.prior_map(error_m=4.0, seed=2)
    nominal = nominal_contour(prior, p["depth"], p["omega"], p["block_size"],
                              scenario.start_state[:3])
    diagram, handles = build_replanning_diagram(scenario.world, nominal, scenario.start_state,
                                                speed=p["speed"], seed=0)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(90.0)
    context = simulator.get_context()
    xyz = handles.state_log.FindLog(context).data()[:3].T
    # Horizontal distance to the row of blocks (the right-most centred on the origin).
    pitch = p["block_size"] + p["block_gap"]
    centres = -pitch * np.arange(20)
    q = np.abs(np.stack([xyz[:, None, 0] - centres, np.broadcast_to(xyz[:, None, 1],
                                                                    (len(xyz), 20))], axis=2))
    distance = np.linalg.norm(np.maximum(q - p["block_size"] / 2, 0.0), axis=2).min(axis=1)
    assert distance.min() > 1.0 + 2.0  # vehicle radius plus a margin
    # Once at the block (after the transit from the start), the offset Omega is kept.
    near = distance < 12.0
    assert near.sum() > 300
    assert abs(distance[near][100:].mean() - p["omega"]) < 1.0
    assert len(handles.mapper.octree_map.occupied_points()) > 500
    assert len(handles.replanner.log) == 90  # at initialisation, then at 1, 2, ..., 89 s


def test_octree_is_drawn_as_one_point_cloud():
    from pydrake.geometry import Meshcat, MeshcatParams

    from drake_auv.visualization.octree import depth_colours, draw_octree

    meshcat = Meshcat(MeshcatParams(host="localhost"))
    omap = OctreeMap(0.5)
    r = _wall_returns(1)
    omap.insert_returns(r)
    assert draw_octree(meshcat, "/drake_auv/octree", omap) == len(omap.occupied_points()) > 0
    assert meshcat.HasPath("/drake_auv/octree")
    colours = depth_colours(np.array([-10.0, -5.0, 0.0]))
    assert colours.shape == (3, 3) and not np.array_equal(colours[0], colours[2])
