"""Linear waves from a JONSWAP spectrum: dispersion, depth decay, the sea's Hs, and the
orbital acceleration, with no Drake."""

import math

import numpy as np
import pytest

from drake_auv.ocean.waves import G, WaveField, WaveSpectrum, wavenumber
from drake_auv.params import ParameterError


@pytest.mark.parametrize("depth", [2.0, 10.0, 50.0, 500.0])
def test_the_dispersion_relation_holds_at_every_depth(depth):
    omega = np.linspace(0.1, 5.0, 200)
    k = wavenumber(omega, depth)
    residual = G * k * np.tanh(k * depth) - omega ** 2
    assert np.max(np.abs(residual) / omega ** 2) < 1e-12


def test_deep_and_shallow_water_limits():
    omega = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(wavenumber(omega, 1000.0), omega ** 2 / G, rtol=1e-12)
    np.testing.assert_array_equal(wavenumber(omega, None), omega ** 2 / G)
    slow = np.array([0.05])  # long wave on 5 m: c = sqrt(g h)
    np.testing.assert_allclose(slow / wavenumber(slow, 5.0), math.sqrt(G * 5.0), rtol=1e-3)


def test_the_jonswap_spectrum_holds_hs_and_peaks_at_tp():
    spectrum = WaveSpectrum(hs_m=2.0, tp_s=10.0)
    omega = np.linspace(0.05, 5.0, 200001)
    density = spectrum.density(omega)
    m0 = np.trapezoid(density, omega)
    assert 4.0 * math.sqrt(m0) == pytest.approx(2.0, rel=0.01)  # A_gamma normalises it
    assert omega[np.argmax(density)] == pytest.approx(2 * math.pi / 10.0, rel=1e-3)
    field = WaveField(spectrum, np.random.default_rng(0))
    assert field.raw_m0 == pytest.approx(0.25, rel=0.03)  # the band [0.5, 3] wp holds it


def test_the_synthesized_surface_has_the_spectrum_hs():
    field = WaveField(WaveSpectrum(hs_m=1.5, tp_s=8.0, components=128),
                      np.random.default_rng(3))
    t = np.arange(0.0, 3 * 3600.0, 0.5)
    eta = np.array([field.elevation(s, [[10.0, -20.0]])[0] for s in t[::4]])
    assert 4.0 * eta.std() == pytest.approx(1.5, rel=0.05)
    assert abs(eta.mean()) < 0.02


def test_orbital_velocity_decays_with_depth_and_vanishes_at_the_seabed():
    depth = 20.0
    field = WaveField(WaveSpectrum(hs_m=1.0, tp_s=7.0, depth_m=depth),
                      np.random.default_rng(1))
    t = np.linspace(0.0, 600.0, 1201)
    rms = []
    for z in (0.0, -5.0, -10.0, -20.0):
        v = np.array([field.water(s, [[0.0, 0.0, z]])[0][0] for s in t[::3]])
        rms.append(np.sqrt((v ** 2).mean(axis=0)))
    rms = np.array(rms)
    assert np.all(np.diff(np.hypot(rms[:, 0], rms[:, 1])) < 0)  # horizontal decays
    assert np.all(np.diff(rms[:, 2]) < 0)  # vertical decays
    assert rms[-1, 2] < 1e-12  # no flow through the seabed
    assert rms[-1, 0] > 0.0  # but it slides along it (finite depth)


def test_a_single_component_matches_airy_theory():
    spectrum = WaveSpectrum(hs_m=1.0, tp_s=6.0, towards_deg=90.0, components=1, depth_m=15.0,
                            spreading=1000.0)
    field = WaveField(spectrum, np.random.default_rng(2))
    a, w, k, h = field.amplitude[0], field.omega[0], field.k[0], 15.0
    assert a == pytest.approx(1.0 / (2 * math.sqrt(2)))  # a^2 / 2 = Hs^2 / 16
    z, t, x = -4.0, 3.0, 7.0
    psi = k * x * math.sin(field.direction[0]) - w * t + field.phase[0]
    velocity, acceleration = field.water(t, [[x, 0.0, z]])
    horizontal = a * w * math.cosh(k * (z + h)) / math.sinh(k * h) * math.cos(psi)
    np.testing.assert_allclose(velocity[0, 2], a * w * math.sinh(k * (z + h)) / math.sinh(k * h)
                               * math.sin(psi), rtol=1e-12)
    np.testing.assert_allclose(np.hypot(velocity[0, 0], velocity[0, 1]), abs(horizontal),
                               rtol=1e-12)
    assert acceleration[0, 2] == pytest.approx(-a * w ** 2 * math.sinh(k * (z + h))
                                               / math.sinh(k * h) * math.cos(psi), rel=1e-12)


def test_the_acceleration_is_the_velocity_rate():
    field = WaveField(WaveSpectrum(hs_m=2.0, tp_s=9.0, depth_m=40.0), np.random.default_rng(4))
    points = np.array([[0.0, 0.0, -3.0], [12.0, -7.0, -15.0]])
    step = 1e-4
    _, acceleration = field.water(5.0, points)
    ahead, _ = field.water(5.0 + step, points)
    behind, _ = field.water(5.0 - step, points)
    np.testing.assert_allclose(acceleration, (ahead - behind) / (2 * step), atol=1e-7)


def test_directions_spread_about_the_mean():
    field = WaveField(WaveSpectrum(hs_m=1.0, tp_s=8.0, towards_deg=30.0, spreading=10.0,
                                   components=2000), np.random.default_rng(5))
    mean = math.degrees(math.atan2(np.sin(field.direction).mean(),
                                   np.cos(field.direction).mean()))
    assert mean == pytest.approx(30.0, abs=2.0)
    # cos^2s(theta/2): the circular spread is sqrt(2 / (s + 1)) rad
    offsets = np.angle(np.exp(1j * (field.direction - math.radians(30.0))))
    spread = math.sqrt(2.0 * (1.0 - abs(np.exp(1j * offsets).mean())))
    assert spread == pytest.approx(math.sqrt(2.0 / 11.0), rel=0.1)


@pytest.mark.parametrize("key, value", [("hs_m", -1.0), ("tp_s", -8.0), ("tp_s", 0.0)])
def test_negative_heights_and_periods_are_refused(key, value):
    with pytest.raises(ParameterError, match=f"{key} = {value!r} is out of range"):
        WaveSpectrum(**{key: value})
