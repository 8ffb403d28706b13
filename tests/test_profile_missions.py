"""Whole profile-following missions in Drake (the built-in mission files, flown by the mission
runner), checked against the true world: the pool's V profile in vertical mode up to its far
wall, and a closed loop around the boulder under the boulder mission's navigation and chart
errors."""

from dataclasses import replace

import numpy as np
import pytest

from drake_auv.mission.config import FollowStep, load_mission
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission


def _follow_only(name: str, overrides=()):
    """The mission `name` reduced to its follow steps."""
    spec = load_mission(name, overrides=overrides)
    return replace(spec, steps=tuple(s for s in spec.steps if isinstance(s, FollowStep)))


def _following(result):
    """(t since the follow leg began, x (12, n), clearance) of the follow leg's samples."""
    leg = next(i for i, leg in enumerate(result.plan.legs) if leg.phase == "follow")
    mask = result.log.leg_at == leg
    t = result.log.times[mask]
    return t - t[0], result.log.state[mask].T, result.log.clearance[mask]


def test_pool_v_profile_to_the_cliff():
    spec = _follow_only("pool", ["limits.max_time_s=150"])
    spec = replace(spec, steps=spec.steps[1:])  # the vertical step alone
    result = run_mission(spec, progress=False)
    assert result.dive.completed and result.dive.outcomes[-1] == "goal"  # the far wall climbed
    t, x, clearance = _following(result)
    assert np.all(np.abs(clearance[t > 10] - 2.0) < 0.3)
    deepest = np.argmin(x[2])
    assert abs(x[0, deepest]) < 1.5 and x[2, deepest] == pytest.approx(-5.0, abs=0.3)  # V apex
    assert x[0, -1] == pytest.approx(6.0, abs=0.2)  # 2 m from the far wall (the cliff) ...
    assert x[2, -1] > -1.5  # ... which it climbed to the depth limit


def test_boulder_closed_loop_without_contact():
    result = run_mission(_follow_only("boulder", ["limits.max_time_s=260"]), progress=False)
    assert result.dive.completed and result.dive.outcomes == ["goal", "goal"]
    t, x, clearance = _following(result)
    lo, hi = result.site.target_mesh.bounds
    centre = 0.5 * (lo + hi)
    angle = np.unwrap(np.arctan2(x[1] - centre[1], x[0] - centre[0]))
    assert abs(angle[-1] - angle[0]) > 0.95 * 2 * np.pi  # closed the loop (true centre)
    assert clearance.min() > 2.0 * VEHICLE_RADIUS
    assert np.abs(clearance[t > 30] - 3.0).mean() < 0.3
    assert np.all(np.abs(x[2] + 34.0) < 0.15)  # constant depth
