"""The `ocean:` section of a mission file, validated (pure Python, numpy for the model).

    ocean: none                       # still water (the default)
    ocean:
      current: {speed_mps, towards_deg}
      profile: {depth_m: [..], factor: [..]} or {seabed_depth_m, boundary_layer_m, exponent}
      tides: [{name, amplitude_mps, phase_deg, flood_towards_deg, ebb_towards_deg,
               speed_deg_per_h}, ...]   or a CSV path (time_utc,east_mps,north_mps)
      turbulence: {speed_sd_mps, direction_sd_deg, time_constant_s}
      waves: {hs_m, tp_s, towards_deg, spreading, gamma, components, depth_m}
      file: PATH                      # a CF netCDF gridded current, added to the rest
      start_utc: "YYYY-MM-DDTHH:MM:SSZ"

Each part's keys, ranges and defaults are its algorithm's parameter class (`MeanCurrent`,
`VerticalProfile`, `TidalConstituent`, `Turbulence`, `WaveSpectrum`). A bad value raises
`OceanSpecError`, one line naming the dotted key, what is wrong and what is allowed.
"""

from __future__ import annotations

import dataclasses
import datetime
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.ocean.clock import TIDE_EPOCH_UTC, UTC_FORMAT, parse_utc
from drake_auv.ocean.current import MAX_CURRENT_MPS, MeanCurrent, VerticalProfile
from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.tides import TidalConstituent, TidalHarmonics, TidalSeries
from drake_auv.ocean.turbulence import Turbulence
from drake_auv.ocean.waves import WaveField, WaveSpectrum
from drake_auv.params import ParameterError, checks, is_number

PARTS = dict(current=MeanCurrent, profile=VerticalProfile, turbulence=Turbulence,
             waves=WaveSpectrum)
OCEAN_KEYS = ("current", "profile", "tides", "turbulence", "waves", "file", "start_utc")
_FILE = "a file path, relative to the mission file"


class OceanSpecError(ValueError):
    """A bad `ocean:` value: `<dotted.key>: <what is wrong>; allowed: <...>`."""

    def __init__(self, where: str, what: str, allowed: str):
        self.where, self.what, self.allowed = where, what, allowed
        super().__init__(" ".join(f"{where}: {what}; allowed: {allowed}".split()))


@dataclass(frozen=True)
class OceanSpec:
    """A validated sea. `tides`: constituents, or `tides_file` a CSV series (not both);
    `waves` None: a flat sea; `file` a CF netCDF current; `start_utc` the dive's t = 0 on
    the UTC clock (None: the file's first time, else the tides' epoch)."""

    current: MeanCurrent = MeanCurrent()
    profile: VerticalProfile = VerticalProfile()
    tides: tuple = ()
    tides_file: Path | None = None
    turbulence: Turbulence = Turbulence()
    waves: WaveSpectrum | None = None
    file: Path | None = None
    start_utc: str | None = None

    def __post_init__(self):
        if self.start_utc is not None:
            try:
                parse_utc(self.start_utc)
            except ValueError:
                raise OceanSpecError("ocean.start_utc", f"{self.start_utc!r} is not a UTC "
                                     "time", UTC_FORMAT) from None
        peak = self.current.speed_mps + sum(c.amplitude_mps for c in self.tides)
        if peak > MAX_CURRENT_MPS:
            raise OceanSpecError("ocean.tides", f"the mean current and the tides' amplitudes "
                                 f"reach {peak:g} m/s", f"a current of at most "
                                 f"{MAX_CURRENT_MPS:g} m/s (speed_mps + sum of amplitude_mps)")

    def start_s(self, file_first_s: float | None = None) -> float:
        """UTC seconds since 1970 of the dive's t = 0: `start_utc`, else the gridded file's
        first time `file_first_s` (UTC s), else the tides' epoch."""
        if self.start_utc is not None:
            return parse_utc(self.start_utc)
        return file_first_s if file_first_s is not None else parse_utc(TIDE_EPOCH_UTC)

    def tidal(self) -> TidalSeries | TidalHarmonics | None:
        """The tides: the CSV series, the harmonics on the tides' epoch, or None."""
        if self.tides_file is not None:
            return TidalSeries.from_csv(self.tides_file)
        return TidalHarmonics(self.tides, parse_utc(TIDE_EPOCH_UTC)) if self.tides else None

    def model(self, wave_rng: np.random.Generator, crs=None, origin=(0.0, 0.0)) -> OceanModel:
        """The `OceanModel` of this sea in a site's local frame (`crs`, `origin`: see
        `GriddedCurrent.from_netcdf`); `wave_rng` draws the waves' phases and directions."""
        gridded = None
        if self.file is not None:
            from drake_auv.ocean.gridded import GriddedCurrent  # netCDF4 only when used
            gridded = GriddedCurrent.from_netcdf(self.file, crs, origin)
        waves = (WaveField(self.waves, wave_rng)
                 if self.waves is not None and self.waves.hs_m > 0.0 else None)
        return OceanModel(self.current, self.profile, self.tidal(), self.turbulence, waves,
                          gridded, self.start_s(gridded.first_time_s if gridded else None))


def _coerce(check, value):
    """A YAML value as the field's type: integers as float (or int where `integer`), lists
    as tuples; anything else left for `validate` to name."""
    if isinstance(value, list):
        return tuple(float(v) if is_number(v) else v for v in value)
    if check.kind == "number" and is_number(value):
        return int(value) if check.integer and float(value).is_integer() else float(value)
    return value


def _part(cls, raw, where: str):
    """`cls` from the mapping `raw` (keys: its checked fields)."""
    fields = checks(cls)
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise OceanSpecError(where, f"{raw!r} is not a mapping", "a mapping of "
                             + ", ".join(fields))
    for key in raw:
        if key not in fields:
            raise OceanSpecError(f"{where}.{key}", "unknown key", ", ".join(fields))
    try:
        return cls(**{key: _coerce(fields[key], value) for key, value in raw.items()})
    except ParameterError as err:
        value = list(err.value) if isinstance(err.value, tuple) else err.value
        raise OceanSpecError(f"{where}.{err.name}", f"{value!r} {err.what}",
                             fields[err.name].allowed()) from None
    except TypeError as err:  # a required field left out
        missing = [k for k, f in fields.items() if k not in raw and _required(cls, k)]
        raise OceanSpecError(f"{where}.{missing[0] if missing else ''}".rstrip("."),
                             "missing (required)", ", ".join(fields)) from err
    except ValueError as err:  # a rule tying fields together
        what, _, allowed = str(err).partition("; must be ")
        raise OceanSpecError(where, what, allowed or "see the ocean section's keys") from None


def _required(cls, name: str) -> bool:
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    return f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING


def ocean_from_raw(raw, base_dir=".", where: str = "ocean") -> OceanSpec | None:
    """The `ocean:` value of a mission file (None or "none": still water, None) as an
    `OceanSpec`; paths relative to `base_dir`."""
    if raw is None or raw == "none":
        return None
    if not isinstance(raw, dict):
        raise OceanSpecError(where, f"{raw!r} is not a mapping", "none or a mapping of "
                             + ", ".join(OCEAN_KEYS))
    for key in raw:
        if key not in OCEAN_KEYS:
            raise OceanSpecError(f"{where}.{key}", "unknown key", ", ".join(OCEAN_KEYS))
    kwargs = {key: _part(cls, raw[key], f"{where}.{key}") for key, cls in PARTS.items()
              if key in raw and not (key == "waves" and raw[key] in (None, "none"))}
    tides = raw.get("tides")
    if isinstance(tides, str):
        kwargs["tides_file"] = _path(tides, base_dir, f"{where}.tides", "a CSV file")
    elif isinstance(tides, list):
        kwargs["tides"] = tuple(_part(TidalConstituent, item, f"{where}.tides[{i}]")
                                for i, item in enumerate(tides))
    elif tides is not None:
        raise OceanSpecError(f"{where}.tides", f"{tides!r} is not a list or a path",
                             "a list of constituents (name, amplitude_mps, phase_deg, "
                             "flood_towards_deg, ...) or a CSV path")
    if raw.get("file") is not None:
        kwargs["file"] = _path(raw["file"], base_dir, f"{where}.file", "a CF netCDF file")
        from drake_auv.ocean.gridded import GriddedCurrent  # netCDF4 only when used
        try:
            GriddedCurrent.check_file(kwargs["file"])
        except ValueError as err:
            what, _, allowed = str(err).partition("; must be ")
            raise OceanSpecError(f"{where}.file", what.removeprefix("ocean.file: "),
                                 allowed or "a CF netCDF current") from None
    if raw.get("start_utc") is not None:
        kwargs["start_utc"] = _utc_text(raw["start_utc"])
    return OceanSpec(**kwargs)


def _utc_text(value):
    """`start_utc` as text: YAML reads an unquoted `2024-03-01T06:00:00Z` (in a file or a
    `--set`) as a UTC datetime, written back here as `YYYY-MM-DDTHH:MM:SSZ`; a time without a
    zone stays a datetime and is refused."""
    if isinstance(value, datetime.datetime) and value.utcoffset() == datetime.timedelta(0):
        return value.strftime("%Y-%m-%dT%H:%M:%SZ")
    return value


def _path(value, base_dir, where: str, what: str) -> Path:
    if not isinstance(value, str) or not value.strip():
        raise OceanSpecError(where, f"{value!r} is not a path", f"{what}: {_FILE}")
    path = (Path(base_dir) / Path(value).expanduser()).resolve()
    if not path.is_file():
        raise OceanSpecError(where, f"{path.name} not found ({path})", f"{what}: {_FILE}")
    return path


def _plain(obj) -> dict:
    out = {}
    for key in checks(type(obj)):
        value = getattr(obj, key)
        out[key] = list(value) if isinstance(value, tuple) else value
    return out


def ocean_to_raw(spec: OceanSpec | None):
    """The mission-file value of `spec` (`ocean_from_raw` reads it back to an equal spec)."""
    if spec is None:
        return "none"
    out = {"current": _plain(spec.current), "profile": _plain(spec.profile),
           "tides": (str(spec.tides_file) if spec.tides_file is not None
                     else [_plain(c) for c in spec.tides]),
           "turbulence": _plain(spec.turbulence),
           "waves": _plain(spec.waves) if spec.waves is not None else None}
    if spec.file is not None:
        out["file"] = str(spec.file)
    if spec.start_utc is not None:
        out["start_utc"] = spec.start_utc
    return out
