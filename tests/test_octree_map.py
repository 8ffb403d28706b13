"""OctreeMap: OctoMap insertion with free-space clearing, occupied voxels against the truth."""


import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from drake_auv.mapping import lattice, octree_map
from drake_auv.mapping.octree_map import OctreeMap


def _fan(n=480, aperture=np.radians(120.0), tilt=0.0):
    """Unit directions of a horizontal fan looking along +x, tilted down by `tilt` rad."""
    a = np.linspace(-aperture / 2, aperture / 2, n)
    d = np.stack([np.cos(a), np.sin(a), np.zeros(n)], axis=1)
    c, s = np.cos(tilt), np.sin(tilt)
    return d @ np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]]).T


def _cast(mesh, origin, directions, max_range):
    """Noiseless ranges from `origin` against `mesh`, NaN beyond max range."""
    loc, ray, _ = mesh.ray.intersects_location(np.tile(origin, (len(directions), 1)),
                                               directions, multiple_hits=False)
    ranges = np.full(len(directions), np.nan)
    ranges[ray] = np.linalg.norm(loc - origin, axis=1)
    ranges[ranges > max_range] = np.nan
    return ranges


def _box_surface_distance(points, centre, extents):
    """Unsigned distance from points to the surface of an axis-aligned box, m."""
    q = np.abs(points - centre) - np.asarray(extents) / 2
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    return np.where(np.all(q <= 0, axis=1), -q.max(axis=1), outside)


def test_occupied_voxels_lie_on_the_true_surface():
    block = trimesh.creation.box(extents=(5.0, 5.0, 12.0))
    block.apply_translation((0.0, 0.0, -4.0))
    omap = OctreeMap(resolution=0.25)
    rng = np.random.default_rng(3)
    for angle in np.linspace(0, 2 * np.pi, 24, endpoint=False):
        origin = np.array([8.5 * np.cos(angle), 8.5 * np.sin(angle), -5.0])
        yaw = angle + np.pi
        for tilt in np.radians([-20.0, 0.0, 20.0]):
            d = _fan(tilt=tilt + rng.uniform(-0.05, 0.05))
            rot = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0],
                            [0, 0, 1]])
            d = d @ rot.T
            omap.insert_scan(origin, d, _cast(block, origin, d, 20.0), 20.0)
    occ = omap.occupied_points()
    assert len(occ) > 500
    dist = _box_surface_distance(occ, (0.0, 0.0, -4.0), (5.0, 5.0, 12.0))
    assert np.mean(dist <= omap.resolution) >= 0.95
    # The map's distance agrees with the true distance to within a voxel diagonal.
    probe = np.array([[6.0, 0.0, -5.0], [0.0, -4.5, -3.0], [-3.5, 2.0, -6.0]])
    true = _box_surface_distance(probe, (0.0, 0.0, -4.0), (5.0, 5.0, 12.0))
    assert np.allclose(omap.distance(probe), true, atol=np.sqrt(3) * omap.resolution)


def test_free_space_is_cleared_by_hits_and_by_no_return_beams():
    omap = OctreeMap(resolution=0.5)
    origin = np.zeros(3)
    d = _fan(n=61, aperture=np.radians(30.0))
    omap.insert_scan(origin, d, np.full(len(d), 10.0), 20.0)  # a wall at 10 m
    wall = origin + d * 10.0
    assert np.all(omap.labels(wall) == 1)
    assert np.all(omap.labels(origin + d * 5.0) == 0)  # crossed by the beams: free
    assert np.all(omap.labels(origin + d * 15.0) == -1)  # behind the wall: unknown
    assert omap.distance(np.array([[5.0, 0.0, 0.0]]))[0] == pytest.approx(5.0, abs=0.75)
    # The wall is gone: beams without a return clear up to max range, not beyond.
    for _ in range(4):
        omap.insert_scan(origin, d, np.full(len(d), np.nan), 20.0)
    assert np.all(omap.labels(wall) == 0)
    assert np.all(omap.labels(origin + d * 19.5) == 0)
    assert np.all(omap.labels(origin + d * 22.0) == -1)
    assert len(omap.occupied_points()) == 0
    assert np.all(np.isinf(omap.distance(np.zeros((2, 3)))))


def test_kdtree_is_rebuilt_only_when_the_map_changed():
    omap = OctreeMap(resolution=0.5)
    d = _fan(n=31, aperture=np.radians(20.0))
    omap.insert_scan(np.zeros(3), d, np.full(len(d), 8.0), 20.0)
    tree = omap.kdtree
    assert omap.kdtree is tree
    omap.insert_scan(np.zeros(3), d, np.full(len(d), 8.0), 20.0)
    assert omap.kdtree is not tree


@pytest.mark.parametrize("kwargs, match", [
    ({"resolution": 0.0}, "resolution"), ({"resolution": np.nan}, "resolution"),
    ({"prob_hit": 0.4}, "prob_hit"), ({"prob_miss": 0.6}, "prob_miss"),
    ({"clamp_min": 0.6}, "clamp_min")])
def test_bad_parameters_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        OctreeMap(**kwargs)


def test_bad_scan_raises():
    omap = OctreeMap(0.5)
    with pytest.raises(ValueError, match="origin"):
        omap.insert_scan([np.nan, 0, 0], np.ones((2, 3)), np.ones(2), 20.0)
    with pytest.raises(ValueError, match="directions"):
        omap.insert_scan(np.zeros(3), np.ones((2, 3)), np.ones(3), 20.0)
    with pytest.raises(ValueError, match="max_range"):
        omap.insert_scan(np.zeros(3), np.ones((2, 3)), np.ones(2), -1.0)
    with pytest.raises(ValueError, match="ranges must be >= 0"):
        omap.insert_scan(np.zeros(3), np.ones((2, 3)), np.array([1.0, -1.0]), 20.0)


def test_beams_without_a_finite_direction_are_left_out():
    d = _fan(n=31, aperture=np.radians(60.0))
    ranges = np.linspace(6.0, 9.0, len(d))
    kept = np.ones(len(d), bool)
    kept[[3, 17]] = False
    broken = d.copy()
    broken[3, 1], broken[17] = np.nan, np.inf
    with_broken, without = OctreeMap(0.5), OctreeMap(0.5)
    with_broken.insert_scan(np.zeros(3), broken, ranges, 20.0)
    without.insert_scan(np.zeros(3), d[kept], ranges[kept], 20.0)
    assert with_broken.tree.writeBinary() == without.tree.writeBinary()
    assert np.array_equal(with_broken.occupied_points(), without.occupied_points())
    nothing = OctreeMap(0.5)
    nothing.insert_scan(np.zeros(3), np.full((2, 3), np.nan), np.ones(2), 20.0)
    assert nothing.num_scans == 0 and nothing.tree.getNumLeafNodes() == 0


def test_box_query_matches_the_whole_map_and_sees_clearing():
    omap = OctreeMap(resolution=0.5)
    d = _fan(n=121, aperture=np.radians(90.0))
    omap.insert_scan(np.zeros(3), d, np.full(len(d), 10.0), 20.0)
    lo, hi = np.array([0.0, -3.0, -1.0]), np.array([20.0, 3.0, 1.0])
    boxed = omap.occupied_points(lo, hi)  # while the map is dirty: checks the box only
    every = omap.occupied_points()
    inside = every[np.all((every >= lo) & (every <= hi), axis=1)]
    assert 0 < len(boxed) < len(every)
    assert sorted(map(tuple, boxed)) == sorted(map(tuple, inside))
    assert np.array_equal(omap.occupied_points(lo, hi), inside)  # from the clean cache
    for _ in range(4):  # clear the wall with beams that return nothing
        omap.insert_scan(np.zeros(3), d, np.full(len(d), np.nan), 20.0)
    assert len(omap.occupied_points(lo, hi)) == 0
    assert len(omap.occupied_points()) == 0


def _lazy_octomap(resolution):
    """OctoMap's own tree with the same sensor model, fed lazily below: never pruned."""
    import octomap

    tree = octomap.OcTree(resolution)
    tree.setProbHit(0.7), tree.setProbMiss(0.4)
    tree.setClampingThresMin(0.12), tree.setClampingThresMax(0.97)
    return tree


def test_pruning_changes_no_label_log_odds_or_occupied_voxel_and_the_file_is_complete(tmp_path):
    import octomap

    block = trimesh.creation.box(extents=(5.0, 5.0, 12.0))
    block.apply_translation((0.0, 0.0, -4.0))
    omap, lazy = OctreeMap(resolution=0.5), _lazy_octomap(0.5)
    for angle in np.tile(np.linspace(0, 2 * np.pi, 16, endpoint=False), 4):  # sweeps again
        origin = np.array([8.5 * np.cos(angle), 8.5 * np.sin(angle), -5.0])
        c, s = np.cos(angle + np.pi), np.sin(angle + np.pi)
        for tilt in (0.1, 0.3, 0.5):
            d = _fan(n=240, tilt=tilt) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
            r = _cast(block, origin, d, 20.0)
            omap.insert_scan(origin, d, r, 20.0)
            lazy.insertPointCloud(origin + d * np.where(np.isfinite(r), r, 21.0)[:, None],
                                  origin, maxrange=20.0, lazy_eval=True)
    # The map did prune (else this test compares a tree with itself).
    assert omap.memory()["leaves"] < 0.9 * lazy.getNumLeafNodes()
    probe = np.random.default_rng(5).uniform([-22, -22, -25], [22, 22, 12], (50000, 3))
    surface = trimesh.sample.sample_surface(block, 2000, seed=6)[0]
    probe = np.vstack([probe, surface])
    labels = omap.labels(probe)
    assert np.array_equal(labels, np.asarray(lazy.getLabels(probe)))
    assert (labels == 1).sum() > 100 and (labels == 0).sum() > 1000
    known = probe[labels >= 0]
    assert np.array_equal([omap.tree.search(p).getLogOdds() for p in known],
                          [lazy.search(p).getLogOdds() for p in known])
    centres = omap.candidates()[0]
    want = centres[np.asarray(lazy.getLabels(centres)) == 1]
    assert sorted(map(tuple, omap.occupied_points())) == sorted(map(tuple, want))
    # The written file carries the inner nodes too: read back, it answers the same.
    omap.write(tmp_path / "map.bt")
    back = octomap.OcTree(0.5)
    assert back.readBinary(str(tmp_path / "map.bt").encode())
    assert np.array_equal(np.asarray(back.getLabels(probe)), labels)


def test_leaves_stay_bounded_over_repeated_free_space_sweeps():
    # A downward fan flown over a flat floor, pass after pass: once the water it crosses
    # reaches the free clamping threshold its uniform subtrees are pruned, so the tree holds
    # a fraction of the voxels known, and further passes add nothing.
    a = np.linspace(-np.radians(60), np.radians(60), 240)
    d = np.stack([np.zeros_like(a), np.sin(a), -np.cos(a)], axis=1)
    omap, lazy = OctreeMap(resolution=0.5), _lazy_octomap(0.5)
    leaves = []
    for _ in range(6):
        for x in np.arange(0.0, 16.0, 0.25):
            origin = np.array([x, 0.3, -5.0])
            r = 15.0 / np.cos(a)
            r[r > 20.0] = np.nan  # beyond the floor's reach: clears up to max range
            omap.insert_scan(origin, d, r, 20.0)
            lazy.insertPointCloud(origin + d * np.where(np.isfinite(r), r, 21.0)[:, None],
                                  origin, maxrange=20.0, lazy_eval=True)
        leaves.append(omap.memory()["leaves"])
    known = lazy.getNumLeafNodes()  # every voxel crossed, unpruned
    assert known > 30000
    assert max(leaves[1:]) <= leaves[0] and leaves[-1] < 0.25 * known
    assert np.count_nonzero(omap.labels(omap.candidates()[0]) == 1) > 500  # the floor's hits


def _brute_force_occupied(omap, lo, hi):
    """Occupied voxel centres in the box, every voxel ever hit read from the octree."""
    centres = omap.candidates()[0]
    centres = centres[np.all((centres >= lo) & (centres <= hi), axis=1)]
    return centres[np.asarray(omap.tree.getLabels(centres)) == 1] if len(centres) else centres


def test_cached_labels_match_reading_every_voxel_through_moving_scans_and_clearing():
    # Scans against a block that then moves (as a navigation jump would), so voxels are hit,
    # then cleared; fans at random attitudes and some non-coplanar scans; box queries at
    # random moments must equal reading every candidate's label from the octree.
    rng = np.random.default_rng(21)
    omap = OctreeMap(resolution=0.5)
    checked = 0
    for k in range(160):
        block = trimesh.creation.box(extents=(4.0, 4.0, 8.0))
        block.apply_translation((0.0 if k < 80 else 2.5, 0.0, -4.0))
        angle = 0.15 * k
        origin = np.array([9.0 * np.cos(angle), 9.0 * np.sin(angle), rng.uniform(-8.0, 0.0)])
        if k % 7 == 3:  # rays in every direction: not coplanar
            d = rng.normal(size=(150, 3))
            d /= np.linalg.norm(d, axis=1, keepdims=True)
        else:
            yaw, roll = angle + np.pi + rng.uniform(-0.5, 0.5), rng.uniform(-np.pi, np.pi)
            cr, sr, cy, sy = np.cos(roll), np.sin(roll), np.cos(yaw), np.sin(yaw)
            rot = (np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
                   @ np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]]))
            d = _fan(n=120) @ rot.T
        omap.insert_scan(origin, d, _cast(block, origin, d, 12.0), 12.0)
        if rng.random() < 0.3:
            centre = origin + rng.uniform(-6.0, 6.0, 3)
            half = rng.uniform(3.0, 15.0, 3)
            lo, hi = centre - half, centre + half
            got, want = omap.occupied_points(lo, hi), _brute_force_occupied(omap, lo, hi)
            assert sorted(map(tuple, got)) == sorted(map(tuple, want))
            centres, log_odds = omap.occupied_points(lo, hi, log_odds=True)
            assert np.array_equal(log_odds, [omap.tree.search(c).getLogOdds() for c in centres])
            checked += len(want)
        if k == 79:
            before = np.sum(omap.occupied_points()[:, 0] < 0.5)  # only the first block there
    assert checked > 500  # the queries did see structure
    everything = omap.occupied_points()
    assert sorted(map(tuple, everything)) == sorted(map(tuple, _brute_force_occupied(
        omap, np.full(3, -np.inf), np.full(3, np.inf))))
    # Many of the first block's voxels were cleared once it moved (the rest are occluded).
    assert before > 100 and np.sum(everything[:, 0] < 0.5) < 0.75 * before


def test_log_odds_reads_give_unknown_voxels_minus_infinity():
    omap = OctreeMap(resolution=0.5)
    omap.insert_scan(np.zeros(3), np.array([[1.0, 0.0, 0.0]]), np.array([3.0]), 10.0)
    # the voxel hit, one the beam crossed, one no beam reached
    got = omap._read_log_odds(np.array([[3.25, 0.25, 0.25], [1.25, 0.25, 0.25],
                                        [0.25, 5.25, 0.25]]))
    assert got[0] == omap.tree.getProbHitLog() and got[1] == omap.tree.getProbMissLog()
    assert got[2] == -np.inf


def test_returns_on_a_voxel_face_are_occupied_where_octomap_keys_them():
    """OctoMap keys points in single precision: ends on a flat seabed at z = -30 m (a voxel
    face) computed a hair below it must still be found among the occupied voxels."""
    m = OctreeMap(0.5)
    a, c = np.sqrt(0.125), np.sqrt(0.75)
    directions = np.array([[a, a, -c], [-a, a, -c], [-a, -a, -c], [a, -a, -c]])
    ends = np.array([1.0, 0.0, -10.0]) + directions * 23.094011
    assert np.any(ends[:, 2] < -30.0)  # in double precision, just below the face
    m.insert_scan([1.0, 0.0, -10.0], directions, np.full(4, 23.094011), 80.0)
    occupied = m.occupied_points()
    assert len(occupied) == 4 and np.all(m.labels(occupied) == 1)


def test_candidates_read_as_free_leave_the_index_and_every_answer_stays_the_same():
    # A wall scanned with noisy ranges from a drifting vehicle, then moved (a navigation jump):
    # many voxels are hit once and cleared by later beams. Every answer must equal reading the
    # label of every voxel ever hit (tracked here, keyed as OctoMap keys them), while the index
    # holds far fewer candidates than were ever hit, and re-hit voxels come back.
    rng = np.random.default_rng(8)
    omap = OctreeMap(resolution=0.5)
    ever: set[tuple] = set()
    queries = 0
    for k in range(240):
        wall = trimesh.creation.box(extents=(1.0, 30.0, 12.0))
        wall.apply_translation((10.0 if k < 120 else 11.5, 0.0, -6.0))
        origin = np.array([0.0, -10.0 + 0.08 * (k % 120), -6.0]) + rng.normal(0.0, 0.3, 3)
        d = _fan(n=160, aperture=np.radians(100.0), tilt=rng.uniform(-0.4, 0.4))
        r = _cast(wall, origin, d, 20.0)
        r += rng.normal(0.0, 0.4, len(r))  # noise spreads the returns over several voxels
        omap.insert_scan(origin, d, r, 20.0)
        hit = np.isfinite(r) & (r <= 20.0)
        ends = (origin + d[hit] * r[hit, None]).astype(np.float32).astype(float)
        ever.update(map(tuple, np.floor(ends / 0.5).astype(int).tolist()))
        if k % 5 == 4:  # the replanner's box around the vehicle
            lo, hi = origin - [1.0, 8.0, 6.0], origin + [16.0, 8.0, 6.0]
            everything = (np.array(sorted(ever)) + 0.5) * 0.5
            inside = everything[np.all((everything >= lo) & (everything <= hi), axis=1)]
            want = inside[np.asarray(omap.tree.getLabels(inside)) == 1]
            got, log_odds = omap.occupied_points(lo, hi, log_odds=True)
            assert sorted(map(tuple, got)) == sorted(map(tuple, want))
            np.testing.assert_array_equal(log_odds, [omap.tree.search(p).getLogOdds()
                                                     for p in got])
            queries += len(want)
    everything = (np.array(sorted(ever)) + 0.5) * 0.5
    want = everything[np.asarray(omap.tree.getLabels(everything)) == 1]
    assert queries > 1000 and len(want) > 200
    assert sorted(map(tuple, omap.occupied_points())) == sorted(map(tuple, want))
    # The index: the occupied voxels and the unread, not every voxel ever hit.
    centres, unread = omap.candidates()
    memory = omap.memory()
    assert memory["candidates"] == len(centres) == len(want) + np.count_nonzero(unread)
    assert memory["candidates"] < 0.7 * len(ever)  # 3,851 of 5,803: the cleared ones left
    assert omap._count < 0.8 * len(ever)  # rows left by free voxels were taken again
    np.testing.assert_allclose(omap.distance(everything[:50]), cKDTree(want).query(
        everything[:50])[0])


def test_a_beam_without_an_echo_clears_only_no_return_clear_m():
    """No echo is not proof of water: with `no_return_clear_m` 5 m a beam without an echo
    clears 5 m and leaves the water beyond unknown, while a beam with an echo in the same scan
    still clears up to its echo; by default (OctoMap's way) both clear to their end."""
    origin = np.array([0.0, 0.0, -20.0])
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    ranges = np.array([np.nan, 12.0])  # +x: no echo; +y: an echo at 12 m
    probe = np.array([[3.2, 0.1, -19.9], [8.2, 0.1, -19.9], [0.1, 8.2, -19.9],
                      [0.1, 12.1, -19.9]])
    limited = OctreeMap(0.5, no_return_clear_m=5.0)
    limited.insert_scan(origin, directions, ranges, 20.0)
    assert limited.labels(probe).tolist() == [0, -1, 0, 1]
    full = OctreeMap(0.5)
    full.insert_scan(origin, directions, ranges, 20.0)
    assert full.labels(probe).tolist() == [0, 0, 0, 1]
    alone = OctreeMap(0.5, no_return_clear_m=5.0)
    alone.insert_scan(origin, directions[:1], ranges[:1], 20.0)
    assert alone.labels(probe[:2]).tolist() == [0, -1]
    with pytest.raises(ValueError, match="no_return_clear_m must be > 0"):
        OctreeMap(0.5, no_return_clear_m=0.0)


def test_code_set_matches_a_python_set_through_merges(monkeypatch):
    """The candidates' `_CodeSet` against a Python set, with merges every 8 codes: codes
    added, removed, removed from the bulk and added back."""
    monkeypatch.setattr(octree_map, "_MERGE", 8)
    rng = np.random.default_rng(7)
    codes, want = octree_map._CodeSet(), set()
    for _ in range(400):
        batch = np.unique(rng.integers(0, 200, rng.integers(1, 12)))
        if rng.random() < 0.6:
            new = batch[~codes.contains(batch)]
            assert set(new.tolist()) == set(batch.tolist()) - want
            codes.add(new)
            want.update(new.tolist())
        else:
            gone = batch[codes.contains(batch)]
            assert set(gone.tolist()) == set(batch.tolist()) & want
            codes.remove(gone)
            want.difference_update(gone.tolist())
        assert len(codes) == len(want)
    every = np.arange(200)
    assert set(every[codes.contains(every)].tolist()) == want and len(want) > 20
    assert len(codes._bulk) > 8  # merged, not only the small arrays


def _wall_queries(rng_seed=8, scans=120):
    """A noisy wall scanned along its face; the box queries' answers, in their order."""
    rng = np.random.default_rng(rng_seed)
    omap = OctreeMap(resolution=0.5)
    answers = []
    wall = trimesh.creation.box(extents=(1.0, 30.0, 12.0))
    wall.apply_translation((10.0, 0.0, -6.0))
    for k in range(scans):
        origin = np.array([0.0, -10.0 + 0.15 * k, -6.0]) + rng.normal(0.0, 0.3, 3)
        d = _fan(n=160, aperture=np.radians(100.0), tilt=rng.uniform(-0.4, 0.4))
        r = _cast(wall, origin, d, 20.0) + rng.normal(0.0, 0.4, 160)
        omap.insert_scan(origin, d, r, 20.0)
        if k % 3 == 2:
            answers.append(omap.occupied_points(origin - [1.0, 8.0, 6.0],
                                                origin + [16.0, 8.0, 6.0], log_odds=True))
    return omap, answers


def test_compacting_the_rows_tile_by_tile_keeps_every_answer_and_its_order(monkeypatch):
    _, plain = _wall_queries()
    compacted = []

    def spy(self):
        compact(self)
        compacted.append(self._count)
        rows = np.concatenate([self._tiles[k] for k in sorted(self._tiles)])
        assert np.array_equal(rows, np.arange(self._count))  # contiguous, tile by tile
        assert self._count == len(self._candidates) and not self._vacant

    compact = OctreeMap._compact
    monkeypatch.setattr(octree_map, "_COMPACT", 300)
    monkeypatch.setattr(OctreeMap, "_compact", spy)
    omap, answers = _wall_queries()
    assert len(compacted) >= 5 and len(answers) == len(plain)
    for (centres, log_odds), (want, want_log_odds) in zip(answers, plain):
        assert np.array_equal(centres, want) and np.array_equal(log_odds, want_log_odds)
    assert sum(len(c) for c, _ in answers) > 2000


def test_in_box_equals_testing_every_coordinate():
    rng = np.random.default_rng(3)
    points = np.round(rng.uniform(-3.0, 3.0, (2000, 3)), 1)  # many exactly on the faces
    points[::97, 1] = np.nan
    lo, hi = np.array([-1.0, -2.0, 0.5]), np.array([1.0, 0.5, 2.0])
    want = np.all((points >= lo) & (points <= hi), axis=1)
    assert np.array_equal(lattice.in_box(points, lo, hi), want) and 50 < want.sum() < 1900


def test_unique_equals_numpy_unique():
    rng = np.random.default_rng(4)
    codes = lattice.encode(rng.integers(-40, 40, (3000, 3)))
    codes = np.concatenate([codes, codes[::3]])  # every third twice
    for part in (codes, codes[:1], codes[:0], np.sort(codes)):
        got, want = lattice.unique(part), np.unique(part)
        assert got.dtype == want.dtype and np.array_equal(got, want)
    assert len(lattice.unique(codes)) < len(codes)


def test_discretized_insertion_marks_the_same_voxels_and_clears_towards_their_centres():
    """Two beams ending in one voxel cross different water; discretised, one ray goes to the
    voxel's centre instead: the same voxel is occupied, less water is cleared."""
    origin = np.array([0.0, 0.5, 0.5])
    ends = np.array([[9.05, 3.95, 0.5], [9.95, 3.05, 0.5]])  # both in voxel (9, 3, 0)
    directions = (ends - origin) / np.linalg.norm(ends - origin, axis=1, keepdims=True)
    ranges = np.linalg.norm(ends - origin, axis=1)
    every, discretized = OctreeMap(1.0), OctreeMap(1.0, discretize=True)
    for omap in (every, discretized):
        omap.insert_scan(origin, directions, ranges, 20.0)
    assert discretized.discretize and not every.discretize
    np.testing.assert_array_equal(every.occupied_points(), [[9.5, 3.5, 0.5]])
    np.testing.assert_array_equal(discretized.occupied_points(), [[9.5, 3.5, 0.5]])
    x, y = np.meshgrid(np.arange(10) + 0.5, np.arange(5) + 0.5)
    grid = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, 0.5)])
    assert (every.labels(grid) == 0).sum() > (discretized.labels(grid) == 0).sum() > 0
