"""The `plan` step: the off-line plan on the site's prior map (the coverage planner, or the
offset contour of the structure at one depth); a later `survey` flies it. It flies nothing
itself."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from drake_auv.mission.spec import ANGLE_DEG, DEPTH_M, SPEED_MS, MissionFileError
from drake_auv.mission.steps.step import MissionStep
from drake_auv.params import checks, like, param, validate
from drake_auv.planning.parameters import CoverageParameters


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
        The planner's parameters take their defaults and ranges from `CoverageParameters`
        (`omega` is required here).
        depth: depth of the contour, m; contour only, required there.
        end_width_m, end_heading_deg, end_overrun_m: contour only: fly around the end of a
            long structure, `end_width_m` wide, facing `end_heading_deg` (deg from +x, None:
            0), the contour kept `end_overrun_m` further (None: 7 m, the largest prior error
            plus 2 m); see `nominal_contour` (end_width_m None: the whole closed contour).
        speed: survey speed, m/s.
    """

    KIND: ClassVar[str] = "plan"
    omega: float = like(CoverageParameters, "omega", required=True)
    method: str = param("coverage", kind="choice", choices=("coverage", "contour"))
    slice_count: int | None = like(CoverageParameters, "slice_count")
    slice_spacing: float | None = like(CoverageParameters, "slice_spacing")
    slope_threshold: float = like(CoverageParameters, "slope_threshold")
    aperture_deg: float = like(CoverageParameters, "aperture_deg")
    overlap: float = like(CoverageParameters, "overlap")
    min_area_m2: float | None = like(CoverageParameters, "min_area")
    depth: float | None = param(None, **DEPTH_M)
    end_width_m: float | None = param(None, low=0.0, high=1000.0, low_open=True, unit="m",
                                      nullable=True)
    end_heading_deg: float | None = param(None, **ANGLE_DEG, nullable=True)
    end_overrun_m: float | None = param(None, low=0.0, high=100.0, unit="m", nullable=True)
    speed: float = param(0.5, **SPEED_MS)

    def __post_init__(self):
        validate(self)


def nominal_plan(step: PlanStep, site):
    """(nominal path, coverage plan or None) of the plan step."""
    if step.method == "contour":
        from drake_auv.planning.contour import nominal_contour

        path = nominal_contour(
            site.prior, step.depth, step.omega, step.end_width_m,
            end_heading=np.radians(step.end_heading_deg or 0.0),
            **({} if step.end_overrun_m is None else {"overrun": step.end_overrun_m}))
        return path, None
    from drake_auv.planning.coverage_plan import plan_coverage

    plan = plan_coverage(site.prior, CoverageParameters(
        omega=step.omega, aperture_deg=step.aperture_deg, overlap=step.overlap,
        slope_threshold=step.slope_threshold, slice_spacing=step.slice_spacing,
        slice_count=step.slice_count, sensor_range=site.max_range, min_area=step.min_area_m2))
    return plan.path, plan


class Plan(MissionStep):
    spec = PlanStep
    flies = False
    needs_prior = True

    @classmethod
    def check(cls, reader, v, where: str) -> None:
        contour = v.method == "contour"
        if contour and v.depth is None:
            reader.fail(f"{where}.depth", "missing (required by method contour)",
                        checks(PlanStep)["depth"].allowed())
        only = ("depth", "end_width_m", "end_heading_deg", "end_overrun_m") if not contour else (
            "slice_count", "slice_spacing", "min_area_m2")
        for key in only:
            if getattr(v, key) is not None:
                reader.fail(f"{where}.{key}", f"not used by method {v.method}",
                            "null (or the other method)")

    @classmethod
    def check_steps(cls, reader, steps: tuple) -> None:
        plans = [i for i, s in enumerate(steps) if isinstance(s, PlanStep)]
        if len(plans) > 1:
            reader.fail(f"steps[{plans[1]}].plan", "a second plan step", "at most one plan step")

    @classmethod
    def check_site(cls, site, step, where: str, label: str) -> None:
        deepest = float(-np.nanmin(site.prior.z))
        if step.method == "coverage" and step.omega >= deepest:
            raise MissionFileError(label, f"{where}.omega", f"{step.omega:g} m leaves no "
                                   f"water (the prior's deepest point is {deepest:.1f} m)",
                                   f"[0.5, {deepest:.1f}) m")
        if step.method == "contour":
            shallowest = float(-np.nanmax(site.prior.z))
            if not shallowest < step.depth < deepest:
                raise MissionFileError(label, f"{where}.depth", f"{step.depth:g} m cuts "
                                       "no structure in the prior map (its depths span "
                                       f"{shallowest:.1f} to {deepest:.1f} m)",
                                       f"({max(shallowest, 0.0):.1f}, {deepest:.1f}) m")

    @classmethod
    def prepare(cls, planning, index: int, step) -> None:
        from drake_auv.mission.site import check_path_in_water

        planning.nominal, planning.coverage = nominal_plan(step, planning.site)
        check_path_in_water(planning.nominal, planning.site, planning.label,
                            f"steps[{index}].plan")
        planning.method, planning.omega = step.method, step.omega
        planning.survey_speed = step.speed


STEP = Plan
