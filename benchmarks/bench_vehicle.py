"""Vehicle-only speed: 600 s of lawnmower tracking, real-time factor (median of runs).

Target (issue 2): >= 200x real time on the 2-core machine. Also reports the cost of one RK4
plant step and one tracker update, and the factor with Meshcat recording on.
"""

from __future__ import annotations

import statistics
import time
import timeit

import numpy as np
from pydrake.systems.analysis import Simulator

from drake_auv.vehicle.control import TrackingController
from drake_auv.vehicle.diagram import build_tracking_diagram
from drake_auv.planning import Path
from drake_auv.vehicle.model import Girona500Model

SIM_SECONDS = 600.0
RUNS = 5


def lawnmower() -> Path:
    """Lanes of 50 m, 5 m apart, long enough for 600 s at 0.5 m/s."""
    points = []
    for i in range(7):
        xs = (0.0, 50.0) if i % 2 == 0 else (50.0, 0.0)
        points += [(xs[0], 5.0 * i, -10.0), (xs[1], 5.0 * i, -10.0)]
    return Path(np.array(points), 0.0, (0.0, 0.0, -1.0)).resample(1.0)


def real_time_factor(scene=None) -> float:
    diagram, handles = build_tracking_diagram(lawnmower(), scene=scene)
    assert handles.end_time >= SIM_SECONDS
    simulator = Simulator(diagram)
    simulator.Initialize()
    if scene is not None:
        scene.start_recording(playback_speed=10.0)
    start = time.perf_counter()
    simulator.AdvanceTo(SIM_SECONDS)
    return SIM_SECONDS / (time.perf_counter() - start)


def main() -> None:
    factors = [real_time_factor() for _ in range(RUNS)]
    print(f"600 s lawnmower tracking, {RUNS} runs: real-time factor median "
          f"{statistics.median(factors):.0f}x (min {min(factors):.0f}x, max {max(factors):.0f}x); "
          f"target >= 200x")
    model, x, cmd = Girona500Model(), np.zeros(17), np.full(5, 50.0)
    step_us = min(timeit.repeat(lambda: model.step(x, cmd, 0.05), number=2000, repeat=3)) / 2000
    ctrl, ref, state = TrackingController(), np.ones(8), np.zeros(12)
    ctrl_us = min(timeit.repeat(lambda: ctrl.wrench(ref, state, np.zeros(3), 0.05),
                                number=2000, repeat=3)) / 2000
    print(f"RK4 plant step {step_us * 1e6:.0f} us; tracker update {ctrl_us * 1e6:.0f} us")
    from drake_auv.visualization import Scene

    scene = Scene()
    print(f"with Meshcat visualiser and recording: {real_time_factor(scene):.0f}x")


if __name__ == "__main__":
    main()
