"""What a mission step kind is (`MissionStep`) and what it is given: the plan being built
(`Planning`, pure) and the Diagram being built (`Wiring`). Pure: no Drake is loaded here, a
step's behaviour imports its LeafSystem inside `add_behaviour`.

A step kind is a class with class attributes and class methods only, one module per kind
(`drake_auv.mission.steps`): its spec (a frozen dataclass with `KIND` and `param` fields, read
from the mission file by `drake_auv.mission.config`), its file rules (`check`, across steps
`check_steps`, on the loaded site `check_site`), its legs (`prepare`, `start`, `plan`) and its
behaviour's wiring into the Diagram (`add_behaviour`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from drake_auv.mission.legs import Leg
from drake_auv.planning.surface import TerrainSurface
from drake_auv.vehicle.path_leg import PathLeg

if TYPE_CHECKING:
    from drake_auv.mission.site import Site
    from drake_auv.mission.spec import MissionSpec

LOG_PERIOD = 0.1  # s, of the behaviours' logs (the mission's state logs' period)
TIME_SLACK = 120.0  # s a leg may last beyond `limits.time_margin` times its nominal duration
TRANSIT_SPEED = 0.5  # m/s
SENSOR_AZIMUTH = {"port": np.pi / 2, "starboard": -np.pi / 2}  # payload axis in the body frame


def charted_centre(site: Site) -> np.ndarray:
    """(2,) the structure's centre on the operator's chart: the target footprint's centre,
    moved by the prior map's error (the chart and the prior map agree)."""
    lo, hi = site.target_mesh.bounds
    return 0.5 * (lo[:2] + hi[:2]) + site.prior_shift


def terrain_elevation(site: Site):
    """The prior map's elevation as a callable (x, y) -> z, for transits."""
    return TerrainSurface(site.prior).elevation


@dataclass
class Planning:
    """The off-line plan while `plan_mission` builds it, step after step.

    Attributes:
        spec, site, label: the mission, where it flies, and the name its errors give.
        nominal, coverage, omega, method, survey_speed: the plan step's nominal path,
            `CoveragePlan` (None: contour), offset (m), method and survey speed (m/s).
        legs: the legs so far; behaviours: {behaviour name: {leg index: the parameters its
            LeafSystem takes for that leg}}; profiler_planes: legs whose profiler scans the
            vertical plane; budget: the legs' time budgets summed, s.
        position, yaw: where the vehicle is when the next step begins (local frame, m, rad).
        prepared: {step index: what the step's `prepare` computed (a fly step's file)}.
    """

    spec: MissionSpec
    site: Site
    label: str
    nominal: object = None
    coverage: object = None
    omega: float | None = None
    method: str = "coverage"
    survey_speed: float = 0.5
    legs: list = field(default_factory=list)
    behaviours: dict = field(default_factory=dict)
    profiler_planes: dict = field(default_factory=dict)
    budget: float = 0.0
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    yaw: float = 0.0
    prepared: dict = field(default_factory=dict)

    @property
    def margin(self) -> float:
        """`limits.time_margin`: a leg's budget is this times its nominal duration (+ slack)."""
        return self.spec.limits.time_margin

    def add(self, leg: Leg, params=None) -> int:
        """Appends `leg` flown by its behaviour with `params`; returns its index."""
        self.legs.append(leg)
        self.budget += leg.max_duration
        index = len(self.legs) - 1
        self.behaviours.setdefault(leg.behaviour, {})[index] = params
        return index

    def add_transit(self, step_index: int, target, end_yaw, speed: float,
                    handover: float | None = None) -> int:
        """A transit leg (the path reference) from `position` to `target` (3,), ending at
        `end_yaw` rad (None: as it arrives); within `handover` m the next leg takes over."""
        target = np.asarray(target, dtype=float)
        duration = self.margin * np.linalg.norm(target - self.position) / speed + TIME_SLACK
        index = self.add(Leg("transit", step_index, "path", "arrive", duration,
                             target=tuple(target), tolerance=1.5, handover=handover),
                         PathLeg("goto", tuple(target), end_yaw, speed))
        self.position, self.yaw = target, self.yaw if end_yaw is None else end_yaw
        return index

    def default_start(self, depth: float | None) -> np.ndarray:
        """(12,) a start 30 m west (-x) of the charted centre at `depth` m (None: 5 m)."""
        start = np.zeros(12)
        xy = charted_centre(self.site) + [-30.0, 0.0]
        start[:3] = (xy[0], xy[1], -(depth or 5.0))
        return start


@dataclass
class Wiring:
    """The mission Diagram while `build_mission_diagram` builds it: what a step's behaviour
    may connect to.

    Attributes:
        builder, spec, plan, site, caster: the `DiagramBuilder`, the mission, its
            `MissionPlan`, the site and the `RayCaster` of its true world.
        vehicle: the `VehicleSystems`; estimated: the estimated-state port downstream reads.
        mapper: the `OctreeMapper`; returns: {sensor: its returns port}; profiler: the
            pencil-beam profiler.
        nominal: the off-line plan's source port (None without a plan step).
        logs: {name: VectorLogSink} the runner spools (a step adds its behaviour's).
        added: {name: system} of the sensors added on demand (`dvl()`).
    """

    builder: object
    spec: MissionSpec
    plan: object
    site: Site
    caster: object
    vehicle: object
    estimated: object
    mapper: object
    returns: dict
    profiler: object
    nominal: object = None
    logs: dict = field(default_factory=dict)
    added: dict = field(default_factory=dict)

    def dvl(self):
        """The DVL (added on first call: ray casting on the true world, realistic unless the
        sonars are clean; its beams feed the mapper's `dvl_returns`)."""
        if "dvl" not in self.added:
            from drake_auv.sonar.altimeter import DvlAltimeter

            dvl = self.added["dvl"] = self.builder.AddNamedSystem("dvl", DvlAltimeter(
                self.caster, noise=self.spec.sonar_noise.to_noise() is not None,
                seed=self.spec.seed))
            self.builder.Connect(self.vehicle.dynamics.state_output, dvl.true_state_input)
            self.builder.Connect(self.estimated, dvl.estimated_state_input)
            self.builder.Connect(dvl.returns_output, self.mapper.returns_inputs["dvl"])
        return self.added["dvl"]

    def log(self, name: str, port, period: float) -> None:
        """Logs `port` every `period` s as `logs[name]`."""
        from pydrake.systems.primitives import LogVectorOutput

        self.logs[name] = LogVectorOutput(port, self.builder, period)


class MissionStep:
    """A step kind (see the module docstring). Subclass it and register it
    (`drake_auv.mission.steps.register`).

    Attributes:
        spec: the frozen dataclass a mission file's step of this kind is read into (its
            `KIND` is the step's key in the file).
        behaviour: the name of the behaviour its legs fly (its `PortSwitch` input and the
            supervisor's `<name>_status`), None for a step that flies nothing itself.
        flies: whether the step flies (False: off-line only, like `plan`).
        needs_prior: whether it reads the site's prior map.
    """

    spec: ClassVar[type]
    behaviour: ClassVar[str | None] = None
    flies: ClassVar[bool] = True
    needs_prior: ClassVar[bool] = False

    @classmethod
    def check(cls, reader, step, where: str) -> None:
        """The rules tying the step's fields together (`reader.fail` on a broken one)."""

    @classmethod
    def check_steps(cls, reader, steps: tuple) -> None:
        """The rules across the mission's steps (e.g. a survey needs an earlier plan)."""

    @classmethod
    def check_site(cls, site: Site, step, where: str, label: str) -> None:
        """The rules on the loaded site (raise `MissionFileError`)."""

    @classmethod
    def prepare(cls, planning: Planning, index: int, step) -> None:
        """Off-line work done before any leg (a plan, a file read)."""

    @classmethod
    def start(cls, planning: Planning, index: int, step) -> np.ndarray:
        """(12,) where the vehicle starts when this is the first step that flies and the
        site gives no start."""
        return planning.default_start(None)

    @classmethod
    def plan(cls, planning: Planning, index: int, step) -> None:
        """Adds the step's legs to `planning` and moves its `position`."""

    @classmethod
    def add_behaviour(cls, wiring: Wiring, legs: dict):
        """Adds the behaviour flying `legs` ({leg index: parameters}) to `wiring.builder`,
        with its own inputs connected (its `estimated_state`, `leg`, `reference` and
        `status` are wired by the Diagram builder); returns it."""
        raise NotImplementedError(f"step {cls.spec.KIND!r} has no behaviour of its own")
