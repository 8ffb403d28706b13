"""The reference every benchmark divides by, measured in the same run: the vehicle alone
(dynamics, thruster allocation, tracker, navigation) tracking a 600 s lawnmower.

Absolute real-time factors differ several-fold between machines and with the load of a shared
one; a figure over this reference, taken minutes apart in the same process, moves much less.
Durations are also given in "vehicle-seconds": how many simulated seconds the vehicle alone
advances in that wall time (a wall time times the reference real-time factor).
"""

from __future__ import annotations

import datetime
import os
import platform
import statistics
import subprocess
import time

import numpy as np

from drake_auv.planning import PlannedPath

SIM_SECONDS = 600.0


def lawnmower() -> PlannedPath:
    """Lanes of 50 m, 5 m apart, at -10 m: long enough for 600 s at 0.5 m/s."""
    points = []
    for i in range(7):
        xs = (0.0, 50.0) if i % 2 == 0 else (50.0, 0.0)
        points += [(xs[0], 5.0 * i, -10.0), (xs[1], 5.0 * i, -10.0)]
    return PlannedPath(np.array(points), 0.0, (0.0, 0.0, -1.0)).resample(1.0)


def vehicle_real_time_factor(scene=None) -> float:
    """Simulated over wall seconds of 600 s of `lawnmower` tracking (one run); with a
    `Scene`, the Meshcat visualiser records meanwhile. (Drake is imported here, so that
    `machine` serves a benchmark run in a Python without it.)"""
    from pydrake.systems.analysis import Simulator

    from drake_auv.vehicle.diagram import build_tracking_diagram

    diagram, handles = build_tracking_diagram(lawnmower(), scene=scene)
    simulator = Simulator(diagram)
    simulator.Initialize()
    if scene is not None:
        scene.start_recording(playback_speed=10.0)
    start = time.perf_counter()
    simulator.AdvanceTo(SIM_SECONDS)
    return SIM_SECONDS / (time.perf_counter() - start)


def reference_factor(runs: int = 3) -> float:
    """Median vehicle-only real-time factor over `runs` runs."""
    return statistics.median(vehicle_real_time_factor() for _ in range(runs))


def machine() -> str:
    """CPU model, cores, load average, date, Python and Drake versions: one line ("drake not
    installed" in a Python without it)."""
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        model = next(line.split(":", 1)[1].strip() for line in lscpu.splitlines()
                     if line.startswith("Model name"))
    except (OSError, subprocess.CalledProcessError, StopIteration):
        model = platform.processor() or platform.machine()
    from importlib.metadata import PackageNotFoundError, version

    try:
        drake = f"drake {version('drake')}"
    except PackageNotFoundError:
        drake = "drake not installed"
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (f"machine: {model}, {os.cpu_count()} cores, load average {load}; "
            f"{datetime.date.today().isoformat()}; Python {platform.python_version()}, "
            f"{drake}")


def print_reference(factor: float) -> None:
    print(f"reference (vehicle alone, 600 s lawnmower, median of 3): {factor:.0f}x real time")
