"""From a mission file to what the Diagram flies: the off-line plan and the legs.

`check_against_site` first judges what only the loaded site can (the start, each step's kind's
`check_site`).
`plan_mission` asks every step's kind (`drake_auv.mission.steps`), in the file's order, to
prepare (the `plan` step runs the coverage planner or the offset contour on the site's prior
map; a `fly` step reads its exported file and places its items in the local frame), then to
add its legs (`drake_auv.mission.legs`): a transit to where the step begins, then the step's
behaviour, each with the parameters its LeafSystem needs and a time budget. Pure: no Drake is
loaded (the legs' parameters are plain data classes), so a mission plans where pydrake is
missing.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_auv.mission.legs import Leg
from drake_auv.mission.site import Site, check_in_water, check_inside
from drake_auv.mission.spec import MissionSpec
from drake_auv.mission.steps import STEPS
from drake_auv.mission.steps.step import Planning
from drake_auv.planning.path import PlannedPath


@dataclass
class MissionPlan:
    """The off-line part of a mission.

    Attributes:
        nominal: the nominal path of the survey (None without a plan step).
        coverage: the `CoveragePlan` when the plan step used the coverage planner.
        omega: the plan's offset, m (None without a plan step).
        method: the plan step's method ("coverage" or "contour"; the replanner's offset metric
            follows it).
        legs: every leg in order.
        behaviours: {behaviour name: {leg index: the parameters its LeafSystem takes for that
            leg}} ("path": `PathLeg`, "follow": `FollowConfig`, "replan": None, "autopilot":
            the `FlownMission` of a fly step, "explore": `ExploreParameters`, a step's own).
        profiler_planes: legs whose profiler scans the vertical plane.
        survey_speed: m/s along the nominal path (the plan step's).
        start_state: (12,) where the vehicle starts (local frame).
        budget: sum of the legs' time budgets, s.
    """

    nominal: PlannedPath | None
    coverage: object
    omega: float | None
    method: str
    legs: tuple[Leg, ...]
    behaviours: dict[str, dict[int, object]]
    profiler_planes: dict[int, str]
    survey_speed: float
    start_state: np.ndarray
    budget: float = field(default=0.0)

    def time_cap(self, spec: MissionSpec) -> tuple[float, str]:
        """The dive's simulated time cap, s (the runner stops there, and the sea's files are
        checked over it), and where it comes from: `limits.max_time_s`, or when that is null
        the legs' time budgets summed (each its nominal duration times `limits.time_margin`,
        plus slack)."""
        if spec.limits.max_time_s is not None:
            return float(spec.limits.max_time_s), "limits.max_time_s"
        return float(self.budget), ("the legs' time budgets summed (limits.max_time_s is "
                                    "null)")

    def legs_of(self, behaviour: str) -> dict[int, object]:
        """{leg index: parameters} of the legs `behaviour` flies (empty: none)."""
        return self.behaviours.get(behaviour, {})


def check_against_site(spec: MissionSpec, site: Site) -> None:
    """Checks the mission values only the site can judge, against the prior map (what the
    operator knows) and the world's bounds: the start inside the world's bounds and in the
    water (`check_in_water`: against the world itself), and each step's own (its kind's
    `check_site`: follow depths above the seabed under the structure, plan offsets and contour
    depths that leave water). Raises MissionFileError (one line) on the first problem."""
    label = spec.source.name if spec.source is not None else spec.name
    if spec.site.start is not None:
        x, y = check_inside(site, spec.site.start, "site.start", label)
        check_in_water(site, [x, y, spec.site.start[2]], label, "site.start", "")
    for i, step in enumerate(spec.steps):
        STEPS[step.KIND].check_site(site, step, f"steps[{i}].{step.KIND}", label)


def plan_mission(spec: MissionSpec, site: Site) -> MissionPlan:
    """Plans the mission `spec` at `site` (see the module docstring)."""
    label = spec.source.name if spec.source is not None else spec.name
    planning = Planning(spec, site, label)
    steps = [(k, step, STEPS[step.KIND]) for k, step in enumerate(spec.steps)]
    for k, step, kind in steps:
        kind.prepare(planning, k, step)
    start = site.start_state
    if start is None:  # at the beginning of the first simulated step
        k, step, kind = next(((k, s, kind) for k, s, kind in steps if kind.flies),
                             (None, None, None))
        if kind is None:
            raise ValueError(f"mission {spec.name!r} has no simulated step")
        start = kind.start(planning, k, step)
        check_in_water(site, start[:3], label, f"steps[{k}].{step.KIND}",
                       f"where the dive starts, at ({start[0]:.1f}, {start[1]:.1f}) local")
    else:
        check_in_water(site, start[:3], label, "site.start", "")
    planning.position, planning.yaw = np.asarray(start[:3], float), float(start[5])
    for k, step, kind in steps:
        kind.plan(planning, k, step)
    if not planning.legs:
        raise ValueError(f"mission {spec.name!r} has no simulated step (follow or survey)")
    return MissionPlan(planning.nominal, planning.coverage, planning.omega, planning.method,
                       tuple(planning.legs), planning.behaviours, planning.profiler_planes,
                       planning.survey_speed, np.asarray(start, float), planning.budget)
