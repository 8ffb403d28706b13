"""The table of random streams: distinct across sources and seeds, reproducible, and the only
way a run's sources seed their draws."""

import re
import zlib
from pathlib import Path

import numpy as np
import pytest
import trimesh

from drake_auv.geometry.raycast import RayCaster
from drake_auv.random_streams import MAX_SEED, STREAMS, child, generator, stream
from drake_auv.signals import NavigationError, VehicleState
from drake_auv.sonar.altimeter import DvlAltimeter
from drake_auv.sonar.multibeam import MultibeamSonar
from drake_auv.sonar.profiler import PencilBeamProfiler
from drake_auv.sonar.sensor import stream_of
from drake_auv.vehicle.navigation import NavigationParams, update_error

PACKAGE = Path(__file__).resolve().parents[1] / "drake_auv"


def _draws(seed, name, *keys):
    return tuple(generator(seed, name, *keys).integers(0, 2 ** 63, size=4))


def _all_draws(seeds, children=range(3)):
    """{(seed, name, key): first draws} for every stream and its first `children` children."""
    out = {}
    for seed in seeds:
        for name in STREAMS:
            out[(seed, name)] = _draws(seed, name)
            for k in children:
                out[(seed, name, k)] = _draws(seed, name, k)
                out[(seed, name, k, 0)] = _draws(seed, name, k, 0)
    return out


@pytest.mark.parametrize("seed", [0, 1, 41, 2 ** 32, MAX_SEED - 1])
def test_streams_distinct_across_sources_and_seeds_s_and_s_plus_1(seed):
    draws = _all_draws([seed, seed + 1])
    assert len(set(draws.values())) == len(draws)  # no two streams of the two runs coincide


def test_the_old_collisions_are_gone():
    for s in range(4):
        for n in range(4):  # seed s's profiler was seed s+1's navigation; [s, 0] was s
            assert _draws(s, "profiler", n) != _draws(s + 1, "navigation", n)
            assert _draws(s, "navigation", n) != _draws(s, "multibeam", n)
        assert _draws(s, "navigation", 0) != _draws(s, "navigation")
        plain = tuple(np.random.default_rng(s).integers(0, 2 ** 63, size=4))
        assert plain not in {_draws(s, name) for name in STREAMS}


def test_a_stream_is_reproducible_and_its_children_are_spawned_children():
    assert _draws(7, "replanner", 2, 5) == _draws(7, "replanner", 2, 5)
    assert stream(7, "dvl", 3).generate_state(4).tolist() == \
        child(stream(7, "dvl"), 3).generate_state(4).tolist()
    spawned = np.random.SeedSequence(7).spawn(STREAMS["ocean.waves"] + 1)[-1]
    assert stream(7, "ocean.waves").generate_state(4).tolist() == \
        spawned.generate_state(4).tolist()
    parent = stream(7, "exploration", 1, 2)
    assert child(parent, 0).generate_state(2).tolist() == \
        child(parent, 0).generate_state(2).tolist()  # made afresh, unlike spawn
    assert child(parent, 0).generate_state(2).tolist() != \
        child(parent, 1).generate_state(2).tolist()


def test_the_table_keys_are_unique():
    assert len(set(STREAMS.values())) == len(STREAMS)


@pytest.mark.parametrize("args, match", [
    ((0, "sonar"), "not in the table"), ((-1, "navigation"), "seed must be"),
    ((MAX_SEED + 1, "navigation"), "seed must be"), ((1.5, "navigation"), "seed must be"),
    ((0, "navigation", -1), "keys must be"), ((0, "navigation", 0.5), "keys must be")])
def test_bad_streams_are_refused(args, match):
    with pytest.raises(ValueError, match=match):
        stream(*args)


def test_navigation_draws_its_own_stream():
    params = NavigationParams(position_noise=1.0, seed=3)
    error = NavigationError.zeros()
    error.index = 5
    out = NavigationError(update_error(params, error[:], VehicleState.zeros()[:]))
    n = generator(3, "navigation", 5).standard_normal(6)
    assert np.allclose([out.noise_x, out.noise_y], n[2:4])


def test_each_sonar_draws_from_its_own_stream():
    caster = RayCaster(trimesh.creation.box((50.0, 50.0, 1.0)))
    sonars = [MultibeamSonar(caster, seed=4), PencilBeamProfiler(caster, seed=4),
              DvlAltimeter(caster, seed=4)]
    assert [s.stream for s in sonars] == [("multibeam",), ("profiler",), ("dvl",)]
    assert MultibeamSonar(caster, stream="profiler").stream == ("profiler",)
    # a configured sensor: a child of the `sensors` stream keyed by its name
    extra = MultibeamSonar(caster, stream=stream_of("starboard_multibeam"))
    assert extra.stream == ("sensors", zlib.crc32(b"starboard_multibeam"))
    with pytest.raises(ValueError, match="not in the table"):
        MultibeamSonar(caster, stream="sidescan")


# Who may build a generator: the table, and code seeded by its caller's stream or by a fixed
# seed of its own (the site's shape, the scoring's samples), never by a run's seed plus an
# offset.
ALLOWED = {
    "random_streams.py": "the table",
    "replanning/stomp.py": "STOMP: seeded by its caller (the replanner's, the view paths' stream)",
    "exploration/gains.py": "the random strategy: seeded by the view planner's stream",
    "following/behaviours.py": "the follower's RANSAC: seeded by the `following` stream",
    "perception/profile_estimation.py": "RANSAC: the caller's generator (seed 0 alone)",
    "reconstruction/scoring.py": "the scoring's samples: fixed, the same for every run",
    "planning/metrics3d.py": "the 3D metrics' faces sampled on large meshes: fixed, every plan",
    "scenarios.py": "the boulder's shape: the site, the same for every run",
    "terrain/synthetic.py": "synthetic seabeds: the site, seeded by the command",
}


def test_only_the_table_seeds_a_runs_draws():
    pattern = re.compile(r"default_rng\(|RandomState\(|np\.random\.seed\(|SeedSequence\(")
    users = {str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
             if pattern.search(p.read_text())}
    assert users == set(ALLOWED)
    offsets = re.compile(r"seed\s*[+-]\s*\w|\[\s*(self\.|params\.|spec\.)?seed\s*,")
    for path in PACKAGE.rglob("*.py"):
        if path.name != "random_streams.py":  # its docstring names the old ways
            assert not offsets.search(path.read_text()), path
