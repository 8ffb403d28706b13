"""IHO S-44 survey orders: the lane spacing follows the order's coverage and the report
states the order, the coverage achieved and the feature size the footprint supports."""

import pytest

from drake_auv.cli import main
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.orders import ORDERS, coverage_multiplicity, survey_order
from drake_auv.planning.report import report_dict
from drake_auv.terrain.synthetic import random_seabed


@pytest.fixture(scope="module")
def seabed():
    return random_seabed(4, shape=(50, 60), relief=4.0)


def test_exclusive_doubles_the_coverage_of_special(seabed):
    special = plan_coverage(seabed, CoverageParameters(omega=2.0, order="special"),
                            compute_metrics=False)
    exclusive = plan_coverage(seabed, CoverageParameters(omega=2.0, order="exclusive"),
                              compute_metrics=False)
    assert exclusive.lane_spacing == pytest.approx(special.lane_spacing / 2)
    rs, rx = report_dict(special)["survey_order"], report_dict(exclusive)["survey_order"]
    assert rs["order"] == "Special" and rx["order"] == "Exclusive"
    assert rs["achieved_percent"] >= 99.0 and rx["achieved_percent"] >= 95.0
    p = special.parameters
    twice = coverage_multiplicity(special.surface, special.path, p.aperture_deg,
                                  p.sensor_range) >= 2
    assert twice[special.surface.valid].mean() < 0.6  # Special alone is not 200 %
    assert rx["meets_feature_detection"] and rx["detectable_feature_m"] <= 0.5


def test_order_2_is_sparse_and_reports_its_gaps(seabed):
    plan = plan_coverage(seabed, CoverageParameters(omega=2.0, order="2"), compute_metrics=False)
    r = report_dict(plan)["survey_order"]
    assert r["required_feature_m"] is None and r["meets_feature_detection"] is None
    assert 3.0 <= r["achieved_percent"] <= 40.0  # 5 % nominal on a 60 m x 50 m grid
    assert r["largest_gap_m"] > 10 * plan.parameters.omega


def test_1a_feature_size_grows_beyond_40_m():
    assert ORDERS["1a"].required_feature(30.0) == 2.0
    assert ORDERS["1a"].required_feature(200.0) == pytest.approx(20.0)
    assert survey_order("Exclusive") is ORDERS["exclusive"]


def test_unknown_order_is_one_line(tmp_path, capsys):
    assert main(["plan", "caldera", "--order", "3", "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'3'" in err[0] and "exclusive" in err[0]
