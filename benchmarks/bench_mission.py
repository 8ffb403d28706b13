"""Real-time factor of the whole one-dive boulder mission (target: >= 30x real time).

Runs the built-in `boulder` mission (`drake_auv.mission.runner.run_mission`) headless (no
Meshcat): vehicle dynamics, navigation, both sonars, the octree mapper, profile following,
the replanner, the supervisor and the coverage recorders, in one Diagram. Reports simulated
seconds over the simulation's wall seconds (the real-time factor), over the CPU seconds of the
whole run (site, plan and truth computations included), the replanning step times, what the
dive achieved (coverage, least clearance, contact: what a `--set` that makes it cheaper must
not cost), and the mission's factor over the vehicle-only one measured in the same run
(`_reference.py`: the ratio says how much the mission's sensing and planning cost whatever the
machine's speed); medians over `--runs` runs. The same ratio in CPU time (the simulation's CPU
seconds, read by a probe at the first and last simulator step, against the reference's CPU
seconds) is printed beside it: on a shared machine whose load changes between the mission and
the reference, the wall-time ratio moves with the load and the CPU one much less.

`--shares` adds one run that times the systems' callbacks and the native calls inside them
(`CallTimer`: wall-clock wrappers, no profiler, so the shares are those of a normal run) and
prints where the simulation's wall time goes, and the mission's floor: the vehicle alone over
the same simulated time (the reference) plus the native ray casts and OctoMap insertions, the
work this mission does at this fidelity whatever its Python costs; its ratio to the reference
is the most this mission could reach.

`--sea` instead measures what the sea costs: the mission as given (the boulder's default sea)
and the same mission in still water (`ocean=none`), run after run in turns, compared per
simulated second (the dives differ in length) in wall and in CPU seconds of simulation.

    .venv/bin/python benchmarks/bench_mission.py [--runs 3] [--seed 0] [--set KEY=VALUE]
        [--shares | --sea]
"""

from __future__ import annotations

import argparse
import functools
import time

import numpy as np

from _reference import SIM_SECONDS, machine, print_reference, reference_factor
import drake_auv.mapping.octree_map as octree_map
import drake_auv.replanning.replanner as replanner_module
from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.following.controller import ProfileFollowingController
from drake_auv.geometry.raycast import RayCaster
from drake_auv.geometry.visibility import coverage_share
from drake_auv.mapping.mapper import OctreeMapper
from drake_auv.mission.config import load_mission
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.mission.supervisor import MissionSupervisor
from drake_auv.signals import ReplanningStep
from drake_auv.sonar.range_sonar import RangeSonar
from drake_auv.vehicle.dynamics import Girona500Dynamics
from drake_auv.vehicle.navigation_system import Navigation
from drake_auv.vehicle.tracker import TrajectoryTracker

# (owner, attribute, label, nested): the callbacks and calls `CallTimer` times; a nested one
# runs inside a row above it (its time is part of that row's), the others do not overlap.
TIMED = (
    (octree_map.OctreeMap, "insert_scan", "octree insertion (`OctreeMap.insert_scan`)", False),
    (octree_map.octomap.OcTree, "insertPointCloud", "of which OctoMap (C++)", True),
    (replanner_module, "replan_section", "replanning step (`replan_section`)", False),
    (octree_map.OctreeMap, "occupied_points", "of which the map query", True),
    (RangeSonar, "_update_returns", "sonar updates", False),
    (RayCaster, "cast_unit", "ray casts (Embree), sonars' and camera's", True),
    (Girona500Dynamics, "_update_state", "vehicle dynamics", False),
    (TrajectoryTracker, "_update_wrench", "tracker", False),
    (Navigation, "_update_error", "navigation", False),
    (CoverageRecorder, "_update_best", "coverage recorders", False),
    (ProfileFollowingController, "_update_reference", "profile following", False),
    (OctreeMapper, "_update_log", "mapper's log", False),
    (MissionSupervisor, "_update_leg", "supervisor", False),
)


class _TimedTree:
    """An `octomap.OcTree` whose `insertPointCloud` is timed (a Cython class's methods cannot
    be replaced): everything else goes to the tree itself."""

    def __init__(self, tree, insert_point_cloud):
        self._tree, self.insertPointCloud = tree, insert_point_cloud

    def __getattr__(self, name):
        return getattr(self._tree, name)


class CallTimer:
    """While in use, the `TIMED` callables are wrapped to add their wall time (s) and calls
    to `seconds` / `calls` by label."""

    def __init__(self):
        self.seconds = {label: 0.0 for _, _, label, _ in TIMED}
        self.calls = dict.fromkeys(self.seconds, 0)
        self._saved = []

    def _wrapped(self, function, label):
        seconds, calls, clock = self.seconds, self.calls, time.perf_counter

        @functools.wraps(function)
        def timed(*args, **kwargs):
            start = clock()
            try:
                return function(*args, **kwargs)
            finally:
                seconds[label] += clock() - start
                calls[label] += 1
        return timed

    def __enter__(self):
        for owner, name, label, _ in TIMED:
            if owner is octree_map.octomap.OcTree:  # through `_TimedTree`, below
                tree_label = label
                continue
            self._saved.append((owner, name, getattr(owner, name)))
            setattr(owner, name, self._wrapped(getattr(owner, name), label))
        init = octree_map.OctreeMap.__init__
        self._saved.append((octree_map.OctreeMap, "__init__", init))

        def timed_init(octree, *args, **kwargs):
            init(octree, *args, **kwargs)
            octree.tree = _TimedTree(octree.tree, self._wrapped(octree.tree.insertPointCloud,
                                                                tree_label))
        octree_map.OctreeMap.__init__ = timed_init
        return self

    def __exit__(self, *exc):
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)
        self._saved = []


def shares(spec, vehicle_factor: float) -> None:
    """One timed run of `spec`: where its simulation's wall time goes, and its floor."""
    with CallTimer() as timer:
        result = run_mission(spec, progress=False)
    wall, sim = result.run.wall_s, result.log.duration_s
    print(f"\nwhere the time goes (one run with `CallTimer`: {sim:.0f} s simulated in "
          f"{wall:.1f} s wall, {sim / wall / vehicle_factor:.3f} of the reference)")
    print("| part | wall (s) | share | calls | per call (us) |")
    print("|---|---|---|---|---|")
    top = 0.0
    for _, _, label, nested in TIMED:
        seconds, calls = timer.seconds[label], timer.calls[label]
        top += 0.0 if nested else seconds
        print(f"| {'  ' if nested else ''}{label} | {seconds:.2f} | {seconds / wall:.1%} | "
              f"{calls} | {1e6 * seconds / max(calls, 1):.0f} |")
    print(f"| the rest (Drake's stepping and event dispatch, other systems) | {wall - top:.2f} "
          f"| {(wall - top) / wall:.1%} | | |")
    floor = (sim / vehicle_factor + timer.seconds["of which OctoMap (C++)"]
             + timer.seconds["ray casts (Embree), sonars' and camera's"])
    print(f"floor: the vehicle alone for {sim:.0f} s ({sim / vehicle_factor:.1f} s at the "
          f"reference's {vehicle_factor:.0f}x) + the native ray casts and OctoMap insertions = "
          f"{floor:.1f} s: at most {sim / floor / vehicle_factor:.3f} of the reference; the "
          f"rest ({wall - floor:.1f} s today) is Python and Drake's event dispatch")



def one_run(spec) -> dict:
    marks = []  # process CPU time at the first and the latest simulator step

    def probe(_context):
        now = time.process_time()
        if marks:
            marks[1:] = [now]
        else:
            marks.append(now)

    cpu, wall = time.process_time(), time.perf_counter()
    result = run_mission(spec, progress=False, probe=probe)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    steps = ReplanningStep(result.mapping.replanning).wall_time * 1e3
    return dict(sim=result.log.duration_s, wall=result.run.wall_s, total_wall=wall, cpu=cpu,
                sim_cpu=marks[-1] - marks[0],
                rtf=result.log.duration_s / result.run.wall_s, rtf_cpu=result.log.duration_s / cpu,
                steps=len(steps),  # none when a short time cap ends the dive first: NaN
                step_median=float(np.median(steps)) if len(steps) else float("nan"),
                step_p95=float(np.percentile(steps, 95)) if len(steps) else float("nan"),
                completed=result.dive.completed, outcome=outcome(result))


def outcome(result) -> str:
    """What the dive achieved, as the report measures it: what a `--set` that makes the
    mission cheaper must not cost."""
    clearance = float(result.log.clearance.min())
    coverage = result.coverage
    return (f"multibeam coverage {coverage_share(coverage.multibeam_best, coverage.areas):.4f}, "
            f"camera {coverage_share(coverage.camera_best, coverage.areas):.4f}, least clearance "
            f"{clearance:.2f} m, contact {'yes' if clearance <= VEHICLE_RADIUS else 'no'}")


def sea_cost(spec, still, runs: int) -> None:
    """Medians over `runs` alternating pairs of the wall and CPU seconds of simulation per
    simulated second, `spec` (a sea) against `still` (the same mission in still water)."""
    pairs = [(one_run(spec), one_run(still)) for _ in range(runs)]

    def per_s(run, key):
        return run[key] / run["sim"]

    for key, name in (("wall", "wall"), ("sim_cpu", "CPU")):
        sea = float(np.median([per_s(a, key) for a, _ in pairs]))
        calm = float(np.median([per_s(b, key) for _, b in pairs]))
        print(f"{name} seconds of simulation per simulated second: sea {1e3 * sea:.2f} ms, "
              f"still water {1e3 * calm:.2f} ms: the sea costs {sea / calm - 1:+.1%} "
              "(target <= +10 %)")
    for label, index in (("sea", 0), ("still water", 1)):
        outcomes = sorted({pair[index]["outcome"] for pair in pairs})
        print(f"the dive in {label}: {'; '.join(outcomes)}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="override the mission file (repeatable)")
    parser.add_argument("--shares", action="store_true",
                        help="one more run, timed by parts, and the mission's floor")
    parser.add_argument("--sea", action="store_true",
                        help="the sea's cost: the mission against itself in still water")
    args = parser.parse_args(argv)
    spec = load_mission("boulder", seed=args.seed, overrides=args.overrides)
    if args.sea:
        print(machine())
        print(f"{args.runs} pair(s) of runs of the boulder mission, seed {args.seed}"
              + (f", {' '.join(args.overrides)}" if args.overrides else ""))
        sea_cost(spec, load_mission("boulder", seed=args.seed,
                                    overrides=[*args.overrides, "ocean=none"]), args.runs)
        return 0
    runs = [one_run(spec) for _ in range(args.runs)]
    med = {k: float(np.median([r[k] for r in runs])) for k in runs[0] if k != "outcome"}
    print(machine())
    cpu = time.process_time()
    vehicle = reference_factor()
    vehicle_cpu = 3 * SIM_SECONDS / (time.process_time() - cpu)  # its 3 runs, CPU time
    print_reference(vehicle)
    print(f"reference in CPU time: {vehicle_cpu:.0f} simulated s per CPU s")
    print(f"{args.runs} run(s) of the boulder mission, seed {args.seed}"
          + (f", {' '.join(args.overrides)}" if args.overrides else "")
          + ("" if all(r["completed"] for r in runs) else " (time cap reached)"))
    print(f"simulated {med['sim']:.0f} s in {med['wall']:.1f} s wall of simulation "
          f"({med['total_wall']:.1f} s wall, {med['cpu']:.1f} s CPU with site, plan and "
          f"truth computations)")
    print(f"real-time factor, whole mission: {med['rtf']:.1f}x (target >= 30x); "
          f"simulated / CPU seconds {med['rtf_cpu']:.1f}x")
    print(f"whole mission over the reference: {med['rtf'] / vehicle:.3f}; in CPU time "
          f"{med['sim'] / med['sim_cpu'] / vehicle_cpu:.3f} ({med['sim_cpu']:.1f} s CPU of "
          f"simulation)")
    print(f"replanning step ({med['steps']:.0f} steps): median {med['step_median']:.1f} ms, "
          f"95th percentile {med['step_p95']:.1f} ms")
    outcomes = sorted({r["outcome"] for r in runs})
    print(f"the dive: {outcomes[0]}" if len(outcomes) == 1
          else "the runs differ (not deterministic): " + "; ".join(outcomes))
    if args.shares:
        shares(spec, vehicle)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
