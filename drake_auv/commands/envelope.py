"""`drake-auv envelope MISSION --speeds A:B:STEP --directions N --seeds A:B -o OUT`: the
current a mission stays safe in.

Flies the mission over mean-current speed x direction x seed (speed 0 once per seed) with the
campaign machinery: one Dask task per run, its row appended to OUT/envelope.csv the moment it
finishes (a rerun runs only the missing rows), OUT locked for the whole run. Then writes
OUT/envelope.png (polar plots), envelope.md / envelope.json and prints the verdict: the
highest current, from every direction, at which no seed touched. Every argument, every run's
mission, OUT and the scheduler are checked before anything is written.
"""

from __future__ import annotations

import functools
from pathlib import Path

from drake_auv.commands import whole_number
from drake_auv.commands.campaign import add_runs_options

OUTPUTS = ("campaign.json", "envelope.csv", "envelope.png", "envelope.md", "envelope.json",
           ".lock")


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "envelope", help="the current (speed x direction) in which a mission stays safe, on Dask",
        description="Runs a mission for every mean current of --speeds x --directions (speed 0 "
                    "once) and every seed of --seeds, one Dask task per run, and writes "
                    "envelope.csv (a row per run, appended as it finishes; a rerun runs only "
                    "the missing rows), envelope.png, envelope.md and envelope.json into OUT; "
                    "prints the highest current, from every direction, at which no seed "
                    "touched.")
    parser.add_argument("mission", help="a mission YAML file or a built-in mission's name")
    parser.add_argument("--speeds", required=True, metavar="A:B:STEP",
                        help="mean current speeds A, A+STEP, ..., B in m/s (within [0, 5])")
    parser.add_argument("--directions", required=True, type=whole_number, metavar="N",
                        help="N directions the current flows towards, evenly spaced "
                             "clockwise from north (towards 0, 360/N, ... deg)")
    parser.add_argument("--seeds", required=True,
                        help="A:B runs seeds A, A+1, ..., B-1 (or one seed)")
    add_runs_options(parser, "envelope.csv")
    parser.set_defaults(func=run)


def run(args) -> int:
    from drake_auv.campaign import parse_seeds, run_task
    from drake_auv.campaign.engine import check_workers
    from drake_auv.campaign.envelope import (COLUMNS, KEYS, envelope_row, envelope_runs,
                                             parse_directions, parse_speeds, write_envelope)
    from drake_auv.commands.campaign import fly_runs
    from drake_auv.mission.config import load_mission, mission_to_dict

    # Everything that can refuse the command, before anything is written.
    speeds = parse_speeds(args.speeds)
    directions = parse_directions(args.directions)
    seeds = parse_seeds(args.seeds)
    if args.scheduler is None:
        check_workers(args.workers)
    base = mission_to_dict(load_mission(args.mission, overrides=args.overrides))
    runs = envelope_runs(args.mission, speeds, directions, seeds, args.overrides)
    base.pop("seed")
    out = Path(args.out)
    meta = dict(mission=base["name"], speeds=args.speeds, directions=args.directions,
                seeds=args.seeds, vary_keys=list(KEYS), overrides=list(args.overrides),
                base_mission=base)
    fixed = ("base_mission", "overrides", "vary_keys", "directions")

    def finish(results):
        meta.pop("base_mission")
        return write_envelope(results.rows(), out, base["name"], meta)[1]

    line, counts, retried = fly_runs(
        args, out, meta, runs, "envelope.csv", KEYS, finish, fixed=fixed, outputs=OUTPUTS,
        header=COLUMNS, task=functools.partial(run_task, row=envelope_row), desc="envelope",
        products="the envelope")
    print(f"envelope {base['name']}: {counts['total']} runs ({counts['skipped']} already in "
          f"envelope.csv, {retried} failed ones run again, {counts['ok']} ok, "
          f"{counts['failed']} failed now); plot in {out / 'envelope.png'}")
    print(line)
    return 0
