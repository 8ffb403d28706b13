"""The mission's dataclasses: what a mission file holds, validated (pure Python, no Drake).

A mission names a site (a built-in scenario or the user's own files), the error sources
(navigation drift, sonar noise, prior-map shift), the replanner, the payload, the limits and the
steps flown in order in one dive (`plan`, `follow`, `survey`, `fly`), and optional injected
`faults` (a silent sonar, a failed thruster, a navigation jump) for campaigns. Units are SI with
the unit in the key's name where it is not obvious (`_m`, `_s`, `_deg`); depths are positive
down, metres.

Every field carries its range (`drake_auv.params.param`) and every class validates itself, so
`dataclasses.replace` checks too. Where a section is an algorithm's parameter class it is that
class (`navigation`: `NavigationParams`; `replanner.params`: `ReplanningParameters`), with its
defaults; a step field that is an algorithm's parameter takes its check and default from there
(`like`). `mission_keys` gives a section's mission-file keys (the fields' `key` where the file
names a field otherwise, e.g. `R` for `radius`); reading and writing files is
`drake_auv.mission.config`, the `--set` language `drake_auv.mission.overrides`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from drake_auv.exploration.planner import ExploreParameters
from drake_auv.following.behaviours import FollowingParams
from drake_auv.ocean.spec import OceanSpec
from drake_auv.params import CHECK, NESTED, like, nested, param, validate
from drake_auv.random_streams import MAX_SEED, SEED_RANGE
from drake_auv.replanning.section import OPTIMIZERS, ReplanningParameters
from drake_auv.scenarios import list_scenarios
from drake_auv.sonar.noise import SonarNoise
from drake_auv.vehicle.model import THRUSTER_NAMES
from drake_auv.vehicle.navigation import NavigationParams

# The "realistic" sonar (docs/sensors.md, "Sonar model"): 10 cm range noise, 5 % of returns
# lost, 2 % water-column clutter; half the rays reaching the sea surface reflected on
# (multipath, echoes at the path length along the beam); a side lobe 20 deg off the axis at
# -11 dB; echoes detected above 0.05 of a normal on-axis one (grazing echoes are lost).
REALISTIC_NOISE = dict(range_sigma=0.1, dropout_prob=0.05, spurious_prob=0.02,
                       surface_prob=0.5, side_lobe_deg=20.0, side_lobe_gain=0.08,
                       echo_threshold=0.05)

NO_RETURN_CLEAR_M = 12.0  # m, explore's free-water clearing by beams without an echo
SCENARIOS = tuple(name for name, _ in list_scenarios())
_FILE = "a file path, relative to the mission file"
_DEPTH = dict(low=0.0, high=11000.0, low_open=True, unit="m", nullable=True)
_TIME = dict(low=0.0, low_open=True, unit="s", nullable=True)
_SPEED = dict(low=0.05, high=1.4, unit="m/s")
_ANGLE = dict(low=-360.0, high=360.0, unit="deg")


class MissionFileError(ValueError):
    """A bad mission: `<file or mission>: <dotted.field>: <what is wrong>; allowed: <...>`."""

    def __init__(self, label: str, where: str, what: str, allowed: str):
        self.label, self.where, self.what, self.allowed = label, where, what, allowed
        head = f"{label}: {where}: " if where else f"{label}: "
        super().__init__(" ".join(f"{head}{what}; allowed: {allowed}".split()))


def mission_keys(cls) -> dict:
    """{mission-file key: (field path, Check)} of a section read into `cls`: its checked fields
    (only those with a `key` when the class names any: an algorithm's class exposes the
    parameters a mission sets, not its internals) and, in place, those of its `nested` ones."""
    fields = dataclasses.fields(cls)
    keyed = any(CHECK in f.metadata and f.metadata[CHECK].key for f in fields)
    out = {}
    for f in fields:
        if NESTED in f.metadata:
            out.update({key: ((f.name, *path), check)
                        for key, (path, check) in mission_keys(f.metadata[NESTED]).items()})
        elif CHECK in f.metadata and (f.metadata[CHECK].key or not keyed):
            out[f.metadata[CHECK].key or f.name] = ((f.name,), f.metadata[CHECK])
    return out


@dataclass(frozen=True)
class SiteSpec:
    """Where the mission flies: exactly one of `scenario` (built-in), `world` (a mesh file) or
    `tile` (a survey grid whose site files are generated on first use, `mission.site`).

    Attributes:
        scenario: a name of `drake_auv.scenarios.list_scenarios()`.
        world: true world mesh (PLY/OBJ/STL/GLB), seabed and structure, m, z up, sea surface
            z = 0, in the site's horizontal coordinates (those of the prior raster's CRS).
        target: mesh of the structure whose coverage is scored (None: the whole world).
        prior: prior bathymetry raster the planner sees (None: the site has no prior map; the
            plan, follow and fly steps need one, explore steps do not).
        prior_from_world: with no `prior` raster, sample one from the world mesh as a survey
            from above sees it (overhangs hidden), for a site given as a mesh alone.
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

    scenario: str | None = param(None, kind="choice", choices=SCENARIOS, nullable=True)
    world: Path | None = param(None, kind="path", nullable=True, note=_FILE)
    target: Path | None = param(None, kind="path", nullable=True, note=_FILE)
    prior: Path | None = param(None, kind="path", nullable=True, note=_FILE)
    prior_from_world: bool = param(False, kind="bool")
    prior_error_m: float = param(0.0, low=0.0, high=5.0, unit="m")
    prior_spacing_m: float | None = param(None, low=0.0, high=100.0, low_open=True, unit="m",
                                          nullable=True)
    crs: str | None = param(None, kind="text", nullable=True)
    start: tuple | None = param(None, kind="vector", names=("x", "y", "z", "yaw_deg"),
                                unit="m, m, m, deg", nullable=True)
    max_range_m: float = param(20.0, low=0.0, high=200.0, low_open=True, unit="m")
    tile: Path | None = param(None, kind="path", nullable=True,
                              note="a georeferenced bathymetry grid (GeoTIFF), relative to "
                                   "the mission file")
    roi: tuple | None = param(None, kind="vector", names=("xmin", "ymin", "xmax", "ymax"),
                              unit="m, the tile's world frame", nullable=True)

    def __post_init__(self):
        validate(self)


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
        params: the `ReplanningParameters` (their defaults), of which the file sets
            `R` (radius), `K` (max_waypoints), `clearance_m` (clearance), `rollouts` and
            `iterations` (the STOMP ones) and `current_aware` (the cost knows the forecast
            current of the `ocean:` section); `omega` comes from the plan step.
        period_s: replanning period, s.
        voxel_m: edge of the on-line octree map's voxels, m.
        multibeam_stride: every n-th multibeam beam goes into the on-line map (the profiler's
            all do); the multibeam's coverage is scored on every beam whatever this is.
        discretize: OctoMap's discretised insertion into the on-line map, one ray per endpoint
            voxel (`OctreeMap`): faster, free water cleared towards voxel centres.
        offset_metric: "horizontal" or "3d" distance to the map for the offset (see
            `ReplanningParameters`); "auto": "3d" after a coverage plan (offsets along the
            surface normal), "horizontal" after a contour plan.
    """

    optimizer: str = param("stomp", kind="choice", choices=OPTIMIZERS)
    params: ReplanningParameters = nested(ReplanningParameters)
    period_s: float = param(1.0, low=0.1, high=10.0, unit="s")
    voxel_m: float = param(0.5, low=0.1, high=2.0, unit="m")
    multibeam_stride: int = param(2, low=1, high=16, integer=True)
    discretize: bool = param(False, kind="bool")
    offset_metric: str = param("auto", kind="choice", choices=("auto", "horizontal", "3d"))

    def __post_init__(self):
        validate(self)

    def to_params(self, omega: float, plan_method: str) -> ReplanningParameters:
        """`params` for the offset `omega` (m) after a `plan_method` plan."""
        metric = self.offset_metric
        if metric == "auto":
            metric = "horizontal" if plan_method == "contour" else "3d"
        return dataclasses.replace(self.params, omega=omega, offset_metric=metric)


@dataclass(frozen=True)
class PayloadSpec:
    """Attributes: multibeam_mount: where the multibeam looks; camera_range_m: distance up to
    which the camera resolves the surface, m; camera_aperture_deg: its full aperture, deg."""

    multibeam_mount: str = param("port", kind="choice",
                                 choices=("port", "starboard", "down", "forward"))
    camera_range_m: float = param(12.0, low=0.5, high=50.0, unit="m")
    camera_aperture_deg: float = param(60.0, low=5.0, high=170.0, unit="deg")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class LimitsSpec:
    """Attributes: max_time_s: cap on the dive's simulated time, s (None: none);
    time_margin: a step may last this many times its nominal duration."""

    max_time_s: float | None = param(None, **_TIME)
    time_margin: float = param(1.4, low=1.0, high=5.0)

    def __post_init__(self):
        validate(self)


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
    omega: float = param(low=0.5, high=100.0, unit="m")
    method: str = param("coverage", kind="choice", choices=("coverage", "contour"))
    slice_count: int | None = param(None, low=1, high=20, integer=True, nullable=True)
    slice_spacing: float | None = param(None, low=0.0, high=50.0, low_open=True, unit="m",
                                        nullable=True)
    slope_threshold: float = param(0.5, low=0.0, high=10.0, low_open=True)
    aperture_deg: float = param(60.0, low=5.0, high=170.0, unit="deg")
    overlap: float = param(0.1, low=0.0, high=0.9)
    min_area_m2: float | None = param(None, low=0.0, unit="m^2", nullable=True)
    depth: float | None = param(None, **_DEPTH)
    end_width_m: float | None = param(None, low=0.0, high=1000.0, low_open=True, unit="m",
                                      nullable=True)
    end_heading_deg: float | None = param(None, **_ANGLE, nullable=True)
    end_overrun_m: float | None = param(None, low=0.0, high=100.0, unit="m", nullable=True)
    speed: float = param(0.5, **_SPEED)

    def __post_init__(self):
        validate(self)


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
    mode: str = param(kind="choice", choices=("horizontal", "vertical"))
    offset: float = like(FollowingParams, "offset", required=True)
    depth: float | None = param(None, **_DEPTH)
    loops: float = param(1.0, low=0.0, high=100.0, low_open=True)
    distance_m: float | None = param(None, low=0.0, high=10000.0, low_open=True, unit="m",
                                     nullable=True)
    end_depth_m: float | None = param(None, **_DEPTH)
    heading_deg: float | None = param(None, **_ANGLE, nullable=True)
    start: tuple | None = param(None, kind="vector", names=("x", "y"), unit="m, site coordinates",
                                nullable=True)
    speed: float = like(FollowingParams, "speed")
    corner_weight: float = like(FollowingParams, "corner_weight")
    min_depth_m: float = like(FollowingParams, "min_depth")
    max_time_s: float | None = param(None, **_TIME)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class SurveyStep:
    """The plan of the earlier `plan` step, flown with realtime replanning (or as planned).

    Attributes: replanning: replan against the on-line map; max_time_s: cap, s (None: the
    plan's duration times `limits.time_margin`)."""

    KIND: ClassVar[str] = "survey"
    replanning: bool = param(True, kind="bool")
    max_time_s: float | None = param(None, **_TIME)

    def __post_init__(self):
        validate(self)


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
    file: Path = param(kind="path", note="a COLA2 mission (.xml) or QGroundControl plan (.plan) "
                                         "file, relative to the mission file")
    heave_in_3d: bool = param(False, kind="bool")
    speed: float = param(0.5, **_SPEED)
    max_time_s: float | None = param(None, **_TIME)

    def __post_init__(self):
        validate(self)

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
        no_return_clear_m: how far a sonar beam without an echo clears free water in the
            on-line map while the mission explores, m (`mapping.OctreeMap`; the sonar's range
            or more: cleared to it). No echo is not proof of water, and explore's paths
            cross only the water the map holds.
    """

    KIND: ClassVar[str] = "explore"
    region: tuple = param(kind="vector", names=("xmin", "ymin", "zmin", "xmax", "ymax", "zmax"),
                          unit="m, site coordinates")
    omega: float = like(ExploreParameters, "omega")
    max_time_s: float = param(1800.0, low=0.0, low_open=True, unit="s")
    clearance_m: float = like(ExploreParameters, "clearance")
    strategy: str = like(ExploreParameters, "strategy")
    min_gain_m2: float = like(ExploreParameters, "min_gain_m2")
    no_return_clear_m: float = param(NO_RETURN_CLEAR_M, low=0.0, low_open=True, unit="m")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class SonarSilentFault:
    """A sonar that returns nothing from `start_s` for `duration_s` s (None: no fault).
    Attributes: sensor: "multibeam", "profiler" or "both"."""

    sensor: str = param("both", kind="choice", choices=("multibeam", "profiler", "both"))
    start_s: float | None = param(None, low=0.0, unit="s", nullable=True)
    duration_s: float = param(30.0, low=0.0, low_open=True, unit="s")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class ThrusterFailureFault:
    """One thruster (`vehicle.model.THRUSTER_NAMES`) gives no force from `start_s` s on
    (None: no fault); the allocation is not told."""

    thruster: str = param("surge_port", kind="choice", choices=THRUSTER_NAMES)
    start_s: float | None = param(None, low=0.0, unit="s", nullable=True)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class NavigationJumpFault:
    """A late position fix: at `time_s` s (None: no fault) the estimated position jumps by
    `error_m` m horizontally towards `direction_deg` (deg from +x, local frame)."""

    time_s: float | None = param(None, low=0.0, unit="s", nullable=True)
    error_m: float = param(3.0, low=0.0, high=100.0, unit="m")
    direction_deg: float = param(0.0, **_ANGLE)

    def __post_init__(self):
        validate(self)


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


# The step kinds, in the order error messages list them. A new kind: a frozen dataclass with
# `KIND` and `param` fields, added to `Step` and `STEP_KINDS` here; a rule tying its fields
# together goes in `drake_auv.mission.config.RULES`, how it flies in `mission.plan`.
Step = PlanStep | FollowStep | SurveyStep | FlyStep | ExploreStep
STEP_KINDS = {cls.KIND: cls
              for cls in (PlanStep, FollowStep, SurveyStep, FlyStep, ExploreStep)}
FAULT_CLASSES = {"sonar_silent": SonarSilentFault, "thruster_failure": ThrusterFailureFault,
                 "navigation_jump": NavigationJumpFault}


@dataclass(frozen=True)
class MissionSpec:
    """A validated mission. `source` is the file it was read from (not compared)."""

    name: str = param(kind="text")
    site: SiteSpec
    steps: tuple
    seed: int = param(0, low=0, high=MAX_SEED, integer=True, note=SEED_RANGE)
    description: str | None = param(None, kind="text", nullable=True)
    navigation: NavigationParams = NavigationParams()
    sonar_noise: SonarNoiseSpec = SonarNoiseSpec()
    replanner: ReplannerSpec = ReplannerSpec()
    payload: PayloadSpec = PayloadSpec()
    limits: LimitsSpec = LimitsSpec()
    faults: FaultsSpec = FaultsSpec()
    ocean: OceanSpec | None = None  # None: still water (`ocean: none`)
    source: Path | None = field(default=None, compare=False)

    def __post_init__(self):
        validate(self)


# The sections of a mission file besides `sonar_noise`, `faults` and `steps`, read by
# `mission_keys` of their class.
SECTIONS = dict(site=SiteSpec, navigation=NavigationParams, replanner=ReplannerSpec,
                payload=PayloadSpec, limits=LimitsSpec)
TOP_KEYS = ("name", "description", "seed", "site", "navigation", "sonar_noise", "replanner",
            "payload", "limits", "faults", "ocean", "steps")
