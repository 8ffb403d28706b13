"""Survey-scale dives: the scan log streamed to its file with a bounded memory
window, box queries of the octree through its tiles, points.ply streamed, tile sites, and (slow)
the long built-in mission on real data."""

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator

from drake_auv.mapping.mapper import OctreeMapper, map_memory
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mapping.scan_log import CACHE_BATCHES, ScanBatch, ScanLog
from drake_auv.mission.config import MissionFileError, mission_from_dict
from drake_auv.reconstruction.pointcloud import from_scan_log, read_ply, write_ply
from drake_auv.sonar.returns import SonarReturns


def _fan(rng, n=40):
    a = rng.uniform(-1.0, 1.0, n)
    d = np.stack([np.cos(a), np.sin(a), -0.3 * np.ones(n)], axis=1)
    d /= np.linalg.norm(d, axis=1)[:, None]
    ranges = rng.uniform(2.0, 15.0, n)
    ranges[rng.random(n) < 0.2] = np.nan
    return d, ranges


def _log(count, seed=0):
    rng, log, batches = np.random.default_rng(seed), ScanLog(), []
    for k in range(count):
        d, r = _fan(rng)
        batch = ScanBatch.make(0.1 * k, ("multibeam", "profiler")[k % 2], rng.normal(size=3),
                               d, r, 20.0)
        log = log.append(batch)
        batches.append(batch)
    return log, batches


def test_scan_log_keeps_a_bounded_window_in_memory_and_reads_the_rest_back():
    log, batches = _log(3 * CACHE_BATCHES)
    assert log.store.cached == CACHE_BATCHES  # the window, not the log
    assert log.returns == sum(np.isfinite(b.ranges).sum() for b in batches)
    read = list(log.iter_batches())
    assert len(read) == len(batches)
    for got, want in zip(read, batches):
        assert (got.time, got.source, got.max_range) == (want.time, want.source, want.max_range)
        np.testing.assert_array_equal(got.origin, want.origin)
        np.testing.assert_array_equal(got.directions, want.directions)
        np.testing.assert_array_equal(got.ranges, want.ranges)
        with pytest.raises(ValueError):
            got.ranges[0] = 1.0  # read back read-only
    chunked = [b for chunk in log.chunks(7) for b in chunk.batches()]
    assert [b.time for b in chunked] == [b.time for b in batches]
    # A version of its past still reads only its own batches; a fresh log has its own file.
    past = log
    for _ in range(CACHE_BATCHES + 5):
        past = past.parent
    assert [b.time for b in past.iter_batches()] == [b.time for b in batches[:past.count]]
    assert _log(1)[0].store is not log.store


def _returns(sequence, x_wall):
    a = np.linspace(-0.5, 0.5, 61)
    d = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    r = x_wall / d[:, 0]
    return SonarReturns(0.1 * sequence, np.zeros(3), a, r, d, d * r[:, None], d * r[:, None],
                        20.0, sequence)


def test_a_cloned_mapper_context_diverges_from_its_original_through_a_shared_file():
    mapper = OctreeMapper(resolution=0.5, period=0.1, multibeam_stride=1)
    context = mapper.CreateDefaultContext()
    mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_returns(1, 8.0)))
    Simulator(mapper, context).AdvanceTo(0.15)
    clone = context.Clone()
    mapper.returns_inputs["multibeam"].FixValue(context, AbstractValue.Make(_returns(2, 9.0)))
    mapper.returns_inputs["multibeam"].FixValue(clone, AbstractValue.Make(_returns(2, 12.0)))
    Simulator(mapper, context).AdvanceTo(0.35)
    Simulator(mapper, clone).AdvanceTo(0.35)
    mine, theirs = mapper.scan_log(context), mapper.scan_log(clone)
    assert mine.store is theirs.store and mine.parent is theirs.parent  # one past, one file
    assert [b.ranges.min() for b in mine.batches()] == pytest.approx([8.0, 9.0])
    assert [b.ranges.min() for b in theirs.batches()] == pytest.approx([8.0, 12.0])
    far = mapper.map_output.Eval(clone).map.occupied_points()[:, 0]
    near = mapper.map_output.Eval(context).map.occupied_points()[:, 0]
    assert far.max() > 11.5 and near.max() < 10.0
    fresh = mapper.CreateDefaultContext()
    assert mapper.scan_log(fresh).count == 0 and mapper.scan_log(fresh).store is None
    memory = map_memory(mapper.map_output.Eval(context), mine)
    assert memory["batches"] == 2 and memory["octree_mb"] > 0 and memory["scan_file_mb"] > 0


def test_box_queries_visit_only_their_tiles_and_read_exact_log_odds():
    rng = np.random.default_rng(3)
    omap = OctreeMap(0.5)
    for x0 in (0.0, 60.0):  # two mapped areas 60 m apart
        for k in range(30):
            origin = np.array([x0 + 0.3 * k, 0.0, -5.0])
            d, r = _fan(rng, 200)
            omap.insert_scan(origin, d, r, 20.0)
    lo, hi = np.array([-5.0, -20.0, -15.0]), np.array([25.0, 20.0, 0.0])
    points, log_odds = omap.occupied_points(lo, hi, log_odds=True)
    every = omap.occupied_points()
    inside = every[np.all((every >= lo) & (every <= hi), axis=1)]
    assert len(points) > 100
    np.testing.assert_array_equal(np.sort(points, axis=0), np.sort(inside, axis=0))
    np.testing.assert_allclose(log_odds, [omap.tree.search(p).getLogOdds() for p in points])
    # After the whole-map read above, a fresh map's box query leaves the far area unread.
    again = OctreeMap(0.5)
    rng = np.random.default_rng(3)
    for x0 in (0.0, 60.0):
        for k in range(30):
            d, r = _fan(rng, 200)
            again.insert_scan(np.array([x0 + 0.3 * k, 0.0, -5.0]), d, r, 20.0)
    again.occupied_points(lo, hi)
    centres, unread = again.candidates()
    far = centres[:, 0] > 40.0
    assert far.any() and np.all(unread[far]) and not unread[~far].all()


def test_points_ply_is_streamed_in_the_format_of_write_ply(tmp_path):
    from drake_auv.reconstruction.products import dive_cloud, write_points
    from drake_auv.rosio.replay import ReplaySite

    log, _ = _log(2 * CACHE_BATCHES + 3)
    shift = np.array([4.5e5, 4.6e6, 0.0])
    assert write_points(log, ReplaySite(shift[:2]), tmp_path / "streamed.ply") == log.returns
    write_ply(from_scan_log(log).shifted(lambda p: p + shift), tmp_path / "whole.ply")
    assert (tmp_path / "streamed.ply").read_bytes() == (tmp_path / "whole.ply").read_bytes()
    assert len(read_ply(tmp_path / "streamed.ply")) == log.returns
    # the surface's cloud, thinned a chunk at a time, is the whole log thinned
    np.testing.assert_array_equal(dive_cloud(log, 0.2).points,
                                  from_scan_log(log).thin(0.2).points)


@pytest.mark.parametrize("site, message", [
    ({"tile": "t.tif"}, "site.roi: goes with tile"),
    ({"roi": [0, 0, 1, 1], "scenario": "pool"}, "site.roi: goes with tile"),
    ({"tile": "t.tif", "roi": [10, 0, 1, 1]}, "has min >= max"),
    ({"tile": "t.tif", "roi": [0, 0, 1]}, "site.roi"),
    ({"tile": "t.tif", "roi": [0, 0, 1, 1], "prior": "p.tif"}, "site.prior: only for a site"),
    ({"tile": "t.tif", "world": "w.ply", "roi": [0, 0, 1, 1]}, "exactly one of scenario"),
])
def test_tile_sites_are_validated(tmp_path, site, message):
    raw = {"name": "x", "site": site, "steps": [{"plan": {"omega": 10.0}}]}
    with pytest.raises(MissionFileError, match=message):
        mission_from_dict(raw, tmp_path, "x.yaml")


def test_a_missing_tile_names_the_field(tmp_path):
    from drake_auv.mission.site import load_site

    spec = mission_from_dict({"name": "x", "site": {"tile": "none.tif", "roi": [0, 0, 9, 9]},
                              "steps": [{"plan": {"omega": 10.0}}]}, tmp_path, "x.yaml")
    with pytest.raises(MissionFileError, match="site.tile: none.tif not found"):
        load_site(spec.site, 0, label="x.yaml")


@pytest.mark.slow
def test_the_long_monterey_mission_flies_at_survey_scale(tmp_path, monkeypatch):
    """The built-in 3.8 h mission on real data: completes without contact, covers the wall,
    keeps only the window of batches in memory and streams its points (figures: the
    benchmark, docs/benchmarks.md)."""
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.report.summary import summarise
    from drake_auv.mission.runner import run_mission
    from drake_auv.reconstruction.products import write_points

    monkeypatch.setenv("DRAKE_AUV_CACHE", str(tmp_path / "cache"))
    result = run_mission(load_mission("monterey_wall"), progress=False)
    summary = summarise(result)
    assert result.dive.completed and result.log.duration_s > 2 * 3600
    assert not summary["contact"] and summary["coverage"]["multibeam"] > 0.9
    # The offset on the true seabed, not `distance_to_target`: the target is the ROI, and the
    # lanes that cover its edges fly outside it, where the nearest target point is the edge.
    # The plan is made on a prior shifted by 2 m, so the replanned survey must hold Omega to
    # within that error.
    survey = np.array([result.plan.legs[leg].phase == "survey" for leg in result.log.leg_at])
    assert (abs(result.log.clearance[survey].mean() - result.plan.omega)
            < result.spec.site.prior_error_m)
    log = result.mapping.scan_log
    assert log.store.cached <= CACHE_BATCHES < log.count
    assert summary["map"]["batches"] == log.count and summary["map"]["octree_mb"] > 0
    assert write_points(log, result.site, tmp_path / "points.ply") == log.returns
    assert len(read_ply(tmp_path / "points.ply")) == log.returns
