"""What writing `dive.mcap` costs a dive: wall time and memory, the same run with and without.

Flies the built-in `boulder` mission capped at `--cap` simulated seconds, alternately without
and with the MCAP log (`rosio.McapRecorder`), `--runs` times each, and prints the medians of
the dive's wall and CPU time (`run_mission`: the Diagram's build, the simulation and the
results; the simulation alone is not the measure, because the log's octree markers bring the
map up to date during it, work a run without the log does after it) and their ratios
(target <= 1.15; on a shared machine the CPU ratio is the one that does not move with the
load), the log's size per simulated second, and the resident memory's growth over the
dive's second half (read by a probe at the simulator's steps): a log streamed to disk adds
none that grows with the dive. On a loaded machine two runs' times differ by more than the
log costs, so the recorder's own CPU time is also measured inside the runs with the log (its
update, less the octree insertions its map markers bring forward, which a run without the log
does after the simulation) and given as a share of the rest of the dive's CPU time: the
added time that does not depend on which run the load fell on.

    .venv/bin/python benchmarks/bench_mcap.py [--runs 3] [--cap 120]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mission.config import load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.rosio.recorder import McapRecorder
from drake_auv.rosio.writer import dive_log

PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE / 2**20


class Spent:
    """CPU s spent in the recorder's updates, and in the octree catch-ups inside them."""

    recorder = catch_up = 0.0
    inside = False


def time_the_recorder() -> None:
    """Wraps `McapRecorder._update_log` and `OnlineMap.catch_up` to add up `Spent`."""
    update, catch_up = McapRecorder._update_log, OnlineMap.catch_up

    def timed_update(self, context, state):
        start, Spent.inside = time.process_time(), True
        try:
            return update(self, context, state)
        finally:
            Spent.inside = False
            Spent.recorder += time.process_time() - start

    def timed_catch_up(self, log):
        if not Spent.inside:
            return catch_up(self, log)
        start = time.process_time()
        try:
            return catch_up(self, log)
        finally:
            Spent.catch_up += time.process_time() - start

    McapRecorder._update_log, OnlineMap.catch_up = timed_update, timed_catch_up


def one_run(spec, site, plan, folder: Path | None, cap: float) -> tuple:
    """(wall s, CPU s, RSS growth over the second half MB, the recorder's own CPU s) of one
    dive."""
    marks = {}

    def probe(context):
        t = context.get_time()
        for key, at in (("half", 0.5 * cap), ("end", cap - 1.0)):
            if key not in marks and t >= at:
                marks[key] = rss_mb()

    Spent.recorder = Spent.catch_up = 0.0
    wall, cpu = time.perf_counter(), time.process_time()
    log = dive_log(folder / "dive.mcap", spec, site) if folder is not None else None
    run_mission(spec, site, progress=False, plan=plan, probe=probe, mcap=log)
    return (time.perf_counter() - wall, time.process_time() - cpu,
            marks.get("end", np.nan) - marks.get("half", np.nan),
            Spent.recorder - Spent.catch_up)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--cap", type=float, default=120.0, help="simulated s (default 120)")
    args = parser.parse_args(argv)
    time_the_recorder()
    spec = load_mission("boulder", overrides=[f"limits.max_time_s={args.cap}"])
    site = load_site(spec.site, spec.seed, label=spec.name)
    plan = plan_mission(spec, site)
    runs = {False: [], True: []}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for _ in range(args.runs):
            for mcap in (False, True):
                runs[mcap].append(one_run(spec, site, plan, folder if mcap else None, args.cap))
        size = (folder / "dive.mcap").stat().st_size / 2**20
    without, with_ = (np.median(runs[k], axis=0) for k in (False, True))
    print(f"boulder capped at {args.cap:g} s, median of {args.runs} runs each:")
    for k, what in ((0, "wall"), (1, "CPU")):
        print(f"  dive {what} time without the log {without[k]:.2f} s, with it {with_[k]:.2f} "
              f"s: ratio {with_[k] / without[k]:.3f} (target <= 1.15)")
    own = with_[3]
    print(f"  the recorder's own CPU time {own:.2f} s ({1e3 * own / (10 * args.cap):.2f} ms a "
          f"0.1 s tick), {100 * own / (with_[1] - own):.1f} % of the rest of the dive's: "
          f"ratio {1 + own / (with_[1] - own):.3f}")
    print(f"  dive.mcap {size:.1f} MB, {size / args.cap * 1024:.0f} kB per simulated s")
    print(f"  RSS growth over the dive's second half: without {without[2]:.1f} MB, with "
          f"{with_[2]:.1f} MB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
