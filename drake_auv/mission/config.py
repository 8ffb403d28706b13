"""Mission files: reading and writing them (pure Python, no Drake).

`load_mission` reads a file or a built-in mission (`builtin_missions()`), applies `--set`-style
overrides to the raw mapping (`drake_auv.mission.overrides`), then validates it into the frozen
dataclasses of `drake_auv.mission.spec`; `mission_to_dict` gives the validated mission back as a
plain mapping (defaults filled in) that `mission_from_dict` reads. Paths are relative to the
mission file and stored resolved absolute; a field whose file unit differs (`scale`, e.g.
`navigation.heading_bias_deg`) is converted here, both ways.

Every bad value raises `MissionFileError`, one line naming the file, the dotted key and what is
allowed there: the ranges are the dataclasses' own (`drake_auv.params.validate`), this module
only converts the YAML types and ties fields together (`RULES`; a step's: its kind's `check`,
`drake_auv.mission.steps`). The names below are
re-exported so `from drake_auv.mission.config import X` serves every class of the spec.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import yaml

from drake_auv.mission.overrides import apply_overrides, one_line
from drake_auv.ocean.spec import OceanSpecError, ocean_from_raw, ocean_to_raw
from drake_auv.mission.spec import (FAULT_CLASSES, REALISTIC_NOISE, SECTIONS, TOP_KEYS,
                                    FaultsSpec, LimitsSpec, MissionFileError, MissionSpec,
                                    NavigationJumpFault, PayloadSpec, ReplannerSpec, SensorSpec,
                                    SiteSpec, SonarNoiseSpec, SonarSilentFault,
                                    ThrusterFailureFault, mission_keys)
from drake_auv.mission.steps import STEPS, step_specs
from drake_auv.mission.steps.explore import ExploreStep
from drake_auv.mission.steps.fly import FLY_FORMATS, FlyStep
from drake_auv.mission.steps.follow import FollowStep
from drake_auv.mission.steps.plan import PlanStep
from drake_auv.mission.steps.survey import SurveyStep
from drake_auv.mission.yaml_text import MAX_BYTES, MAX_VALUES, YamlLimitError, load_yaml_file
from drake_auv.params import NESTED, ParameterError, is_number, checks
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.sensor import BUILT_IN

SENSOR_NAME = re.compile(r"[a-z][a-z0-9_]*")  # a port's, a topic's and a system's name
BUILTIN_DIR = Path(__file__).resolve().parent / "missions"


def _steps_allowed() -> str:
    return "a non-empty list of one-key mappings: " + ", ".join(STEPS)


def builtin_missions() -> list[str]:
    """Names of the missions shipped in `BUILTIN_DIR`."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.yaml"))


def _coerce(check, value, base_dir):
    """A YAML value as the field's type, in the file's unit (a wrong type is left as it is,
    for `validate` to name): numbers to float or int, a path resolved, a list to a tuple."""
    if check.kind == "number" and is_number(value):
        return int(value) if check.integer and math.isfinite(value) and int(value) == value \
            else float(value)
    if check.kind == "path" and isinstance(value, str) and value.strip():
        return (Path(base_dir) / Path(value).expanduser()).resolve()
    if check.kind == "vector" and isinstance(value, list) and check.problem(value) is None:
        return tuple(float(v) for v in value)
    return value


class _Reader:
    """Validation of one mission: its label (for messages) and the folder paths start from."""

    def __init__(self, label: str, base_dir):
        self.label, self.base_dir = label, Path(base_dir)

    def fail(self, where: str, what: str, allowed: str):
        raise MissionFileError(self.label, where, what, allowed)

    def mapping(self, raw, where: str, keys) -> dict:
        """`raw` as a mapping whose keys are among `keys` (None: empty)."""
        if raw is None:
            return {}
        if not isinstance(raw, dict):
            self.fail(where, f"{raw!r} is not a mapping", "a mapping of " + ", ".join(keys))
        for key in raw:
            if key not in keys:
                self.fail(_join(where, key), "unknown key", ", ".join(keys))
        return raw

    def build(self, cls, values: dict, keys: dict, where: str, path=(), base=None):
        """`cls` from `values` ({field path: value}), or `base` (a `cls`) with them set; a
        nested field is its default with its values set. A `ParameterError` becomes a
        `MissionFileError` naming the key (the value as in the file)."""
        kwargs = {}
        for f in dataclasses.fields(cls):
            inner = {p[1:]: v for p, v in values.items() if p[0] == f.name and len(p) > 1}
            if NESTED in f.metadata and inner:
                default = (getattr(base, f.name) if base is not None
                           else f.default_factory())
                kwargs[f.name] = self.build(type(default), inner, keys, where,
                                            (*path, f.name), default)
            elif (f.name,) in values:
                kwargs[f.name] = values[(f.name,)]
        try:
            return cls(**kwargs) if base is None else dataclasses.replace(base, **kwargs)
        except ParameterError as err:
            key = next(k for k, (p, _) in keys.items() if p == (*path, err.name))
            check = keys[key][1]
            value = (_to_file(check, err.value) if is_number(err.value)
                     else list(err.value) if isinstance(err.value, tuple) else err.value)
            self.fail(_join(where, key), f"{value!r} {err.what}", check.allowed(in_file=True))

    def section(self, cls, raw, where: str):
        """The section `raw` (a mapping of `mission_keys(cls)`, None: all defaults) as `cls`,
        then its `RULES`."""
        keys = mission_keys(cls)
        raw = self.mapping(raw, where, tuple(keys))
        values = {}
        for key, (path, check) in keys.items():
            if key in raw:
                value = _coerce(check, raw[key], self.base_dir)
                values[path] = value * check.scale if check.scale != 1.0 and is_number(
                    value) else value
            elif not _has_default(cls, path):
                self.fail(_join(where, key), "missing (required)", check.allowed(in_file=True))
        obj = self.build(cls, values, keys, where)
        rule = RULES.get(cls)
        if rule is not None:
            rule(self, obj, where)
        return obj

    def payload(self, raw) -> PayloadSpec:
        """The `payload` section, its `sensors` mapping read into `SensorSpec`s in order."""
        raw = dict(self.mapping(raw, "payload", (*mission_keys(PayloadSpec), "sensors")))
        table = raw.pop("sensors", None) or {}
        if not isinstance(table, dict):
            self.fail("payload.sensors", f"{table!r} is not a mapping",
                      "a mapping of sensor name to " + ", ".join(mission_keys(SensorSpec)))
        sensors = []
        for name, body in table.items():
            where = f"payload.sensors.{name}"
            if not isinstance(name, str) or not SENSOR_NAME.fullmatch(name) or name in BUILT_IN:
                self.fail(where, "is not a sensor name", "lower-case letters, digits and _, "
                          "a letter first; not " + ", ".join(BUILT_IN))
            sensors.append(dataclasses.replace(self.section(SensorSpec, body, where), name=name))
        return dataclasses.replace(self.section(PayloadSpec, raw, "payload"),
                                   sensors=tuple(sensors))

    def sonar_noise(self, raw) -> SonarNoiseSpec:
        allowed = "clean, realistic or a mapping of " + ", ".join(mission_keys(SonarNoise))
        if raw == "clean":
            return SonarNoiseSpec("clean", {})
        if raw is None or raw == "realistic":
            return SonarNoiseSpec()
        if not isinstance(raw, dict):
            self.fail("sonar_noise", f"{raw!r} is not a preset or a mapping", allowed)
        noise = self.section(SonarNoise, raw, "sonar_noise")
        return SonarNoiseSpec("custom", {key: getattr(noise, key) for key in raw})

    def faults(self, raw) -> FaultsSpec:
        raw = self.mapping(raw, "faults", tuple(FAULT_CLASSES))
        return FaultsSpec(**{name: self.section(cls, raw.get(name), f"faults.{name}")
                             for name, cls in FAULT_CLASSES.items()})

    def ocean(self, raw):
        """The `ocean:` section (`drake_auv.ocean.spec`): None for still water."""
        try:
            return ocean_from_raw(raw, self.base_dir)
        except OceanSpecError as err:
            self.fail(err.where, err.what, err.allowed)

    def steps(self, raw) -> tuple:
        if not isinstance(raw, list) or not raw:
            self.fail("steps", f"{raw!r} is not a non-empty list", _steps_allowed())
        steps = []
        for i, item in enumerate(raw):
            where = f"steps[{i}]"
            if isinstance(item, str):
                kind, body = item, None
            elif isinstance(item, dict) and len(item) == 1:
                (kind, body), = item.items()
            else:
                self.fail(where, f"{item!r} is not a one-key mapping", _steps_allowed())
            if kind not in STEPS:
                self.fail(where, f"unknown step {kind!r}", ", ".join(STEPS))
            step = self.section(STEPS[kind].spec, body, f"{where}.{kind}")
            STEPS[kind].check(self, step, f"{where}.{kind}")
            steps.append(step)
        for kind in STEPS.values():
            kind.check_steps(self, tuple(steps))
        return tuple(steps)

    def prior_needed(self, site: SiteSpec, steps: tuple) -> None:
        """A site given by its world file alone has no prior map: the steps that plan or
        place themselves on one (plan, follow, fly) are refused, explore steps need none."""
        if site.world is None or site.prior is not None or site.prior_from_world:
            return
        for i, step in enumerate(steps):
            if STEPS[step.KIND].needs_prior:
                self.fail(f"steps[{i}].{step.KIND}", "needs a prior map and the site has "
                          "none (site.prior is missing)", "site.prior: <raster>, site."
                          "prior_from_world: true (sampled from the world mesh), or explore "
                          "steps only")

    def mission(self, raw, source) -> MissionSpec:
        raw = self.mapping(raw, "", TOP_KEYS)
        for key in ("site", "steps"):
            if key not in raw:
                self.fail(key, "missing (required)",
                          "a site mapping" if key == "site" else _steps_allowed())
        top = {key: raw.get(key, default) for key, default in
               (("name", Path(self.label).stem), ("seed", 0), ("description", None))}
        for key, value in top.items():  # MissionSpec's own checks, before its sections
            check = checks(MissionSpec)[key]
            top[key] = value = _coerce(check, value, self.base_dir)
            what = check.problem(value)
            if what is not None:
                self.fail(key, f"{value!r} {what}", check.allowed())
        sections = {key: self.payload(raw.get(key)) if cls is PayloadSpec
                    else self.section(cls, raw.get(key), key) for key, cls in SECTIONS.items()}
        steps = self.steps(raw["steps"])
        self.prior_needed(sections["site"], steps)
        return MissionSpec(**top, **sections,
                           sonar_noise=self.sonar_noise(raw.get("sonar_noise")),
                           faults=self.faults(raw.get("faults")),
                           ocean=self.ocean(raw.get("ocean")), steps=steps, source=source)


def _has_default(cls, path) -> bool:
    f = next(f for f in dataclasses.fields(cls) if f.name == path[0])
    return (len(path) > 1 or f.default is not dataclasses.MISSING
            or f.default_factory is not dataclasses.MISSING)


def _to_file(check, value):
    """A field value in the mission file's unit (12 significant digits where scaled, so a
    value read from a file is written back as it was)."""
    return float(f"{value / check.scale:.12g}") if check.scale != 1.0 else value


def _join(where: str, key) -> str:
    return f"{where}.{key}" if where else str(key)


def _site_rule(reader: _Reader, v, where: str):
    if sum(getattr(v, key) is not None for key in ("scenario", "world", "tile")) != 1:
        reader.fail(where, "needs exactly one of scenario, world or tile",
                    "scenario: <name>, world: <mesh file> or tile: <GeoTIFF> with roi")
    if (v.tile is None) != (v.roi is None):
        reader.fail(f"{where}.roi", "goes with tile (both or neither)",
                    checks(SiteSpec)["roi"].allowed() + ", with tile")
    if v.roi is not None and not (v.roi[0] < v.roi[2] and v.roi[1] < v.roi[3]):
        reader.fail(f"{where}.roi", f"{list(v.roi)} has min >= max",
                    "xmin < xmax and ymin < ymax")
    if v.world is None:
        for key in ("target", "prior", "crs"):
            if getattr(v, key) is not None:
                reader.fail(f"{where}.{key}", "only for a site given by its world file",
                            "null with a scenario or a tile")
    if v.prior_from_world and (v.world is None or v.prior is not None):
        reader.fail(f"{where}.prior_from_world", "only for a world file without a prior "
                    "raster", "false, or true with world and no prior")


RULES = {SiteSpec: _site_rule}  # a section's rules; a step's are its kind's `check`


def mission_from_dict(raw: dict, base_dir, label: str, source: Path | None = None
                      ) -> MissionSpec:
    """Validates a raw mission mapping (paths relative to `base_dir`); errors name `label`."""
    return _Reader(label, base_dir).mission(raw, source)


def _plain(obj) -> dict:
    """The mission-file mapping of a section (`mission_keys` of its class)."""
    out = {}
    for key, (path, check) in mission_keys(type(obj)).items():
        value = obj
        for name in path:
            value = getattr(value, name)
        out[key] = (str(value) if isinstance(value, Path)
                    else list(value) if isinstance(value, tuple)
                    else _to_file(check, value) if is_number(value) else value)
    return out


def mission_to_dict(spec: MissionSpec) -> dict:
    """The validated mission as a plain YAML-able mapping, defaults filled in, paths absolute
    (`mission_from_dict` reads it back to an equal spec); still water leaves `ocean` out."""
    noise = spec.sonar_noise
    sea = {} if spec.ocean is None else dict(ocean=ocean_to_raw(spec.ocean))
    sections = {key: _plain(getattr(spec, key)) for key in SECTIONS}
    if spec.payload.sensors:
        sections["payload"]["sensors"] = {s.name: _plain(s) for s in spec.payload.sensors}
    return dict(name=spec.name, description=spec.description, seed=spec.seed, **sections,
                sonar_noise=dict(noise.params) if noise.preset == "custom" else noise.preset,
                faults={name: _plain(getattr(spec.faults, name)) for name in FAULT_CLASSES},
                **sea, steps=[{s.KIND: _plain(s)} for s in spec.steps])


def _resolve(source) -> Path:
    path = Path(source).expanduser()
    if path.is_file():
        return path.resolve()
    names = builtin_missions()
    if str(source) in names:
        return BUILTIN_DIR / f"{source}.yaml"
    raise MissionFileError(path.name or str(source), "", "mission file not found",
                           "a YAML mission file or a built-in mission: " + ", ".join(names))


def load_mission(source, seed: int | None = None, overrides=()) -> MissionSpec:
    """Reads a mission file (or a built-in mission by name), applies `overrides`
    (`dotted.key=value` strings) and `seed` (replaces the file's), and validates it."""
    path = _resolve(source)
    label = path.name
    try:
        raw = load_yaml_file(path)
    except (OSError, UnicodeDecodeError) as err:
        raise MissionFileError(label, "", f"cannot be read ({one_line(err)})",
                               "a readable YAML text file") from None
    except YamlLimitError as err:
        raise MissionFileError(label, "", one_line(err),
                               f"at most {MAX_BYTES} bytes and {MAX_VALUES} values with its "
                               "aliases expanded") from None
    except yaml.YAMLError as err:
        raise MissionFileError(label, "", f"is not valid YAML ({one_line(err)})",
                               "a YAML mapping of " + ", ".join(TOP_KEYS)) from None
    if not isinstance(raw, dict):
        raise MissionFileError(label, "", f"holds {type(raw).__name__}, not a mapping",
                               "a YAML mapping of " + ", ".join(TOP_KEYS))
    raw = apply_overrides(raw, overrides, label=f"{label} (--set)")
    if seed is not None:
        raw["seed"] = seed
    return mission_from_dict(raw, path.parent, label, source=path)


__all__ = ["BUILTIN_DIR", "FAULT_CLASSES", "FLY_FORMATS", "REALISTIC_NOISE", "RULES",
           "STEPS", "TOP_KEYS", "ExploreStep", "FaultsSpec", "FlyStep", "FollowStep",
           "LimitsSpec", "MissionFileError", "MissionSpec", "NavigationJumpFault",
           "PayloadSpec", "PlanStep", "ReplannerSpec", "SensorSpec", "SiteSpec", "SonarNoiseSpec",
           "SonarSilentFault", "SurveyStep", "step_specs", "ThrusterFailureFault", "apply_overrides", "builtin_missions",
           "load_mission", "mission_from_dict", "mission_to_dict"]
