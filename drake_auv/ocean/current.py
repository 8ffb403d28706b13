"""The mean current and its vertical profile (pure numpy).

Directions are the way the water flows TOWARDS, in degrees clockwise from north; the world
frame is x east, y north, z up (sea surface z = 0, depth = -z). A profile is a factor of depth
that scales the depth-uniform part of the current (mean, tides, turbulence), either

- a depth table: factors `factor` at depths `depth_m`, linear between them, the end values
  beyond; or
- a power-law boundary layer towards the seabed: factor (h_b / delta)^alpha at a height h_b
  above a seabed at `seabed_depth_m`, within a layer of thickness delta (`boundary_layer_m`,
  default the whole water column), 1 above it and 0 below the seabed; alpha = 1/7 (the
  classical turbulent boundary-layer exponent) by default.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate

MAX_CURRENT_MPS = 5.0  # the fastest tidal races run at 4-5 m/s; anything above is a typo
_DIRECTION = dict(low=-360.0, high=360.0, unit="deg")


def towards_unit(towards_deg) -> np.ndarray:
    """World-frame horizontal unit vectors (..., 2) (east, north) of directions `towards_deg`
    (deg clockwise from north)."""
    angle = np.radians(towards_deg)
    return np.stack([np.sin(angle), np.cos(angle)], axis=-1)


def horizontal_velocity(speed_mps, towards_deg) -> np.ndarray:
    """World-frame velocity (..., 2), m/s, of a flow of `speed_mps` towards `towards_deg`."""
    return np.asarray(speed_mps, dtype=float)[..., None] * towards_unit(towards_deg)


@dataclass(frozen=True)
class MeanCurrent:
    """A steady current of `speed_mps` flowing towards `towards_deg` (clockwise from north)."""

    speed_mps: float = param(0.0, low=0.0, high=MAX_CURRENT_MPS, unit="m/s")
    towards_deg: float = param(0.0, **_DIRECTION)

    def __post_init__(self):
        validate(self)

    def velocity(self) -> np.ndarray:
        """World-frame horizontal velocity (2,), m/s."""
        return horizontal_velocity(self.speed_mps, self.towards_deg)


@dataclass(frozen=True)
class VerticalProfile:
    """The current's factor over depth: a table (`depth_m`, `factor`) or a power law
    (`seabed_depth_m`, `boundary_layer_m`, `exponent`); neither: uniform (factor 1)."""

    depth_m: tuple | None = param(None, low=0.0, high=11000.0, unit="m", nullable=True)
    factor: tuple | None = param(None, low=0.0, high=10.0, nullable=True)
    seabed_depth_m: float | None = param(None, low=0.0, high=11000.0, low_open=True, unit="m",
                                         nullable=True)
    boundary_layer_m: float | None = param(None, low=0.0, high=11000.0, low_open=True,
                                           unit="m", nullable=True)
    exponent: float = param(1.0 / 7.0, low=0.0, high=1.0, low_open=True)

    def __post_init__(self):
        validate(self)
        table = self.depth_m is not None or self.factor is not None
        if table and self.seabed_depth_m is not None:
            raise ValueError("a depth table (depth_m, factor) and a power law (seabed_depth_m) "
                             "together; must be one of them")
        if table:
            depth = np.atleast_1d(np.asarray(self.depth_m if self.depth_m is not None else (),
                                             dtype=float))
            count = np.atleast_1d(np.asarray(self.factor if self.factor is not None else ())).size
            if depth.size == 0 or depth.size != count:
                raise ValueError(f"depth_m has {depth.size} values and factor {count}; must "
                                 "be non-empty lists of equal length")
            if np.any(np.diff(depth) <= 0.0):
                raise ValueError(f"depth_m = {depth.tolist()} is not strictly increasing; "
                                 "must be depths in m, positive down, increasing")
        if self.boundary_layer_m is not None and (
                self.seabed_depth_m is None or self.boundary_layer_m > self.seabed_depth_m):
            raise ValueError(f"boundary_layer_m = {self.boundary_layer_m!r} without "
                             "seabed_depth_m or deeper than it; must be in (0, seabed_depth_m] m")

    @property
    def uniform(self) -> bool:
        """Neither a table nor a power law: the factor is 1 at every depth."""
        return self.depth_m is None and self.seabed_depth_m is None

    def factor_at(self, z) -> np.ndarray:
        """The factor at world heights `z` (m, z up), same shape."""
        z = np.asarray(z, dtype=float)
        if self.depth_m is not None:
            return np.interp(-z, np.atleast_1d(self.depth_m), np.atleast_1d(self.factor))
        if self.seabed_depth_m is not None:
            layer = (self.seabed_depth_m if self.boundary_layer_m is None
                     else self.boundary_layer_m)
            return np.minimum(np.maximum((z + self.seabed_depth_m) / layer, 0.0), 1.0) \
                ** self.exponent
        return np.ones_like(z)
