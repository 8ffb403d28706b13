"""The water column bounds every path: no sample above the minimum operating depth, shallow
cells are no-go, and the report says how much of the path the depth holds."""

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.report import report_dict
from drake_auv.terrain.synthetic import random_seabed


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), top=st.floats(-2.5, 1.5), min_depth=st.floats(0.0, 2.0),
       omega=st.floats(1.5, 3.0))
def test_no_sample_above_the_minimum_depth(seed, top, min_depth, omega):
    # A seabed of 8 m relief whose shallowest point is at `top` (it may break the surface).
    base = random_seabed(seed, shape=(40, 50), relief=8.0, smoothness=5.0)
    bathy = base.with_z(base.z - np.nanmax(base.z) + top)
    plan = plan_coverage(bathy, CoverageParameters(omega=omega, min_depth=min_depth),
                         compute_metrics=False)
    for path in (plan.path, plan.lawnmower):
        assert path.points[:, 2].max() <= -min_depth + 1e-9
    shallow = bathy.z > -min_depth
    assert not (plan.bathy.valid & shallow).any()  # never covered
    held = report_dict(plan)["water_column"]["path_depth_limited"]
    # Where covered cells would put Omega above the minimum depth, over a tenth of the grid (so
    # that lanes must cross them), the path is held there.
    limited = (bathy.z <= -min_depth) & (bathy.z + omega > -min_depth + 0.1)
    if limited.mean() > 0.1:
        assert held["samples_share"] > 0 and held["least_altitude_m"] < omega


def test_deep_water_is_not_limited():
    bathy = random_seabed(1, shape=(40, 50))  # around -50 m
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0), compute_metrics=False)
    assert report_dict(plan)["water_column"]["path_depth_limited"]["samples_share"] == 0.0
    capped = plan_coverage(bathy, CoverageParameters(omega=2.0, min_depth=49.0),
                           compute_metrics=False)
    assert capped.path.points[:, 2].max() <= -49.0
    assert report_dict(capped)["water_column"]["path_depth_limited"]["samples_share"] > 0.1
