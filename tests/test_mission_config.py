"""Mission files: the built-in missions, overrides, the round trip and one-line errors."""

import subprocess
import sys

import pytest
import yaml

from drake_auv.mission.config import (REALISTIC_NOISE, FollowStep, MissionFileError, PlanStep,
                                      SurveyStep, apply_overrides, builtin_missions,
                                      load_mission, mission_from_dict, mission_to_dict)
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.sonar.noise import SonarNoise
from drake_auv.vehicle.navigation import NavigationParams

WRECK = dict(
    name="wreck", seed=0,
    site=dict(scenario="boulder", prior_error_m=3.0),
    navigation=dict(heading_bias_deg=1.0, dvl_scale_error=0.01, random_walk=0.02),
    sonar_noise="clean", replanner=dict(optimizer="stomp", R=5.0, K=10),
    payload=dict(multibeam_mount="port", camera_range_m=12), limits=dict(max_time_s=None),
    steps=[dict(plan=dict(omega=6.0, slice_count=2, slice_spacing=2.0)),
           dict(follow=dict(mode="horizontal", depth=25.5, offset=3.0, loops=1)),
           dict(survey=dict(replanning=True))])


def _write(tmp_path, raw, name="wreck.yaml"):
    path = tmp_path / name
    path.write_text(raw if isinstance(raw, str) else yaml.safe_dump(raw, sort_keys=False))
    return path


def _error(tmp_path, raw, overrides=()) -> str:
    with pytest.raises(MissionFileError) as info:
        load_mission(_write(tmp_path, raw), overrides=overrides)
    message = str(info.value)
    assert "\n" not in message and "; allowed: " in message
    return message


def _with(**changes):
    raw = yaml.safe_load(yaml.safe_dump(WRECK))
    for dotted, value in changes.items():
        *path, key = dotted.split("__")
        node = raw
        for part in path:
            node = node[int(part)] if part.isdigit() else node[part]
        node[key] = value
    return raw


def test_builtin_missions_load():
    assert builtin_missions() == ["boulder", "boulder_explore", "breakwater",
                                  "breakwater_current", "breakwater_explore", "c_object",
                                  "monterey_wall", "pool"]
    for name in builtin_missions():
        spec = load_mission(name)
        assert spec.name == name and spec.steps and spec.source.name == f"{name}.yaml"
        if name == "monterey_wall":  # cut from a shared tile on first use
            assert spec.site.tile.is_file() and spec.site.roi == (80.0, 120.0, 240.0, 280.0)
        else:
            assert spec.site.scenario == name.removesuffix("_explore").removesuffix("_current")
    boulder = load_mission("boulder")
    plan, follow, survey = boulder.steps
    assert (plan.omega, plan.slice_count, plan.slice_spacing) == (10.0, 2, 2.0)
    assert (follow.mode, follow.depth, follow.offset, follow.loops) == ("horizontal", 34.0, 3.0, 1)
    assert isinstance(survey, SurveyStep) and survey.replanning
    assert boulder.site.prior_error_m == 3.0 and boulder.payload.multibeam_mount == "port"
    assert load_mission("breakwater").steps[0].method == "contour"
    sea = load_mission("breakwater_current").ocean  # cross-shore onto the blocks' south face
    assert (sea.current.speed_mps, sea.current.towards_deg) == (0.3, 0.0)
    assert [(c.name, c.amplitude_mps, c.flood_towards_deg) for c in sea.tides] == [("M2", 0.1,
                                                                                   0.0)]
    assert (sea.turbulence.speed_sd_mps, sea.waves.hs_m, sea.waves.tp_s) == (0.03, 1.0, 8.0)
    assert load_mission("monterey_wall").ocean.file.name == "monterey_wall_current.nc"
    vertical = load_mission("pool").steps[1]
    assert (vertical.mode, vertical.start, vertical.end_depth_m) == ("vertical", (-6.0, 0.0), 1.3)


def test_the_issue_schema_validates_with_defaults(tmp_path):
    spec = load_mission(_write(tmp_path, WRECK))
    assert spec.name == "wreck" and spec.seed == 0
    assert [type(s) for s in spec.steps] == [PlanStep, FollowStep, SurveyStep]
    assert spec.replanner.params == ReplanningParameters() and spec.limits.max_time_s is None
    assert spec.replanner.params.clearance == 4.0  # the one default, the missions' own
    assert spec.sonar_noise.to_noise() is None
    nav = spec.navigation  # the algorithm's class, the file's degrees in radians
    assert isinstance(nav, NavigationParams) and nav.seed == 0 and nav.period == 0.1
    assert nav.heading_bias == pytest.approx(0.017453, abs=1e-6) and nav.random_walk == 0.02
    params = spec.replanner.to_params(omega=6.0, plan_method="coverage")
    assert (params.radius, params.max_waypoints, params.offset_metric) == (5.0, 10, "3d")
    assert (params.stomp.num_rollouts, params.stomp.max_iterations) == (10, 40)


def test_sonar_noise_presets_and_mapping(tmp_path):
    realistic = load_mission(_write(tmp_path, _with(sonar_noise="realistic")))
    assert realistic.sonar_noise.to_noise() == SonarNoise(**REALISTIC_NOISE)
    custom = load_mission(_write(tmp_path, _with(sonar_noise=dict(range_sigma=0.2))))
    assert custom.sonar_noise.preset == "custom"
    assert custom.sonar_noise.to_noise() == SonarNoise(range_sigma=0.2)
    assert "sonar_noise.range_sigma: -1.0 is out of range; allowed: >= 0 m" in _error(
        tmp_path, _with(sonar_noise=dict(range_sigma=-1)))
    assert "sonar_noise.range_noise: unknown key; allowed: range_sigma" in _error(
        tmp_path, _with(sonar_noise=dict(range_noise=0.1)))


def test_overrides_and_seed(tmp_path):
    path = _write(tmp_path, WRECK)
    spec = load_mission(path, seed=3, overrides=[
        "replanner.optimizer=none", "sonar_noise=realistic", "site.prior_error_m=2.5",
        "limits.max_time_s=60", "steps.2.survey.replanning=false",
        "steps[1].follow.start=[1, 2]", "payload={multibeam_mount: down}"])
    assert spec.seed == 3 and spec.replanner.optimizer == "none"
    assert spec.sonar_noise.preset == "realistic" and spec.site.prior_error_m == 2.5
    assert spec.limits.max_time_s == 60.0 and spec.steps[2].replanning is False
    assert spec.steps[1].start == (1.0, 2.0) and spec.payload.multibeam_mount == "down"
    assert load_mission(path, overrides=["seed=4"]).seed == 4
    noisy = load_mission(path, overrides=["sonar_noise=realistic", "sonar_noise.range_sigma=0.3"])
    assert noisy.sonar_noise.params == {**REALISTIC_NOISE, "range_sigma": 0.3}
    raw = yaml.safe_load(path.read_text())
    assert apply_overrides(raw, ["seed=9"])["seed"] == 9 and raw["seed"] == 0  # a new dict


@pytest.mark.parametrize("override, message", [
    ("replanner.optimiser=none", "replanner.optimiser: unknown key; allowed: optimizer, R, K"),
    ("limits.max_time=3", "limits.max_time: unknown key; allowed: max_time_s"),
    ("nonsense=1", "nonsense: unknown key; allowed: name, description, seed, site"),
    ("steps.7.survey.replanning=false", "steps.7: no such step; allowed: 0, 1, 2"),
    ("steps.2.plan.omega=3", "steps.2.plan: step 2 is a survey step; allowed: survey"),
    ("seed.x=1", "seed.x: seed is a value, not a section"),
    ("replanner", "replanner: not a KEY=VALUE override"),
    ("replanner.multibeam_stride=0",
     "replanner.multibeam_stride: 0 is out of range; allowed: an integer in [1, 16]"),
    ("replanner.discretize=maybe",
     "replanner.discretize: 'maybe' is not a boolean; allowed: true or false"),
])
def test_bad_overrides_name_the_key(tmp_path, override, message):
    assert message in _error(tmp_path, WRECK, overrides=[override])


def test_round_trip(tmp_path):
    for spec in [load_mission(n) for n in builtin_missions()] + [
            load_mission(_write(tmp_path, _with(sonar_noise=dict(dropout_prob=0.1))))]:
        raw = mission_to_dict(spec)
        again = mission_from_dict(yaml.safe_load(yaml.safe_dump(raw)), tmp_path, "sent.yaml")
        assert again == spec


def test_paths_resolve_against_the_file(tmp_path):
    raw = _with(site=dict(world="site/world.ply", prior="prior.tif"))
    spec = load_mission(_write(tmp_path, raw))
    assert spec.site.world == (tmp_path / "site" / "world.ply").resolve()
    assert spec.site.prior.is_absolute() and spec.site.target is None


@pytest.mark.parametrize("raw, message", [
    (_with(steps__1__follow__offset=-1.0),
     "wreck.yaml: steps[1].follow.offset: -1.0 is out of range; allowed: (0, 20] m"),
    (_with(replanner__optimizer="chomp"),
     "wreck.yaml: replanner.optimizer: 'chomp' is not allowed; allowed: stomp, none"),
    (_with(site=dict(scenario="atlantis")),
     "wreck.yaml: site.scenario: 'atlantis' is not allowed; allowed: caldera, pool, c_object"),
    (_with(steps__0__plan__omga=6.0),
     "wreck.yaml: steps[0].plan.omga: unknown key; allowed: omega, method, slice_count"),
    (_with(payload__lights=True), "wreck.yaml: payload.lights: unknown key"),
    (_with(steps=[dict(survey={}), dict(plan=dict(omega=6.0))]),
     "wreck.yaml: steps[0].survey: no earlier plan step to survey; allowed: a survey after a "
     "plan step"),
    (_with(steps=[dict(plan=dict(omega=6.0)), dict(plan=dict(omega=5.0))]),
     "steps[1].plan: a second plan step; allowed: at most one plan step"),
    (_with(steps=[]), "steps: [] is not a non-empty list"),
    (_with(steps=[dict(dive={})]), "steps[0]: unknown step 'dive'; allowed: plan, follow"),
    (_with(steps=[dict(follow=dict(mode="vertical", offset=2.0))]),
     "steps[0].follow: a vertical follow needs an end; allowed: distance_m and/or end_depth_m"),
    (_with(steps=[dict(follow=dict(mode="horizontal"))]),
     "steps[0].follow.offset: missing (required); allowed: (0, 20] m"),
    (_with(steps__0__plan__method="contour"),
     "steps[0].plan.depth: missing (required by method contour)"),
    (_with(steps__0__plan__slice_count=2.5), "steps[0].plan.slice_count: 2.5 is not an integer"),
    (_with(replanner__K="ten"), "replanner.K: 'ten' is not a number; allowed: an integer in"),
    (_with(steps__2__survey__replanning="yes please"), "replanning: 'yes please' is not a boolean"),
    (_with(seed=-1), "seed: -1 is out of range; allowed: an integer in [0, 2^63 - 1]"),
    (_with(site=dict(scenario="boulder", world="w.ply")),
     "site: needs exactly one of scenario, world or tile"),
    (_with(site=dict(world="w.ply", prior_error_m=6)),
     "site.prior_error_m: 6.0 is out of range; allowed: [0, 5] m"),
    (_with(site=dict(scenario="pool", start=[1, 2])), "site.start: [1, 2] is not 4 finite"),
    ({k: v for k, v in WRECK.items() if k != "site"}, "site: missing (required)"),
    ("name: [unclosed\n", "wreck.yaml: is not valid YAML"),
    ("- just a list\n", "wreck.yaml: holds list, not a mapping"),
])
def test_bad_files_give_one_line_naming_the_field(tmp_path, raw, message):
    assert message in _error(tmp_path, raw)


def test_missing_file_and_unknown_name(tmp_path):
    with pytest.raises(MissionFileError, match=r"^nope.yaml: mission file not found; allowed: "
                                               r"a YAML mission file or a built-in mission: "
                                               r"boulder, boulder_explore, breakwater"):
        load_mission(tmp_path / "nope.yaml")
    with pytest.raises(MissionFileError, match="^atlantis: mission file not found"):
        load_mission("atlantis")


def test_config_and_site_import_no_drake():
    code = ("import sys; import drake_auv.mission.config, drake_auv.mission.site; "
            "sys.exit(any(m.startswith('pydrake') for m in sys.modules))")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0
