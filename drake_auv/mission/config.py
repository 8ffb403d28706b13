"""Mission files: YAML validated into frozen dataclasses (pure Python, no Drake).

A mission names a site (a built-in scenario or the user's own files), the error sources
(navigation drift, sonar noise, prior-map shift), the replanner, the payload, the limits and the
steps flown in order in one dive (`plan`, `follow`, `survey`), and optional injected
`faults` (a silent sonar, a failed thruster, a navigation jump) for campaigns. Units are SI with the unit in the
key's name where it is not obvious (`_m`, `_s`, `_deg`); depths are positive down, metres.
Paths are relative to the mission file and stored resolved absolute.

Every bad value raises `MissionFileError`, one line naming the file, the dotted field and what
is allowed there. `load_mission` reads a file or a built-in mission (`builtin_missions()`),
applies `--set`-style overrides to the raw mapping, then validates; `mission_to_dict` gives the
validated mission back as a plain mapping (defaults filled in) that `mission_from_dict` reads.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import yaml

from drake_auv.replanning.section import ReplanningParameters
from drake_auv.scenarios import list_scenarios
from drake_auv.sonar.noise import SonarNoise
from drake_auv.vehicle.model import THRUSTER_NAMES
from drake_auv.vehicle.navigation import NavigationParams

BUILTIN_DIR = Path(__file__).resolve().parent / "missions"

# The "realistic" sonar (docs/sensors.md, "Sonar model"): 10 cm range noise, 5 % of returns
# lost, 2 % water-column clutter; half the rays reaching the sea surface reflected on
# (multipath, echoes at the path length along the beam); a side lobe 20 deg off the axis at
# -11 dB; echoes detected above 0.05 of a normal on-axis one (grazing echoes are lost).
REALISTIC_NOISE = dict(range_sigma=0.1, dropout_prob=0.05, spurious_prob=0.02,
                       surface_prob=0.5, side_lobe_deg=20.0, side_lobe_gain=0.08,
                       echo_threshold=0.05)


class MissionFileError(ValueError):
    """A bad mission: `<file or mission>: <dotted.field>: <what is wrong>; allowed: <...>`."""

    def __init__(self, label: str, where: str, what: str, allowed: str):
        self.label, self.where, self.what, self.allowed = label, where, what, allowed
        head = f"{label}: {where}: " if where else f"{label}: "
        super().__init__(" ".join(f"{head}{what}; allowed: {allowed}".split()))


def builtin_missions() -> list[str]:
    """Names of the missions shipped in `BUILTIN_DIR`."""
    return sorted(p.stem for p in BUILTIN_DIR.glob("*.yaml"))


# ---------------------------------------------------------------- field checks


@dataclass(frozen=True)
class _Number:
    """A number in [low, high] (ends open when named), in `unit`."""

    low: float
    high: float = math.inf
    unit: str = ""
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    nullable: bool = False

    @property
    def allowed(self) -> str:
        if math.isinf(self.high):
            text = f"{'>' if self.low_open else '>='} {self.low:g}"
        else:
            text = (f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                    f"{')' if self.high_open else ']'}")
        if self.integer:
            text = f"an integer {text}" if math.isinf(self.high) else f"an integer in {text}"
        text += f" {self.unit}" if self.unit else ""
        return text + (" or null" if self.nullable else "")

    def parse(self, value, fail, base_dir):
        if value is None and self.nullable:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            fail(f"{value!r} is not a number")
        if self.integer and not (math.isfinite(value) and int(value) == value):
            fail(f"{value!r} is not an integer")
        value = int(value) if self.integer else float(value)
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        if not (math.isfinite(value) and above and below):
            fail(f"{value!r} is out of range")
        return value


@dataclass(frozen=True)
class _Choice:
    values: tuple
    nullable: bool = False

    @property
    def allowed(self) -> str:
        return ", ".join(self.values) + (" or null" if self.nullable else "")

    def parse(self, value, fail, base_dir):
        if value is None and self.nullable:
            return None
        if value not in self.values:
            fail(f"{value!r} is not allowed")
        return value


@dataclass(frozen=True)
class _Bool:
    allowed: str = "true or false"

    def parse(self, value, fail, base_dir):
        if not isinstance(value, bool):
            fail(f"{value!r} is not a boolean")
        return value


@dataclass(frozen=True)
class _Text:
    nullable: bool = False

    @property
    def allowed(self) -> str:
        return "a string" + (" or null" if self.nullable else "")

    def parse(self, value, fail, base_dir):
        if value is None and self.nullable:
            return None
        if not isinstance(value, str) or not value.strip():
            fail(f"{value!r} is not a non-empty string")
        return value


@dataclass(frozen=True)
class _File:
    allowed: str = "a file path, relative to the mission file, or null"

    def parse(self, value, fail, base_dir):
        if value is None:
            return None
        if not isinstance(value, str) or not value.strip():
            fail(f"{value!r} is not a file path")
        return (Path(base_dir) / Path(value).expanduser()).resolve()


@dataclass(frozen=True)
class _Vector:
    """A list of finite numbers, one per name, or null."""

    names: tuple
    units: str

    @property
    def allowed(self) -> str:
        return f"[{', '.join(self.names)}] ({self.units}) or null"

    def parse(self, value, fail, base_dir):
        if value is None:
            return None
        if not (isinstance(value, (list, tuple)) and len(value) == len(self.names)
                and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                        and math.isfinite(v) for v in value)):
            fail(f"{value!r} is not {len(self.names)} finite numbers")
        return tuple(float(v) for v in value)


# ---------------------------------------------------------------- the sections


@dataclass(frozen=True)
class SiteSpec:
    """Where the mission flies: exactly one of `scenario` (built-in), `world` (a mesh file) or
    `tile` (a survey grid whose site files are generated on first use, `mission.site`).

    Attributes:
        scenario: a name of `drake_auv.scenarios.list_scenarios()`.
        world: true world mesh (PLY/OBJ/STL/GLB), seabed and structure, m, z up, sea surface
            z = 0, in the site's horizontal coordinates (those of the prior raster's CRS).
        target: mesh of the structure whose coverage is scored (None: the whole world).
        prior: prior bathymetry raster the planner sees (None: sampled from the world).
        prior_error_m: horizontal shift of the prior, m, in a direction drawn from the seed.
        prior_spacing_m: cell of the prior when sampled from the world, m (None: the
            scenario's, or 1.0 m).
        crs: CRS of the world's coordinates when no prior raster gives one (e.g. EPSG:32631).
        start: (x, y, z, yaw_deg) start pose in site coordinates, m and deg (None: the
            scenario's, or chosen by the runner).
        max_range_m: range of the sonars, m.
        tile: georeferenced bathymetry grid (GeoTIFF) the site is cut from: a 1 m world
            interpolated from it, its faces inside `roi` the target, the grid the prior.
        roi: (xmin, ymin, xmax, ymax) of the region of interest in the tile's world frame
            (m from its first cell), required with `tile`.
    """

    scenario: str | None = None
    world: Path | None = None
    target: Path | None = None
    prior: Path | None = None
    prior_error_m: float = 0.0
    prior_spacing_m: float | None = None
    crs: str | None = None
    start: tuple | None = None
    max_range_m: float = 20.0
    tile: Path | None = None
    roi: tuple | None = None


@dataclass(frozen=True)
class NavigationSpec:
    """DVL + compass dead-reckoning error (see `drake_auv.vehicle.navigation`).

    Attributes:
        heading_bias_deg: compass bias, deg.
        dvl_scale_error: DVL scale-factor error (fraction).
        random_walk: drift random walk, m per sqrt(m travelled).
    """

    heading_bias_deg: float = 0.0
    dvl_scale_error: float = 0.0
    random_walk: float = 0.0

    def to_params(self, seed: int) -> NavigationParams:
        """The `NavigationParams` (heading bias in rad) drawing from `seed`."""
        return NavigationParams(heading_bias=math.radians(self.heading_bias_deg),
                                scale_error=self.dvl_scale_error,
                                random_walk=self.random_walk, seed=int(seed))


@dataclass(frozen=True)
class SonarNoiseSpec:
    """Sonar errors: `preset` "realistic" (`REALISTIC_NOISE`, the default: range noise,
    dropouts, clutter, side lobes, surface multipath), "clean" (none, asked for explicitly)
    or "custom" (`params` given in the file), `params` being `SonarNoise` fields."""

    preset: str = "realistic"
    params: dict = field(default_factory=lambda: dict(REALISTIC_NOISE))

    def to_noise(self) -> SonarNoise | None:
        """The `SonarNoise`, or None for a clean sonar."""
        return None if self.preset == "clean" else SonarNoise(**self.params)


@dataclass(frozen=True)
class ReplannerSpec:
    """The realtime replanner (see `drake_auv.replanning.section`).

    Attributes:
        optimizer: "stomp" (each section optimised against the on-line map), or "none"
            (each section's initial trajectory, through the nominal waypoints from the
            vehicle's position, flown unoptimised: the ablation baseline).
        R: sections gather the waypoints within this radius of the vehicle, m.
        K: most waypoints in one section.
        clearance_m: obstacle margin of the cost, m.
        period_s: replanning period, s.
        voxel_m: edge of the on-line octree map's voxels, m.
        rollouts, iterations: STOMP rollouts per iteration and iteration cap.
        offset_metric: "horizontal" or "3d" distance to the map for the offset (see
            `ReplanningParameters`); "auto": "3d" after a coverage plan (offsets along the
            surface normal), "horizontal" after a contour plan.
    """

    optimizer: str = "stomp"
    R: float = 5.0
    K: int = 10
    clearance_m: float = 4.0
    period_s: float = 1.0
    voxel_m: float = 0.5
    rollouts: int = 10
    iterations: int = 40
    offset_metric: str = "auto"

    def to_params(self, omega: float, plan_method: str) -> ReplanningParameters:
        """`ReplanningParameters` for the offset `omega` (m) after a `plan_method` plan."""
        metric = self.offset_metric
        if metric == "auto":
            metric = "horizontal" if plan_method == "contour" else "3d"
        stomp = dataclasses.replace(ReplanningParameters().stomp, num_rollouts=self.rollouts,
                                    max_iterations=self.iterations)
        return ReplanningParameters(radius=self.R, max_waypoints=self.K, omega=omega,
                                    clearance=self.clearance_m, offset_metric=metric,
                                    stomp=stomp)


@dataclass(frozen=True)
class PayloadSpec:
    """Attributes: multibeam_mount: where the multibeam looks; camera_range_m: distance up to
    which the camera resolves the surface, m; camera_aperture_deg: its full aperture, deg."""

    multibeam_mount: str = "port"
    camera_range_m: float = 12.0
    camera_aperture_deg: float = 60.0


@dataclass(frozen=True)
class LimitsSpec:
    """Attributes: max_time_s: cap on the dive's simulated time, s (None: none);
    time_margin: a step may last this many times its nominal duration."""

    max_time_s: float | None = None
    time_margin: float = 1.4


@dataclass(frozen=True)
class PlanStep:
    """Off-line plan on the prior map; a later `survey` flies it.

    Attributes:
        omega: offset to the terrain, m.
        method: "coverage" (`plan_coverage`: lanes and slices) or "contour" (one contour at
            `depth`, `drake_auv.planning.contour.nominal_contour`).
        slice_count, slice_spacing: slicing planes per high-slope region and their spacing, m
            (None: from the footprint); coverage only.
        slope_threshold, aperture_deg, overlap, min_area_m2: classification and sensor
            parameters of `plan_coverage` (deg, fraction, m^2); coverage only.
        depth: depth of the contour, m; contour only, required there.
        end_width_m, end_heading_deg, end_overrun_m: contour only: fly around the end of a
            long structure, `end_width_m` wide, facing `end_heading_deg` (deg from +x, None:
            0), the contour kept `end_overrun_m` further (None: 7 m, the largest prior error
            plus 2 m); see `nominal_contour` (end_width_m None: the whole closed contour).
        speed: survey speed, m/s.
    """

    KIND: ClassVar[str] = "plan"
    omega: float
    method: str = "coverage"
    slice_count: int | None = None
    slice_spacing: float | None = None
    slope_threshold: float = 0.5
    aperture_deg: float = 60.0
    overlap: float = 0.1
    min_area_m2: float | None = None
    depth: float | None = None
    end_width_m: float | None = None
    end_heading_deg: float | None = None
    end_overrun_m: float | None = None
    speed: float = 0.5


@dataclass(frozen=True)
class FollowStep:
    """Sensor-based profile following with the pencil-beam profiler.

    Attributes:
        mode: "horizontal" (around the structure at a constant depth) or "vertical" (in a
            vertical plane, over and under the profile).
        offset: distance to keep from the profile, m.
        depth: depth where following starts (horizontal: and holds), m (None: the depth of
            the vehicle when the step starts).
        loops: horizontal: laps around the structure.
        distance_m: vertical: end after this horizontal distance along the plane, m.
        end_depth_m: vertical: end once shallower than this (with `distance_m`: both), m.
        heading_deg: vertical: yaw of the plane, deg (None: the vehicle's heading).
        start: (x, y) in site coordinates where following begins, m (None: by the runner).
        speed: speed along the profile, m/s.
        corner_weight: weight of the range along the normal in the controlled distance (see
            `FollowingParams`), in [0, 1].
        min_depth_m: the following never rises above this depth, m.
        max_time_s: cap on the step's simulated time, s.
    """

    KIND: ClassVar[str] = "follow"
    mode: str
    offset: float
    depth: float | None = None
    loops: float = 1.0
    distance_m: float | None = None
    end_depth_m: float | None = None
    heading_deg: float | None = None
    start: tuple | None = None
    speed: float = 0.3
    corner_weight: float = 0.0
    min_depth_m: float = 1.0
    max_time_s: float | None = None


@dataclass(frozen=True)
class SurveyStep:
    """The plan of the earlier `plan` step, flown with realtime replanning (or as planned).

    Attributes: replanning: replan against the on-line map; max_time_s: cap, s (None: the
    plan's duration times `limits.time_margin`)."""

    KIND: ClassVar[str] = "survey"
    replanning: bool = True
    max_time_s: float | None = None


@dataclass(frozen=True)
class FlyStep:
    """An exported vehicle mission flown the way its autopilot executes it
    (`drake_auv.autopilot`): COLA2 goto/section/park or ArduSub AUTO waypoints.

    Attributes:
        file: the mission file, relative to the mission file: COLA2 mission XML (`.xml`) or a
            QGroundControl plan (`.plan`, flown as ArduSub AUTO); the extension names the
            format.
        heave_in_3d: COLA2 only: the vehicle is configured with heave_in_3D (depth
            interpolated along each section).
        speed: m/s where the file commands none (ArduSub before its first DO_CHANGE_SPEED).
        max_time_s: cap, s (None: the file's nominal duration times `limits.time_margin`).
    """

    KIND: ClassVar[str] = "fly"
    file: Path
    heave_in_3d: bool = False
    speed: float = 0.5
    max_time_s: float | None = None

    @property
    def autopilot(self) -> str:
        return FLY_FORMATS[self.file.suffix.lower()]


FLY_FORMATS = {".xml": "cola2", ".plan": "ardusub"}


@dataclass(frozen=True)
class ExploreStep:
    """On-line view planning from the octree, no prior map (`drake_auv.exploration`).

    Attributes:
        region: [xmin, ymin, zmin, xmax, ymax, zmax] where the structure is believed to be,
            site coordinates, m (z up, negative below the sea surface).
        omega: preferred viewing distance, m, above `clearance_m`.
        max_time_s: cap on the step's simulated time, s.
        clearance_m: least distance of a viewpoint to mapped or unknown space, m.
        strategy: "gain" (surface newly seen against travel), "nearest" (nearest frontier
            first) or "random" (a random frontier, seeded by the mission seed).
        min_gain_m2: exploring ends when no viewpoint would newly see this, m^2.
    """

    KIND: ClassVar[str] = "explore"
    region: tuple
    omega: float = 6.0
    max_time_s: float = 1800.0
    clearance_m: float = 3.0
    strategy: str = "gain"
    min_gain_m2: float = 1.0


@dataclass(frozen=True)
class SonarSilentFault:
    """A sonar that returns nothing from `start_s` for `duration_s` s (None: no fault).
    Attributes: sensor: "multibeam", "profiler" or "both"."""

    sensor: str = "both"
    start_s: float | None = None
    duration_s: float = 30.0


@dataclass(frozen=True)
class ThrusterFailureFault:
    """One thruster (`vehicle.model.THRUSTER_NAMES`) gives no force from `start_s` s on
    (None: no fault); the allocation is not told."""

    thruster: str = "surge_port"
    start_s: float | None = None


@dataclass(frozen=True)
class NavigationJumpFault:
    """A late position fix: at `time_s` s (None: no fault) the estimated position jumps by
    `error_m` m horizontally towards `direction_deg` (deg from +x, local frame)."""

    time_s: float | None = None
    error_m: float = 3.0
    direction_deg: float = 0.0


@dataclass(frozen=True)
class FaultsSpec:
    """Injected faults (campaign variables), each off unless its time is set; the mission
    supervisor detects and answers them (`drake_auv.mission.supervisor.SafetyRules`)."""

    sonar_silent: SonarSilentFault = SonarSilentFault()
    thruster_failure: ThrusterFailureFault = ThrusterFailureFault()
    navigation_jump: NavigationJumpFault = NavigationJumpFault()

    @property
    def active(self) -> dict:
        """{fault name: its spec} of the faults that happen."""
        return {name: f for name, f in (("sonar_silent", self.sonar_silent),
                                        ("thruster_failure", self.thruster_failure),
                                        ("navigation_jump", self.navigation_jump))
                if (f.time_s if name == "navigation_jump" else f.start_s) is not None}


Step = PlanStep | FollowStep | SurveyStep | FlyStep | ExploreStep
STEP_KINDS = {cls.KIND: cls for cls in (PlanStep, FollowStep, SurveyStep, FlyStep, ExploreStep)}


@dataclass(frozen=True)
class MissionSpec:
    """A validated mission. `source` is the file it was read from (not compared)."""

    name: str
    site: SiteSpec
    steps: tuple
    seed: int = 0
    description: str | None = None
    navigation: NavigationSpec = NavigationSpec()
    sonar_noise: SonarNoiseSpec = SonarNoiseSpec()
    replanner: ReplannerSpec = ReplannerSpec()
    payload: PayloadSpec = PayloadSpec()
    limits: LimitsSpec = LimitsSpec()
    faults: FaultsSpec = FaultsSpec()
    source: Path | None = field(default=None, compare=False)


_DEPTH = _Number(0.0, 11000.0, "m", low_open=True, nullable=True)
_TIME = _Number(0.0, unit="s", low_open=True, nullable=True)
_CHECKS = {
    SiteSpec: dict(
        scenario=_Choice(tuple(name for name, _ in list_scenarios()), nullable=True),
        world=_File(), target=_File(), prior=_File(),
        prior_error_m=_Number(0.0, 5.0, "m"),
        prior_spacing_m=_Number(0.0, 100.0, "m", low_open=True, nullable=True),
        crs=_Text(nullable=True),
        start=_Vector(("x", "y", "z", "yaw_deg"), "m, m, m, deg"),
        max_range_m=_Number(0.0, 200.0, "m", low_open=True),
        tile=_File("a georeferenced bathymetry grid (GeoTIFF), relative to the mission file, "
                   "or null"),
        roi=_Vector(("xmin", "ymin", "xmax", "ymax"), "m, the tile's world frame")),
    NavigationSpec: dict(
        heading_bias_deg=_Number(-10.0, 10.0, "deg"),
        dvl_scale_error=_Number(-0.1, 0.1), random_walk=_Number(0.0, 1.0, "m/sqrt(m)")),
    ReplannerSpec: dict(
        optimizer=_Choice(("stomp", "none")), R=_Number(0.5, 50.0, "m"),
        K=_Number(1, 200, integer=True), clearance_m=_Number(0.5, 20.0, "m"),
        period_s=_Number(0.1, 10.0, "s"), voxel_m=_Number(0.1, 2.0, "m"),
        rollouts=_Number(2, 100, integer=True), iterations=_Number(1, 500, integer=True),
        offset_metric=_Choice(("auto", "horizontal", "3d"))),
    PayloadSpec: dict(
        multibeam_mount=_Choice(("port", "starboard", "down", "forward")),
        camera_range_m=_Number(0.5, 50.0, "m"), camera_aperture_deg=_Number(5.0, 170.0, "deg")),
    LimitsSpec: dict(max_time_s=_TIME, time_margin=_Number(1.0, 5.0)),
    PlanStep: dict(
        omega=_Number(0.5, 100.0, "m"), method=_Choice(("coverage", "contour")),
        slice_count=_Number(1, 20, integer=True, nullable=True),
        slice_spacing=_Number(0.0, 50.0, "m", low_open=True, nullable=True),
        slope_threshold=_Number(0.0, 10.0, low_open=True),
        aperture_deg=_Number(5.0, 170.0, "deg"), overlap=_Number(0.0, 0.9),
        min_area_m2=_Number(0.0, unit="m^2", nullable=True), depth=_DEPTH,
        end_width_m=_Number(0.0, 1000.0, "m", low_open=True, nullable=True),
        end_heading_deg=_Number(-360.0, 360.0, "deg", nullable=True),
        end_overrun_m=_Number(0.0, 100.0, "m", nullable=True),
        speed=_Number(0.05, 1.4, "m/s")),
    FollowStep: dict(
        mode=_Choice(("horizontal", "vertical")), offset=_Number(0.0, 20.0, "m", low_open=True),
        depth=_DEPTH, loops=_Number(0.0, 100.0, low_open=True),
        distance_m=_Number(0.0, 10000.0, "m", low_open=True, nullable=True),
        end_depth_m=_DEPTH, heading_deg=_Number(-360.0, 360.0, "deg", nullable=True),
        start=_Vector(("x", "y"), "m, site coordinates"), speed=_Number(0.05, 1.4, "m/s"),
        corner_weight=_Number(0.0, 1.0), min_depth_m=_Number(0.0, 100.0, "m"),
        max_time_s=_TIME),
    SurveyStep: dict(replanning=_Bool(), max_time_s=_TIME),
    FlyStep: dict(file=_File("a COLA2 mission (.xml) or QGroundControl plan (.plan) file, "
                             "relative to the mission file"),
                  heave_in_3d=_Bool(), speed=_Number(0.05, 1.4, "m/s"), max_time_s=_TIME),
    SonarSilentFault: dict(sensor=_Choice(("multibeam", "profiler", "both")),
                           start_s=_Number(0.0, unit="s", nullable=True),
                           duration_s=_Number(0.0, unit="s", low_open=True)),
    ThrusterFailureFault: dict(thruster=_Choice(THRUSTER_NAMES),
                               start_s=_Number(0.0, unit="s", nullable=True)),
    NavigationJumpFault: dict(time_s=_Number(0.0, unit="s", nullable=True),
                              error_m=_Number(0.0, 100.0, "m"),
                              direction_deg=_Number(-360.0, 360.0, "deg")),
}
FAULT_CLASSES = {"sonar_silent": SonarSilentFault, "thruster_failure": ThrusterFailureFault,
                 "navigation_jump": NavigationJumpFault}
_TOP = dict(name=_Text(), seed=_Number(0, integer=True), description=_Text(nullable=True))
_SECTIONS = dict(site=SiteSpec, navigation=NavigationSpec, replanner=ReplannerSpec,
                 payload=PayloadSpec, limits=LimitsSpec)
TOP_KEYS = ("name", "description", "seed", "site", "navigation", "sonar_noise", "replanner",
            "payload", "limits", "faults", "steps")
_NOISE_FIELDS = tuple(f.name for f in dataclasses.fields(SonarNoise))
_STEP_ALLOWED = "a non-empty list of one-key mappings: " + ", ".join(STEP_KINDS)


# ---------------------------------------------------------------- validation


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

    def values(self, checks: dict, raw: dict, where: str, defaults: dict) -> dict:
        """Each key of `checks` checked, or its default (missing: required)."""
        out = {}
        for name, check in checks.items():
            key = _join(where, name)
            if name in raw:
                def fail(what, key=key, allowed=check.allowed):
                    self.fail(key, what, allowed)
                out[name] = check.parse(raw[name], fail, self.base_dir)
            elif name in defaults:
                out[name] = defaults[name]
            else:
                self.fail(key, "missing (required)", check.allowed)
        return out

    def section(self, cls, raw, where: str):
        checks = _CHECKS[cls]
        raw = self.mapping(raw, where, tuple(checks))
        defaults = {f.name: (f.default_factory() if f.default_factory is not dataclasses.MISSING
                             else f.default)
                    for f in dataclasses.fields(cls)
                    if f.default is not dataclasses.MISSING
                    or f.default_factory is not dataclasses.MISSING}
        values = self.values(checks, raw, where, defaults)
        rule = _RULES.get(cls)
        if rule is not None:
            rule(self, values, where)
        return cls(**values)

    def sonar_noise(self, raw) -> SonarNoiseSpec:
        allowed = "clean, realistic or a mapping of " + ", ".join(_NOISE_FIELDS)
        if raw == "clean":
            return SonarNoiseSpec("clean", {})
        if raw is None or raw == "realistic":
            return SonarNoiseSpec()
        if not isinstance(raw, dict):
            self.fail("sonar_noise", f"{raw!r} is not a preset or a mapping", allowed)
        raw = self.mapping(raw, "sonar_noise", _NOISE_FIELDS)
        for name, value in raw.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                self.fail(f"sonar_noise.{name}", f"{value!r} is not a number",
                          "a number (see SonarNoise)")
            try:
                SonarNoise(**{name: value})
            except ValueError as err:
                match = re.search(r"must be (.*?), got", str(err))
                self.fail(f"sonar_noise.{name}", f"{value!r} is out of range",
                          match.group(1) if match else str(err))
        return SonarNoiseSpec("custom", {k: float(v) for k, v in raw.items()})

    def faults(self, raw) -> FaultsSpec:
        raw = self.mapping(raw, "faults", tuple(FAULT_CLASSES))
        return FaultsSpec(**{name: self.section(cls, raw.get(name), f"faults.{name}")
                             for name, cls in FAULT_CLASSES.items()})

    def steps(self, raw) -> tuple:
        if not isinstance(raw, list) or not raw:
            self.fail("steps", f"{raw!r} is not a non-empty list", _STEP_ALLOWED)
        steps = []
        for i, item in enumerate(raw):
            where = f"steps[{i}]"
            if isinstance(item, str):
                kind, body = item, None
            elif isinstance(item, dict) and len(item) == 1:
                (kind, body), = item.items()
            else:
                self.fail(where, f"{item!r} is not a one-key mapping", _STEP_ALLOWED)
            if kind not in STEP_KINDS:
                self.fail(where, f"unknown step {kind!r}", ", ".join(STEP_KINDS))
            steps.append(self.section(STEP_KINDS[kind], body, f"{where}.{kind}"))
        plans = [i for i, s in enumerate(steps) if isinstance(s, PlanStep)]
        if len(plans) > 1:
            self.fail(f"steps[{plans[1]}].plan", "a second plan step", "at most one plan step")
        for i, step in enumerate(steps):
            if isinstance(step, SurveyStep) and not (plans and plans[0] < i):
                self.fail(f"steps[{i}].survey", "no earlier plan step to survey",
                          "a survey after a plan step")
        return tuple(steps)

    def mission(self, raw, source) -> MissionSpec:
        raw = self.mapping(raw, "", TOP_KEYS)
        for key in ("site", "steps"):
            if key not in raw:
                self.fail(key, "missing (required)",
                          "a site mapping" if key == "site" else _STEP_ALLOWED)
        top = self.values(_TOP, raw, "", dict(name=Path(self.label).stem, seed=0,
                                               description=None))
        sections = {key: self.section(cls, raw.get(key), key) for key, cls in _SECTIONS.items()}
        return MissionSpec(**top, **sections, sonar_noise=self.sonar_noise(raw.get("sonar_noise")),
                           faults=self.faults(raw.get("faults")),
                           steps=self.steps(raw["steps"]), source=source)


def _join(where: str, key) -> str:
    return f"{where}.{key}" if where else str(key)


def _site_rule(reader: _Reader, v: dict, where: str):
    if sum(v[key] is not None for key in ("scenario", "world", "tile")) != 1:
        reader.fail(where, "needs exactly one of scenario, world or tile",
                    "scenario: <name>, world: <mesh file> or tile: <GeoTIFF> with roi")
    if (v["tile"] is None) != (v["roi"] is None):
        reader.fail(f"{where}.roi", "goes with tile (both or neither)",
                    _CHECKS[SiteSpec]["roi"].allowed + ", with tile")
    if v["roi"] is not None and not (v["roi"][0] < v["roi"][2] and v["roi"][1] < v["roi"][3]):
        reader.fail(f"{where}.roi", f"{list(v['roi'])} has min >= max",
                    "xmin < xmax and ymin < ymax")
    if v["world"] is None:
        for key in ("target", "prior", "crs"):
            if v[key] is not None:
                reader.fail(f"{where}.{key}", "only for a site given by its world file",
                            "null with a scenario or a tile")


def _plan_rule(reader: _Reader, v: dict, where: str):
    contour = v["method"] == "contour"
    if contour and v["depth"] is None:
        reader.fail(f"{where}.depth", "missing (required by method contour)",
                    _CHECKS[PlanStep]["depth"].allowed)
    only = ("depth", "end_width_m", "end_heading_deg", "end_overrun_m") if not contour else (
        "slice_count", "slice_spacing", "min_area_m2")
    for key in only:
        if v[key] is not None:
            reader.fail(f"{where}.{key}", f"not used by method {v['method']}",
                        "null (or the other method)")


def _follow_rule(reader: _Reader, v: dict, where: str):
    ends = ("distance_m", "end_depth_m")
    if v["mode"] == "vertical" and all(v[k] is None for k in ends):
        reader.fail(where, "a vertical follow needs an end",
                    "distance_m and/or end_depth_m")
    if v["mode"] == "horizontal":
        for key in ends:
            if v[key] is not None:
                reader.fail(f"{where}.{key}", "only for mode vertical",
                            "null for a horizontal follow (it ends after `loops` laps)")


def _fly_rule(reader: _Reader, v: dict, where: str):
    path = v["file"]
    allowed = _CHECKS[FlyStep]["file"].allowed
    if path is None:
        reader.fail(f"{where}.file", "missing (required)", allowed)
    if path.suffix.lower() not in FLY_FORMATS:
        reader.fail(f"{where}.file", f"{path.name}: unknown mission format "
                    f"{path.suffix or '(no extension)'!r}", ", ".join(FLY_FORMATS))
    if not path.is_file():
        reader.fail(f"{where}.file", f"{path.name} not found ({path})", allowed)
    if v["heave_in_3d"] and FLY_FORMATS[path.suffix.lower()] != "cola2":
        reader.fail(f"{where}.heave_in_3d", "only for COLA2 missions (.xml)",
                    "false for a .plan file")


_RULES = {SiteSpec: _site_rule, PlanStep: _plan_rule, FollowStep: _follow_rule,
          FlyStep: _fly_rule}


def _explore_rule(reader: _Reader, v: dict, where: str):
    region = v["region"]
    if region is None:
        reader.fail(f"{where}.region", "missing (required)",
                    _CHECKS[ExploreStep]["region"].allowed)
    if not all(region[k] < region[k + 3] for k in range(3)):
        reader.fail(f"{where}.region", f"{list(region)} has min >= max on an axis",
                    "xmin < xmax, ymin < ymax, zmin < zmax")
    if region[2] >= 0.0:
        reader.fail(f"{where}.region", f"zmin {region[2]:g} is not below the sea surface",
                    "zmin < 0 m (z up, sea surface z = 0)")
    if v["omega"] <= v["clearance_m"]:
        reader.fail(f"{where}.omega", f"{v['omega']:g} m is not above clearance_m "
                    f"{v['clearance_m']:g} m (a viewpoint at omega would break the clearance)",
                    f"omega > clearance_m ({v['clearance_m']:g} m)")


_CHECKS[ExploreStep] = dict(
    region=_Vector(("xmin", "ymin", "zmin", "xmax", "ymax", "zmax"), "m, site coordinates"),
    omega=_Number(0.5, 100.0, "m"), max_time_s=_Number(0.0, unit="s", low_open=True),
    clearance_m=_Number(0.5, 20.0, "m"), strategy=_Choice(("gain", "nearest", "random")),
    min_gain_m2=_Number(0.0, unit="m^2"))
_RULES[ExploreStep] = _explore_rule


def mission_from_dict(raw: dict, base_dir, label: str, source: Path | None = None
                      ) -> MissionSpec:
    """Validates a raw mission mapping (paths relative to `base_dir`); errors name `label`."""
    return _Reader(label, base_dir).mission(raw, source)


def mission_to_dict(spec: MissionSpec) -> dict:
    """The validated mission as a plain YAML-able mapping, defaults filled in, paths absolute
    (`mission_from_dict` reads it back to an equal spec)."""

    def plain(obj) -> dict:
        out = {}
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            out[f.name] = (str(value) if isinstance(value, Path)
                           else list(value) if isinstance(value, tuple) else value)
        return out

    noise = spec.sonar_noise
    return dict(name=spec.name, description=spec.description, seed=spec.seed,
                site=plain(spec.site), navigation=plain(spec.navigation),
                sonar_noise=dict(noise.params) if noise.preset == "custom" else noise.preset,
                replanner=plain(spec.replanner), payload=plain(spec.payload),
                limits=plain(spec.limits),
                faults={name: plain(getattr(spec.faults, name)) for name in FAULT_CLASSES},
                steps=[{s.KIND: plain(s)} for s in spec.steps])


# ---------------------------------------------------------------- overrides and loading


def apply_overrides(raw: dict, overrides, label: str = "--set") -> dict:
    """A copy of `raw` with each `dotted.key=value` set (value read as YAML; step index as in
    `steps.2.survey.replanning`). Keys are checked against the schema, not the file, so a
    section the file leaves out can be set."""
    out = copy.deepcopy(raw) if isinstance(raw, dict) else {}
    for item in overrides:
        if not isinstance(item, str) or "=" not in item:
            raise MissionFileError(label, str(item), "not a KEY=VALUE override",
                                   "dotted.key=value, e.g. replanner.optimizer=none")
        key, text = item.split("=", 1)
        key = re.sub(r"\[(\d+)\]", r".\1", key.strip())
        try:
            value = yaml.safe_load(text)
        except yaml.YAMLError as err:
            raise MissionFileError(label, key, f"value {text!r} is not YAML ({_one_line(err)})",
                                   "a YAML value: number, string, true/false, null, [..], {..}")
        _set(out, key.split("."), value, label)
    return out


def _set(raw: dict, parts: list[str], value, label: str):
    """Sets raw[parts...] = value, checking each key against what the schema allows there."""

    def fail(i: int, what: str, allowed):
        raise MissionFileError(label, ".".join(parts[:i + 1]), what, ", ".join(allowed))

    head, rest = parts[0], parts[1:]
    if head not in TOP_KEYS:
        fail(0, "unknown key", TOP_KEYS)
    if not rest:
        raw[head] = value
        return
    if head == "steps":
        steps = raw.get("steps")
        count = len(steps) if isinstance(steps, list) else 0
        if not (rest[0].isdigit() and int(rest[0]) < count):
            fail(1, "no such step", [str(i) for i in range(count)] or ["(the file has none)"])
        index = int(rest[0])
        step = steps[index]
        if isinstance(step, str):
            kind = step
        else:
            kind = next(iter(step)) if isinstance(step, dict) and len(step) == 1 else None
        if kind not in STEP_KINDS:
            fail(1, "not a valid step to set keys in", STEP_KINDS)
        if len(rest) == 1:
            steps[index] = value
            return
        if rest[1] != kind:
            fail(2, f"step {index} is a {kind} step", [kind])
        if len(rest) == 2:
            steps[index] = {kind: value}
            return
        if isinstance(step, str) or step[kind] is None:
            step = steps[index] = {kind: {}}
        node, keys, offset = step[kind], _CHECKS[STEP_KINDS[kind]], 3
    elif head == "sonar_noise":
        preset = raw.get("sonar_noise")
        node = (dict(REALISTIC_NOISE) if preset in (None, "realistic")
                else preset if isinstance(preset, dict) else {})
        raw["sonar_noise"], keys, offset = node, _NOISE_FIELDS, 1
    elif head == "faults":  # faults.<kind>.<key>
        if not isinstance(raw.get(head), dict):
            raw[head] = {}
        if rest[0] not in FAULT_CLASSES:
            fail(1, "unknown fault", FAULT_CLASSES)
        if len(rest) == 1:
            raw[head][rest[0]] = value
            return
        if not isinstance(raw[head].get(rest[0]), dict):
            raw[head][rest[0]] = {}
        node, keys, offset = raw[head][rest[0]], _CHECKS[FAULT_CLASSES[rest[0]]], 2
    elif head in _SECTIONS:
        if not isinstance(raw.get(head), dict):
            raw[head] = {}
        node, keys, offset = raw[head], _CHECKS[_SECTIONS[head]], 1
    else:
        fail(1, f"{head} is a value, not a section", [head])
    leaf = parts[offset:]
    if not leaf:
        fail(offset - 1, "needs a key below it", keys)
    if leaf[0] not in keys:
        fail(offset, "unknown key", keys)
    if len(leaf) > 1:
        fail(offset + 1, f"{leaf[0]} is a value, not a section", [".".join(parts[:offset + 1])])
    node[leaf[0]] = value


def _one_line(err: Exception) -> str:
    return " ".join(str(err).split())


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
        raw = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError) as err:
        raise MissionFileError(label, "", f"cannot be read ({_one_line(err)})",
                               "a readable YAML text file") from None
    except yaml.YAMLError as err:
        raise MissionFileError(label, "", f"is not valid YAML ({_one_line(err)})",
                               "a YAML mapping of " + ", ".join(TOP_KEYS)) from None
    if not isinstance(raw, dict):
        raise MissionFileError(label, "", f"holds {type(raw).__name__}, not a mapping",
                               "a YAML mapping of " + ", ".join(TOP_KEYS))
    raw = apply_overrides(raw, overrides, label=f"{label} (--set)")
    if seed is not None:
        raw["seed"] = seed
    return mission_from_dict(raw, path.parent, label, source=path)


__all__ = ["BUILTIN_DIR", "FAULT_CLASSES", "REALISTIC_NOISE", "FaultsSpec", "FollowStep",
           "LimitsSpec", "MissionFileError", "MissionSpec", "NavigationJumpFault",
           "NavigationSpec", "SonarSilentFault", "ThrusterFailureFault", "PayloadSpec", "PlanStep", "ReplannerSpec",
           "SiteSpec", "SonarNoiseSpec", "Step", "SurveyStep", "apply_overrides",
           "builtin_missions", "load_mission", "mission_from_dict", "mission_to_dict"]
