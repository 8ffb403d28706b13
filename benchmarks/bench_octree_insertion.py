"""OctoMap insertion, lazy against eager, and several pings per insertion: the per-ping cost
and the tree's size.

Flies the first `--max-time` simulated seconds of the built-in `monterey_wall` mission, then
inserts its recorded sonar batches again into two fresh OctoMap trees with the map's sensor
model (`OctreeMap`'s, 0.5 m): one lazily (`lazy_eval=True`: inner nodes deferred, never
pruned), one eagerly (`lazy_eval=False`: what `OctreeMap` does, pruning uniform subtrees), the
two in turn `--repeats` times. Prints per mode and sonar the median and mean insertion time
per ping (ms), the whole replay's time, and the leaves and `memoryUsage` of the tree every
quarter of the batches; checks that both trees give the same label at every voxel centre the
scans hit and at random points of the surveyed box.

Then the lever of several pings per insertion: the multibeam's consecutive pings
merged `--merge` at a time into one eager insertion (one point cloud, from the mean of their
origins; OctoMap updates a voxel once per insertion, so the free water two pings share is
updated once), the other sonars' batches as they are. Prints the multibeam's time per ping
against one ping an insertion, in turn in the same run, and the share of voxels (hit voxel
centres and random points) whose label differs from the one-ping tree's.

    .venv/bin/python benchmarks/bench_octree_insertion.py [--max-time 1200] [--repeats 2]
        [--merge 2 3 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import octomap

from _reference import machine
from bench_long_mission import long_mission
from drake_auv.mission.runner import run_mission
from drake_auv.sonar.sensor import BUILT_IN

RESOLUTION = 0.5


def new_tree() -> octomap.OcTree:
    """An empty tree with `OctreeMap`'s sensor model."""
    tree = octomap.OcTree(RESOLUTION)
    tree.setProbHit(0.7), tree.setProbMiss(0.4)
    tree.setClampingThresMin(0.12), tree.setClampingThresMax(0.97)
    return tree


def endpoints(b) -> np.ndarray:
    """(n, 3) the beams' ends as `OctreeMap.insert_scan` places them (no echo: beyond range)."""
    ranges = b.ranges.astype(float)
    hit = np.isfinite(ranges) & (ranges <= b.max_range)
    length = np.where(hit, ranges, b.max_range + 2.0 * RESOLUTION)
    return b.origin + b.directions.astype(float) * length[:, None]


def replay(batches, lazy: bool):
    """Inserts `batches` as `OctreeMap.insert_scan` does; returns the tree, the per-batch
    insertion times (s) and (batches inserted, leaves, MB) rows at each quarter."""
    tree = new_tree()
    times, sizes = np.zeros(len(batches)), []
    quarter = max(len(batches) // 4, 1)
    for i, b in enumerate(batches):
        cloud = endpoints(b)
        start = time.perf_counter()
        tree.insertPointCloud(cloud, b.origin, maxrange=float(b.max_range), lazy_eval=lazy)
        times[i] = time.perf_counter() - start
        if (i + 1) % quarter == 0 or i + 1 == len(batches):
            sizes.append((i + 1, tree.getNumLeafNodes(), tree.memoryUsage() / 2**20))
    return tree, times, sizes


def replay_merged(batches, merge: int):
    """Inserts `batches` eagerly, the multibeam's runs of consecutive pings `merge` to an
    insertion (from their origins' mean); returns the tree and the multibeam's time (s)."""
    tree, spent, run = new_tree(), 0.0, []

    def flush():
        nonlocal spent, run
        if run:
            cloud = np.concatenate([endpoints(b) for b in run])
            origin = np.mean([b.origin for b in run], axis=0)
            start = time.perf_counter()
            tree.insertPointCloud(cloud, origin, maxrange=float(run[0].max_range),
                                  lazy_eval=False)
            spent += time.perf_counter() - start
            run = []

    for b in batches:
        if BUILT_IN[b.source] != "multibeam":
            tree.insertPointCloud(endpoints(b), b.origin, maxrange=float(b.max_range),
                                  lazy_eval=False)
            continue
        run.append(b)
        if len(run) == merge:
            flush()
    flush()
    return tree, spent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--max-time", type=float, default=1200.0, help="simulated s")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--merge", type=int, nargs="*", default=[2, 3, 5],
                        help="multibeam pings per insertion to try, each >= 2")
    args = parser.parse_args()
    if not args.max_time > 0 or args.repeats < 1 or any(m < 2 for m in args.merge):
        parser.error("--max-time must be > 0 s, --repeats >= 1 and every --merge >= 2")
    print(machine())
    result = run_mission(long_mission("monterey_wall", 0, 1, args.max_time), progress=False)
    batches = list(result.mapping.scan_log.iter_batches())
    sources = np.array([b.source for b in batches])
    print(f"{result.log.duration_s:.0f} s simulated: {len(batches)} batches, "
          f"{sum(len(b.ranges) for b in batches)} beams")
    trees = {}
    for _ in range(args.repeats):
        for name, lazy in (("lazy", True), ("eager", False)):
            tree, times, sizes = replay(batches, lazy)
            trees[name] = tree
            per = "; ".join(f"{BUILT_IN[s]} median {1e3 * np.median(times[sources == s]):.3f} "
                            f"mean {1e3 * times[sources == s].mean():.3f} ms"
                            for s in np.unique(sources))
            print(f"{name}: {times.sum():.2f} s for the replay; {per}")
            print("   " + ", ".join(f"{n} batches: {leaves} leaves {mb:.1f} MB"
                                    for n, leaves, mb in sizes))
    hits = np.concatenate([b.points() for b in batches])
    centres = (np.unique(np.floor(hits / RESOLUTION), axis=0) + 0.5) * RESOLUTION
    lo, hi = hits.min(axis=0) - 20.0, hits.max(axis=0) + 20.0
    points = np.vstack([centres, np.random.default_rng(0).uniform(lo, hi, (200000, 3))])
    reference = trees["eager"].getLabels(points)
    same = np.array_equal(trees["lazy"].getLabels(points), reference)
    print(f"labels equal at {len(centres)} hit voxels and 200000 random points: {same}")
    multibeam = sources == BUILT_IN.index("multibeam")
    pings = int(multibeam.sum())
    for merge in args.merge:
        one, merged = [], []
        for _ in range(args.repeats):
            one.append(replay(batches, False)[1][multibeam].sum())
            tree, spent = replay_merged(batches, merge)
            merged.append(spent)
        labels = tree.getLabels(points)
        print(f"multibeam, {merge} pings an insertion: {1e3 * min(merged) / pings:.3f} ms a "
              f"ping against {1e3 * min(one) / pings:.3f} one ping an insertion "
              f"({min(merged) / min(one):.2f}x, least of {args.repeats}); labels differ at "
              f"{np.mean(labels[:len(centres)] != reference[:len(centres)]):.2%} of the hit "
              f"voxels and {np.mean(labels[len(centres):] != reference[len(centres):]):.2%} "
              f"of the random points; {tree.getNumLeafNodes()} leaves")


if __name__ == "__main__":
    main()
