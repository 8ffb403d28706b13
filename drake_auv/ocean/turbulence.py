"""Turbulence: an exact Ornstein-Uhlenbeck process on the current's speed and direction (pure
numpy).

The state is the deviation d = (speed deviation, m/s; direction deviation, rad) of the
turbulent current from its deterministic part (mean + tide): the water then flows at
|U| + d_speed towards the direction of U turned by d_direction. Each deviation is a
stationary OU process of standard deviation sigma and time constant T, advanced over a step dt
by its exact transition

    d_{k+1} = exp(-dt/T) d_k + sigma sqrt(1 - exp(-2 dt/T)) N(0, 1),

so its mean (0), variance (sigma^2) and autocorrelation exp(-|tau|/T) are those of the
parameters whatever the step. (The Euler Gauss-Markov update of UUV Simulator and DAVE,
v += -mu dt v + noise, decays to zero, has a variance that depends on dt and is unstable for
mu dt > 2.) Between updates the deviation is held, so it contributes no acceleration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate

TURBULENCE_SIZE = 2  # (speed deviation m/s, direction deviation rad)


@dataclass(frozen=True)
class Turbulence:
    """Stationary standard deviations of speed (`speed_sd_mps`) and direction
    (`direction_sd_deg`), and their correlation time `time_constant_s`."""

    speed_sd_mps: float = param(0.0, low=0.0, high=2.0, unit="m/s")
    direction_sd_deg: float = param(0.0, low=0.0, high=90.0, unit="deg")
    time_constant_s: float = param(300.0, low=0.0, high=1e6, low_open=True, unit="s")

    def __post_init__(self):
        validate(self)

    @property
    def enabled(self) -> bool:
        return self.speed_sd_mps > 0.0 or self.direction_sd_deg > 0.0

    def sd(self) -> np.ndarray:
        """Stationary standard deviations (2,): m/s, rad."""
        return np.array([self.speed_sd_mps, math.radians(self.direction_sd_deg)])

    def initial(self, rng: np.random.Generator) -> np.ndarray:
        """A draw (2,) from the stationary distribution."""
        return self.sd() * rng.standard_normal(TURBULENCE_SIZE)

    def step(self, deviation, dt: float, rng: np.random.Generator) -> np.ndarray:
        """The deviation (2,) (or (m, 2): m independent processes) after `dt` seconds, by
        the exact OU transition."""
        deviation = np.asarray(deviation, dtype=float)
        return self.advance(deviation, dt, rng.standard_normal(deviation.shape))

    def advance(self, deviation, dt: float, normals) -> np.ndarray:
        """The exact OU transition over `dt` seconds of `deviation` (2,) or (m, 2), given
        its standard normal draws `normals` (same shape)."""
        decay, spread = self.transition(dt)
        return decay * np.asarray(deviation, dtype=float) + spread * np.asarray(normals)

    def transition(self, dt: float) -> tuple[float, np.ndarray]:
        """The exact OU transition's coefficients over `dt` seconds: the deviation's decay
        and the standard deviations (2,) its normal draws are scaled by."""
        return (math.exp(-dt / self.time_constant_s),
                self.sd() * math.sqrt(-math.expm1(-2.0 * dt / self.time_constant_s)))


def perturb(velocity, rate, deviation) -> tuple[np.ndarray, np.ndarray]:
    """The horizontal velocity U (2,) (east, north, m/s) with its speed S raised by
    deviation[0] (m/s) and its heading theta turned clockwise by deviation[1] (rad), and the
    time derivative of that (2,) given U's derivative `rate` (the deviation held):
    d/dt[(S + ds) e(theta + dtheta)] = S' e + (S + ds) theta' e', e(a) = (sin a, cos a).
    A still current (S = 0) takes the speed deviation towards north."""
    east, north = float(velocity[0]), float(velocity[1])
    d_speed, d_heading = float(deviation[0]), float(deviation[1])
    speed = math.hypot(east, north)
    heading = math.atan2(east, north) + d_heading  # clockwise from north
    sin, cos = math.sin(heading), math.cos(heading)  # along = (sin, cos), across = (cos, -sin)
    if speed == 0.0:
        return np.array([d_speed * sin, d_speed * cos]), np.asarray(rate, dtype=float).copy()
    rate_east, rate_north = float(rate[0]), float(rate[1])
    speed_rate = (east * rate_east + north * rate_north) / speed
    heading_rate = (north * rate_east - east * rate_north) / speed ** 2
    total = speed + d_speed
    turn = total * heading_rate
    return (np.array([total * sin, total * cos]),
            np.array([speed_rate * sin + turn * cos, speed_rate * cos - turn * sin]))
