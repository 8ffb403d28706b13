"""The mission's dataclasses: what a mission file holds, validated (pure Python, no Drake).

A mission names a site (a built-in scenario or the user's own files), the error sources
(navigation drift, sonar noise, prior-map shift), the replanner, the payload, the limits and the
steps flown in order in one dive (`plan`, `follow`, `survey`, `fly`, `explore`, ...: each
kind's spec lives in its module of `drake_auv.mission.steps`), and optional injected
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

from drake_auv.ocean.spec import OceanSpec
from drake_auv.params import CHECK, NESTED, nested, param, validate
from drake_auv.random_streams import MAX_SEED, SEED_RANGE
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import OPTIMIZERS
from drake_auv.scenarios import list_scenarios
from drake_auv.signals import THRUSTER_NAMES
from drake_auv.sonar.beams import MOUNT_ROTATIONS
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.sensor import source_table
from drake_auv.vehicle.navigation import NavigationParams

# The "realistic" sonar (docs/sensors.md, "Sonar model"): 10 cm range noise, 5 % of returns
# lost, 2 % water-column clutter; half the rays reaching the sea surface reflected on
# (multipath, echoes at the path length along the beam); a side lobe 20 deg off the axis at
# -11 dB; echoes detected above 0.05 of a normal on-axis one (grazing echoes are lost).
REALISTIC_NOISE = dict(range_sigma=0.1, dropout_prob=0.05, spurious_prob=0.02,
                       surface_prob=0.5, side_lobe_deg=20.0, side_lobe_gain=0.08,
                       echo_threshold=0.05)

SCENARIOS = tuple(name for name, _ in list_scenarios())
_FILE = "a file path, relative to the mission file"
# the ranges of the steps' fields of one kind (`param(**DEPTH_M)`)
DEPTH_M = dict(low=0.0, high=11000.0, low_open=True, unit="m", nullable=True)
TIME_S = dict(low=0.0, low_open=True, unit="s", nullable=True)
SPEED_MS = dict(low=0.05, high=1.4, unit="m/s")
ANGLE_DEG = dict(low=-360.0, high=360.0, unit="deg")
SENSOR_KINDS = ("multibeam", "profiler")


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
class SensorSpec:
    """A payload sonar of the `payload.sensors` table (docs/mission.md, "Payload sensors"),
    built like the built-in ones (`mission.diagram.sonar_table`): ray casting on the true
    world to the site's `max_range_m`, with the mission's `sonar_noise`, its returns mapped,
    logged and recorded under its name.

    Attributes:
        name: the sensor's name (the table's key: its system, ports, topics and point-cloud
            source), not one of `sonar.sensor.BUILT_IN`.
        kind: "multibeam" (a fan of `num_beams` over `fan_deg` at `rate_hz` pings/s) or
            "profiler" (the pencil-beam head of profile following, `rate_hz` batches/s).
        mount: the sensor frame's rotation on the vehicle (`sonar.beams.MOUNT_ROTATIONS`: a
            multibeam's fan plane, a profiler's scan plane); position_m: its origin in the
            body frame, m.
        map_stride: every n-th beam goes into the on-line map.
    """

    name: str = ""
    kind: str = param("multibeam", kind="choice", choices=SENSOR_KINDS)
    mount: str = param("starboard", kind="choice", choices=tuple(MOUNT_ROTATIONS))
    position_m: tuple = param((0.0, 0.0, 0.0), kind="vector", names=("x", "y", "z"), unit="m")
    rate_hz: float = param(10.0, low=0.1, high=30.0, unit="Hz")
    num_beams: int = param(480, low=1, high=2048, integer=True)
    fan_deg: float = param(120.0, low=0.0, high=360.0, high_open=True, unit="deg")
    map_stride: int = param(1, low=1, high=16, integer=True)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class PayloadSpec:
    """Attributes: multibeam_mount: where the multibeam looks; camera_range_m: distance up to
    which the camera resolves the surface, m; camera_aperture_deg: its full aperture, deg;
    sensors: the configured sonars (`SensorSpec`, the file's `sensors:` mapping of name to
    keys), carried besides the built-in multibeam, profiler and DVL."""

    multibeam_mount: str = param("port", kind="choice",
                                 choices=("port", "starboard", "down", "forward"))
    camera_range_m: float = param(12.0, low=0.5, high=50.0, unit="m")
    camera_aperture_deg: float = param(60.0, low=5.0, high=170.0, unit="deg")
    sensors: tuple = ()

    def __post_init__(self):
        validate(self)
        source_table(tuple(s.name for s in self.sensors))  # unique names, none built-in


@dataclass(frozen=True)
class LimitsSpec:
    """Attributes: max_time_s: cap on the dive's simulated time, s (None: none);
    time_margin: a step may last this many times its nominal duration."""

    max_time_s: float | None = param(None, **TIME_S)
    time_margin: float = param(1.4, low=1.0, high=5.0)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class OutputsSpec:
    """Attributes: mcap: `drake-auv run` and `demo` write `dive.mcap`, the dive as ROS 2
    messages (`drake_auv.rosio`), as it flies (a campaign's runs write none);
    reconstruction: build the surface of the dive's returns (`reconstruction.ply`, its figure
    and report section) after the dive; off, `points.ply` is still written."""

    mcap: bool = param(False, kind="bool")
    reconstruction: bool = param(True, kind="bool")

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
    """One thruster (`signals.THRUSTER_NAMES`) gives no force from `start_s` s on
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
    direction_deg: float = param(0.0, **ANGLE_DEG)

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
    outputs: OutputsSpec = OutputsSpec()
    faults: FaultsSpec = FaultsSpec()
    ocean: OceanSpec | None = None  # None: still water (`ocean: none`)
    source: Path | None = field(default=None, compare=False)

    def __post_init__(self):
        validate(self)


# The sections of a mission file besides `sonar_noise`, `faults` and `steps`, read by
# `mission_keys` of their class.
SECTIONS = dict(site=SiteSpec, navigation=NavigationParams, replanner=ReplannerSpec,
                payload=PayloadSpec, limits=LimitsSpec, outputs=OutputsSpec)
TOP_KEYS = ("name", "description", "seed", "site", "navigation", "sonar_noise", "replanner",
            "payload", "limits", "outputs", "faults", "ocean", "steps")
