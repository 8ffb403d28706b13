"""Survey-scale dive: the built-in `monterey_wall` mission (a steep 160 m x 160 m
window of a Monterey Bay tile, 1 m world, the ~10 m survey as prior, Omega 10 m, plan and
replanned survey, about 3.8 h of dive), its cost per simulated hour.

Per simulated hour: the replanning step's median and p95 (wall, ms) and its map query's
median; STOMP's iterations and the box's occupied voxels (medians) and the step less its query
per iteration (median, ms), what a step's cost follows; the real-time factor, the process's
resident memory at the hour's end and its peak so far (MB); the octree's leaves, own memory,
candidates' index (MB, candidates) and the live `ScanLog` versions at the hour's end
(`OctreeMap.memory()`, a search of live objects); the mission's coverage, true distance and
contact. Acceptance (docs/benchmarks.md, "Survey-scale dives"): step median <= 10 ms and p95
<= 25 ms in every hour, the last hour's median within 1.5x of the first's, resident memory
growing by less than 100 MB per hour after the first.
The vehicle-only reference (`_reference.py`) is measured before and after the dive in the
same process; the step's medians are also given in vehicle-seconds (ms times the reference's
real-time factor, the mean of both measurements): the figure that compares across days on
machines whose speed moves by 2x.
`--surveys N` flies the replanned survey N times in the dive (the single one is already 3.8 h);
`--max-time S` stops it after S simulated seconds. `--trace-python A:B` splits the growth of
resident memory from A to B simulated seconds into the OctoMap tree's (`memoryUsage`), the
Python heap's (`tracemalloc`, with the lines that allocated most of it), tracemalloc's own
and the rest (native memory that none of them counts: the allocator's overhead on the tree's
many small nodes, Drake's logs, libraries); tracing Python's allocations makes the dive
several times slower, so its timings do not count.

    .venv/bin/python benchmarks/bench_long_mission.py [--surveys 2] [--max-time S] [--json F]
        [--trace-python A:B]
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import yaml

# This checkout's package first: the venv's editable install may point at another one.
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _reference import machine, reference_factor  # noqa: E402
from drake_auv.mapping.mapper import OnlineMap  # noqa: E402
from drake_auv.mapping.scan_log import ScanLog  # noqa: E402
from drake_auv.mission.config import BUILTIN_DIR, mission_from_dict  # noqa: E402
from drake_auv.mission.report.summary import summarise  # noqa: E402
from drake_auv.mission.runner import run_mission  # noqa: E402
from drake_auv.reconstruction.products import write_points  # noqa: E402
from drake_auv.signals import ReplanningStep  # noqa: E402

HOUR = 3600.0


def rss_mb() -> float:
    """Current resident set size of this process, MB (Linux /proc; the peak elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize() / 2**20
    except OSError:
        return peak_mb()


def peak_mb() -> float:
    """Peak resident set size of this process so far, MB."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10


def octree_memory() -> dict:
    """`OctreeMap.memory()` of the dive's map, found among the live objects (the runner's
    probe sees only the Context; the mapper's cache holds one `OnlineMap`), with the number
    of live `ScanLog` versions (`versions`: bounded by the log's chunk, not the dive)."""
    live = gc.get_objects()
    maps = [o for o in live if isinstance(o, OnlineMap) and o.version is not None]
    versions = sum(isinstance(o, ScanLog) for o in live)
    best = max((m.map.memory() for m in maps), key=lambda m: m["leaves"], default={})
    return dict(best, versions=versions)


class Probe:
    """Samples wall time and memory every `every` simulated seconds (the runner's probe), and
    the octree's memory every `map_every` s (a search of the live objects: not every step)."""

    def __init__(self, every: float = 60.0, map_every: float = 600.0, trace=None):
        self.every, self.next = every, 0.0
        self.map_every = map_every
        self.trace = trace  # (A, B) simulated s: `tracemalloc` snapshots there, see `traced`
        # (sim s, snapshot (the first dumped to a file, so it takes no memory meanwhile), RSS
        # MB, octree MB, tracemalloc's own MB)
        self.snapshots: list[tuple] = []
        self.dump_path = None
        if trace is not None:
            handle, self.dump_path = tempfile.mkstemp(prefix="drake_auv-trace-")
            os.close(handle)
        self.rows: list[tuple] = []  # (sim s, wall s, rss MB, peak MB)
        # (sim s, leaves, octree MB, candidates' index MB, candidates, ScanLog versions)
        self.maps: list[tuple] = []
        self.start = time.perf_counter()

    def __call__(self, context) -> None:
        t = context.get_time()
        if self.trace is not None and len(self.snapshots) < 2 and t >= self.trace[
                len(self.snapshots)]:
            rss, own = rss_mb(), tracemalloc.get_tracemalloc_memory() / 2**20
            octree = octree_memory().get("octree_mb", 0.0)
            snapshot = tracemalloc.take_snapshot()
            if not self.snapshots:
                snapshot.dump(self.dump_path)
                snapshot = None
            self.snapshots.append((t, snapshot, rss, octree, own))
        if t >= self.next:
            self.rows.append((t, time.perf_counter() - self.start, rss_mb(), peak_mb()))
            self.next += self.every
            if t % self.map_every < self.every and t > 0:
                m = octree_memory()
                self.maps.append((t, m.get("leaves", 0), m.get("octree_mb", 0.0),
                                  m.get("index_mb", 0.0), m.get("candidates", 0),
                                  m["versions"]))
            if len(self.rows) > 1 and t % HOUR < self.every:  # an hour done: progress line
                leaves, octree = self.maps[-1][1:3]
                print(f"  {t:.0f} s simulated, {self.rows[-1][1]:.0f} s wall, RSS "
                      f"{self.rows[-1][2]:.0f} MB, octree {leaves} leaves {octree:.0f} MB",
                      flush=True)


def traced(probe: Probe, top: int = 8) -> dict:
    """The growth of resident memory between the probe's two snapshots, MB: the OctoMap
    tree's `memoryUsage`, the Python heap (traced) and the rest, with the `top` source lines
    whose allocations grew most."""
    (t0, _, rss0, tree0, own0), (t1, second, rss1, tree1, own1) = probe.snapshots
    first = tracemalloc.Snapshot.load(probe.dump_path)
    stats = second.compare_to(first, "lineno")
    python = sum(stat.size_diff for stat in stats) / 2**20
    lines = [dict(where=f"{Path(stat.traceback[0].filename).name}:{stat.traceback[0].lineno}",
                  mb=stat.size_diff / 2**20) for stat in stats[:top]]
    return dict(from_s=t0, to_s=t1, rss_mb=rss1 - rss0, octree_mb=tree1 - tree0,
                python_mb=python, tracemalloc_mb=own1 - own0,
                rest_mb=rss1 - rss0 - (tree1 - tree0) - python - (own1 - own0), lines=lines)


def per_hour(result, probe: Probe, reference: float) -> list[dict]:
    """One row per simulated hour (the last one partial): steps, real-time factor, memory;
    the step's median also in vehicle-seconds (`reference`: the vehicle-only real-time
    factor)."""
    steps = ReplanningStep(result.mapping.replanning)
    t_step, wall, query = steps.time, 1e3 * steps.wall_time, 1e3 * steps.query_time
    iterations = steps.iterations
    # What a STOMP iteration costs (the step less its map query, per iteration): flat over
    # the dive when the step's cost follows the optimisation's work, not the dive's length.
    per_iteration = np.where(iterations > 0, (wall - query) / np.maximum(iterations, 1), np.nan)
    samples = np.array(probe.rows)
    maps = np.array(probe.maps).reshape(-1, 6)
    rows = []
    for h in range(int(np.ceil(result.log.duration_s / HOUR))):
        hour = (t_step >= h * HOUR) & (t_step < (h + 1) * HOUR)
        mine = wall[hour]
        inside = samples[(samples[:, 0] >= h * HOUR) & (samples[:, 0] <= (h + 1) * HOUR)]
        if len(mine) == 0 or len(inside) < 2:
            continue
        (t0, w0), (t1, w1) = inside[0, :2], inside[-1, :2]
        last = maps[maps[:, 0] <= t1 + 1e-9][-1] if np.any(maps[:, 0] <= t1 + 1e-9) else None
        rows.append(dict(hour=h + 1, sim_s=float(t1 - t0), steps=int(len(mine)),
                         step_median_ms=float(np.median(mine)),
                         step_median_vehicle_s=float(np.median(mine)) / 1e3 * reference,
                         step_p95_ms=float(np.percentile(mine, 95)),
                         query_median_ms=float(np.median(query[hour])),
                         iterations_median=float(np.median(iterations[hour])),
                         map_voxels_median=float(np.median(steps.map_voxels[hour])),
                         iteration_median_ms=float(np.nanmedian(per_iteration[hour]))
                         if np.any(iterations[hour] > 0) else float("nan"),
                         real_time_factor=float((t1 - t0) / max(w1 - w0, 1e-9)),
                         rss_end_mb=float(inside[-1, 2]), peak_mb=float(inside[-1, 3]),
                         octree_leaves=int(last[1]) if last is not None else 0,
                         octree_mb=float(last[2]) if last is not None else 0.0,
                         index_mb=float(last[3]) if last is not None else 0.0,
                         candidates=int(last[4]) if last is not None else 0,
                         versions=int(last[5]) if last is not None else 0))
    return rows


def long_mission(name: str, seed: int, surveys: int = 1, max_time: float | None = None):
    """The built-in mission `name` with its survey step flown `surveys` times and the time cap
    `max_time` (s; None: the legs' budgets)."""
    path = BUILTIN_DIR / f"{name}.yaml"
    raw = yaml.safe_load(path.read_text())
    survey = [step for step in raw["steps"] if "survey" in step]
    raw["steps"] += survey * (surveys - 1)
    raw["seed"] = seed
    if max_time is not None:
        raw.setdefault("limits", {})["max_time_s"] = max_time
    return mission_from_dict(raw, path.parent, path.name, source=path)


def parse_trace(text: str, until: float | None = None) -> tuple[float, float]:
    """`A:B` -> (A, B) simulated s, 0 <= A < B <= `until` (`--max-time`, when given: the dive
    would end before B); one line naming the problem otherwise."""
    try:
        a, b = (float(v) for v in text.split(":"))
    except ValueError:
        a = b = float("nan")
    limit = np.inf if until is None else until
    if not 0 <= a < b <= limit:
        raise SystemExit(f"--trace-python: give A:B simulated seconds with 0 <= A < B"
                         f"{'' if until is None else f' <= --max-time {until:g}'}, got "
                         f"{text!r}")
    return a, b


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mission", default="monterey_wall")
    parser.add_argument("--surveys", type=int, default=1,
                        help="fly the replanned survey this many times")
    parser.add_argument("--max-time", type=float, default=None, help="simulated s cap")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", help="write the figures to this file")
    parser.add_argument("--trace-python", metavar="A:B",
                        help="split the memory growth from A to B simulated s (slow)")
    args = parser.parse_args()
    trace = parse_trace(args.trace_python, args.max_time) if args.trace_python else None
    print(machine())
    spec = long_mission(args.mission, args.seed, args.surveys, args.max_time)
    if trace is not None:
        tracemalloc.start()
    before = reference_factor()
    probe = Probe(trace=trace)
    start = time.perf_counter()
    result = run_mission(spec, progress=False, probe=probe)
    wall = time.perf_counter() - start
    after = reference_factor()
    reference = float(np.mean([before, after]))
    summary = summarise(result)
    rows = per_hour(result, probe, reference)
    print(f"reference (vehicle alone, 600 s lawnmower, median of 3): {before:.0f}x real time "
          f"before the dive, {after:.0f}x after; the dive's real-time factor is "
          f"{result.log.duration_s / wall / reference:.3f} of their mean")
    print(f"\n{args.mission}: {result.log.duration_s:.0f} s simulated in {wall:.0f} s wall "
          f"({result.log.duration_s / wall:.1f}x), completed {result.dive.completed}, multibeam "
          f"coverage {100 * summary['coverage']['multibeam']:.1f} %, true distance mean "
          f"{summary['distance_to_target']['mean_m']:.2f} m (sd "
          f"{summary['distance_to_target']['sd_m']:.2f}), contact {summary['contact']}")
    m = summary["map"]
    print(f"map: {m['leaves']} OctoMap leaves, {m['octree_mb']:.0f} MB; {m['candidates']} "
          f"candidate voxels, index {m['index_mb']:.0f} MB; {m['batches']} batches, "
          f"{m['returns']} returns, scan file {m['scan_file_mb']:.0f} MB (on disk)")
    print("\n| hour | steps | step median (ms) | step median (vehicle-s) | step p95 (ms) | "
          "map query median (ms) | "
          "STOMP iterations median | box voxels median | per iteration median (ms) | "
          "real-time factor | RSS at end "
          "(MB) | peak RSS (MB) | octree leaves | octree (MB) | index (MB) | candidates | "
          "ScanLog versions |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['hour']} | {r['steps']} | {r['step_median_ms']:.1f} | "
              f"{r['step_median_vehicle_s']:.2f} | "
              f"{r['step_p95_ms']:.1f} | {r['query_median_ms']:.1f} | "
              f"{r['iterations_median']:.0f} | {r['map_voxels_median']:.0f} | "
              f"{r['iteration_median_ms']:.2f} | "
              f"{r['real_time_factor']:.1f} | {r['rss_end_mb']:.0f} | "
              f"{r['peak_mb']:.0f} | {r['octree_leaves']} | {r['octree_mb']:.1f} | "
              f"{r['index_mb']:.1f} | {r['candidates']} | {r['versions']} |")
    memory = None
    if trace is not None:
        memory = traced(probe) if len(probe.snapshots) == 2 else None
        Path(probe.dump_path).unlink()
        if memory is None:
            print(f"\n--trace-python: the dive ended at {result.log.duration_s:.0f} s, before "
                  f"{trace[1]:.0f} s: nothing to compare")
        else:
            print(f"\nmemory from {memory['from_s']:.0f} to {memory['to_s']:.0f} s: RSS "
                  f"+{memory['rss_mb']:.1f} MB = OctoMap tree (memoryUsage) "
                  f"+{memory['octree_mb']:.1f} + Python heap (traced) "
                  f"+{memory['python_mb']:.1f} + tracemalloc's own "
                  f"+{memory['tracemalloc_mb']:.1f} + the rest {memory['rest_mb']:+.1f}; the "
                  f"Python lines that grew most:")
            for line in memory["lines"]:
                print(f"  {line['mb']:+.2f} MB {line['where']}")
    with tempfile.TemporaryDirectory() as folder:
        t0 = time.perf_counter()
        n = write_points(result.mapping.scan_log, result.site, Path(folder) / "points.ply")
        size = (Path(folder) / "points.ply").stat().st_size
        print(f"\npoints.ply: {n} returns, {size / 2**20:.0f} MB, written in "
              f"{time.perf_counter() - t0:.1f} s; peak RSS after it {peak_mb():.0f} MB")
    if args.json:
        Path(args.json).write_text(json.dumps(dict(
            machine=machine(), duration_s=result.log.duration_s, wall_s=wall,
            reference=dict(before=before, after=after, mean=reference), hours=rows,
            coverage=summary["coverage"], distance=summary["distance_to_target"],
            contact=summary["contact"], map=summary["map"], memory=memory), indent=1))


if __name__ == "__main__":
    main()
