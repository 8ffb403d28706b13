"""Off-line planners and optimisers, pure numpy/scipy (no Drake)."""

from drake_auv.planning.coverage_plan import CoveragePlan, plan_coverage
from drake_auv.planning.lawnmower import plan_lawnmower
from drake_auv.planning.path import Path

__all__ = ["CoveragePlan", "Path", "plan_coverage", "plan_lawnmower"]
