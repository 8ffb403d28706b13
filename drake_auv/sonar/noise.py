"""Sonar error models: range noise, dropouts, spurious returns, sea-surface reflections.

All are off by default and draw from a generator the caller seeds, so a run is repeatable.
The order of application: surface reflection, spurious return, dropout, then range noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SonarNoise:
    """Error options of a sonar (all zero: a perfect sensor).

    Attributes:
        range_sigma: standard deviation of Gaussian range noise, m, >= 0.
        dropout_prob: probability that a return is lost, in [0, 1].
        spurious_prob: probability that a beam reports a random range, uniform in
            (0, max_range), whatever it hit (water-column clutter), in [0, 1].
        surface_prob: probability that a beam reaching the sea surface (z = 0) before any
            other return echoes from it, in [0, 1] (the outliers of the reference's maps).
    """

    range_sigma: float = 0.0
    dropout_prob: float = 0.0
    spurious_prob: float = 0.0
    surface_prob: float = 0.0

    def __post_init__(self):
        if not (np.isfinite(self.range_sigma) and self.range_sigma >= 0):
            raise ValueError(f"SonarNoise.range_sigma must be >= 0 m, got {self.range_sigma}")
        for name in ("dropout_prob", "spurious_prob", "surface_prob"):
            value = getattr(self, name)
            if not (np.isfinite(value) and 0.0 <= value <= 1.0):
                raise ValueError(f"SonarNoise.{name} must be in [0, 1], got {value}")

    @property
    def enabled(self) -> bool:
        return bool(self.range_sigma or self.dropout_prob or self.spurious_prob
                    or self.surface_prob)


def apply_noise(ranges: np.ndarray, origin_world: np.ndarray, directions_world: np.ndarray,
                max_range: float, noise: SonarNoise, rng: np.random.Generator) -> np.ndarray:
    """Noisy copy of `ranges` (n,), NaN for no return.

    Args:
        ranges: true first-hit ranges, m, NaN for no hit.
        origin_world: (3,) true sensor origin (world frame, sea surface at z = 0).
        directions_world: (n, 3) unit beam directions in the world frame.
        max_range: m; noisy ranges beyond it are dropped, below zero clipped to zero.
        noise: the error options.
        rng: seeded generator.
    """
    out = np.array(ranges, dtype=float)
    if not noise.enabled:
        return out
    n = len(out)
    if noise.surface_prob > 0 and origin_world[2] < 0:
        up = directions_world[:, 2] > 1e-9
        t = np.full(n, np.inf)
        t[up] = -origin_world[2] / directions_world[up, 2]
        first = (t < max_range) & ~(out <= t)  # NaN (no hit) compares False: surface first
        reflect = first & (rng.random(n) < noise.surface_prob)
        out[reflect] = t[reflect]
    if noise.spurious_prob > 0:
        spurious = rng.random(n) < noise.spurious_prob
        out[spurious] = rng.uniform(0.0, max_range, size=int(spurious.sum()))
    if noise.dropout_prob > 0:
        out[rng.random(n) < noise.dropout_prob] = np.nan
    if noise.range_sigma > 0:
        out = np.maximum(out + rng.normal(0.0, noise.range_sigma, size=n), 0.0)
        out[out > max_range] = np.nan
    return out
