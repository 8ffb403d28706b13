"""`OceanModel`: the water's velocity and acceleration anywhere, any time (pure numpy).

The water velocity at time t (s, the dive's clock) and world point p = (x east, y north,
z up) is

    v(t, p) = f(z) [U_turb(t) ; 0] + v_file(t0 + t, p) + v_waves(t, p)

with U_turb the horizontal mean current plus tides perturbed by the turbulence's deviation
(`turbulence.perturb`), f the vertical profile, v_file the gridded current and v_waves the
orbital velocity; t0 (`start_s`) places the dive on the UTC clock of the tides and the file.
The acceleration is the local time derivative dv/dt of the same terms (the turbulence held
between its updates). The turbulence state is an argument: the model is a pure function.
"""

from __future__ import annotations

import numpy as np

from drake_auv.ocean.current import MeanCurrent, VerticalProfile
from drake_auv.ocean.tides import TidalSeries
from drake_auv.ocean.turbulence import Turbulence, perturb


class OceanModel:
    """The composed sea; each part optional (None) but the mean current and profile."""

    def __init__(self, mean: MeanCurrent | None = None, profile: VerticalProfile | None = None,
                 tides=None, turbulence: Turbulence | None = None, waves=None, gridded=None,
                 start_s: float = 0.0):
        """`tides`: a `TidalHarmonics` or `TidalSeries`; `waves`: a `WaveField`; `gridded`:
        a `GriddedCurrent`; `start_s`: UTC seconds since 1970 of the dive's t = 0."""
        self.mean = mean if mean is not None else MeanCurrent()
        self.profile = profile if profile is not None else VerticalProfile()
        self.tides, self.waves, self.gridded = tides, waves, gridded
        self.turbulence = turbulence if turbulence is not None else Turbulence()
        self.start_s = float(start_s)
        self._mean_velocity = self.mean.velocity()

    def check(self, box, deepest_m: float, duration_s: float, route=None,
              span: str = "") -> None:
        """Refuses (one line) a dive the sea's files do not cover: the site's local box
        (xmin, ymin, xmax, ymax, m), its deepest point (m), the dive's `duration_s` from
        t = 0 (`span`: what sets it, for the refusal) and, for a gridded file, the `route`'s
        local points (n, 3) in water cells."""
        end_s = self.start_s + duration_s
        if isinstance(self.tides, TidalSeries):
            self.tides.check_span(self.start_s, end_s, span)
        if self.gridded is not None:
            self.gridded.check_coverage(box, deepest_m, self.start_s, end_s, span)
            if route is not None:
                self.gridded.check_route(route, self.start_s, end_s)

    def horizontal(self, t: float, deviation) -> tuple[np.ndarray, np.ndarray]:
        """The depth-uniform current U_turb (2,) m/s and its rate (2,) m/s^2 at time t."""
        velocity, rate = self._mean_velocity, np.zeros(2)
        if self.tides is not None:
            tide, tide_rate = self.tides.velocity(self.start_s + t)
            velocity, rate = velocity + tide, rate + tide_rate
        if self.turbulence.enabled:
            velocity, rate = perturb(velocity, rate, deviation)
        return velocity, rate

    def water(self, t: float, positions, deviation=(0.0, 0.0)
              ) -> tuple[np.ndarray, np.ndarray]:
        """World-frame water velocity (n, 3) m/s and acceleration (n, 3) m/s^2 at time `t`
        (s) and `positions` (n, 3), m; `deviation` the turbulence state (2,)."""
        both = self.sample(t, positions, deviation)
        return both[:, :3], both[:, 3:]

    def sample(self, t: float, positions, deviation=(0.0, 0.0)) -> np.ndarray:
        """`water` as one array (n, 6): velocity then acceleration (the `Ocean` system's
        sample, built with few array operations)."""
        positions = np.asarray(positions, dtype=float).reshape(-1, 3)
        both = np.zeros((positions.shape[0], 6))  # f(z) [U_turb, 0, its rate, 0], then ...
        both[:, :2], both[:, 3:5] = self.horizontal(t, deviation)
        if not self.profile.uniform:
            both *= self.profile.factor_at(positions[:, 2:3])
        if self.gridded is not None:
            v, a = self.gridded.water(self.start_s + t, positions)
            both[:, :3] += v
            both[:, 3:] += a
        if self.waves is not None:
            both += self.waves.sample(t, positions)
        return both
