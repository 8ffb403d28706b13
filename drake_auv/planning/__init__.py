"""Off-line planners and optimisers, pure numpy/scipy (no Drake)."""

from drake_auv.planning.path import Path

__all__ = ["Path"]
