"""Timing of the on-line octree map and the STOMP replanner on the breakwater mission.

Measures:
- octree insertion of one 480-beam multibeam scan (20 m range, 0.5 m voxels, free-space ray
  casting), every beam and every other beam (what the mapper inserts), over scans taken along
  the block's offset contour;
- the replanning step (map query: occupied voxels and KD-trees, plus STOMP) over a whole
  breakwater run, median and 95th percentile, split into map query and optimisation;
- the whole mission's real-time factor (vehicle, both sonars, mapper, replanner), with and
  without the two coverage recorders.
Targets (issue 6): step median <= 25 ms, p95 <= 50 ms; insertion <= 5 ms per 480-beam scan.
Ratios to the vehicle-only reference measured in the same run (`_reference.py`): the mission's
real-time factor over the reference's, and the step's median in vehicle-seconds (simulated
seconds the vehicle alone advances in that wall time).

    .venv/bin/python benchmarks/bench_replanning.py [--error 5] [--seed 0]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path as FilePath

import numpy as np
from pydrake.systems.analysis import Simulator

from drake_auv.diagrams.replanning import build_replanning_diagram
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.beams import fan_angles

sys.path.insert(0, str(FilePath(__file__).resolve().parents[1] / "examples"))
from _reference import machine, print_reference, reference_factor  # noqa: E402
from breakwater_replanning import nominal_contour  # noqa: E402


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


def run(scenario, nominal, speed, coverage: bool, seed: int):
    diagram, h = build_replanning_diagram(
        scenario.world, nominal, scenario.start_state, speed=speed, seed=seed,
        coverage=coverage, target_faces=scenario.target_faces)
    simulator = Simulator(diagram)
    duration = 1.25 * nominal.times(speed)[-1] + 20.0
    t0 = time.perf_counter()
    simulator.AdvanceTo(duration)
    return duration / (time.perf_counter() - t0), h


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--error", type=float, default=5.0, help="prior-map error, m")
    parser.add_argument("--seed", type=int, default=0, help="prior-map error seed")
    args = parser.parse_args()
    scenario = get_scenario("breakwater")
    p = scenario.params
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    for stride in (1, 2):
        ms = bench_insertion(scenario, stride)
        print(f"octree insertion, {480 // stride} beams: median {np.median(ms):.2f} ms, "
              f"p95 {np.percentile(ms, 95):.2f} ms (target <= 5 ms for 480)")
    prior = scenario.prior_map(error_m=args.error, seed=args.seed)
    nominal = nominal_contour(prior, p["depth"], p["omega"], p["block_size"],
                              scenario.start_state[:3])
    rtf, h = run(scenario, nominal, p["speed"], coverage=True, seed=args.seed)
    steps = 1e3 * np.array([s.wall_time for s in h.replanner.log])
    print(f"replanning step ({len(steps)} steps): median {np.median(steps):.1f} ms, "
          f"p95 {np.percentile(steps, 95):.1f} ms, max {steps.max():.1f} ms "
          f"(targets 25 / 50 ms); median = {np.median(steps) / 1e3 * reference:.1f} "
          f"vehicle-seconds")
    cpu = 1e3 * np.array([s.cpu_time for s in h.replanner.log])
    print(f"  CPU time of the step (its thread): median {np.median(cpu):.1f} ms, "
          f"p95 {np.percentile(cpu, 95):.1f} ms")
    query = 1e3 * np.array([s.query_time for s in h.replanner.log])
    print(f"  of which map query (occupied voxels and rebuild): median {np.median(query):.1f} "
          f"ms, p95 {np.percentile(query, 95):.1f} ms; section + STOMP: median "
          f"{np.median(steps - query):.1f} ms, p95 {np.percentile(steps - query, 95):.1f} ms")
    print(f"mission real-time factor, with coverage recorders: {rtf:.1f}x, "
          f"{rtf / reference:.3f} of the reference")
    rtf, _ = run(scenario, nominal, p["speed"], coverage=False, seed=args.seed)
    print(f"mission real-time factor, without coverage recorders: {rtf:.1f}x, "
          f"{rtf / reference:.3f} of the reference")


if __name__ == "__main__":
    main()
