"""Sonar error models: the beam's side lobes and detection threshold, sea-surface multipath,
clutter, dropouts and range noise.

All are off by default and draw from a generator the caller seeds, so a run is repeatable.
The beam pattern, the threshold and the surface multipath act on the rays of each beam in
`drake_auv.sonar.beams.scan` (they need the ray casting); `apply_noise` then adds, in order,
spurious returns, dropouts and range noise to the beams' ranges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate


@dataclass(frozen=True)
class SonarNoise:
    """Error options of a sonar (all zero: a perfect sensor).

    Attributes:
        range_sigma: standard deviation of Gaussian range noise, m, >= 0.
        dropout_prob: probability that a return is lost, in [0, 1].
        spurious_prob: probability that a beam reports a random range, uniform in
            (0, max_range), whatever it hit (water-column clutter), in [0, 1].
        surface_prob: probability that a ray of a beam reaching the sea surface (z = 0) before
            anything else is reflected there (mirrored) and goes on (the rest is scattered
            away), in [0, 1]; an echo of the reflected ray comes back along the same path and
            is reported at the total path length along the beam's axis, i.e. in the water
            column (the outliers of the reference's breakwater map).
        side_lobe_deg: angle of the beam's side lobe from its axis, deg, in [0, 90]; two
            rays, across the scan plane on either side of it, are cast there.
        side_lobe_gain: the side lobe's two-way intensity relative to the axis, in [0, 1]
            (0: no side lobe).
        echo_threshold: detection threshold on a ray's echo intensity, gain * cos^2(incidence)
            (Lambertian backscatter, after the sonar's time-varied gain has removed the
            spreading loss), relative to an on-axis echo at normal incidence, in [0, 1); the
            beam reports the first detected echo. 0: every echo is detected.
    """

    range_sigma: float = param(0.0, low=0.0, unit="m")
    dropout_prob: float = param(0.0, low=0.0, high=1.0)
    spurious_prob: float = param(0.0, low=0.0, high=1.0)
    surface_prob: float = param(0.0, low=0.0, high=1.0)
    side_lobe_deg: float = param(0.0, low=0.0, high=90.0, unit="deg")
    side_lobe_gain: float = param(0.0, low=0.0, high=1.0)
    echo_threshold: float = param(0.0, low=0.0, high=1.0, high_open=True)

    def __post_init__(self):
        validate(self)

    @property
    def enabled(self) -> bool:
        return bool(self.range_sigma or self.dropout_prob or self.spurious_prob
                    or self.surface_prob or self.side_lobe_gain or self.echo_threshold)

    @property
    def side_lobe(self) -> bool:
        """Whether side-lobe rays are cast."""
        return self.side_lobe_gain > 0 and self.side_lobe_deg > 0


def apply_noise(ranges: np.ndarray, max_range: float, noise: SonarNoise,
                rng: np.random.Generator) -> np.ndarray:
    """Noisy copy of the beams' `ranges` (n,), m, NaN for no return: clutter, dropouts, range
    noise (noisy ranges beyond `max_range` are dropped, below zero clipped to zero)."""
    out = np.array(ranges, dtype=float)
    n = len(out)
    if noise.spurious_prob > 0:
        spurious = rng.random(n) < noise.spurious_prob
        out[spurious] = rng.uniform(0.0, max_range, size=int(spurious.sum()))
    if noise.dropout_prob > 0:
        out[rng.random(n) < noise.dropout_prob] = np.nan
    if noise.range_sigma > 0:
        out = np.maximum(out + rng.normal(0.0, noise.range_sigma, size=n), 0.0)
        out[out > max_range] = np.nan
    return out
