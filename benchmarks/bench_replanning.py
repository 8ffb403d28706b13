"""Timing of the on-line octree map and the STOMP replanner on the breakwater mission.

Measures:
- octree insertion of one 480-beam multibeam scan (20 m range, 0.5 m voxels, free-space ray
  casting), every beam and every other beam (what the mapper inserts), over scans taken along
  the block's offset contour;
- the replanning step (map query: occupied voxels and KD-trees, plus STOMP) over a whole dive
  of the built-in `breakwater` mission, median and 95th percentile, split into map query and
  optimisation;
- that mission's real-time factor (vehicle, both sonars, mapper, replanner, supervisor and the
  two coverage recorders).
Targets (issue 6): step median <= 25 ms, p95 <= 50 ms; insertion <= 5 ms per 480-beam scan.
Ratios to the vehicle-only reference measured in the same run (`_reference.py`): the mission's
real-time factor over the reference's, and the step's median in vehicle-seconds (simulated
seconds the vehicle alone advances in that wall time).

    .venv/bin/python benchmarks/bench_replanning.py [--error 5] [--seed 0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from _reference import machine, print_reference, reference_factor
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mission.config import load_mission
from drake_auv.mission.runner import run_mission
from drake_auv.replanning.replanner import STEP_FIELDS
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.beams import fan_angles


def bench_insertion(scenario, stride: int) -> np.ndarray:
    """ms (wall) per insertion of a port-looking 480-beam fan at 200 poses around the block."""
    caster = RayCaster(scenario.world)
    a = fan_angles(480, np.radians(120.0))
    omap = OctreeMap(0.5)
    times = []
    for s in np.linspace(0.0, np.pi, 200):
        origin = np.array([8.5 * np.sin(s), -8.5 * np.cos(s), -5.0])
        yaw = s  # moving counter-clockwise, the port side faces the block
        side = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
        d = np.outer(np.cos(a), side) + np.outer(np.sin(a), [0.0, 0.0, 1.0])
        hits = caster.cast(np.tile(origin, (len(d), 1)), d, 20.0)
        t0 = time.perf_counter()
        omap.insert_scan(origin, d[::stride], hits.ranges[::stride], 20.0)
        times.append(time.perf_counter() - t0)
    return 1e3 * np.array(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--error", type=float, default=5.0, help="prior-map error, m")
    parser.add_argument("--seed", type=int, default=0, help="prior-map error seed")
    args = parser.parse_args()
    scenario = get_scenario("breakwater")
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    for stride in (1, 2):
        ms = bench_insertion(scenario, stride)
        print(f"octree insertion, {480 // stride} beams: median {np.median(ms):.2f} ms, "
              f"p95 {np.percentile(ms, 95):.2f} ms (target <= 5 ms for 480)")
    result = run_mission(load_mission("breakwater", seed=args.seed,
                                      overrides=[f"site.prior_error_m={args.error}"]),
                         progress=False)
    step = {name: 1e3 * result.replanning[:, k] for k, name in enumerate(STEP_FIELDS)}
    steps, query = step["wall_time"], step["query_time"]
    print(f"replanning step ({len(steps)} steps): median {np.median(steps):.1f} ms, "
          f"p95 {np.percentile(steps, 95):.1f} ms, max {steps.max():.1f} ms "
          f"(targets 25 / 50 ms)")
    print(f"  median in vehicle-seconds: {np.median(steps) / 1e3 * reference:.2f}")
    print(f"  of which map query (occupied voxels and rebuild): median {np.median(query):.1f} "
          f"ms, p95 {np.percentile(query, 95):.1f} ms; section + STOMP: median "
          f"{np.median(steps - query):.1f} ms, p95 {np.percentile(steps - query, 95):.1f} ms")
    print(f"breakwater mission real-time factor ({result.duration_s:.0f} s simulated): "
          f"{result.duration_s / result.wall_s:.1f}x, "
          f"{result.duration_s / result.wall_s / reference:.3f} of the reference")


if __name__ == "__main__":
    main()
