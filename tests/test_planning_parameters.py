"""`CoverageParameters` is the one statement of the planner's defaults and ranges: the mission's
plan step, `drake-auv plan` and the table in docs/planning.md read them from there."""

import dataclasses
import math
from pathlib import Path

import pytest

from drake_auv.commands import option_range
from drake_auv.commands.plan import OPTIONS
from drake_auv.mission.steps.plan import PlanStep
from drake_auv.params import ParameterError, checks, defaults
from drake_auv.planning.parameters import CoverageParameters

DOC = Path(__file__).resolve().parents[1] / "docs" / "planning.md"


def _shown(value) -> str:
    return "None" if value is None else f"{value:g}" if isinstance(value, float) else str(value)


def parameter_rows() -> list[list[str]]:
    """Name, default, allowed values, `drake-auv plan` option and mission key of every field."""
    plan_keys = {id(c): k for k, c in checks(PlanStep).items()}
    return [[f"`{name}`", _shown(defaults(CoverageParameters)[name]), option_range(check),
             f"`{OPTIONS[name]}`" if name in OPTIONS else "",
             f"`{plan_keys[id(check)]}`" if id(check) in plan_keys else ""]
            for name, check in checks(CoverageParameters).items()]


def test_the_docs_table_matches_the_dataclass():
    rows = [[c.strip() for c in line.strip().strip("|").split("|")][:5]
            for line in DOC.read_text().splitlines() if line.startswith("| `")
            and line.split("|")[1].strip().strip("`") in defaults(CoverageParameters)]
    assert rows == parameter_rows()


def test_the_plan_step_and_the_command_line_share_each_check_and_default():
    from drake_auv.cli import build_parser

    shared = checks(CoverageParameters)
    for key, field in {"omega": "omega", "slice_count": "slice_count",
                       "slice_spacing": "slice_spacing", "slope_threshold": "slope_threshold",
                       "aperture_deg": "aperture_deg", "overlap": "overlap",
                       "min_area_m2": "min_area"}.items():
        assert checks(PlanStep)[key] is shared[field]
    args = build_parser().parse_args(["plan", "grid.tif", "-o", "out"])
    assert CoverageParameters(**{f: getattr(args, f) for f in OPTIONS}) == CoverageParameters()


def test_fields_are_checked_on_construction_and_replace():
    with pytest.raises(ParameterError, match=r"CoverageParameters.omega = 0.2 is out of range"):
        CoverageParameters(omega=0.2)
    with pytest.raises(ParameterError, match="overlap"):
        dataclasses.replace(CoverageParameters(), overlap=math.nan)
