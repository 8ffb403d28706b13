"""Waves: linear (Airy) waves from a directional JONSWAP spectrum (pure numpy).

The sea surface is a sum of N components i of amplitude a_i, angular frequency w_i,
wavenumber k_i, direction theta_i (towards, clockwise from north) and random phase phi_i:

    eta(t, x, y) = sum_i a_i cos(psi_i)
    psi_i = k_i (x sin theta_i + y cos theta_i) - w_i t + phi_i

with the finite-depth dispersion relation w^2 = g k tanh(k h) solved per component (Newton,
from Guo's explicit approximation). Below the surface (-h <= z <= 0) the orbital velocity and
its local time derivative are, along the component's direction and up,

    u_h = a w C cos psi,        w_z = a w S sin psi
    du_h/dt = a w^2 C sin psi,  dw_z/dt = -a w^2 S cos psi
    C = cosh(k (z + h)) / sinh(k h),   S = sinh(k (z + h)) / sinh(k h)

(deep water, h -> inf: C = S = exp(k z)); z is clamped to [-h, 0] (no stretching above the
mean surface). The spectrum (DNV-RP-C205 3.5.5):

    S(w) = A_g 5/16 Hs^2 wp^4 w^-5 exp(-5/4 (w/wp)^-4) gamma^exp(-(w - wp)^2 / (2 s^2 wp^2))

s = 0.07 below the peak, 0.09 above, A_g = 1 - 0.287 ln gamma; the components take the band
[0.5, 3] wp in N equal bins, one frequency drawn uniformly in each (no repeat period), with
amplitudes a_i = sqrt(2 S(w_i) dw) scaled so that sum a_i^2 / 2 = Hs^2 / 16 exactly. Their
directions are drawn from the cos^(2s)((theta - theta_0) / 2) spreading (one direction per
component: the single-summation method, whose sea is ergodic). All draws come from the
generator given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate

G = 9.80665  # m/s^2


@dataclass(frozen=True)
class WaveSpectrum:
    """A JONSWAP sea: significant height `hs_m`, peak period `tp_s`, mean direction
    `towards_deg` (clockwise from north), spreading exponent `spreading` (s of
    cos^2s(dtheta/2)), peak enhancement `gamma`, `components`, water depth `depth_m` (None:
    deep water)."""

    hs_m: float = param(0.0, low=0.0, high=20.0, unit="m")
    tp_s: float = param(8.0, low=1.0, high=30.0, unit="s")
    towards_deg: float = param(0.0, low=-360.0, high=360.0, unit="deg")
    spreading: float = param(10.0, low=1.0, high=1000.0)
    gamma: float = param(3.3, low=1.0, high=7.0)
    components: int = param(64, low=1, high=2000, integer=True)
    depth_m: float | None = param(None, low=0.0, high=11000.0, low_open=True, unit="m",
                                  nullable=True)

    def __post_init__(self):
        validate(self)

    def density(self, omega) -> np.ndarray:
        """The JONSWAP spectral density S(w) (m^2 s) at angular frequencies `omega` (rad/s)."""
        omega = np.asarray(omega, dtype=float)
        wp = 2.0 * math.pi / self.tp_s
        sigma = np.where(omega <= wp, 0.07, 0.09)
        peak = self.gamma ** np.exp(-((omega - wp) ** 2) / (2.0 * sigma ** 2 * wp ** 2))
        pm = 5.0 / 16.0 * self.hs_m ** 2 * wp ** 4 * omega ** -5.0 * np.exp(
            -1.25 * (omega / wp) ** -4.0)
        return (1.0 - 0.287 * math.log(self.gamma)) * pm * peak


def wavenumber(omega, depth_m: float | None) -> np.ndarray:
    """k (rad/m) with w^2 = g k tanh(k h) for each `omega` (rad/s); `depth_m` None: deep
    water (k = w^2 / g)."""
    omega = np.asarray(omega, dtype=float)
    k_deep = omega ** 2 / G
    if depth_m is None:
        return k_deep
    x = k_deep * depth_m  # Guo (2002): k h ~ x (1 - exp(-x^(5/4)))^(-2/5), within 0.75 %
    k = x * (1.0 - np.exp(-(x ** 1.25))) ** -0.4 / depth_m
    for _ in range(20):  # Newton on f(k) = g k tanh(k h) - w^2
        t = np.tanh(k * depth_m)
        f = G * k * t - omega ** 2
        k = k - f / (G * (t + k * depth_m * (1.0 - t ** 2)))
        if np.all(np.abs(f) <= 1e-13 * omega ** 2):
            break
    return k


class WaveField:
    """The components of a seeded sea: its orbital velocity and acceleration anywhere."""

    def __init__(self, spectrum: WaveSpectrum, rng: np.random.Generator):
        self.spectrum = spectrum
        n, wp = spectrum.components, 2.0 * math.pi / spectrum.tp_s
        edges = np.linspace(0.5 * wp, 3.0 * wp, n + 1)
        d_omega = edges[1] - edges[0]
        self.omega = edges[:-1] + d_omega * rng.random(n)
        density = spectrum.density(self.omega)
        amplitude = np.sqrt(2.0 * density * d_omega)
        self.raw_m0 = float(np.sum(amplitude ** 2) / 2.0)  # before the exact scaling
        target = spectrum.hs_m ** 2 / 16.0
        self.amplitude = amplitude * math.sqrt(target / self.raw_m0) if self.raw_m0 > 0 \
            else amplitude
        self.direction = np.radians(spectrum.towards_deg) + _spreading_draw(
            spectrum.spreading, rng, n)
        self.phase = 2.0 * math.pi * rng.random(n)
        self.k = wavenumber(self.omega, spectrum.depth_m)
        self._kx = self.k * np.sin(self.direction)  # east
        self._ky = self.k * np.cos(self.direction)  # north
        h = spectrum.depth_m
        # C = (exp(kz) + exp(-k(z + 2h))) q and S = (exp(kz) - exp(-k(z + 2h))) q with
        # q = 1 / (1 - exp(-2kh)) (deep water: C = S = exp(kz)); q is folded into the gains
        q = 1.0 if h is None else 1.0 / -np.expm1(-2.0 * self.k * h)
        aw, aw2 = self.amplitude * self.omega * q, self.amplitude * self.omega ** 2 * q
        east, north = np.sin(self.direction), np.cos(self.direction)
        # one (4 components, 6) gain matrix: the rows multiply [C cos, S sin, C sin, S cos]
        # of each component, the columns give [velocity xyz, acceleration xyz]
        n = spectrum.components
        self._gains = np.zeros((4 * n, 6))
        self._gains[:n, 0], self._gains[:n, 1] = aw * east, aw * north
        self._gains[n:2 * n, 2] = aw
        self._gains[2 * n:3 * n, 3], self._gains[2 * n:3 * n, 4] = aw2 * east, aw2 * north
        self._gains[3 * n:, 5] = -aw2

    def _phase(self, t: float, positions: np.ndarray) -> np.ndarray:
        return (positions[:, :1] * self._kx + positions[:, 1:2] * self._ky
                - self.omega * t + self.phase)  # (n, components)

    def elevation(self, t: float, xy) -> np.ndarray:
        """Surface elevation (n,) m at time `t` (s) and world points `xy` (n, 2+)."""
        return np.cos(self._phase(t, np.atleast_2d(xy))) @ self.amplitude

    def water(self, t: float, positions) -> tuple[np.ndarray, np.ndarray]:
        """Orbital velocity (n, 3) m/s and its time derivative (n, 3) m/s^2 at time `t` (s)
        and world positions (n, 3) (x east, y north, z up)."""
        both = self.sample(t, positions)
        return both[:, :3], both[:, 3:]

    def sample(self, t: float, positions) -> np.ndarray:
        """`water` as one array (n, 6): velocity then acceleration (the `Ocean` system's
        sample)."""
        positions = np.asarray(positions, dtype=float).reshape(-1, 3)
        h = self.spectrum.depth_m
        z = np.minimum(positions[:, 2:3], 0.0)
        if h is not None:
            np.maximum(z, -h, out=z)
        psi = self._phase(t, positions)
        terms = np.empty((positions.shape[0], 4, self.k.size))  # [C cos, S sin, C sin, S cos]
        np.cos(psi, out=terms[:, 0])
        np.sin(psi, out=terms[:, 1])
        terms[:, 2], terms[:, 3] = terms[:, 1], terms[:, 0]
        grow = np.exp(z * self.k)  # (n, components)
        if h is None:
            terms *= grow[:, None]  # C = S = grow
        else:
            mirror = np.exp(-(z + 2.0 * h) * self.k)
            terms[:, 0::2] *= (grow + mirror)[:, None]  # C and S without q
            terms[:, 1::2] *= (grow - mirror)[:, None]
        return terms.reshape(positions.shape[0], -1) @ self._gains


def _spreading_draw(s: float, rng: np.random.Generator, n: int) -> np.ndarray:
    """`n` direction offsets (rad) from the density cos^(2s)(theta / 2) on [-pi, pi] (inverse
    transform sampling on a fine grid)."""
    theta = np.linspace(-math.pi, math.pi, 4001)
    cdf = np.concatenate([[0.0], np.cumsum(np.cos(theta[1:] / 2.0) ** (2.0 * s)
                                           + np.cos(theta[:-1] / 2.0) ** (2.0 * s))])
    return np.interp(rng.random(n), cdf / cdf[-1], theta)
