"""What a replanning step of a survey-scale dive spends its time on, replayed.

Flies the built-in `monterey_wall` mission to `--until` simulated seconds and records every
replanning step that starts inside the `--windows` (the inputs of `replan_section` and the
box's voxels and log-odds that its map query returned), then replays the recorded steps
through `replan_section` with the box given as arrays: the same trajectories bit for bit
(checked), without the dive's other work in between. Per window: the box's voxels, the
dive's step and map query (medians, ms), the replayed step without the query (median and p95,
the least of `--repeats` runs), its STOMP part and what is left (the fields, trees, tube and
warm start), STOMP's iterations and one iteration's cost; then the same steps with other
STOMP budgets (rollouts, iteration cap, patience; every budget in turn on each step, the
least of the repeats) and how much of the initial cost each removes (median of 1 - cost /
initial cost). The budgets are compared open loop, from the recorded warm starts: what the
closed loop covers decides (docs/replanning.md). The replayed medians are also given in
vehicle-seconds (times the vehicle-only reference of `_reference.py`, measured in the same
run), the figure to compare across machines.

`--save FILE` keeps the recorded steps (a pickle, about 0.3 MB a step late in the dive);
`--load FILE` replays a saved recording instead of flying (its steps in `--windows`), the way
to time a change of the step's code against the same steps in minutes: the replayed
trajectories are checked against the recorded ones, so a change that plans differently shows.
Load only recordings you made: a pickle runs code when it is read.

    .venv/bin/python benchmarks/bench_step_replay.py [--until 3400]
        [--windows 300:700,3000:3400] [--repeats 3] [--save FILE | --load FILE]
"""

from __future__ import annotations

import argparse
import dataclasses
import pickle
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _reference import machine, print_reference, reference_factor  # noqa: E402
from bench_long_mission import long_mission  # noqa: E402
import drake_auv.replanning.replanner as replanner_module  # noqa: E402
from drake_auv.mission.runner import run_mission  # noqa: E402
from drake_auv.progress import track  # noqa: E402
from drake_auv.replanning import section as section_module  # noqa: E402

BUDGETS = {  # STOMP's budget of the replay's other rows: overrides of `StompParameters`
    "20 rollouts, at most 20 iterations": dict(num_rollouts=20, max_iterations=20),
    "30 rollouts, at most 15 iterations": dict(num_rollouts=30, max_iterations=15),
    "10 rollouts, at most 20 iterations": dict(max_iterations=20),
    "10 rollouts, patience 4": dict(patience=4),
}


class RecordedBox:
    """The map query of a recorded step: `occupied_points` gives the box's recorded voxels
    (and log-odds) whatever box it is asked for (the replay asks for the same one)."""

    def __init__(self, voxels: np.ndarray, log_odds: np.ndarray, resolution: float):
        self.voxels, self.log_odds, self.resolution = voxels, log_odds, resolution

    def occupied_points(self, lo, hi, log_odds: bool = False):
        return (self.voxels, self.log_odds) if log_odds else self.voxels


class CopyingBox:
    """The on-line map as `replan_section` reads it, keeping a copy of what its box query
    returned (`got`, a `RecordedBox`: the map's buffers change as it grows)."""

    def __init__(self, online):
        self.online, self.resolution, self.got = online, online.resolution, None

    def occupied_points(self, lo, hi, log_odds: bool = False):
        voxels, values = (np.array(a) for a in self.online.occupied_points(lo, hi,
                                                                           log_odds=True))
        self.got = RecordedBox(voxels, values, self.resolution)
        return (voxels, values) if log_odds else voxels


class StepRecorder:
    """Wraps the Replanner's `replan_section` while in use: records the steps that start in
    `windows` ((start, end) s), with their wall and query times. `probe` (the mission's
    probe, or a Simulator monitor's) tells it the simulated time."""

    def __init__(self, windows):
        self.windows, self.steps, self._now = windows, [], 0.0
        self._replan = replanner_module.replan_section

    def probe(self, context) -> None:
        self._now = context.get_time()

    def __enter__(self):
        replanner_module.replan_section = self._record
        return self

    def __exit__(self, *exc):
        replanner_module.replan_section = self._replan

    def _record(self, position, waypoints, next_index, occupied, params, **kwargs):
        if not (hasattr(occupied, "occupied_points")
                and any(a <= self._now < b for a, b in self.windows)):
            return self._replan(position, waypoints, next_index, occupied, params, **kwargs)
        box = CopyingBox(occupied)
        start = time.perf_counter()
        plan = self._replan(position, waypoints, next_index, box, params, **kwargs)
        wall = time.perf_counter() - start
        if plan is not None:
            self.steps.append(dict(
                time=self._now, args=(np.array(position), np.array(waypoints), next_index),
                params=params, kwargs=kwargs, box=box.got, wall=wall, query=plan.query_time,
                trajectory=plan.trajectory))
        return plan


class StompTimer:
    """Times `stomp` inside `replan_section` (the step's optimisation, apart from its
    fields, trees and warm start)."""

    def __init__(self):
        self.total, self._stomp = 0.0, section_module.stomp

    def __enter__(self):
        def timed(*args, **kwargs):
            start = time.perf_counter()
            try:
                return self._stomp(*args, **kwargs)
            finally:
                self.total += time.perf_counter() - start

        section_module.stomp = timed
        return self

    def __exit__(self, *exc):
        section_module.stomp = self._stomp


def replay(step, params=None, repeats: int = 1):
    """(plan, least wall time, its STOMP part) of one recorded step, s."""
    position, waypoints, next_index = step["args"]
    best = (np.inf, 0.0)
    for _ in range(repeats):
        with StompTimer() as timer:
            start = time.perf_counter()
            plan = section_module.replan_section(
                position, waypoints, next_index, step["box"],
                step["params"] if params is None else params, **step["kwargs"])
            wall = time.perf_counter() - start
        best = min(best, (wall, timer.total))
    return plan, best[0], best[1]


def with_budget(params, overrides):
    return dataclasses.replace(params, stomp=dataclasses.replace(params.stomp, **overrides))


def parse_windows(text: str, until: float = np.inf):
    """`START:END,...` -> [(START, END), ...] s, 0 <= START < END <= `until` (the dive's
    end: a window after it would record nothing); one line naming the problem otherwise."""
    try:
        windows = [tuple(float(v) for v in part.split(":")) for part in text.split(",")]
    except ValueError:
        windows = []
    if not windows or any(len(w) != 2 or not 0 <= w[0] < w[1] <= until for w in windows):
        raise SystemExit(f"--windows: give START:END pairs (0 <= START < END <= --until "
                         f"{until:g} s) separated by commas, got {text!r}")
    return windows


def open_save(path):
    """`path` opened for `save_steps`, before any work (one line naming the problem when it
    cannot be written)."""
    try:
        return open(path, "wb")
    except OSError as error:
        raise SystemExit(f"--save: cannot write {path}: {error.strerror}")


def save_steps(steps: list, file) -> None:
    """Writes recorded `steps` to `file` (`open_save`'s) and closes it."""
    with file:
        pickle.dump(steps, file, protocol=pickle.HIGHEST_PROTOCOL)


def load_steps(path) -> list:
    """The steps saved by `save_steps` at `path` (one line naming the problem when the file
    is missing or is not such a recording)."""
    try:
        with open(path, "rb") as f:
            steps = pickle.load(f)
    except OSError as error:
        raise SystemExit(f"--load: cannot read {path}: {error.strerror}")
    except Exception as error:  # a truncated or foreign file: whatever unpickling raised
        raise SystemExit(f"--load: {path} is not a recording of bench_step_replay.py --save "
                         f"({type(error).__name__})")
    if not (isinstance(steps, list)
            and all(isinstance(s, dict) and {"time", "args", "box", "trajectory"} <= s.keys()
                    for s in steps)):
        raise SystemExit(f"--load: {path} is not a recording of bench_step_replay.py --save")
    return steps


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--until", type=float, default=3400.0,
                        help="simulated seconds of the dive (> 0)")
    parser.add_argument("--windows", default="300:700,3000:3400",
                        help="START:END,... simulated seconds whose steps are recorded")
    parser.add_argument("--repeats", type=int, default=3, help="replays of each step (>= 1)")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--save", metavar="FILE", help="keep the recorded steps in FILE")
    source.add_argument("--load", metavar="FILE",
                        help="replay the steps saved in FILE instead of flying")
    args = parser.parse_args(argv)
    if not args.until > 0 or args.repeats < 1:
        raise SystemExit(f"--until must be > 0 s and --repeats >= 1, got {args.until}, "
                         f"{args.repeats}")
    windows = parse_windows(args.windows, np.inf if args.load else args.until)
    steps = load_steps(args.load) if args.load else None
    save = open_save(args.save) if args.save else None
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    if steps is None:
        spec = long_mission("monterey_wall", 0, 1, args.until)
        start = time.perf_counter()
        with StepRecorder(windows) as recorder:
            run_mission(spec, progress=True, probe=recorder.probe)
        steps = recorder.steps
        print(f"monterey_wall to {args.until:.0f} s: {time.perf_counter() - start:.0f} s "
              f"wall, {len(steps)} steps recorded in {args.windows}")
        if save is not None:
            save_steps(steps, save)
    else:
        print(f"{len(steps)} steps loaded from {args.load}")
    by_window = {w: [s for s in steps if w[0] <= s["time"] < w[1]] for w in windows}
    print("| window (s) | steps | box voxels | dive: step / query (ms) | replayed without the "
          "query: median / p95 (ms) | the same in vehicle-seconds | of which STOMP / the "
          "rest (ms) | iterations | one iteration (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    identical = 0
    for (a, b), steps in by_window.items():
        if not steps:
            print(f"| {a:.0f}-{b:.0f} | 0 | | | | | | | |")
            continue
        rows = []
        for step in track(steps, f"replay {a:.0f}-{b:.0f} s"):
            plan, wall, stomp_s = replay(step, repeats=args.repeats)
            identical += np.array_equal(plan.trajectory, step["trajectory"])
            rows.append((wall, stomp_s, plan.iterations))
        wall, stomp_s, iterations = (np.array(c, dtype=float) for c in zip(*rows))
        per_iteration = stomp_s[iterations > 0] / iterations[iterations > 0]
        print(f"| {a:.0f}-{b:.0f} | {len(steps)} | "
              f"{np.median([len(s['box'].voxels) for s in steps]):.0f} | "
              f"{1e3 * np.median([s['wall'] for s in steps]):.2f} / "
              f"{1e3 * np.median([s['query'] for s in steps]):.2f} | "
              f"{1e3 * np.median(wall):.2f} / {1e3 * np.percentile(wall, 95):.2f} | "
              f"{reference * np.median(wall):.2f} / {reference * np.percentile(wall, 95):.2f} | "
              f"{1e3 * np.median(stomp_s):.2f} / {1e3 * np.median(wall - stomp_s):.2f} | "
              f"{np.median(iterations):.1f} | "
              f"{1e3 * np.median(per_iteration) if len(per_iteration) else float('nan'):.3f} |")
    print(f"replayed trajectories identical to the dive's: {identical} of "
          f"{sum(len(v) for v in by_window.values())}")
    print("\n| STOMP budget | window (s) | replayed median / p95 (ms) | iterations | cost "
          "removed, median |")
    print("|---|---|---|---|---|")
    budgets = {"10 rollouts, at most 40 iterations (the default)": {}, **BUDGETS}
    for (a, b), steps in by_window.items():
        # Budgets in turn on each step (the least of the repeats), so a change of the
        # machine's load falls on all of them alike.
        rows = {label: [] for label in budgets}
        for step in track(steps, f"budgets {a:.0f}-{b:.0f} s"):
            for label, overrides in budgets.items():
                plan, wall, _ = replay(step, with_budget(step["params"], overrides),
                                       args.repeats)
                gain = 1.0 - plan.cost / plan.initial_cost if plan.initial_cost > 0 else 0.0
                rows[label].append((wall, plan.iterations, gain))
        for label, values in rows.items():
            if not values:
                continue
            wall, iterations, gain = (np.array(c, dtype=float) for c in zip(*values))
            print(f"| {label} | {a:.0f}-{b:.0f} | {1e3 * np.median(wall):.2f} / "
                  f"{1e3 * np.percentile(wall, 95):.2f} | {np.median(iterations):.1f} | "
                  f"{statistics.median(gain):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
