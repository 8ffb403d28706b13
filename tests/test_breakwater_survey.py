"""The breakwater survey flown in the one mission Diagram, judged by its quality: with STOMP
the replanner keeps the vehicle off the blocks and nearer the offset Omega than the same
sections flown unoptimised (`replanner.optimizer=none`) on the same seed, and sees at least as
much of the target with the camera. An optimiser that returns its initial trajectory fails
it."""

import numpy as np
import pytest

from drake_auv.mission.config import load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.report.summary import summarise
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.mission.site import load_site

# The transit (18.5 s) and the first 50 s of the contour: the sections around the block's
# east end, where the prior map's 5 m error puts the nominal path into the wall.
CAP = ["limits.max_time_s=70"]


@pytest.fixture(scope="module")
def flown():
    """{optimizer: (MissionResult, summary)} on seed 0, one site and plan for both."""
    spec = load_mission("breakwater", seed=0, overrides=CAP)
    site = load_site(spec.site, spec.seed, label=spec.name)
    plan = plan_mission(spec, site)
    out = {}
    for optimizer in ("stomp", "none"):
        result = run_mission(load_mission("breakwater", seed=0,
                                          overrides=[*CAP, f"replanner.optimizer={optimizer}"]),
                             site=site, plan=plan, progress=False)
        out[optimizer] = result, summarise(result)
    return out


def offset_error(result) -> float:
    """Mean |true distance to the target - Omega| over the survey samples within 2 Omega, m."""
    survey = np.array([result.plan.legs[leg].phase == "survey" for leg in result.log.leg_at])
    near = survey & (result.log.distance < 2.0 * result.plan.omega)
    assert near.sum() > 200  # at least 20 s of survey near the block
    return float(np.mean(np.abs(result.log.distance[near] - result.plan.omega)))


def test_the_survey_flies_in_the_diagram_until_the_cap(flown):
    for result, summary in flown.values():
        assert [p["name"] for p in summary["phases"]] == ["transit", "survey"]
        assert result.dive.outcomes == ["goal", "flying"] and len(result.mapping.replanning) >= 40


def test_stomp_keeps_off_the_blocks_and_nearer_omega_than_the_unoptimised_sections(flown):
    (stomp, optimised), (none, unoptimised) = flown["stomp"], flown["none"]
    assert not optimised["contact"] and optimised["min_clearance_m"] > VEHICLE_RADIUS + 2.0
    error, baseline = offset_error(stomp), offset_error(none)
    assert error < baseline - 0.5, (error, baseline)
    camera, camera_baseline = optimised["coverage"]["camera"], unoptimised["coverage"]["camera"]
    assert camera >= camera_baseline, (camera, camera_baseline)
