"""Ablation of the replanning cost's current terms: current-aware against current-blind STOMP
on the breakwater mission in a steady current pushing onto the block.

The built-in `breakwater` mission (5 m prior error, navigation drift, realistic sonar) with
`ocean.current.speed_mps=SPEED`, `ocean.current.towards_deg=TOWARDS` (default 0.4 m/s towards
north: cross-shore, onto the block's south face, along its east end, off its north face) and
replanning, flown with `replanner.current_aware` true and false over the same seeds. Per dive:
contact (clearance at or below the vehicle radius), least clearance to anything over the dive
and over its replanned survey phase, least and mean true distance to the block and mean
abs(d - Omega), multibeam and camera coverage, the survey's duration, the ocean report's thrust
saturation share and tracking error p95; then the means per arm and the seeds where aware is
at least as good as blind.

Rows go to `--rows` (JSON lines) as each dive ends, and dives already there are not flown
again, so an interrupted run resumes; `--json` writes them all, `--markdown` the tables.

    .venv/bin/python benchmarks/bench_current_ablation.py --seeds 0:4 [--jobs 2]
        [--speed 0.4] [--towards 0] [--rows FILE.jsonl] [--json docs/current_ablation.json]
        [--markdown FILE.md] [--set KEY=VALUE ...]
    .venv/bin/python benchmarks/bench_current_ablation.py --seeds 0:50 --speed 0 --arms aware
        (still water: one arm, the current's terms off)
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import time
from pathlib import Path

import numpy as np

from _reference import machine
from drake_auv.mission.config import load_mission
from drake_auv.mission.report.summary import _scored_samples, summarise
from drake_auv.mission.runner import run_mission

ARMS = ("aware", "blind")


def run_arm(task: tuple) -> dict:
    """One dive: (seed, arm, speed, towards, extra overrides) -> a metrics row."""
    seed, arm, speed, towards, extra = task
    overrides = [f"ocean.current.speed_mps={speed}", f"ocean.current.towards_deg={towards}",
                 f"replanner.current_aware={'true' if arm == 'aware' else 'false'}", *extra]
    start = time.perf_counter()
    result = run_mission(load_mission("breakwater", seed=seed, overrides=overrides),
                         progress=False)
    summary = summarise(result)
    d = summary["distance_to_target"]
    near = result.log.distance[_scored_samples(result)]
    survey = [p for p in summary["phases"] if p["name"] == "survey"]
    ocean = summary.get("ocean", {})
    return dict(seed=seed, arm=arm, speed_mps=speed, towards_deg=towards,
                overrides=overrides, completed=bool(result.dive.completed),
                contact=bool(summary["contact"]), min_clearance_m=summary["min_clearance_m"],
                survey_clearance_m=min(p["clearance_min_m"] for p in survey),
                min_m=d["min_m"], mean_m=d["mean_m"],
                abs_error_m=float(np.abs(near - result.plan.omega).mean()),
                multibeam=summary["coverage"]["multibeam"], camera=summary["coverage"]["camera"],
                duration_s=float(result.log.duration_s),
                survey_s=float(sum(p["duration_s"] for p in survey)),
                thrust_saturation_share=ocean.get("thrust_saturation_share"),
                tracking_error_p95_m=ocean.get("tracking_error_p95_m"),
                wall_s=time.perf_counter() - start)


COLUMNS = (("contact", "contacts"), ("min_clearance_m", "least clearance, dive (m)"),
           ("survey_clearance_m", "least clearance, survey (m)"),
           ("min_m", "least d to block (m)"), ("mean_m", "mean d (m)"),
           ("abs_error_m", "mean abs(d - Omega) (m)"), ("multibeam", "multibeam"),
           ("camera", "camera"), ("duration_s", "dive (s)"))


def markdown(rows: list[dict]) -> str:
    """The per-seed and mean tables, and the seed-by-seed comparison."""
    seeds = sorted({r["seed"] for r in rows})
    by = {(r["seed"], r["arm"]): r for r in rows}
    seeds = [s for s in seeds if all((s, a) in by for a in ARMS)]
    out = ["| seed | arm | " + " | ".join(title for _, title in COLUMNS) + " |",
           "|---" * (len(COLUMNS) + 2) + "|"]
    for s in seeds:
        for arm in ARMS:
            r = by[(s, arm)]
            out.append(f"| {s} | {arm} | " + " | ".join(
                ("yes" if r[k] else "no") if k == "contact" else f"{r[k]:.3f}"
                if k in ("multibeam", "camera") else f"{r[k]:.0f}" if k == "duration_s"
                else f"{r[k]:.2f}" for k, _ in COLUMNS) + " |")
    out += ["", "| arm | " + " | ".join(title for _, title in COLUMNS) + " |",
            "|---" * (len(COLUMNS) + 1) + "|"]
    for arm in ARMS:
        mine = [by[(s, arm)] for s in seeds]
        cells = [f"{sum(r['contact'] for r in mine)} of {len(mine)}"]
        for k, _ in COLUMNS[1:]:
            values = [r[k] for r in mine]
            if k in ("min_clearance_m", "survey_clearance_m", "min_m"):
                cells.append(f"{np.mean(values):.2f} (worst {min(values):.2f})")
            else:
                cells.append(f"{np.mean(values):.3f}" if k in ("multibeam", "camera")
                             else f"{np.mean(values):.0f}" if k == "duration_s"
                             else f"{np.mean(values):.2f}")
        out.append(f"| {arm} | " + " | ".join(cells) + " |")
    clear = sum(by[(s, "aware")]["min_clearance_m"] >= by[(s, "blind")]["min_clearance_m"]
                for s in seeds)
    cover = sum(by[(s, "aware")]["multibeam"] >= by[(s, "blind")]["multibeam"] for s in seeds)
    out += ["", f"aware's least clearance >= blind's in {clear} of {len(seeds)} seeds; its "
            f"multibeam coverage >= blind's in {cover} of {len(seeds)}."]
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", default="0:3", help="A:B, seeds A .. B-1")
    parser.add_argument("--speed", type=float, default=0.4, help="current speed, m/s")
    parser.add_argument("--towards", type=float, default=0.0,
                        help="current direction, deg clockwise from north (towards)")
    parser.add_argument("--jobs", type=int, default=2, help="dives at once")
    parser.add_argument("--arms", default="aware,blind",
                        help="the arms flown, of aware,blind (one alone, e.g. with --speed 0: "
                             "still water, where both are the same dive)")
    parser.add_argument("--rows", default="current_ablation_rows.jsonl",
                        help="JSON lines, one row per dive, appended as dives end")
    parser.add_argument("--json", help="write all rows to this file")
    parser.add_argument("--markdown", help="write the tables to this file")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="extra mission override for every dive (repeatable)")
    args = parser.parse_args()
    first, _, stop = args.seeds.partition(":")
    seeds = range(int(first), int(stop)) if stop else [int(first)]
    print(machine())
    rows_path = Path(args.rows)
    rows = [json.loads(line) for line in rows_path.read_text().splitlines()
            if line.strip()] if rows_path.is_file() else []
    rows = [r for r in rows if r["speed_mps"] == args.speed and r["towards_deg"] == args.towards]
    done = {(r["seed"], r["arm"]) for r in rows}
    arms = [a for a in ARMS if a in args.arms.split(",")]
    tasks = [(seed, arm, args.speed, args.towards, tuple(args.set)) for seed in seeds
             for arm in arms if (seed, arm) not in done]
    start = time.perf_counter()
    with multiprocessing.get_context("spawn").Pool(args.jobs) as pool:
        for row in pool.imap_unordered(run_arm, tasks, chunksize=1):
            rows.append(row)
            with rows_path.open("a") as f:
                f.write(json.dumps(row) + "\n")
            print(f"seed {row['seed']} {row['arm']}: contact {row['contact']}, clearance "
                  f"{row['min_clearance_m']:.2f} m, multibeam {row['multibeam']:.3f} "
                  f"({row['wall_s']:.0f} s wall)", flush=True)
    print(f"{len(tasks)} dives in {time.perf_counter() - start:.0f} s, "
          f"{args.jobs} at once\n")
    rows.sort(key=lambda r: (r["seed"], ARMS.index(r["arm"])))
    if len(arms) == 1:  # one arm: its contacts and means, no comparison
        mine = [r for r in rows if r["arm"] == arms[0] and r["seed"] in seeds]
        table = (f"{arms[0]}, {args.speed:g} m/s: {sum(r['contact'] for r in mine)} contacts "
                 f"in {len(mine)} dives (seeds "
                 f"{', '.join(str(r['seed']) for r in mine if r['contact']) or 'none'}); "
                 f"least clearance mean {np.mean([r['min_clearance_m'] for r in mine]):.2f} m; "
                 f"multibeam {np.mean([r['multibeam'] for r in mine]):.3f}, camera "
                 f"{np.mean([r['camera'] for r in mine]):.3f}; dive "
                 f"{np.mean([r['duration_s'] for r in mine]):.0f} s")
    else:
        table = markdown(rows)
    print(table)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    if args.markdown:
        Path(args.markdown).write_text(table + "\n")


if __name__ == "__main__":
    main()
