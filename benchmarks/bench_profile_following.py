"""Profile following speed: the estimator, one follower update, and the pool mission.

No target in issue 5; the figures show where the time goes. The profiler head runs at 30
pings/s batched at 10 Hz, so the controller updates at 10 Hz: one update must stay well below
100 ms of wall time for a simulation faster than real time, and the whole mission (vehicle,
profiler ray casting, controller) is reported as a real-time factor (median of runs) and
relative to the vehicle-only reference measured in the same run (`_reference.py`).
"""

from __future__ import annotations

import statistics
import time
import timeit

import numpy as np
from pydrake.systems.analysis import Simulator

from _reference import machine, print_reference, reference_factor
from drake_auv.diagrams.profile_following import build_profile_following_diagram
from drake_auv.perception import FollowingParams, HorizontalFollower, estimate_profile
from drake_auv.scenarios import get_scenario

SIM_SECONDS = 120.0
RUNS = 3


def corner_points(n_wall=300, n_spurious=30, seed=0):
    """A 90 degree corner (two walls of 300 returns each) and spurious returns, 2D."""
    rng = np.random.default_rng(seed)
    t = np.linspace(-4, 2, n_wall)
    walls = np.vstack([np.column_stack([np.full(n_wall, 2.0), t]),
                       np.column_stack([t, np.full(n_wall, 2.0)])])
    return np.vstack([walls + rng.normal(0, 0.03, walls.shape),
                      rng.uniform(-5, 5, (n_spurious, 2))])


def pool_real_time_factor() -> float:
    scenario = get_scenario("pool")
    start = scenario.start_state.copy()
    start[2] = -4.0
    diagram, _ = build_profile_following_diagram(
        scenario.world, start, "horizontal", FollowingParams(offset=2.0, corner_weight=0.5))
    simulator = Simulator(diagram)
    simulator.Initialize()
    start_time = time.perf_counter()
    simulator.AdvanceTo(SIM_SECONDS)
    return SIM_SECONDS / (time.perf_counter() - start_time)


def main() -> None:
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    points = corner_points()
    rng = np.random.default_rng(1)
    est_ms = min(timeit.repeat(lambda: estimate_profile(points, rng=rng), number=50,
                               repeat=5)) / 50 * 1e3
    print(f"estimate_profile, corner of 600 returns + 30 spurious: {est_ms:.2f} ms")

    follower = HorizontalFollower(FollowingParams(offset=2.0, max_age=1e6))
    state = np.zeros(12)
    state[2] = -4.0
    world_points = np.column_stack([points, np.full(len(points), -4.0)])
    follower.update(0.0, state, world_points)
    clock = iter(np.arange(1, 10_000) * 0.1)
    upd_ms = min(timeit.repeat(lambda: follower.update(next(clock), state, np.empty((0, 3))),
                               number=50, repeat=5)) / 50 * 1e3
    print(f"HorizontalFollower.update (map of {len(follower.map)} returns): {upd_ms:.2f} ms")

    factors = [pool_real_time_factor() for _ in range(RUNS)]
    median = statistics.median(factors)
    print(f"pool horizontal following, {SIM_SECONDS:.0f} s simulated, {RUNS} runs: real-time "
          f"factor median {median:.0f}x (min {min(factors):.0f}x, max {max(factors):.0f}x), "
          f"{median / reference:.3f} of the reference")


if __name__ == "__main__":
    main()
