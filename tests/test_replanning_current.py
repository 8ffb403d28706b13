"""The replanning cost's current terms: effort in the velocity through the forecast water and a
clearance inflated on the side the current pushes towards; off without a current, and with
`current_aware` false the Replanner is today's."""

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.ocean.forecast import forecast
from drake_auv.ocean.spec import ocean_from_raw
from drake_auv.planning.path import PlannedPath
from drake_auv.replanning.cost import ReplanningCost
from drake_auv.replanning.fields import SliceMap
from drake_auv.replanning.replanner import Replanner
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import replan_section


def _wall(y=6.0):
    """Voxel centres of a wall along x at `y`, 0.5 m apart, z in [-3, 3]."""
    x, z = np.meshgrid(np.arange(-10.0, 20.01, 0.5), np.arange(-3.0, 3.01, 0.5))
    return np.column_stack([x.ravel(), np.full(x.size, y), z.ravel()])


def _lane(y=3.0, n=21):
    return np.column_stack([np.linspace(0.0, 10.0, n), np.full(n, y), np.zeros(n)])


def _cost(params, wall, lane, current=None, speed=0.3):
    slice_map = SliceMap(wall, (-1.0, 1.0), params.depth_band, 10.0)
    water = None if current is None else np.tile(current, (len(lane), 1))
    return ReplanningCost(slice_map, lane[[0, -1]], lane, params, np.zeros(len(lane), bool),
                          current=water, speed=speed)


def test_clearance_is_larger_where_the_current_pushes_towards_the_wall():
    params = ReplanningParameters(clearance=4.0, current_margin_s=5.0)
    wall, lane = _wall(6.0), _lane(3.0)  # 3 m from the wall, inside the 4 m clearance
    still = _cost(params, wall, lane).terms(lane[None])["obstacle"]
    towards = _cost(params, wall, lane, [0.0, 0.4, 0.0]).terms(lane[None])["obstacle"]
    away = _cost(params, wall, lane, [0.0, -0.4, 0.0]).terms(lane[None])["obstacle"]
    along = _cost(params, wall, lane, [0.4, 0.0, 0.0]).terms(lane[None])["obstacle"]
    middle = len(lane) // 2  # the nearest voxel straight ahead across: (4 + 5 * 0.4 - 3)^2
    assert still[0, middle] == pytest.approx(1.0)
    assert towards[0, middle] == pytest.approx(9.0)
    assert away[0, middle] == pytest.approx(1.0) and along[0, middle] == pytest.approx(1.0)
    assert np.all(towards >= still) and np.all(away == still)
    # Beyond the inflated clearance nothing changes: 7 m from the wall.
    far = _lane(-1.0)
    assert not _cost(params, wall, far, [0.0, 0.4, 0.0]).terms(far[None])["obstacle"].any()


def test_a_replanned_lane_beside_a_wall_keeps_further_off_when_the_current_pushes_at_it():
    params = ReplanningParameters(clearance=4.0, omega=6.0, margin=4.0)
    wall = _wall(6.0)
    waypoints = _lane(3.2, 11)[1:]
    waypoints[:, 2] = 0.0

    def least_distance(towards):
        """From 3 m on (the vehicle starts 2.8 m from the wall), m."""
        velocity = np.array([0.0, 0.4 * towards, 0.0])
        plan = replan_section([0.0, 3.2, 0.0], waypoints, 0, wall, params, seed=3,
                              keep_offset=np.zeros(len(waypoints), bool),
                              current=None if towards == 0
                              else lambda p: np.tile(velocity, (len(p), 1)), speed=0.3)
        return (6.0 - plan.trajectory[plan.trajectory[:, 0] > 3.0, 1]).min()

    # The clearance, 4 m, grows to 4 + 5 s x 0.4 m/s = 6 m where the current pushes at the
    # wall; pushing away, the lane keeps the still-water clearance.
    still = least_distance(0)
    assert 3.7 < still < 4.3
    assert least_distance(-1) == pytest.approx(still, abs=0.2)
    assert least_distance(+1) > still + 1.2


def test_effort_grows_with_a_head_current_and_is_absent_in_still_water():
    params = ReplanningParameters()
    wall, lane = _wall(30.0), _lane(0.0)  # along +x, the wall out of reach

    def effort(u):
        return _cost(params, wall, lane, [u, 0.0, 0.0], speed=0.3).terms(lane[None])["effort"]

    head = [effort(-u)[0, 1:].mean() for u in (0.0, 0.2, 0.4)]
    assert head == pytest.approx([1.0, (0.5 / 0.3) ** 2, (0.7 / 0.3) ** 2])
    assert effort(0.2)[0, 1:].mean() == pytest.approx((0.1 / 0.3) ** 2)  # a tail current helps
    assert np.all(effort(0.4)[:, 0] == 0)
    still = _cost(params, wall, lane)
    assert not still.terms(lane[None])["effort"].any()
    with_current = _cost(params, wall, lane, [-0.4, 0.0, 0.0])
    assert np.allclose(with_current(lane[None]) - still(lane[None]),
                       params.current_weight * effort(-0.4))


def test_the_cost_refuses_a_current_of_the_wrong_shape():
    params = ReplanningParameters()
    lane = _lane()
    with pytest.raises(ValueError, match="current must be finite of shape"):
        ReplanningCost(SliceMap(_wall(), (-1.0, 1.0), 1.5, 4.0), lane[[0, -1]], lane, params,
                       current=np.zeros((3, 3)))


def _replanned(params, current):
    waypoints = np.stack([np.arange(1.0, 11.0), np.zeros(10), np.full(10, -5.0)], axis=1)
    replanner = Replanner(params, speed=0.3, period=1.0, current=current)
    context = replanner.CreateDefaultContext()
    state = np.zeros(12)
    state[2] = -5.0
    replanner.state_input.FixValue(context, state)
    replanner.map_input.FixValue(context, AbstractValue.Make(OnlineMap(0.5)))
    replanner.nominal_input.FixValue(context, AbstractValue.Make(
        PlannedPath(waypoints, 0.0, (0.0, 1.0, 0.0))))
    Simulator(replanner, context).AdvanceTo(3.0)
    return replanner.section(context).trajectory


def test_a_current_blind_replanner_is_the_still_water_one_bit_for_bit():
    sea = forecast(ocean_from_raw({"current": {"speed_mps": 0.4, "towards_deg": 0.0}}))
    still = _replanned(ReplanningParameters(), None)
    blind = _replanned(ReplanningParameters(current_aware=False), sea)
    aware = _replanned(ReplanningParameters(), sea)
    assert np.array_equal(blind, still)
    assert not np.array_equal(aware, still)  # the same seed sees the cross current


def test_the_forecast_is_the_mean_current_and_the_tides_without_turbulence_or_waves():
    spec = ocean_from_raw({"current": {"speed_mps": 0.3, "towards_deg": 90.0},
                           "tides": [{"name": "M2", "amplitude_mps": 0.2, "phase_deg": 0.0,
                                      "flood_towards_deg": 0.0}],
                           "turbulence": {"speed_sd_mps": 0.1, "direction_sd_deg": 10.0},
                           "waves": {"hs_m": 1.0, "tp_s": 8.0, "towards_deg": 0.0}})
    f = forecast(spec)
    omega = np.radians(28.9841042) / 3600.0
    for t in (0.0, 1000.0, 5000.0):
        tide = 0.2 * np.cos(omega * t)
        expected = [0.3, abs(tide) * np.sign(tide), 0.0]
        assert f(t, np.array([[0.0, 0.0, -5.0], [3.0, 1.0, -2.0]])) == pytest.approx(
            np.array([expected, expected]), abs=1e-12)
    assert forecast(None) is None
    assert forecast(ocean_from_raw({"current": {"speed_mps": 0.0}})) is None
