"""Real-time factor of the whole one-dive boulder mission (target: >= 30x real time).

Runs the built-in `boulder` mission (`drake_auv.mission.runner.run_mission`) headless (no
Meshcat): vehicle dynamics, navigation, both sonars, the octree mapper, profile following,
the replanner, the supervisor and the coverage recorders, in one Diagram. Reports simulated
seconds over the simulation's wall seconds (the real-time factor), over the CPU seconds of the
whole run (site, plan and truth computations included), the replanning step times, and the
mission's factor over the vehicle-only one measured in the same run (`_reference.py`: the
ratio says how much the mission's sensing and planning cost whatever the machine's speed);
medians over `--runs` runs. The same ratio in CPU time (the simulation's CPU seconds, read by a
probe at the first and last simulator step, against the reference's CPU seconds) is printed
beside it: on a shared machine whose load changes between the mission and the reference, the
wall-time ratio moves with the load and the CPU one much less.

    .venv/bin/python benchmarks/bench_mission.py [--runs 3] [--seed 0] [--set KEY=VALUE]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from _reference import SIM_SECONDS, machine, print_reference, reference_factor
from drake_auv.mission.config import load_mission
from drake_auv.mission.runner import run_mission
from drake_auv.signals import ReplanningStep



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
    steps = ReplanningStep(result.replanning).wall_time * 1e3
    return dict(sim=result.duration_s, wall=result.wall_s, total_wall=wall, cpu=cpu,
                sim_cpu=marks[-1] - marks[0],
                rtf=result.duration_s / result.wall_s, rtf_cpu=result.duration_s / cpu,
                steps=len(steps),  # none when a short time cap ends the dive first: NaN
                step_median=float(np.median(steps)) if len(steps) else float("nan"),
                step_p95=float(np.percentile(steps, 95)) if len(steps) else float("nan"),
                completed=result.completed)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="override the mission file (repeatable)")
    args = parser.parse_args(argv)
    spec = load_mission("boulder", seed=args.seed, overrides=args.overrides)
    runs = [one_run(spec) for _ in range(args.runs)]
    med = {k: float(np.median([r[k] for r in runs])) for k in runs[0]}
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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
