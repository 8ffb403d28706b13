"""Sonar scans and coverage drawn in Meshcat (localhost)."""

import base64
import re

import msgpack
import numpy as np
import pytest
from pydrake.geometry import Meshcat, MeshcatParams
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from drake_auv.geometry import RayCaster
from drake_auv.scenarios import get_scenario
from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.sonar.multibeam import MultibeamSonar
from drake_auv.visualization.sensors import (CoverageVisualizer, SonarVisualizer, angle_colors,
                                             coverage_bands, draw_coverage)


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat(MeshcatParams(host="localhost"))


def test_angle_colours():
    rgb = angle_colors(np.array([0.0, np.pi / 4, np.pi / 2, np.nan]))
    np.testing.assert_allclose(rgb[0], [0, 1, 0.15])
    np.testing.assert_allclose(rgb[1], [1, 1, 0.15])
    np.testing.assert_allclose(rgb[2], [1, 0, 0.15])
    np.testing.assert_allclose(rgb[3], [0.55, 0.55, 0.55])


def test_scan_and_coverage_layers_in_a_diagram(meshcat):
    sc = get_scenario("breakwater")
    caster = RayCaster(sc.world)
    builder = DiagramBuilder()
    pose = np.zeros(12)
    pose[:6] = 0.0, -8.5, -5.0, 0.0, 0.0, np.pi / 2
    state = builder.AddNamedSystem("state", ConstantVectorSource(pose))
    sonar = builder.AddNamedSystem("multibeam", MultibeamSonar(caster, mount="forward"))
    recorder = builder.AddNamedSystem("coverage", CoverageRecorder(
        caster, sc.target_faces, axis_body=(1.0, 0.0, 0.0), max_range=12.0))
    for port in ("true_state", "estimated_state"):
        builder.Connect(state.get_output_port(), sonar.GetInputPort(port))
    builder.Connect(state.get_output_port(), recorder.GetInputPort("true_state"))
    scan_vis = builder.AddNamedSystem("multibeam_visualizer", SonarVisualizer(
        meshcat, "/drake_auv/sonar/multibeam", history=3))
    builder.Connect(sonar.GetOutputPort("returns"), scan_vis.GetInputPort("returns"))
    CoverageVisualizer.for_recorder(builder, recorder, meshcat, "/drake_auv/coverage", period=0.5)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(0.55)
    for path in ("/drake_auv/sonar/multibeam/beams", "/drake_auv/sonar/multibeam/points",
                 "/drake_auv/coverage"):
        assert meshcat.HasPath(path), path
    context = recorder.GetMyContextFromRoot(simulator.get_context())
    # The camera faces the block's south face from 6 m: part of it is covered, nothing else.
    assert 0.1 < recorder.coverage(context) < 0.5
    # 6 scans so far, all alike (a fixed pose): the cloud holds history 3 + the last
    returns = sonar.GetOutputPort("returns").Eval(sonar.GetMyContextFromRoot(
        simulator.get_context()))
    assert returns.hit.sum() > 10
    assert _drawn_points(meshcat, "/drake_auv/sonar/multibeam/points") == 4 * returns.hit.sum()


def _drawn_points(meshcat, path: str) -> int:
    """How many points the point cloud at `path` holds, read from Meshcat's scene (its static
    HTML: msgpack commands, typed arrays as extension types)."""
    for b64 in re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"',
                          meshcat.StaticHtml()):
        command = msgpack.unpackb(base64.b64decode(b64), strict_map_key=False,
                                  ext_hook=lambda code, data: len(data))
        if command.get("type") == "set_object" and command.get("path") == path:
            position = command["object"]["geometries"][0]["data"]["attributes"]["position"]
            return position["array"] // (4 * position["itemSize"])  # float32 xyz
    raise AssertionError(f"no object at {path}")


def test_draw_coverage_checks_its_input(meshcat):
    sc = get_scenario("pool")
    angles = np.full(len(sc.world.faces), np.nan)
    angles[sc.target_faces] = 0.3
    draw_coverage(meshcat, "/drake_auv/test_pool_coverage", sc.world, angles, sc.target_faces)
    # 0.3 rad (17 deg) falls in the 15-30 deg band alone
    bands = {name: meshcat.HasPath(f"/drake_auv/test_pool_coverage/{name}")
             for name, _ in coverage_bands()}
    assert [name for name, drawn in bands.items() if drawn] == ["15-30_deg"]
    # half of them seen head-on, the rest unseen: the 15-30 deg band is gone
    angles[sc.target_faces] = np.where(np.arange(sc.target_faces.sum()) % 2, 0.05, np.nan)
    draw_coverage(meshcat, "/drake_auv/test_pool_coverage", sc.world, angles, sc.target_faces)
    assert [name for name, _ in coverage_bands()
            if meshcat.HasPath(f"/drake_auv/test_pool_coverage/{name}")] == ["0-15_deg", "unseen"]
    with pytest.raises(ValueError, match="one value per world face"):
        draw_coverage(meshcat, "/x", sc.world, angles[:10])
    with pytest.raises(ValueError, match="no faces"):
        draw_coverage(meshcat, "/x", sc.world, angles, np.zeros(len(angles), bool))
    with pytest.raises(ValueError, match="history"):
        SonarVisualizer(meshcat, "/x", history=-1)
