"""Off-line planners and optimisers, pure numpy/scipy (no Drake).

`PlannedPath` is imported eagerly; the planners load on first use (they pull in scipy, contourpy and
matplotlib.path, which modules that only need `PlannedPath` should not pay for).
"""

from drake_auv.planning.path import PlannedPath

_LAZY = {
    "CoveragePlan": "drake_auv.planning.coverage_plan",
    "plan_coverage": "drake_auv.planning.coverage_plan",
    "plan_lawnmower": "drake_auv.planning.lawnmower",
}

__all__ = ["CoveragePlan", "PlannedPath", "plan_coverage", "plan_lawnmower"]


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'drake_auv.planning' has no attribute {name!r}")
