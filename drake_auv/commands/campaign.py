"""`drake-auv campaign MISSION --seeds A:B [--vary KEY=V1,V2,...]... -o OUT`: seeded Monte
Carlo runs of a mission on Dask.

Every (seed, variant) is one task: the worker builds and flies the mission and returns a
metrics row, which this process appends to OUT/results.csv at once. A rerun with the same OUT
runs only the rows missing (`--retry-failed`: also those that failed). At the end
OUT/summary.md, summary.json and the plots are written from every row of results.csv. The
arguments, the scheduler and OUT are checked before anything is written; OUT is locked for
the whole campaign, so a second campaign into it is refused. `--workers N` starts a local cluster of N processes (default:
the machine's cores); `--scheduler tcp://HOST:8786` uses a running Dask cluster instead (see
docs/campaigns.md).
"""

from __future__ import annotations

import json
from pathlib import Path

from drake_auv.commands import whole_number
from drake_auv.output_files import write_json

CAMPAIGN_FILE = "campaign.json"


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "campaign", help="seeded Monte Carlo runs of a mission over errors and faults, on Dask",
        description="Runs a mission for every seed of --seeds and every combination of the "
                    "--vary values, one Dask task per run, and writes results.csv (a row per "
                    "run, appended as it finishes; a rerun runs only the missing rows), "
                    "summary.md, summary.json and plots into OUT.")
    parser.add_argument("mission", help="a mission YAML file or a built-in mission's name")
    parser.add_argument("--seeds", required=True,
                        help="A:B runs seeds A, A+1, ..., B-1 (or one seed)")
    parser.add_argument("--vary", action="append", default=[], metavar="KEY=V1,V2,...",
                        help="a dotted key of the mission file and its values (repeatable: "
                             "the runs cover every combination), e.g. "
                             "site.prior_error_m=0,2.5,5")
    add_runs_options(parser, "results.csv")
    parser.set_defaults(func=run)


def add_runs_options(parser, rows: str) -> None:
    """The options of a command that flies a grid of runs on Dask into OUT/`rows`: `--set`,
    `--workers` or `--scheduler`, `-o/--out`, `--retry-failed` and `--quiet` (shared with
    `drake-auv envelope`)."""
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="a fixed override for every run (repeatable)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=whole_number, default=None,
                       help="local worker processes (default: this machine's cores)")
    where.add_argument("--scheduler", default=None,
                       help="address of a running Dask scheduler, e.g. tcp://HOST:8786")
    parser.add_argument("-o", "--out", required=True, help="output folder")
    parser.add_argument("--retry-failed", action="store_true",
                        help=f"run again the runs whose row in OUT/{rows} failed (their rows "
                             "are replaced)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def check_same_campaign(out: Path, meta: dict, write: bool = True,
                        fixed=("base_mission", "overrides", "vary_keys")) -> None:
    """Checks that OUT holds no campaign or this one (the same `fixed` entries of `meta`: base
    mission, fixed overrides and varied keys; seeds and values may be added) and, when
    `write`, writes OUT/campaign.json."""
    path = out / CAMPAIGN_FILE
    fixed = {k: meta[k] for k in fixed}
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError) as err:
            raise ValueError(f"{path}: unreadable ({err}); allowed: a campaign.json written "
                             "by drake-auv campaign, or another -o folder") from None
        for key, value in fixed.items():
            if old.get(key) != value:
                raise ValueError(f"{out}: holds another campaign ({key} differs from this "
                                 f"command's); allowed: the same mission, --set and --vary "
                                 "keys, or another -o folder")
    if write:
        write_json(path, meta)


def fly_runs(args, out: Path, meta: dict, runs, rows_file: str, keys, finish,
             fixed=("base_mission", "overrides", "vary_keys"), outputs=None, header=None,
             task=None, desc: str = "campaign", products: str = "the summary"):
    """Flies `runs` on Dask into OUT/`rows_file` (rows with `keys`, `header` columns), OUT
    checked (its `outputs`), held by no other campaign (`fixed` entries of `meta`) and locked
    for the whole flight; `finish(results)` writes the products while it is still locked and
    returns what this returns with (counts, runs retried); `products` names them in an error.
    `task`: the task function (default `run_task`); `desc`: the progress bar's label."""
    from drake_auv.campaign import CampaignError, ResultsFile, connect, run_campaign, run_task
    from drake_auv.campaign.engine import probe_scheduler, require_dask
    from drake_auv.campaign.folder import check_output, locked
    from drake_auv.campaign.task import one_line

    require_dask()
    check_output(out, *(() if outputs is None else (outputs,)))
    check_same_campaign(out, meta, write=False, fixed=fixed)
    if args.scheduler is not None:
        probe_scheduler(args.scheduler)
    with locked(out):
        try:
            check_same_campaign(out, meta, fixed=fixed)  # again: no other campaign can write
            results = ResultsFile(out / rows_file, keys, header=header)
            retried = results.drop(results.failed() & {run.key for run in runs}) \
                if args.retry_failed else 0
        except OSError as err:
            raise CampaignError(f"-o {out}: cannot write there ({one_line(err)}); allowed: a "
                                "writable folder") from None
        client, cluster = connect(args.workers, args.scheduler)
        try:
            counts = run_campaign(runs, results, client, progress=not args.quiet,
                                  task=task or run_task, desc=desc)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        try:
            products = finish(results)
        except OSError as err:
            raise CampaignError(f"-o {out}: cannot write {products} ({one_line(err)}); the "
                                f"rows are in {results.path}; allowed: a writable folder"
                                ) from None
    return products, counts, retried


def run(args) -> int:
    from drake_auv.campaign import expand_runs, parse_seeds, parse_vary, write_summary
    from drake_auv.campaign.engine import check_workers
    from drake_auv.mission.config import load_mission, mission_to_dict

    # Everything that can refuse the command, before anything is written.
    seeds = parse_seeds(args.seeds)
    vary = parse_vary(args.vary)
    if args.scheduler is None:
        check_workers(args.workers)
    base = mission_to_dict(load_mission(args.mission, overrides=args.overrides))
    base.pop("seed")
    runs = expand_runs(args.mission, seeds, vary, args.overrides)
    keys = [k for k, _ in vary]
    meta = dict(mission=base["name"], seeds=args.seeds, vary=dict(vary),
                vary_keys=keys, overrides=list(args.overrides), base_mission=base)

    def finish(results):
        rows = results.rows()  # this command's and earlier ones' (more seeds, more values)
        seeds_done = sorted({int(r["seed"]) for r in rows})
        meta.pop("base_mission")
        meta["seeds"] = f"{seeds_done[0]}..{seeds_done[-1]} ({len(seeds_done)} seeds)"
        return write_summary(rows, keys, out, meta)

    out = Path(args.out)
    summary, counts, retried = fly_runs(args, out, meta, runs, "results.csv", keys, finish)
    overall = summary["overall"]
    print(f"campaign {base['name']}: {counts['total']} runs ({counts['skipped']} already in "
          f"results.csv, {retried} failed ones run again, {counts['ok']} ok, "
          f"{counts['failed']} failed now); contacts {overall['contacts']}/{overall['ok']}; "
          f"summary in {out / 'summary.md'}")
    return 0
