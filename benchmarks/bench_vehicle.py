"""Vehicle-only speed: 600 s of lawnmower tracking, real-time factor (median of runs).

Target: >= 200x real time on the 2-core machine. This run is the reference the
other benchmarks divide by (`_reference.py`). Also reports the cost of one RK4 plant step and
one tracker update, the share of a 50 ms simulated step they take (the rest is the framework:
events, ports, navigation, logging), and the factor with Meshcat recording on, relative to
the plain run.
"""

from __future__ import annotations

import statistics
import timeit

import numpy as np

from _reference import SIM_SECONDS, machine, vehicle_real_time_factor
from drake_auv.vehicle.control import TrackingController
from drake_auv.vehicle.model import Girona500Model

RUNS = 5
TIME_STEP = 0.05  # s, the plant's RK4 step and the tracker's period


def main() -> None:
    print(machine())
    factors = [vehicle_real_time_factor() for _ in range(RUNS)]
    reference = statistics.median(factors)
    print(f"{SIM_SECONDS:.0f} s lawnmower tracking, {RUNS} runs: real-time factor median "
          f"{reference:.0f}x (min {min(factors):.0f}x, max {max(factors):.0f}x); "
          f"target >= 200x")
    model, x, cmd = Girona500Model(), np.zeros(17), np.full(5, 50.0)
    step_s = min(timeit.repeat(lambda: model.step(x, cmd, TIME_STEP), number=2000,
                               repeat=3)) / 2000
    ctrl, ref, state = TrackingController(), np.ones(8), np.zeros(12)
    ctrl_s = min(timeit.repeat(lambda: ctrl.wrench(ref, state, np.zeros(3), TIME_STEP),
                               number=2000, repeat=3)) / 2000
    per_step = TIME_STEP / reference  # wall seconds per simulated step of the diagram
    print(f"RK4 plant step {step_s * 1e6:.0f} us; tracker update {ctrl_s * 1e6:.0f} us; "
          f"together {(step_s + ctrl_s) / per_step:.0%} of a simulated 50 ms step "
          f"({per_step * 1e6:.0f} us)")
    from drake_auv.visualization import Scene

    recording = vehicle_real_time_factor(Scene())
    print(f"with Meshcat visualiser and recording: {recording:.0f}x, "
          f"{recording / reference:.2f} of the plain run")


if __name__ == "__main__":
    main()
