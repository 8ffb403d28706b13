"""The one validator: ranges as field metadata, checked at construction and by `replace`; the
mission file reads the algorithms' own parameter classes; the off-line plan needs no Drake."""

import dataclasses
import math
import subprocess
import sys
import textwrap

import pytest

from drake_auv.following.behaviours import FollowConfig, FollowingParams
from drake_auv.mission.config import MissionFileError, load_mission, mission_to_dict
from drake_auv.mission.spec import mission_keys
from drake_auv.mission.steps.follow import FollowStep
from drake_auv.params import ParameterError, param, validate
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.stomp import StompParameters
from drake_auv.vehicle.navigation import NavigationParams


@dataclasses.dataclass(frozen=True)
class _Probe:
    gain: float = param(1.0, low=0.0, high=2.0, high_open=True, unit="m")
    count: int = param(3, low=1, integer=True)
    mode: str = param("a", kind="choice", choices=("a", "b"))
    limit: float | None = param(None, low=0.0, nullable=True)

    def __post_init__(self):
        validate(self)


@pytest.mark.parametrize("change, message", [
    (dict(gain=2.0), "_Probe.gain = 2.0 is out of range; must be in [0, 2) m"),
    (dict(gain=math.nan), "_Probe.gain = nan is out of range"),
    (dict(gain="1"), "_Probe.gain = '1' is not a number; must be in [0, 2) m"),
    (dict(gain=True), "_Probe.gain = True is not a number"),
    (dict(count=2.5), "_Probe.count = 2.5 is not an integer; must be an integer >= 1"),
    (dict(mode="c"), "_Probe.mode = 'c' is not allowed; must be a, b"),
    (dict(limit=-1.0), "_Probe.limit = -1.0 is out of range; must be >= 0 or null"),
])
def test_construction_and_replace_name_the_field(change, message):
    with pytest.raises(ParameterError, match="^" + message.replace("(", r"\(")
                       .replace("[", r"\[").replace(")", r"\)")):
        _Probe(**change)
    with pytest.raises(ParameterError, match=message.split(" ")[0]):
        dataclasses.replace(_Probe(), **change)
    assert _Probe(limit=None).limit is None and _Probe(gain=0.0).gain == 0.0


def test_the_algorithms_validate_themselves_on_replace():
    with pytest.raises(ValueError, match=r"ReplanningParameters.clearance = -1 is out of range; "
                                         r"must be in \[0.5, 20\] m"):
        dataclasses.replace(ReplanningParameters(), clearance=-1)
    with pytest.raises(ValueError, match="StompParameters.num_rollouts = 1 is out of range"):
        dataclasses.replace(StompParameters(), num_rollouts=1)
    with pytest.raises(ValueError, match="NavigationParams.seed = -1"):
        dataclasses.replace(NavigationParams(), seed=-1)
    with pytest.raises(ValueError, match="FollowConfig.mode = 'diagonal' is not allowed"):
        FollowConfig("diagonal")


def test_one_default_and_one_range_per_parameter():
    # the mission's replanner is the algorithm's class with its defaults (clearance 4 m, the
    # missions' value, was 3 m in the class and 4 m in the mission spec)
    assert load_mission("monterey_wall").replanner.params == ReplanningParameters()
    assert ReplanningParameters().clearance == 4.0
    # a follow step takes the default and the range of the behaviour's parameters
    step = FollowStep(mode="horizontal", offset=2.0)
    follow = FollowingParams()
    assert (step.speed, step.corner_weight, step.min_depth_m) == (
        follow.speed, follow.corner_weight, follow.min_depth)
    with pytest.raises(ValueError, match="FollowStep.speed = 2.0 is out of range; must be in "
                                         r"\[0.05, 1.4\] m/s"):
        FollowStep(mode="horizontal", offset=2.0, speed=2.0)
    with pytest.raises(ValueError, match="FollowingParams.speed = 2.0 is out of range"):
        FollowingParams(speed=2.0)


def test_mission_keys_map_the_algorithm_fields_in_one_place(tmp_path):
    keys = mission_keys(type(load_mission("boulder").replanner))
    assert {k: v[0] for k, v in keys.items() if k in ("R", "K", "clearance_m", "rollouts")} == {
        "R": ("params", "radius"), "K": ("params", "max_waypoints"),
        "clearance_m": ("params", "clearance"), "rollouts": ("params", "stomp", "num_rollouts")}
    assert list(mission_keys(NavigationParams)) == ["heading_bias_deg", "dvl_scale_error",
                                                    "random_walk"]
    spec = load_mission("boulder", overrides=["navigation.heading_bias_deg=2.5",
                                              "replanner.rollouts=12", "replanner.R=7"])
    assert spec.navigation.heading_bias == pytest.approx(math.radians(2.5), rel=1e-15)
    assert spec.replanner.params.stomp.num_rollouts == 12 and spec.replanner.params.radius == 7
    # the rest of the nested STOMP parameters keep the replanner's defaults, not STOMP's own
    assert spec.replanner.params.stomp.smoothness_weight == 50.0
    written = mission_to_dict(spec)
    assert written["navigation"]["heading_bias_deg"] == 2.5 and written["replanner"]["R"] == 7
    for override, message in (
            ("replanner.clearance_m=-1",
             "boulder.yaml: replanner.clearance_m: -1.0 is out of range; allowed: [0.5, 20] m"),
            ("navigation.heading_bias_deg=50",
             "navigation.heading_bias_deg: 50.0 is out of range; allowed: [-45, 45] deg"),
            ("replanner.iterations=0", "replanner.iterations: 0 is out of range; allowed: an "
                                       "integer in [1, 500]")):
        with pytest.raises(MissionFileError) as info:
            load_mission("boulder", overrides=[override])
        assert message in str(info.value) and "\n" not in str(info.value)


def test_plan_runs_without_pydrake():
    code = textwrap.dedent("""
        import sys

        class NoDrake:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] == "pydrake":
                    raise ImportError("pydrake made unimportable by the test")

        sys.meta_path.insert(0, NoDrake())
        from drake_auv.mission.config import load_mission
        from drake_auv.mission.plan import plan_mission
        from drake_auv.mission.site import load_site

        spec = load_mission("pool")
        plan = plan_mission(spec, load_site(spec.site, spec.seed))
        assert len(plan.legs) == 4 and len(plan.legs_of("follow")) == 2, plan.legs
        assert not any(m.split(".")[0] == "pydrake" for m in sys.modules)
        print("planned", len(plan.legs))
    """)
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0 and "planned 4" in run.stdout, run.stderr[-2000:]
