"""benchmarks/bench_view_paths.py: the recorder's file round-trips and the comparison's metrics
on a hand-made grid (no OMPL, no dive)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_view_paths as bench  # noqa: E402
from drake_auv.exploration.frontiers import FREE, OCCUPIED, UNKNOWN, LabelGrid  # noqa: E402
from drake_auv.exploration.paths import PathCost, TravelField, path_clear, plan_path  # noqa: E402


@pytest.fixture
def travel() -> TravelField:
    """12 x 8 x 6 cells of 1 m from (0, 0, -8), all known water but a wall at x in [5, 6]
    from the floor (z = -8) to z = -4 and unknown water at x in [9, 12], y in [0, 2];
    clearance 1 m (KEEP: 0.75 m from wall cell centres)."""
    labels = np.full((12, 8, 6), FREE, np.int8)
    labels[5, :, :4] = OCCUPIED
    labels[9:, :2] = UNKNOWN
    grid = LabelGrid(np.array([0.0, 0.0, -8.0]), 1.0, labels,
                     np.array([0.0, 0.0, -8.0, 12.0, 8.0, -2.0]))
    return TravelField.build(PathCost(grid, 1.0), [1.5, 4.5, -6.5])


def test_query_round_trips(tmp_path, travel):
    goal = np.array([10.5, 4.5, -6.5])
    path = plan_path(travel, goal, seed=3)
    assert path is not None and path[:, 2].max() > -4.0  # over the wall
    bench.save_query(tmp_path / "q.npz", travel, goal, 3, path, 12.5)
    q = bench.load_query(tmp_path / "q.npz")
    grid = q.travel.cost.grid
    np.testing.assert_array_equal(grid.labels, travel.cost.grid.labels)
    np.testing.assert_array_equal(grid.origin, travel.cost.grid.origin)
    np.testing.assert_array_equal(grid.region, travel.cost.grid.region)
    assert grid.cell == 1.0 and q.travel.cost.clearance == 1.0 and q.seed == 3 and q.ms == 12.5
    np.testing.assert_array_equal(q.travel.passable, travel.passable)
    np.testing.assert_array_equal(q.travel.start, travel.start)
    np.testing.assert_array_equal(q.goal, goal)
    np.testing.assert_array_equal(q.path, path)
    np.testing.assert_array_equal(plan_path(q.travel, q.goal, seed=q.seed), path)
    bench.save_query(tmp_path / "none.npz", travel, goal, 0, None, 1.0)
    assert bench.load_query(tmp_path / "none.npz").path is None


def test_load_query_refuses_another_field(tmp_path, travel):
    bench.save_query(tmp_path / "q.npz", travel, [10.5, 4.5, -6.5], 0, None, 1.0)
    data = dict(np.load(tmp_path / "q.npz"))
    data["passable"] = ~data["passable"]
    np.savez(tmp_path / "bad.npz", **data)
    with pytest.raises(ValueError, match="bad.npz: the rebuilt TravelField"):
        bench.load_query(tmp_path / "bad.npz")
    (tmp_path / "junk.npz").write_bytes(b"not an npz")
    with pytest.raises(ValueError, match="junk.npz: not a bench_view_paths query"):
        bench.load_query(tmp_path / "junk.npz")


def test_validity_is_path_clears_rule(travel):
    goal = np.array([10.5, 4.5, -6.5])
    valid = bench.Validity(travel, goal)
    points = np.array([[5.5, 4.5, -6.5],   # in the wall
                       [4.5, 4.5, -6.5],   # its cell centre 1 m from the wall's: kept
                       [5.5, 4.5, -3.5],   # 1 m above the wall's top cell centre
                       [5.5, 4.5, -7.9],   # below the floor (-7.5)
                       [5.5, 4.5, -1.5],   # above z = -1 m's cell: not passable
                       [-0.5, 4.5, -6.5],  # outside the grid
                       [10.5, 0.5, -6.5]])  # unknown water, not between known water
    expected = [False, True, True, False, False, False, False]
    assert valid.points(points).tolist() == expected
    assert [valid(p) for p in points] == expected
    straight, over = np.array([travel.start, goal]), plan_path(travel, goal)
    assert not bench.path_valid(valid, straight) and bench.path_valid(valid, over)
    assert path_clear(travel, over) and not path_clear(travel, resample_line(straight))


def resample_line(path):
    return np.linspace(path[0], path[-1], 21)


def test_min_clearance_and_metrics(travel):
    grid = travel.cost.grid
    over = np.array([[1.5, 4.5, -2.5], [10.5, 4.5, -2.5]])  # 2 m above the wall's top centre
    assert bench.min_clearance(grid, over) == pytest.approx(2.0)
    assert bench.min_clearance(grid, [[1.5, 4.5, -6.5], [10.5, 4.5, -6.5]]) == pytest.approx(0.0)
    empty = LabelGrid(grid.origin, 1.0, np.full_like(grid.labels, FREE), grid.region)
    assert bench.min_clearance(empty, over) == math.inf
    keep = 0.75  # KEEP * clearance 1 m
    assert not bench.encroaches(grid, [[5.5, 4.5, -3.6], [5.5, 7.5, -3.6]], 1.0)  # at its start's
    assert bench.encroaches(grid, [[5.5, 4.5, -3.0], [5.5, 7.5, -3.9]], keep)  # 0.6 m at its end
    assert not bench.encroaches(grid, [[5.5, 4.5, -3.0], [5.5, 7.5, -3.0]], keep)
    q = bench.Query(travel, over[-1], 0, None, 0.0, np.empty((0, 3)), 0)
    bent = np.vstack([over[0], [6.0, 4.5, -2.5], over[1]])  # the same line, one more point
    ratio, clearance, to_unknown, valid, clear, near = bench.metrics(q, bent, over)
    assert ratio == pytest.approx(1.0) and clearance == pytest.approx(2.0) and valid and clear
    assert not near
    assert to_unknown == pytest.approx(2.0)  # the wall is nearer than unknown water
    assert bench.min_clearance(grid, over, (UNKNOWN,)) == pytest.approx(3.0)  # y 1.5, z -2.5
    detour = np.array([[1.5, 4.5, -2.5], [6.0, 7.5, -2.5], [10.5, 4.5, -2.5]])
    assert bench.metrics(q, detour, over)[0] == pytest.approx(
        2 * math.hypot(4.5, 3.0) / 9.0)
    into = np.array([[6.5, 4.5, -2.5], [10.5, 0.5, -2.5], [10.5, 4.5, -2.5]])
    assert bench.metrics(q, into, over)[3:] == (False, True, False)  # unknown water, far from rock
    through = [[1.5, 4.5, -6.5], [10.5, 4.5, -6.5]]  # the wall
    assert bench.metrics(q, through, over)[3:] == (False, False, True)
    assert bench.metrics(q, None, over)[3:] == (False,) * 3
    assert all(math.isnan(v) for v in bench.metrics(q, None, over)[:3])


def test_bad_arguments_one_line(tmp_path, capsys):
    assert bench.main(["compare", "--queries", str(tmp_path)]) == 2
    assert "no .npz in" in capsys.readouterr().err
    (tmp_path / "q.npz").write_bytes(b"")
    assert bench.main(["compare", "--queries", str(tmp_path), "--planners", "BITstar"]) == 2
    assert "--planners: 'BITstar' is not NAME:ms" in capsys.readouterr().err
