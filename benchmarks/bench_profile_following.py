"""Profile following speed: the estimator, one follower update, and the pool mission.

No target; the figures show where the time goes. The profiler head runs at 30
pings/s batched at 10 Hz, so the controller updates at 10 Hz: one update must stay well below
100 ms of wall time for a simulation faster than real time, and the first 120 s of the
built-in `pool` mission (vehicle, both sonars, mapper, supervisor, horizontal following) are
reported as a real-time factor (median of runs), also relative to the vehicle-only reference
measured in the same run (`_reference.py`).
"""

from __future__ import annotations

import statistics
import timeit

import numpy as np

from _reference import machine, print_reference, reference_factor
from drake_auv.mission.config import load_mission
from drake_auv.mission.runner import run_mission
from drake_auv.following import FollowingParams, HorizontalFollower
from drake_auv.perception import estimate_profile

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
    """Simulated over wall seconds of the pool mission's first `SIM_SECONDS` (the laps)."""
    result = run_mission(load_mission("pool", overrides=[f"limits.max_time_s={SIM_SECONDS}"]),
                         progress=False)
    return result.log.duration_s / result.run.wall_s


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
    held, _ = follower.update(follower.initial_state(), 0.0, state, world_points)
    clock = iter(np.arange(1, 10_000) * 0.1)
    upd_ms = min(timeit.repeat(lambda: follower.update(held, next(clock), state,
                                                       np.empty((0, 3))),
                               number=50, repeat=5)) / 50 * 1e3
    print(f"HorizontalFollower.update (map of {len(held.map)} returns): {upd_ms:.2f} ms")

    factors = [pool_real_time_factor() for _ in range(RUNS)]
    median = statistics.median(factors)
    print(f"pool mission, horizontal following, {SIM_SECONDS:.0f} s simulated, {RUNS} runs: "
          f"real-time factor median {median:.0f}x (min {min(factors):.0f}x, max "
          f"{max(factors):.0f}x), {median / reference:.3f} of the reference")


if __name__ == "__main__":
    main()
