"""Transits (pure) and the PathReference system: above the terrain, below the surface, timed
from the moment their leg begins; and the legs' goals."""

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_auv.mission.legs import Leg, advance_progress, goal_reached, start_progress
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.transit import transit
from drake_auv.vehicle.path_reference import PathLeg, PathReference


def ridge(x, y):
    """A 10 m ridge across x = 0 on a seabed at -30 m."""
    return -30.0 + 10.0 * np.exp(-(np.asarray(x) / 3.0) ** 2)


def test_transit_climbs_over_the_terrain_and_stays_in_the_water():
    path = transit((-20.0, 0.0, -27.0), (20.0, 0.0, -27.0), 0.0, np.pi / 2, terrain=ridge,
                   clearance=3.0, min_depth=1.0)
    z = path.points[:, 2]
    x = path.points[:, 0]
    assert np.all(z[1:-1] >= ridge(x[1:-1], 0.0) + 3.0 - 1e-9)  # 3 m over the ridge
    assert z[np.argmin(np.abs(x))] == pytest.approx(-17.0)
    assert np.allclose(path.points[[0, -1], 2], -27.0)  # the ends are kept
    assert path.heading[0] == 0.0 and path.heading[-1] == pytest.approx(np.pi / 2)
    assert np.all(np.linalg.norm(np.diff(path.points[:, :2], axis=0), axis=1) <= 1.0 + 1e-9)
    shallow = transit((0.0, 0.0, -0.2), (10.0, 0.0, 2.0), 0.0, terrain=None, min_depth=1.0)
    assert shallow.points[:, 2].max() <= -1.0  # never above the minimum depth
    with pytest.raises(ValueError, match="clearance"):
        transit((0, 0, -5), (1, 0, -5), 0.0, clearance=-1.0)


def _context(system, x):
    context = system.CreateDefaultContext()
    system.state_input.FixValue(context, x)
    return context


def test_a_steep_lift_does_not_turn_the_transit():
    """The pool's shallow end: 13 cm across, lifted 2.5 m over the terrain in between. The
    yaw goes the 94 deg from the start's to the goal's, not round through the drift's -137."""
    path = transit((-5.91, 0.09, -4.0), (-6.0, 0.0, -3.0), np.radians(-626.4), 0.0,
                   terrain=lambda x, y: np.full(np.shape(x), -4.5), clearance=3.0)
    assert path.points[1:-1, 2].max() == pytest.approx(-1.5)
    turned = np.degrees(np.diff(path.unwrapped_heading()))
    assert np.abs(turned).sum() == pytest.approx(93.6, abs=0.1)


def test_goto_leg_is_timed_from_the_leg_start_and_ends_at_the_target():
    reference = PathReference({1: PathLeg("goto", (10.0, 0.0, -5.0), 0.0, speed=0.5)})
    x = np.zeros(12)
    x[2] = -5.0
    context = _context(reference, x)
    reference.leg_input.FixValue(context, [0.0, 0.0])
    simulator = Simulator(reference, context)
    simulator.AdvanceTo(3.0)  # leg 0 is not ours: hold where the vehicle is
    assert reference.status_output.Eval(context)[0] == -1.0
    assert reference.reference_output.Eval(context) == pytest.approx([0, 0, -5, 0, 0, 0, 0, 0])
    reference.leg_input.FixValue(context, [1.0, 3.0])
    simulator.AdvanceTo(7.0)
    leg, finished, progress = reference.status_output.Eval(context)
    end = reference.held(context).trajectory.end_time()
    assert leg == 1.0 and end == pytest.approx(3.0 + 20.0, abs=0.11)  # 10 m at 0.5 m/s
    assert finished == 0.0 and progress == pytest.approx((7.0 - 3.0) / (end - 3.0))
    ref = reference.reference_output.Eval(context)
    assert ref[0] == pytest.approx(0.5 * (7.0 - 3.0), abs=0.06)
    assert ref[4] == pytest.approx(0.5, abs=1e-6)
    simulator.AdvanceTo(30.0)
    assert reference.reference_output.Eval(context) == pytest.approx([10, 0, -5, 0, 0, 0, 0, 0])
    assert reference.status_output.Eval(context).tolist() == [1.0, 1.0, 1.0]  # flown


def test_nominal_leg_flies_the_input_path_after_a_transit():
    reference = PathReference(PathLeg("nominal", speed=1.0))
    context = _context(reference, np.zeros(12) + np.r_[0, 0, -5, np.zeros(9)])
    nominal = PlannedPath(np.array([[5.0, 0.0, -5.0], [5.0, 10.0, -5.0]]), np.pi / 2, (0, 0, -1))
    reference.nominal_input.FixValue(context, AbstractValue.Make(nominal))
    simulator = Simulator(reference, context)
    simulator.AdvanceTo(1.0)
    end = reference.held(context).trajectory.end_time()
    # 5 m of transit, its last segment also turning 90 deg at 15 deg/s (6 s), then 10 m
    assert end == pytest.approx(4.0 + 6.0 + 10.0, abs=0.2)
    simulator.AdvanceTo(end - 5.0)
    ref = reference.reference_output.Eval(context)
    assert ref[0] == pytest.approx(5.0, abs=1e-6) and ref[1] == pytest.approx(5.0, abs=0.2)
    assert ref[5] == pytest.approx(1.0, abs=1e-6) and ref[3] == pytest.approx(np.pi / 2)


def test_leg_goals():
    x = np.zeros(12)
    loops = Leg("follow", 0, "follow", "loops", 100.0, centre=(0.0, 0.0), loops=1.0)
    progress = start_progress(loops, np.r_[5.0, 0.0, np.zeros(10)])
    for angle in np.linspace(0.0, 2 * np.pi * 0.99, 40):
        x[:2] = 5.0 * np.cos(angle), 5.0 * np.sin(angle)
        progress = advance_progress(loops, progress, x)
    assert not goal_reached(loops, 0, 0.0, x, progress, [-1, 0, 0])
    x[:2] = 5.0, 0.05
    progress = advance_progress(loops, progress, x)
    assert goal_reached(loops, 0, 0.0, x, progress, [-1, 0, 0])
    along = Leg("follow", 0, "follow", "distance", 100.0, direction=(1.0, 0.0), distance=10.0,
                end_depth=2.0)
    progress = start_progress(along, np.zeros(12))
    x = np.zeros(12)
    x[:3] = 11.0, 0.0, -3.0
    assert not goal_reached(along, 0, 0.0, x, progress, [-1, 0, 0])  # too deep
    x[2] = -1.5
    assert goal_reached(along, 0, 0.0, x, progress, [-1, 0, 0])
    arrive = Leg("transit", 2, "path", "arrive", 100.0, target=(1.0, 0.0, 0.0), tolerance=0.5)
    x = np.zeros(12)
    assert not goal_reached(arrive, 2, 5.0, x, progress, [2, 1, 1])  # 1 m away
    x[0] = 0.8
    assert not goal_reached(arrive, 2, 3.0, x, progress, [2, 0, 0.7])  # path not done
    assert goal_reached(arrive, 2, 5.0, x, progress, [2, 1, 1])
    assert not goal_reached(arrive, 2, 5.0, x, progress, [1, 1, 1])  # other leg's
    handing = Leg("transit", 2, "path", "arrive", 100.0, target=(10.0, 0.0, 0.0), handover=5.0)
    x[0] = 4.0
    assert not goal_reached(handing, 2, 1.0, x, progress, [2, 0, 0.1])  # 6 m away
    x[0] = 5.5
    assert goal_reached(handing, 2, 1.0, x, progress, [2, 0, 0.1])  # path not done
    replan = Leg("survey", 3, "replan", "finished", 100.0)
    assert goal_reached(replan, 3, 0.0, x, progress, [3, 1, 7])
    assert not goal_reached(replan, 3, 0.0, x, progress, [2, 1, 7])  # another leg's
    assert not goal_reached(replan, 3, 0.0, x, progress, [3, 0, 7])  # not finished
