"""Real-time factor of the whole boulder mission (issue 7's target: >= 30x real time).

Runs `drake_auv.mission.run_mission` headless (no Meshcat) with the default configuration:
vehicle dynamics, navigation, both sonars, the octree mapper, the replanner and four coverage
recorders. Reports, per phase and in total, simulated seconds over wall seconds and CPU
seconds, and the replanning step times; median over `--runs` runs. The whole mission's
real-time factor is also given over the vehicle-only one measured in the same run
(`_reference.py`).

    .venv/bin/python benchmarks/bench_mission.py [--runs 3] [--seed 0] [--replan-time S]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from _reference import machine, print_reference, reference_factor
from drake_auv.mission import MissionConfig, run_mission


def one_run(config: MissionConfig) -> dict:
    cpu = time.process_time()
    result = run_mission(config, progress=False)
    cpu = time.process_time() - cpu
    sim = sum(p.duration for p in result.phases)
    wall = sum(p.wall for p in result.phases)
    steps = np.concatenate([p.replan_wall for p in result.phases]) * 1e3
    out = dict(sim=sim, wall=wall, cpu=cpu, rtf=sim / wall, rtf_cpu=sim / cpu,
               step_median=float(np.median(steps)), step_p95=float(np.percentile(steps, 95)))
    for p in result.phases:
        out[f"rtf_{p.name}"] = p.duration / p.wall
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--replan-time", type=float, default=None,
                        help="cap the replanning phase's simulated time, s (default: whole plan)")
    args = parser.parse_args(argv)
    config = MissionConfig(seed=args.seed, replan_time=args.replan_time)
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    runs = [one_run(config) for _ in range(args.runs)]
    med = {k: float(np.median([r[k] for r in runs])) for k in runs[0]}
    print(f"{args.runs} run(s), seed {args.seed}")
    print(f"simulated {med['sim']:.0f} s in {med['wall']:.1f} s wall ({med['cpu']:.1f} s CPU, "
          f"including planning and truth computations)")
    print(f"real-time factor, whole mission: {med['rtf']:.1f}x (target >= 30x); "
          f"profile following {med['rtf_profile']:.1f}x, replanning {med['rtf_replan']:.1f}x; "
          f"simulated / CPU seconds {med['rtf_cpu']:.1f}x; whole mission over the reference "
          f"{med['rtf'] / reference:.3f}")
    print(f"replanning step: median {med['step_median']:.1f} ms, "
          f"95th percentile {med['step_p95']:.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
