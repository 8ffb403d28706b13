"""The depth-uniform current: mean, vertical profile, tides (harmonics and CSV), and the exact
Ornstein-Uhlenbeck turbulence, with no Drake."""

import math

import numpy as np
import pytest

from drake_auv.ocean.clock import parse_utc
from drake_auv.ocean.current import MeanCurrent, VerticalProfile, towards_unit
from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.tides import TidalConstituent, TidalHarmonics, TidalSeries
from drake_auv.ocean.turbulence import Turbulence, perturb
from drake_auv.params import ParameterError


def test_directions_are_towards_clockwise_from_north():
    np.testing.assert_allclose(towards_unit([0.0, 90.0, 180.0, 270.0]),
                               [[0, 1], [1, 0], [0, -1], [-1, 0]], atol=1e-15)
    np.testing.assert_allclose(MeanCurrent(0.4, 45.0).velocity(), [0.4 / math.sqrt(2)] * 2)


def test_a_current_beyond_5_mps_is_refused():
    with pytest.raises(ParameterError, match=r"speed_mps = 5.5 is out of range; must be in "
                                             r"\[0, 5\] m/s"):
        MeanCurrent(5.5, 0.0)


def test_depth_table_profile_is_linear_between_depths_and_held_beyond():
    profile = VerticalProfile(depth_m=(0.0, 10.0, 30.0), factor=(1.0, 0.8, 0.4))
    np.testing.assert_allclose(profile.factor_at([1.0, 0.0, -5.0, -10.0, -20.0, -100.0]),
                               [1.0, 1.0, 0.9, 0.8, 0.6, 0.4])
    with pytest.raises(ValueError, match="strictly increasing"):
        VerticalProfile(depth_m=(0.0, 10.0, 5.0), factor=(1.0, 0.8, 0.4))
    with pytest.raises(ValueError, match="equal length"):
        VerticalProfile(depth_m=(0.0, 10.0), factor=(1.0,))


def test_power_law_profile_towards_the_seabed():
    profile = VerticalProfile(seabed_depth_m=40.0, boundary_layer_m=10.0)
    heights = np.array([0.0, 2.5, 5.0, 10.0, 20.0])  # above the seabed
    expected = np.minimum(heights / 10.0, 1.0) ** (1.0 / 7.0)
    np.testing.assert_allclose(profile.factor_at(heights - 40.0), expected)
    assert profile.factor_at(-45.0) == 0.0  # under the seabed
    whole = VerticalProfile(seabed_depth_m=40.0, exponent=0.5)  # the whole column
    assert whole.factor_at(-30.0) == pytest.approx(0.5)


def test_the_profile_scales_the_mean_current_at_depth():
    model = OceanModel(MeanCurrent(0.5, 90.0), VerticalProfile(depth_m=(0.0, 20.0),
                                                               factor=(1.0, 0.5)))
    velocity, acceleration = model.water(0.0, [[0.0, 0.0, -10.0], [5.0, 5.0, -20.0]])
    np.testing.assert_allclose(velocity, [[0.375, 0.0, 0.0], [0.25, 0.0, 0.0]], atol=1e-15)
    np.testing.assert_array_equal(acceleration, 0.0)


def test_tides_against_a_hand_computation():
    epoch = parse_utc("2000-01-01T00:00:00Z")
    m2 = TidalConstituent("M2", amplitude_mps=0.3, phase_deg=40.0, flood_towards_deg=90.0)
    s2 = TidalConstituent("S2", amplitude_mps=0.1, phase_deg=-20.0, flood_towards_deg=0.0,
                          ebb_towards_deg=200.0)
    tides = TidalHarmonics([m2, s2], epoch)
    for hours in (0.0, 1.5, 4.0, 7.25, 100.0):
        # by hand: M2 28.9841042 deg/h, S2 30 deg/h
        s_m2 = 0.3 * math.cos(math.radians(28.9841042 * hours - 40.0))
        s_s2 = 0.1 * math.cos(math.radians(30.0 * hours + 20.0))
        east = s_m2 if s_m2 >= 0 else -s_m2 * math.sin(math.radians(270.0))
        north = 0.0
        if s_s2 >= 0:
            north += s_s2
        else:
            east += -s_s2 * math.sin(math.radians(200.0))
            north += -s_s2 * math.cos(math.radians(200.0))
        velocity, rate = tides.velocity(epoch + hours * 3600.0)
        np.testing.assert_allclose(velocity, [east, north], atol=1e-12)
        # the rate is the derivative of the velocity (away from a slack)
        step = 1.0
        ahead, _ = tides.velocity(epoch + hours * 3600.0 + step)
        behind, _ = tides.velocity(epoch + hours * 3600.0 - step)
        np.testing.assert_allclose(rate, (ahead - behind) / (2 * step), atol=1e-9)


def test_a_constituent_of_unknown_speed_needs_its_speed():
    with pytest.raises(ValueError, match="speed_deg_per_h"):
        TidalConstituent("X9", amplitude_mps=0.1)
    assert TidalConstituent("X9", amplitude_mps=0.1, speed_deg_per_h=15.0).omega() == \
        pytest.approx(math.radians(15.0) / 3600.0)


def test_tidal_series_from_csv_is_linear_in_time(tmp_path):
    path = tmp_path / "tide.csv"
    path.write_text("time_utc,east_mps,north_mps\n2024-03-01T00:00:00Z,0.1,-0.2\n"
                    "2024-03-01T01:00:00Z,0.3,0.2\n2024-03-01T02:00:00Z,0.0,0.0\n")
    series = TidalSeries.from_csv(path)
    t0 = parse_utc("2024-03-01T00:00:00Z")
    velocity, rate = series.velocity(t0 + 900.0)
    np.testing.assert_allclose(velocity, [0.15, -0.1])
    np.testing.assert_allclose(rate, [0.2 / 3600.0, 0.4 / 3600.0])
    with pytest.raises(ValueError, match="not the dive's"):
        series.check_span(t0, t0 + 3 * 3600.0)
    with pytest.raises(ValueError, match="not the dive's"):  # never extrapolated
        series.velocity(t0 + 3 * 3600.0)
    bad = tmp_path / "bad.csv"
    bad.write_text("time,speed\n2024-03-01T00:00:00Z,0.1\n")
    with pytest.raises(ValueError, match="lacks") as err:
        TidalSeries.from_csv(bad)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("dt", [1.0, 10.0])
def test_ou_statistics_match_their_parameters_at_any_step(dt):
    turbulence = Turbulence(speed_sd_mps=0.05, direction_sd_deg=12.0, time_constant_s=30.0)
    sd = turbulence.sd()
    rng = np.random.default_rng(7)
    chains, horizon = 4000, 120.0  # s
    state = sd * rng.standard_normal((chains, 2))  # stationary start
    steps = int(round(horizon / dt))
    history = np.empty((steps + 1, chains, 2))
    history[0] = state
    for k in range(steps):
        state = turbulence.step(state, dt, rng)
        history[k + 1] = state
    flat = history.reshape(-1, 2)
    np.testing.assert_allclose(flat.mean(axis=0) / sd, 0.0, atol=0.03)
    np.testing.assert_allclose(flat.std(axis=0) / sd, 1.0, atol=0.02)
    lag = int(round(30.0 / dt))  # one time constant: correlation exp(-1)
    a, b = history[:-lag].reshape(-1, 2), history[lag:].reshape(-1, 2)
    correlation = (a * b).mean(axis=0) / (a.std(axis=0) * b.std(axis=0))
    np.testing.assert_allclose(correlation, math.exp(-1.0), atol=0.02)
    # the correlation time read back from the one-step correlation
    one = (history[:-1] * history[1:]).reshape(-1, 2).mean(axis=0) / flat.var(axis=0)
    np.testing.assert_allclose(-dt / np.log(one), 30.0, rtol=0.05)


def test_turbulence_perturbs_speed_and_direction_and_its_rate():
    velocity, rate = np.array([0.3, 0.4]), np.array([1e-4, -2e-4])
    turned, turned_rate = perturb(velocity, rate, np.array([0.1, math.radians(90.0)]))
    np.testing.assert_allclose(np.hypot(*turned), 0.6)
    np.testing.assert_allclose(turned, [0.6 * 0.8, -0.6 * 0.6], atol=1e-12)  # clockwise 90
    step = 10.0
    ahead, _ = perturb(velocity + rate * step, rate, np.array([0.1, math.pi / 2]))
    behind, _ = perturb(velocity - rate * step, rate, np.array([0.1, math.pi / 2]))
    np.testing.assert_allclose(turned_rate, (ahead - behind) / (2 * step), atol=1e-9)
