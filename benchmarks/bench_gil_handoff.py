"""The GIL's switch interval against a thread that runs Python: a million rays marched on a
grid (`TerrainSurface.raycast`, its chunks on the usable cores, many short numpy calls each
taking the GIL back) alone and beside a thread running a pure-Python loop (as the figures and
the GeoJSON do beside the plan's metrics), at CPython's 5 ms and at shorter intervals
(`resources.quick_gil_handoff`), with the march's chunk of 32 768 and of 262 144 rays.

Each case runs in a fresh process; the wall times are given over the march alone at 5 ms in
the same run (machines differ two-fold from day to day).

    .venv/bin/python benchmarks/bench_gil_handoff.py
"""

from __future__ import annotations

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _reference import machine  # noqa: E402

CHILD = """
import sys, threading, time
import numpy as np
from scipy import ndimage
from drake_auv.planning.surface import TerrainSurface
from drake_auv.terrain.bathymetry import Bathymetry
interval, chunk, busy = float(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "1"
sys.setswitchinterval(interval)
rng = np.random.default_rng(0)  # the site and the rays, not a run's noise
relief = ndimage.zoom(ndimage.gaussian_filter(rng.standard_normal((100, 100)), 4.0), 10)
surface = TerrainSurface(Bathymetry(-40.0 + 13.0 * relief / relief.std(), (1.0, 1.0)), 0.5)
xy = rng.uniform(5.0, 995.0, (1_000_000, 2))
origins = np.column_stack([xy, surface.elevation(xy[:, 0], xy[:, 1]) + 2.0])
axes = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
stop = []
def python_loop():
    x = 0
    while not stop:
        for i in range(10000):
            x += i
other = threading.Thread(target=python_loop)
if busy:
    other.start()
start = time.perf_counter()
surface.raycast(origins, axes, 4.0, chunk=chunk)
print(time.perf_counter() - start)
stop.append(True)
if busy:
    other.join()
"""


def run(interval: float, chunk: int, busy: bool) -> float:
    done = subprocess.run([sys.executable, "-c", CHILD, str(interval), str(chunk),
                           "1" if busy else "0"], capture_output=True, text=True, check=True)
    return float(done.stdout.split()[-1])


def main() -> None:
    print(machine())
    reference = run(0.005, 262144, False)
    print(f"reference (the march alone, 5 ms, chunk 262 144): {reference:.2f} s")
    print("| switch interval | chunk (rays) | alone: wall (s), over the reference | beside a "
          "Python thread: wall (s), over the reference |")
    print("| ---: | ---: | ---: | ---: |")
    for interval in (0.005, 0.001, 0.0005, 0.0002):
        for chunk in (32768, 262144):
            alone, busy = run(interval, chunk, False), run(interval, chunk, True)
            print(f"| {interval * 1e3:g} ms | {chunk} | {alone:.2f}, {alone / reference:.1f} "
                  f"| {busy:.2f}, {busy / reference:.1f} |")


if __name__ == "__main__":
    main()
