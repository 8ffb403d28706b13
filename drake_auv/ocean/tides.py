"""Tidal currents: harmonic constituents, or a time series read from a CSV (pure numpy).

A constituent i flows along its flood/ebb axis with the signed speed
    s_i(t) = A_i cos(omega_i (t - t_epoch) - phi_i)
(A_i `amplitude_mps`, omega_i the angular speed, deg/h, known by name for the usual
constituents, phi_i `phase_deg`): towards `flood_towards_deg` while s_i >= 0, towards
`ebb_towards_deg` (default: the opposite) while s_i < 0. The phases are referenced to the
tides' epoch t_epoch (`clock.TIDE_EPOCH_UTC` unless given), so `start_utc` places the dive on
the tide. The speeds are the standard ones (Schureman; NOAA's harmonic-constant tables); no
nodal (f, u) corrections are applied: the amplitudes and phases are taken as given for the
period simulated.

A series (`TidalSeries`) is a CSV with a header `time_utc,east_mps,north_mps` (ISO UTC times,
increasing; world-frame components, m/s), interpolated linearly in time.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.ocean.clock import format_utc, parse_utc
from drake_auv.ocean.current import MAX_CURRENT_MPS, towards_unit
from drake_auv.params import param, validate

# Angular speeds, deg per mean solar hour.
CONSTITUENT_SPEEDS_DEG_PER_H = {
    "M2": 28.9841042, "S2": 30.0, "N2": 28.4397295, "K2": 30.0821373, "2N2": 27.8953548,
    "MU2": 27.9682084, "NU2": 28.5125831, "L2": 29.5284789, "T2": 29.9589333,
    "K1": 15.0410686, "O1": 13.9430356, "P1": 14.9589314, "Q1": 13.3986609,
    "M4": 57.9682084, "MS4": 58.9841042, "MN4": 57.4238337, "M6": 86.9523127,
    "M8": 115.9364166, "MF": 1.0980331, "MM": 0.5443747, "SSA": 0.0821373, "SA": 0.0410686,
}
_DIRECTION = dict(low=-360.0, high=360.0, unit="deg")


@dataclass(frozen=True)
class TidalConstituent:
    """One harmonic: `amplitude_mps` along flood (`flood_towards_deg`) and ebb
    (`ebb_towards_deg`, default flood + 180) at `speed_deg_per_h` (default: by `name`)."""

    name: str = param(kind="text")
    amplitude_mps: float = param(0.0, low=0.0, high=MAX_CURRENT_MPS, unit="m/s")
    phase_deg: float = param(0.0, **_DIRECTION)
    flood_towards_deg: float = param(0.0, **_DIRECTION)
    ebb_towards_deg: float | None = param(None, **_DIRECTION, nullable=True)
    speed_deg_per_h: float | None = param(None, low=0.0, high=360.0, low_open=True,
                                          unit="deg/h", nullable=True)

    def __post_init__(self):
        validate(self)
        if self.speed_deg_per_h is None and self.name.upper() not in CONSTITUENT_SPEEDS_DEG_PER_H:
            raise ValueError(f"constituent {self.name!r} has no known angular speed; must be "
                             "given speed_deg_per_h or named among "
                             + ", ".join(CONSTITUENT_SPEEDS_DEG_PER_H))

    def omega(self) -> float:
        """Angular speed, rad/s."""
        speed = (self.speed_deg_per_h if self.speed_deg_per_h is not None
                 else CONSTITUENT_SPEEDS_DEG_PER_H[self.name.upper()])
        return math.radians(speed) / 3600.0

    def ebb_deg(self) -> float:
        return self.flood_towards_deg + 180.0 if self.ebb_towards_deg is None \
            else self.ebb_towards_deg


class TidalHarmonics:
    """The sum of `constituents`, phases referenced to `epoch_s` (s since 1970 UTC)."""

    def __init__(self, constituents, epoch_s: float):
        self.constituents = tuple(constituents)
        self.epoch_s = float(epoch_s)
        self._amplitude = np.array([c.amplitude_mps for c in self.constituents])
        self._omega = np.array([c.omega() for c in self.constituents])
        self._phase = np.radians([c.phase_deg for c in self.constituents])
        # the flood axis while a constituent's signed speed s >= 0, else minus the ebb axis:
        # s times it is |s| along the axis the water flows towards
        self._flood = towards_unit(np.array([c.flood_towards_deg for c in self.constituents]))
        self._ebb_reversed = -towards_unit(np.array([c.ebb_deg() for c in self.constituents]))
        self._rate_gain = -self._amplitude * self._omega

    def velocity(self, clock_s: float) -> tuple[np.ndarray, np.ndarray]:
        """World-frame horizontal velocity (2,) m/s and its time derivative (2,) m/s^2 at
        `clock_s` (s since 1970 UTC)."""
        angle = self._omega * (clock_s - self.epoch_s) - self._phase
        speed = self._amplitude * np.cos(angle)
        axis = np.where((speed >= 0.0)[:, None], self._flood, self._ebb_reversed)
        return speed @ axis, (self._rate_gain * np.sin(angle)) @ axis


class TidalSeries:
    """A world-frame tidal current read from a CSV, linear in time."""

    COLUMNS = ("time_utc", "east_mps", "north_mps")

    def __init__(self, clock_s: np.ndarray, velocity: np.ndarray, label: str = "tides"):
        self.clock_s, self.velocity_table, self.label = clock_s, velocity, label

    @classmethod
    def from_csv(cls, path) -> "TidalSeries":
        path = Path(path)
        label = f"tides: {path.name}"
        try:
            with path.open(newline="") as handle:
                rows = list(csv.reader(handle))
        except (OSError, UnicodeDecodeError) as err:
            raise ValueError(f"{label}: cannot be read ({err.__class__.__name__}: "
                             f"{getattr(err, 'strerror', None) or err}); must be a CSV file "
                             "with columns " + ",".join(cls.COLUMNS)) from None
        header = [h.strip() for h in rows[0]] if rows else []
        if not set(cls.COLUMNS) <= set(header):
            raise ValueError(f"{label}: header {header} lacks "
                             f"{sorted(set(cls.COLUMNS) - set(header))}; must have columns "
                             + ",".join(cls.COLUMNS))
        index = [header.index(c) for c in cls.COLUMNS]
        times, values = [], []
        for n, row in enumerate(rows[1:], start=2):
            if not any(cell.strip() for cell in row):
                continue
            try:
                times.append(parse_utc(row[index[0]].strip(), f"{label}: line {n}: time_utc"))
                values.append([float(row[index[1]]), float(row[index[2]])])
            except (IndexError, ValueError) as err:
                raise ValueError(f"{label}: line {n}: {row!r} is not a row of "
                                 f"{','.join(cls.COLUMNS)} ({err})") from None
        clock, velocity = np.array(times), np.array(values, dtype=float).reshape(-1, 2)
        if clock.size < 2 or np.any(np.diff(clock) <= 0.0):
            raise ValueError(f"{label}: {clock.size} rows; must have at least 2 rows with "
                             "increasing time_utc")
        if not np.all(np.isfinite(velocity)) or np.hypot(*velocity.T).max() > MAX_CURRENT_MPS:
            raise ValueError(f"{label}: a velocity is not finite or above "
                             f"{MAX_CURRENT_MPS:g} m/s; must be in [0, {MAX_CURRENT_MPS:g}] m/s")
        return cls(clock, velocity, label)

    def check_span(self, start_s: float, end_s: float, span: str = "") -> None:
        """Refuses a dive [start_s, end_s] (s since 1970 UTC) outside the series; `span`:
        what sets the dive's end, named in the refusal."""
        if start_s < self.clock_s[0] or end_s > self.clock_s[-1]:
            raise ValueError(f"{self.label}: covers {format_utc(self.clock_s[0])} to "
                             f"{format_utc(self.clock_s[-1])}, not the dive's "
                             f"{format_utc(start_s)} to {format_utc(end_s)}"
                             + (f" ({span})" if span else ""))

    def velocity(self, clock_s: float) -> tuple[np.ndarray, np.ndarray]:
        """World-frame horizontal velocity (2,) m/s and its time derivative (2,) m/s^2;
        ValueError outside the series (it is not extrapolated)."""
        if not self.clock_s[0] <= clock_s <= self.clock_s[-1]:
            self.check_span(clock_s, clock_s)
        k = int(np.clip(np.searchsorted(self.clock_s, clock_s, side="right") - 1, 0,
                        self.clock_s.size - 2))
        span = self.clock_s[k + 1] - self.clock_s[k]
        rate = (self.velocity_table[k + 1] - self.velocity_table[k]) / span
        return self.velocity_table[k] + rate * (clock_s - self.clock_s[k]), rate
