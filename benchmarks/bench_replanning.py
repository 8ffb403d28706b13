"""Timing of the on-line octree map and the STOMP replanner on the breakwater mission.

Measures:
- octree insertion of one 480-beam multibeam scan (20 m range, 0.5 m voxels, free-space ray
  casting), every beam and every other beam (what the mapper inserts), over scans taken along
  the block's offset contour;
- the replanning step (map query: occupied voxels and KD-trees, plus STOMP) over a whole dive
  of the built-in `breakwater` mission, median and 95th percentile, split into map query and
  optimisation;
- that mission's real-time factor (vehicle, both sonars, mapper, replanner, supervisor and the
  two coverage recorders).
Targets: step median <= 10 ms, p95 <= 25 ms; insertion <= 5 ms per 480-beam
scan. Ratios to the vehicle-only reference measured in the same run (`_reference.py`): the
mission's real-time factor over the reference's, and the step's median in vehicle-seconds
(simulated seconds the vehicle alone advances in that wall time).

With `--ablation N`, instead: the optimiser's contribution, the breakwater mission
(5 m prior error, navigation drift, `sonar_noise: realistic` unless `--noise`) over seeds
F .. F+N-1 (`--first-seed`, default 0) with `replanner.optimizer` stomp and none: true
distance to the block (mean, sd, min, mean |d - Omega|), distance to the on-line map's voxels
on the block, contacts (minimum clearance to anything over the dive, and over its replanned
survey phase), multibeam and camera coverage, replanning step median and p95; per seed and
averaged. `--set` adds mission overrides to every dive.
Runs `--jobs` dives at once (each builds its own Diagram from the mission and seed).

With `--long`, instead: the step's median and p95 per simulated hour on the 3.8 h real-data
dive (`bench_long_mission.py`; its options follow, e.g. `--long --surveys 2`).

    .venv/bin/python benchmarks/bench_replanning.py [--error 5] [--seed 0] [--noise realistic]
    .venv/bin/python benchmarks/bench_replanning.py --ablation 10 [--jobs 2] [--json FILE]
        [--figure docs/replanning_breakwater.png] [--set replanner.iterations=20 ...]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time

import numpy as np

from _reference import machine, print_reference, reference_factor
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mission.config import load_mission
from drake_auv.mission.report.summary import _scored_samples, summarise
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.signals import ReplanningStep, VehicleState
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.beams import fan_angles


def bench_insertion(scenario, stride: int) -> np.ndarray:
    """ms (wall) per insertion of a port-looking 480-beam fan at 200 poses around the block."""
    caster = RayCaster(scenario.world)
    a = fan_angles(480, np.radians(120.0))
    omap = OctreeMap(0.5)
    times = []
    for s in np.linspace(0.0, np.pi, 200):
        origin = np.array([8.5 * np.sin(s), -8.5 * np.cos(s), -5.0])
        yaw = s  # moving counter-clockwise, the port side faces the block
        side = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
        d = np.outer(np.cos(a), side) + np.outer(np.sin(a), [0.0, 0.0, 1.0])
        hits = caster.cast(np.tile(origin, (len(d), 1)), d, 20.0)
        t0 = time.perf_counter()
        omap.insert_scan(origin, d[::stride], hits.ranges[::stride], 20.0)
        times.append(time.perf_counter() - t0)
    return 1e3 * np.array(times)


def ablation_run(task: tuple) -> dict:
    """One dive of the ablation: (seed, optimizer, noise, error) -> a metrics row."""
    seed, optimizer, noise, error, extra = task
    result = run_mission(load_mission("breakwater", seed=seed, overrides=[
        f"replanner.optimizer={optimizer}", f"sonar_noise={noise}",
        f"site.prior_error_m={error}", *extra]), progress=False)
    summary = summarise(result)
    d = summary["distance_to_target"]
    near = result.log.distance[_scored_samples(result)]
    steps = 1e3 * ReplanningStep(result.mapping.replanning).wall_time
    track = dict(times=result.log.times, xy=VehicleState(result.log.state).xy,
                 distance=result.log.distance,
                 nominal=result.plan.nominal.points[:, :2], target=_outline(result))
    return dict(seed=seed, optimizer=optimizer, track=track, mean_m=d["mean_m"], sd_m=d["sd_m"],
                min_m=d["min_m"], abs_error_m=float(np.abs(near - result.plan.omega).mean()),
                map_mean_m=d["map_mean_m"], map_sd_m=d["map_sd_m"],
                contact=summary["contact"], min_clearance_m=summary["min_clearance_m"],
                survey_clearance_m=min(phase["clearance_min_m"] for phase in summary["phases"]
                                       if phase["name"] == "survey"),
                omega=float(result.plan.omega), multibeam=summary["coverage"]["multibeam"],
                camera=summary["coverage"]["camera"], completed=bool(result.dive.completed),
                step_median_ms=float(np.median(steps)),
                step_p95_ms=float(np.percentile(steps, 95)))


def _outline(result) -> np.ndarray:
    """(m, 2) horizontal vertices of the target's faces (the block seen from above)."""
    world = result.site.world
    faces = world.faces[np.flatnonzero(result.site.target_faces)]
    return world.vertices[np.unique(faces)][:, :2]


def draw_ablation(rows: list[dict], path: str, seed: int = 0) -> None:
    """The ablation's figure: seed `seed`'s true tracks with each optimiser over the target
    and the nominal (prior-map) contour; its true distance to the target against time; the
    multibeam coverage per seed."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"stomp": "tab:blue", "none": "tab:orange"}
    fig, (top, dist, cover) = plt.subplots(1, 3, figsize=(17, 5.5),
                                           gridspec_kw=dict(width_ratios=[1.1, 1.2, 1.0]))
    mine = {r["optimizer"]: r for r in rows if r["seed"] == seed}
    any_track = next(iter(mine.values()))["track"]
    top.plot(*any_track["target"].T, "s", color="0.35", ms=1.5, label="target (true)")
    top.plot(*any_track["nominal"].T, ".--", color="tab:green", ms=3, lw=1,
             label="nominal (prior map)")
    for name, row in mine.items():
        top.plot(*row["track"]["xy"].T, color=colours[name], lw=1.2, label=f"flown, {name}")
        dist.plot(row["track"]["times"], row["track"]["distance"], color=colours[name],
                  lw=1, label=name)
    omega = rows[0]["omega"]
    dist.axhline(omega, color="k", lw=0.8, ls="--", label=f"Omega = {omega:g} m")
    dist.axhline(VEHICLE_RADIUS, color="tab:red", lw=0.8, ls=":", label="contact")
    top.set(aspect="equal", xlabel="x (m)", ylabel="y (m)",
            title=f"breakwater, seed {seed}: true tracks")
    top.legend(fontsize=8, loc="lower left")
    dist.set(xlabel="time (s)", ylabel="true distance to the target (m)", ylim=(0, 16),
             title="distance to the block")
    dist.legend(fontsize=8)
    seeds = sorted({r["seed"] for r in rows})
    for k, name in enumerate(("stomp", "none")):
        values = [next(r["multibeam"] for r in rows if r["seed"] == s and r["optimizer"] == name)
                  for s in seeds]
        cover.bar(np.array(seeds) + (k - 0.5) * 0.4, values, 0.4, color=colours[name],
                  label=name)
    cover.set(xlabel="seed", ylabel="multibeam coverage of the block", ylim=(0, 1),
              xticks=seeds, title="multibeam coverage per seed")
    cover.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


ABLATION_COLUMNS = ("mean_m", "sd_m", "min_m", "abs_error_m", "map_mean_m", "map_sd_m",
                    "multibeam", "camera", "step_median_ms", "step_p95_ms")


def ablation(seeds: int, jobs: int, noise: str, error: float, extra=(),
             first_seed: int = 0) -> list[dict]:
    """Runs the ablation and prints its tables (markdown); returns the rows."""
    tasks = [(seed, optimizer, noise, error, tuple(extra))
             for seed in range(first_seed, first_seed + seeds)
             for optimizer in ("stomp", "none")]
    with multiprocessing.get_context("spawn").Pool(jobs) as pool:
        rows = pool.map(ablation_run, tasks, chunksize=1)
    print(f"\nbreakwater, prior error {error} m, navigation drift, sonar_noise {noise}, "
          f"seeds {first_seed}-{first_seed + seeds - 1}, {jobs} dives at once"
          + (f", {' '.join(extra)}" if extra else "") + "\n")
    print("| seed | optimizer | mean d | sd d | min d | mean abs(d - Omega) | map mean | map sd "
          "| min clearance: dive / survey | multibeam | camera | step median / p95 (ms) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['seed']} | {r['optimizer']} | {r['mean_m']:.2f} | {r['sd_m']:.2f} | "
              f"{r['min_m']:.2f} | {r['abs_error_m']:.2f} | {r['map_mean_m']:.2f} | "
              f"{r['map_sd_m']:.2f} | {r['min_clearance_m']:.2f} / "
              f"{r['survey_clearance_m']:.2f} | "
              f"{r['multibeam']:.3f} | {r['camera']:.3f} | {r['step_median_ms']:.1f} / "
              f"{r['step_p95_ms']:.1f} |")
    print("\n| optimizer | " + " | ".join(ABLATION_COLUMNS)
          + " | contacts: dive / survey | min of min d |")
    print("|---" * (len(ABLATION_COLUMNS) + 3) + "|")
    for optimizer in ("stomp", "none"):
        mine = [r for r in rows if r["optimizer"] == optimizer]
        cells = [f"{np.mean([r[c] for r in mine]):.3f}" for c in ABLATION_COLUMNS]
        print(f"| {optimizer} | " + " | ".join(cells) + f" | "
              f"{sum(r['contact'] for r in mine)}/{len(mine)} / "
              f"{sum(r['survey_clearance_m'] <= VEHICLE_RADIUS for r in mine)}/{len(mine)} | "
              f"{min(r['min_m'] for r in mine):.2f} |")
    stomp = {r["seed"]: r for r in rows if r["optimizer"] == "stomp"}
    none = {r["seed"]: r for r in rows if r["optimizer"] == "none"}
    better = sum(stomp[s]["multibeam"] >= none[s]["multibeam"] for s in stomp)
    print(f"\nSTOMP's multibeam coverage >= none's in {better}/{len(stomp)} seeds; mean "
          f"abs(d - Omega) {np.mean([r['abs_error_m'] for r in stomp.values()]):.2f} m (stomp) vs "
          f"{np.mean([r['abs_error_m'] for r in none.values()]):.2f} m (none)")
    return rows


def main() -> None:
    if "--long" in sys.argv:
        import bench_long_mission

        sys.argv.remove("--long")
        bench_long_mission.main()
        return
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--error", type=float, default=5.0, help="prior-map error, m")
    parser.add_argument("--seed", type=int, default=0, help="prior-map error seed")
    parser.add_argument("--noise", default="realistic", help="sonar_noise preset")
    parser.add_argument("--ablation", type=int, default=0, metavar="N",
                        help="run the stomp / none ablation over N seeds instead")
    parser.add_argument("--jobs", type=int, default=2, help="ablation dives at once")
    parser.add_argument("--first-seed", type=int, default=0,
                        help="the ablation's seeds are first-seed .. first-seed + N - 1")
    parser.add_argument("--json", help="write the ablation's rows to this file")
    parser.add_argument("--figure", help="draw the ablation's figure (PNG) to this file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="extra mission override for every ablation dive (repeatable), "
                             "e.g. replanner.iterations=20")
    args = parser.parse_args()
    if args.ablation:
        print(machine())
        start = time.perf_counter()
        rows = ablation(args.ablation, args.jobs, args.noise, args.error, args.set,
                        args.first_seed)
        print(f"\n{len(rows)} dives in {time.perf_counter() - start:.0f} s")
        if args.figure:
            draw_ablation(rows, args.figure, seed=args.first_seed)
        if args.json:
            with open(args.json, "w") as f:
                json.dump([{k: v for k, v in r.items() if k != "track"} for r in rows], f,
                          indent=1)
        return
    scenario = get_scenario("breakwater")
    print(machine())
    reference = reference_factor()
    print_reference(reference)
    for stride in (1, 2):
        ms = bench_insertion(scenario, stride)
        print(f"octree insertion, {480 // stride} beams: median {np.median(ms):.2f} ms, "
              f"p95 {np.percentile(ms, 95):.2f} ms (target <= 5 ms for 480)")
    result = run_mission(load_mission("breakwater", seed=args.seed,
                                      overrides=[f"site.prior_error_m={args.error}",
                                                 f"sonar_noise={args.noise}"]),
                         progress=False)
    step = ReplanningStep(1e3 * result.mapping.replanning)
    steps, query = step.wall_time, step.query_time
    print(f"replanning step ({len(steps)} steps): median {np.median(steps):.1f} ms, "
          f"p95 {np.percentile(steps, 95):.1f} ms, max {steps.max():.1f} ms "
          f"(targets 10 / 25 ms; sonar_noise {args.noise})")
    print(f"  median in vehicle-seconds: {np.median(steps) / 1e3 * reference:.2f}")
    print(f"  of which map query (occupied voxels and rebuild): median {np.median(query):.1f} "
          f"ms, p95 {np.percentile(query, 95):.1f} ms; section + STOMP: median "
          f"{np.median(steps - query):.1f} ms, p95 {np.percentile(steps - query, 95):.1f} ms")
    print(f"breakwater mission real-time factor ({result.log.duration_s:.0f} s simulated): "
          f"{result.log.duration_s / result.run.wall_s:.1f}x, "
          f"{result.log.duration_s / result.run.wall_s / reference:.3f} of the reference")


if __name__ == "__main__":
    main()
