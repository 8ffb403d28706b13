"""Camera coverage of a lawnmower flown by the simulated GIRONA 500 (tracking errors and all)."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource

from drake_auv.vehicle.diagram import add_girona500
from drake_auv.planning import PlannedPath
from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh

ALTITUDE = 2.0
FOOTPRINT = 2 * ALTITUDE * np.tan(np.radians(30.0))  # 2.31 m for the 60 deg camera


def _flown_coverage(spacing: float, lanes: int = 4, length: float = 20.0) -> float:
    """Flies lanes `spacing` apart over the rectangle they should cover; returns its coverage."""
    cell = 0.2
    ny, nx = int(round(lanes * spacing / cell)) + 1, int(round(length / cell)) + 1
    world = bathymetry_to_mesh(Bathymetry(np.full((ny, nx), -12.0), (cell, cell), (0.0, 0.0)))
    points = []
    for k in range(lanes):  # lanes overrun the ends by 3 m so turns happen outside the area
        y = (k + 0.5) * spacing
        xs = (-3.0, length + 3.0) if k % 2 == 0 else (length + 3.0, -3.0)
        points += [(xs[0], y, -12.0 + ALTITUDE), (xs[1], y, -12.0 + ALTITUDE)]
    path = PlannedPath(np.array(points), 0.0, (0.0, 0.0, -1.0)).resample(0.5)
    trajectory = path.to_trajectory(0.5)
    builder = DiagramBuilder()
    start = np.zeros(12)
    start[:3] = path.points[0]
    vehicle = add_girona500(builder, initial_state=start)
    source = builder.AddNamedSystem("reference", TrajectorySource(trajectory, 1))
    builder.Connect(source.get_output_port(), vehicle.tracker.reference_input)
    recorder = builder.AddNamedSystem("camera_coverage", CoverageRecorder(world, rate=2.0))
    builder.Connect(vehicle.dynamics.state_output, recorder.true_state_input)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(trajectory.end_time() + 2.0)
    return recorder.coverage(recorder.GetMyContextFromRoot(simulator.get_context()))


def test_lanes_at_footprint_width_cover_at_least_98_percent():
    assert _flown_coverage(FOOTPRINT) >= 0.98


def test_lanes_at_twice_the_footprint_cover_about_half():
    assert _flown_coverage(2 * FOOTPRINT, lanes=3) == pytest.approx(0.5, abs=0.05)
