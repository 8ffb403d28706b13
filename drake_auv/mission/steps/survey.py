"""The `survey` step: the earlier `plan` step's nominal path flown, with realtime replanning
against the on-line map (the `Replanner`) or as planned (the path reference).

Its legs: a transit to the plan's first sample, then the survey. Before a replanned survey the
transit hands over within R of that sample (placed on the shifted prior map, it may lie near
the real structure): the replanner flies the rest against the on-line map.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from drake_auv.mission.legs import Leg
from drake_auv.mission.spec import TIME_S
from drake_auv.mission.steps.step import (SENSOR_AZIMUTH, TIME_SLACK, TRANSIT_SPEED,
                                          MissionStep)
from drake_auv.params import param, validate
from drake_auv.vehicle.path_leg import PathLeg


@dataclass(frozen=True)
class SurveyStep:
    """The plan of the earlier `plan` step, flown with realtime replanning (or as planned).

    Attributes: replanning: replan against the on-line map; max_time_s: cap, s (None: the
    plan's duration times `limits.time_margin`)."""

    KIND: ClassVar[str] = "survey"
    replanning: bool = param(True, kind="bool")
    max_time_s: float | None = param(None, **TIME_S)

    def __post_init__(self):
        validate(self)


class Survey(MissionStep):
    spec = SurveyStep
    behaviour = "replan"

    @classmethod
    def check_steps(cls, reader, steps: tuple) -> None:
        plans = [i for i, s in enumerate(steps) if s.KIND == "plan"]
        for i, step in enumerate(steps):
            if isinstance(step, SurveyStep) and not (plans and plans[0] < i):
                reader.fail(f"steps[{i}].survey", "no earlier plan step to survey",
                            "a survey after a plan step")

    @classmethod
    def start(cls, planning, index: int, step) -> np.ndarray:
        start = np.zeros(12)
        start[:3], start[5] = planning.nominal.points[0], planning.nominal.heading[0]
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        nominal, spec = planning.nominal, planning.spec
        planning.add_transit(k, nominal.points[0], float(nominal.heading[0]), TRANSIT_SPEED,
                             handover=spec.replanner.params.radius if step.replanning else None)
        duration = step.max_time_s or (planning.margin * nominal.times(planning.survey_speed)[-1]
                                       + TIME_SLACK)
        if step.replanning:
            planning.add(Leg("survey", k, "replan", "finished", duration))
        else:
            planning.add(Leg("survey", k, "path", "finished", duration),
                         PathLeg("nominal", speed=planning.survey_speed))
        planning.position = nominal.points[-1]

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        from drake_auv.ocean.forecast import forecast
        from drake_auv.replanning.replanner import Replanner

        spec, plan = wiring.spec, wiring.plan
        replanner = wiring.builder.AddNamedSystem("replanner", Replanner(
            spec.replanner.to_params(plan.omega, plan.method), speed=plan.survey_speed,
            period=spec.replanner.period_s,
            sensor_azimuth=SENSOR_AZIMUTH.get(spec.payload.multibeam_mount),
            seed=spec.seed, legs=tuple(legs), optimizer=spec.replanner.optimizer,
            current=forecast(spec.ocean)))
        connect_replanner(wiring, replanner)
        return replanner


def connect_replanner(wiring, replanner) -> None:
    """`replanner`'s `map` and `nominal` inputs, those it declares, connected; its `step`
    output, if it has one, logged as `replanning`."""
    for name, port in (("map", wiring.mapper.map_output), ("nominal", wiring.nominal)):
        if replanner.HasInputPort(name):
            wiring.builder.Connect(port, replanner.GetInputPort(name))
    if replanner.HasOutputPort("step"):
        wiring.log("replanning", replanner.GetOutputPort("step"), replanner.period)


STEP = Survey
