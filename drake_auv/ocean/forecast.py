"""The current a plan can know in advance: the forecast of a mission's sea (pure numpy).

A vehicle does not measure the water it will meet; what a planner can use is the forecast
the mission states: the mean current with its vertical profile plus the tides, evaluated at
the time. The turbulence and the waves are random (their draws are the simulation's truth,
not a forecast), and a gridded `file:` needs the site's frame to be placed, so neither is in
the forecast. A still sea (no `ocean:`, or no mean current and no tides) has no forecast.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.spec import OceanSpec

Forecast = Callable[[float, np.ndarray], np.ndarray]


def forecast(spec: OceanSpec | None) -> Forecast | None:
    """`f(t, positions) -> (n, 3)`: the forecast water velocity, world frame (x east, y north,
    z up), m/s, at the dive's time `t` (s) and world `positions` (n, 3), m; the mean current
    times the profile's factor plus the tides. None for a still sea (`spec` None, or no mean
    current and no tides). The dive's t = 0 is `start_utc` on the tides' clock, else their
    epoch, else the gridded file's first time (read from the file's time axis)."""
    if spec is None or (spec.current.speed_mps == 0.0 and not spec.tides
                        and spec.tides_file is None):
        return None
    file_first_s = None
    if spec.file is not None and spec.start_utc is None:
        from drake_auv.ocean.gridded import first_time_s  # netCDF4 only when used
        file_first_s = first_time_s(spec.file)
    model = OceanModel(spec.current, spec.profile, spec.tidal(),
                       start_s=spec.start_s(file_first_s))

    def water(t: float, positions) -> np.ndarray:
        return model.water(t, positions)[0]

    return water
