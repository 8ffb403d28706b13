"""The `explore` step: on-line view planning from the octree, no prior map
(`drake_auv.exploration`), flown by the `ViewPlanner` with a DVL guarding the seabed. One
leg, no transit: the view planner flies from wherever the vehicle is; it ends when no
viewpoint is worth seeing or on its time cap."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from drake_auv.exploration.planner import ExploreParameters
from drake_auv.mission.legs import Leg
from drake_auv.mission.spec import MissionFileError
from drake_auv.mission.steps.step import MissionStep
from drake_auv.params import like, param, validate

NO_RETURN_CLEAR_M = 12.0  # m, explore's free-water clearing by beams without an echo
EXPLORE_PERIOD = 5.0  # s, of the view planner's planning steps


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


def explore_region(step: ExploreStep, site) -> np.ndarray:
    """(6,) the step's region in the local frame."""
    region = np.asarray(step.region, dtype=float)
    return np.concatenate([site.to_local(region[:3]), site.to_local(region[3:])])


def explore_start(step: ExploreStep, site) -> np.ndarray:
    """(3,) where an explore step begins when the site gives no start: Omega plus the
    clearance west (-x) of the region, at its mid-height (below z = -2 m)."""
    region = explore_region(step, site)
    return np.array([region[0] - step.omega - step.clearance_m,
                     0.5 * (region[1] + region[4]), min(0.5 * (region[2] + region[5]), -2.0)])


def explore_parameters(step: ExploreStep, site, spec, label: str, where: str):
    """The step's `ExploreParameters` (local frame). Raises MissionFileError (one line
    naming `where`) for a region that holds no part of the world, or whose water the
    vehicle cannot reach (every point of it below the seabed or inside the structure:
    `Site.clearance`)."""
    region = explore_region(step, site)
    axes = [np.linspace(region[k] + 0.25, region[k + 3] - 0.25,
                        int(np.clip((region[k + 3] - region[k]) / 1.0, 2, 24)))
            for k in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    points = points[points[:, 2] < -1.0]
    if np.all(site.clearance.inside(points)):
        raise MissionFileError(label, f"{where}.region", f"{list(step.region)} holds no water "
                               "the vehicle can reach (all of it below the seabed or inside "
                               "the structure)", "a box that holds open water below z = -1 m")
    (sx0, sy0, sz0), (sx1, sy1, sz1) = site.to_site(site.world.bounds)
    triangles = site.world.vertices[site.world.faces]
    lo, hi = triangles.min(axis=1), triangles.max(axis=1)
    if not np.any(np.all((hi >= region[:3]) & (lo <= region[3:]), axis=1)):
        raise MissionFileError(label, f"{where}.region", f"{list(step.region)} holds no part "
                               "of the world", f"a box meeting the world, which spans x "
                               f"[{sx0:.1f}, {sx1:.1f}], y [{sy0:.1f}, {sy1:.1f}], z "
                               f"[{sz0:.1f}, {sz1:.1f}] m")
    return ExploreParameters(
        region=tuple(region), omega=step.omega, clearance=step.clearance_m,
        strategy=step.strategy, min_gain_m2=step.min_gain_m2, max_range=site.max_range,
        mount=spec.payload.multibeam_mount)


class Explore(MissionStep):
    spec = ExploreStep
    behaviour = "explore"

    @classmethod
    def check(cls, reader, v, where: str) -> None:
        region = v.region
        if not all(region[k] < region[k + 3] for k in range(3)):
            reader.fail(f"{where}.region", f"{list(region)} has min >= max on an axis",
                        "xmin < xmax, ymin < ymax, zmin < zmax")
        if region[2] >= 0.0:
            reader.fail(f"{where}.region", f"zmin {region[2]:g} is not below the sea surface",
                        "zmin < 0 m (z up, sea surface z = 0)")
        if v.omega <= v.clearance_m:
            reader.fail(f"{where}.omega", f"{v.omega:g} m is not above clearance_m "
                        f"{v.clearance_m:g} m (a viewpoint at omega would break the clearance)",
                        f"omega > clearance_m ({v.clearance_m:g} m)")

    @classmethod
    def start(cls, planning, k: int, step) -> np.ndarray:
        start = np.zeros(12)
        start[:3] = explore_start(step, planning.site)
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        params = explore_parameters(step, planning.site, planning.spec, planning.label,
                                    f"steps[{k}].explore")
        planning.add(Leg("explore", k, "explore", "finished", step.max_time_s), params)
        planning.position = 0.5 * (np.asarray(params.region[:3]) + params.region[3:])

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        from drake_auv.exploration.view_planner import ViewPlanner

        explorer = wiring.builder.AddNamedSystem("view_planner", ViewPlanner(
            legs, period=EXPLORE_PERIOD, seed=wiring.spec.seed))
        wiring.builder.Connect(wiring.mapper.map_output, explorer.map_input)
        wiring.builder.Connect(wiring.dvl().seabed_output, explorer.seabed_input)
        wiring.log("exploration", explorer.step_output, explorer.period)
        return explorer


STEP = Explore
