"""benchmarks/bench_mission.py's `CallTimer`: it times the callables it wraps (OctoMap's native
insertion through the tree it hands each new map) and puts every one of them back."""

import sys
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_mission as bench  # noqa: E402
from drake_auv.geometry.raycast import RayCaster  # noqa: E402
from drake_auv.mapping.octree_map import OctreeMap  # noqa: E402


def test_call_timer_times_the_wrapped_calls_and_restores_them():
    originals = {(owner, name): getattr(owner, name) for owner, name, _, _ in bench.TIMED}
    init = OctreeMap.__init__
    caster = RayCaster(trimesh.creation.box(extents=(10.0, 10.0, 1.0)))
    with bench.CallTimer() as timer:
        octree = OctreeMap(0.5)
        a = np.linspace(-0.5, 0.5, 11)
        directions = np.column_stack([np.sin(a), np.zeros(11), -np.cos(a)])
        for _ in range(3):
            octree.insert_scan(np.array([0.0, 0.0, 5.0]), directions, np.full(11, 4.5), 20.0)
        ranges, _ = caster.cast_unit(np.array([0.0, 0.0, 5.0]), directions, 20.0)
    assert timer.calls["octree insertion (`OctreeMap.insert_scan`)"] == 3
    assert timer.calls["of which OctoMap (C++)"] == 3
    assert timer.calls["ray casts (Embree), sonars' and camera's"] == 1
    assert 0 < timer.seconds["of which OctoMap (C++)"] <= timer.seconds[
        "octree insertion (`OctreeMap.insert_scan`)"]
    assert len(octree.occupied_points()) > 0  # the timed tree is the map's tree
    np.testing.assert_allclose(ranges, 4.5 / np.cos(a), rtol=1e-5)  # the cast still casts
    assert OctreeMap.__init__ is init
    for (owner, name), original in originals.items():
        assert getattr(owner, name) is original
    assert not isinstance(OctreeMap(0.5).tree, bench._TimedTree)
