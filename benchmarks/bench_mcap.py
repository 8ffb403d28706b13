"""What writing `dive.mcap` costs a dive: wall time and memory, the same run with and without.

Flies the built-in `boulder` mission capped at `--cap` simulated seconds, alternately without
and with the MCAP log (`rosio.McapRecorder`), `--runs` times each, and prints the medians of
the dive's wall and CPU time (`run_mission`: the Diagram's build, the simulation and the
results; the simulation alone is not the measure, because the log's octree markers bring the
map up to date during it, work a run without the log does after it) and their ratios
(target <= 1.15; CPU time counts the log's writing thread too), the log's size per simulated
second, and the resident memory's growth over the dive's second half (read by a probe at the
simulator's steps): a log streamed to disk adds none that grows with the dive. On a loaded
machine two runs' times differ by more than the log costs, so the recorder's own CPU time is
also measured inside the runs with the log: its update on the simulation's thread (less the
octree insertions its map markers bring forward, which a run without the log does after the
simulation) and the log's writing thread (chunks compressed and written), as a share of the
rest of the dive's CPU time: the added time that does not depend on which run the load fell
on. The first run with the log also builds rosbags' type store and serialisers, once a
process: its extra CPU time over the later ones is printed. Last, the log's chunks are
compressed again with each of `McapLog`'s compressions (time and size), and the writer alone
is fed `--writer-alone` simulated seconds of a dive's messages (resident memory before, at
the half, at the end). The load average is printed before and after.

    .venv/bin/python benchmarks/bench_mcap.py [--runs 3] [--cap 120] [--writer-alone 6000]
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
from drake_auv.rosio.writer import COMPRESSIONS, McapLog, dive_log

PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE / 2**20


class Spent:
    """CPU s spent in the recorder's updates and in the octree catch-ups inside them (the
    simulation's thread), and on the log's writing thread."""

    recorder = catch_up = writer = 0.0
    inside = False


def time_the_recorder() -> None:
    """Wraps `McapRecorder._update_log`, `OnlineMap.catch_up` and `McapLog._emit_chunk` to
    add up `Spent` (each its own thread's CPU time)."""
    update, catch_up, emit = McapRecorder._update_log, OnlineMap.catch_up, McapLog._emit_chunk

    def timed_update(self, context, state):
        start, Spent.inside = time.thread_time(), True
        try:
            return update(self, context, state)
        finally:
            Spent.inside = False
            Spent.recorder += time.thread_time() - start

    def timed_catch_up(self, log):
        if not Spent.inside:
            return catch_up(self, log)
        start = time.thread_time()
        try:
            return catch_up(self, log)
        finally:
            Spent.catch_up += time.thread_time() - start

    def timed_emit(self, *args):
        start = time.thread_time()
        try:
            return emit(self, *args)
        finally:
            Spent.writer += time.thread_time() - start

    McapRecorder._update_log, OnlineMap.catch_up = timed_update, timed_catch_up
    McapLog._emit_chunk = timed_emit


def compressions(filename: Path) -> list[tuple[str, float, float]]:
    """[(compression, CPU s, MB)] of the log's chunks compressed again with each of
    `McapLog`'s compressions."""
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader, get_chunk_data_stream

    with open(filename, "rb") as f:
        chunks = [get_chunk_data_stream(record)[0].read(record.uncompressed_size)
                  for record in StreamReader(f, emit_chunks=True).records
                  if isinstance(record, Chunk)]
    out = []
    for name, compress in COMPRESSIONS.items():
        start = time.process_time()
        size = sum(len(compress(c)) if compress else len(c) for c in chunks)
        out.append((name, time.process_time() - start, size / 2**20))
    return out


def one_run(spec, site, plan, folder: Path | None, cap: float) -> tuple:
    """(wall s, CPU s, RSS growth over the second half MB, the recorder's own CPU s on the
    simulation's thread, the writing thread's CPU s) of one dive."""
    marks = {}

    def probe(context):
        t = context.get_time()
        for key, at in (("half", 0.5 * cap), ("end", cap - 1.0)):
            if key not in marks and t >= at:
                marks[key] = rss_mb()

    Spent.recorder = Spent.catch_up = Spent.writer = 0.0
    wall, cpu = time.perf_counter(), time.process_time()
    log = dive_log(folder / "dive.mcap", spec, site) if folder is not None else None
    run_mission(spec, site, progress=False, plan=plan, probe=probe, mcap=log)
    return (time.perf_counter() - wall, time.process_time() - cpu,
            marks.get("end", np.nan) - marks.get("half", np.nan),
            Spent.recorder - Spent.catch_up, Spent.writer)


def writer_memory(folder: Path, seconds: float) -> tuple[float, float, float]:
    """(RSS MB before, at the half, at the end) of an `McapLog` alone fed `seconds` of a
    dive's messages: each 0.1 s tick the vehicle's five (a `MessageBlock`) and a 256-beam
    multibeam cloud."""
    from drake_auv.rosio import messages as m
    from drake_auv.rosio.writer import MessageBlock

    rng = np.random.default_rng(0)
    beams = rng.normal(size=(256, 3))
    beams /= np.linalg.norm(beams, axis=1)[:, None]
    cloud = m.CloudWriter("multibeam")
    marks = [rss_mb()]
    with McapLog(folder / "alone.mcap") as log:
        block = MessageBlock(log, [
            ("/tf", m.tf_template(m.MAP, (m.BASE, m.TRUTH))),
            ("/odometry/navigation", m.odometry_template(m.BASE)),
            ("/odometry/truth", m.odometry_template(m.TRUTH)),
            ("/reference", m.pose_template(m.MAP)),
            ("/thrust", m.array_template(("a", "b", "c", "d", "e")))])
        ticks = int(round(10 * seconds))
        for k in range(ticks):
            t = 0.1 * k
            block.write(rng.normal(size=block.n_floats).tolist(), t)
            log.write_cdr("/sonar/multibeam/points", "sensor_msgs/msg/PointCloud2",
                          cloud.cdr(t, rng.uniform(1, 20, 256), beams), t)
            if k == ticks // 2:
                marks.append(rss_mb())
    marks.append(rss_mb())
    return tuple(marks)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--cap", type=float, default=120.0, help="simulated s (default 120)")
    parser.add_argument("--writer-alone", type=float, default=6000.0,
                        help="simulated s of messages fed to the writer alone (default 6000)")
    args = parser.parse_args(argv)
    time_the_recorder()
    spec = load_mission("boulder", overrides=[f"limits.max_time_s={args.cap}"])
    site = load_site(spec.site, spec.seed, label=spec.name)
    plan = plan_mission(spec, site)
    runs = {False: [], True: []}
    print("load average (1, 5, 15 min) before: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for _ in range(args.runs):
            for mcap in (False, True):
                runs[mcap].append(one_run(spec, site, plan, folder if mcap else None, args.cap))
        size = (folder / "dive.mcap").stat().st_size / 2**20
        recompressed = compressions(folder / "dive.mcap")
        alone = writer_memory(folder, args.writer_alone)
    print("load average (1, 5, 15 min) after: {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    without, with_ = (np.median(runs[k], axis=0) for k in (False, True))
    print(f"boulder capped at {args.cap:g} s, median of {args.runs} runs each:")
    for k, what in ((0, "wall"), (1, "CPU")):
        pairs = " ".join(f"{b[k] / a[k]:.3f}" for a, b in zip(runs[False], runs[True]))
        print(f"  dive {what} time without the log {without[k]:.2f} s, with it {with_[k]:.2f} "
              f"s: ratio {with_[k] / without[k]:.3f} (target <= 1.15; each pair {pairs})")
    own, writer = with_[3], with_[4]
    rest = with_[1] - own - writer
    print(f"  the recorder's own CPU time {own:.2f} s on the simulation's thread "
          f"({1e3 * own / (10 * args.cap):.2f} ms a 0.1 s tick) and {writer:.2f} s on the log's "
          f"writing thread: {100 * own / rest:.1f} % and {100 * writer / rest:.1f} % of the "
          f"rest of the dive's: ratio {1 + (own + writer) / rest:.3f}")
    if args.runs > 1:
        later = np.median([run[1] for run in runs[True][1:]])
        print(f"  the first run with the log (rosbags' type store and serialisers, once a "
              f"process): {runs[True][0][1] - later:+.2f} s CPU over the later runs' median")
    print(f"  dive.mcap {size:.1f} MB, {size / args.cap * 1024:.0f} kB per simulated s")
    print(f"  RSS growth over the dive's second half: without {without[2]:.1f} MB, with "
          f"{with_[2]:.1f} MB")
    print(f"  the writer alone fed {args.writer_alone:g} simulated s of messages: RSS "
          f"{alone[0]:.1f} MB before, {alone[1]:.1f} MB at the half, {alone[2]:.1f} MB at the end")
    print("  the log's chunks compressed again: " + ", ".join(
        f"{name} {1e3 * cpu:.0f} ms CPU, {mb:.1f} MB" for name, cpu, mb in recompressed))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
