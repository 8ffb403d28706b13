"""examples/custom_step.py: a step kind defined outside the package, registered, read from a
mission file and flown."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from drake_auv.mission.config import MissionFileError, mission_from_dict
from drake_auv.mission.steps import STEPS

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "custom_step.py"
spec = importlib.util.spec_from_file_location("custom_step", EXAMPLE)
example = sys.modules["custom_step"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(example)  # registered first: its dataclasses look their module up


@pytest.fixture
def registered():
    yield example.register(example.Circle)
    STEPS.pop("circle")


def test_an_unregistered_step_is_refused_and_a_registered_one_read(tmp_path, registered):
    raw = {"name": "c", "site": {"scenario": "pool"},
           "steps": [{"circle": {"centre": [0.0, 0.0], "laps": 0.0}}]}
    with pytest.raises(MissionFileError, match=r"steps\[0\]\.circle\.laps: 0\.0 is out of"):
        mission_from_dict(raw, tmp_path, "c.yaml")
    raw["steps"][0]["circle"]["laps"] = 2
    assert mission_from_dict(raw, tmp_path, "c.yaml").steps[0].laps == 2
    STEPS.pop("circle")
    with pytest.raises(MissionFileError, match=r"steps\[0\]: unknown step 'circle'"):
        mission_from_dict(raw, tmp_path, "c.yaml")
    example.register(example.Circle)
    with pytest.raises(ValueError, match="already taken"):
        example.register(type("Other", (example.Circle,), {"spec": type(
            "OtherStep", (), {"KIND": "other"})}))


def test_the_follower_circles_from_the_leg_start():
    leg = example.CircleLeg((0.0, 0.0), 2.0, -3.0, 0.5, 1.0)
    follower = example.CircleFollower({1: leg})
    context = follower.CreateDefaultContext()
    follower.state_input.FixValue(context, np.zeros(12))
    follower.leg_input.FixValue(context, [1.0, 10.0])
    context.SetTime(10.0 + leg.duration / 4)  # a quarter lap: the south point
    reference = follower.reference_output.Eval(context)
    np.testing.assert_allclose(reference[:3], [0.0, -2.0, -3.0], atol=1e-9)
    np.testing.assert_allclose(reference[4:7], [0.5, 0.0, 0.0], atol=1e-9)
    assert follower.status_output.Eval(context).tolist() == pytest.approx([1.0, 0.0, 0.25])
    context.SetTime(10.0 + leg.duration)
    assert follower.status_output.Eval(context).tolist() == pytest.approx([1.0, 1.0, 1.0])
    follower.leg_input.FixValue(context, [2.0, 10.0])  # not its leg
    assert follower.status_output.Eval(context)[0] == -1.0


def test_the_example_flies_its_step_from_a_mission_file(tmp_path):
    row = example.fly(tmp_path, laps=0.5)
    STEPS.pop("circle")
    assert (tmp_path / "circle.yaml").is_file()
    assert row["outcomes"] == ["goal", "goal"]
    half = np.pi * 2.0 / 0.4  # half a lap of radius 2 m at 0.4 m/s
    assert row["circling_s"] == pytest.approx(half, abs=0.6)
    assert row["radial_error_m"] < 0.5, row
