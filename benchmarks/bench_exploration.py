"""The exploration ablation: the view planner's gain against nearest-frontier-first and a
random frontier, and the acceptance checks.

`--mission` (default `boulder_explore`, no prior map) is flown with its `explore` step's
`strategy` set to gain, nearest and random on each seed of `--seeds` (`A:B`, seeds A .. B-1;
default 0:10), and its plan + survey counterpart (`boulder`, `breakwater`: a prior map) on the
same seeds. Every dive writes its `report.json` to `--out/<mission>[-<strategy>]/seed<N>/`
(`--reuse` reads back a dive whose report holds the same configuration; the layout is
`examples/explore_vs_plan.py`'s, so the two share their plan + survey dives). Per strategy:
median time to 80 % and 90 % multibeam coverage of the true target (a seed that never reached
it counts as infinitely late), median and worst final coverage, contacts, median believed
coverage. The checks (on the gain strategy): no contact in any seed; >= 90 %
multibeam coverage in every seed; median time to 90 % within 1.5x of plan + survey's; gain
reaches 80 % sooner than nearest on the median; and the wreck of `examples/explore_wreck.py`
(a site given as files, a world mesh and no prior, on a rough seabed; `--wreck-seeds`)
explored to >= 80 % multibeam coverage with no contact. Writes `--markdown` (the tables, the checks,
the machine), `--figure` (coverage against time per strategy) and, with `--json`, the per-dive
rows; exit status 1 when a check fails.

    .venv/bin/python benchmarks/bench_exploration.py [--seeds 0:10] [--jobs 2] [--reuse]
        [--json docs/exploration_ablation.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
from _reference import machine  # noqa: E402
from drake_auv.campaign.grid import parse_seeds  # noqa: E402
from drake_auv.commands.outputs import output_folder  # noqa: E402
from explore_vs_plan import (PLAN_MISSION, dive_row, figure, median_time, run_all,  # noqa: E402
                             _s, strategy_override, table)
from explore_wreck import write_wreck_mission  # noqa: E402

STRATEGIES = ("gain", "nearest", "random")
SLOWDOWN = 1.5  # the acceptance's bound on explore's median time to 90 % over plan + survey's


def _secs(t: float) -> str:
    return _s(t) + (" s" if np.isfinite(t) else "")


WRECK = "wreck (files, no prior)"


def checks(groups: dict[str, list[dict]], plan_mode: str) -> list[tuple[str, bool, str]]:
    """The acceptance checks: (what, passed, the measured figures)."""
    gain, plan = groups["gain"], groups[plan_mode]
    wreck = [] if WRECK not in groups else [
        ("a site given as files, no prior (the wreck): >= 80 % multibeam, no contact",
         all(r["multibeam"] >= 0.8 and not r["contact"] for r in groups[WRECK]),
         ", ".join(f"seed {r['seed']}: {100 * r['multibeam']:.1f} %, min clearance "
                   f"{r['clearance']:.2f} m" for r in groups[WRECK]))]
    contacts = sum(r["contact"] for r in gain)
    worst = min(r["multibeam"] for r in gain)
    t90, plan90 = median_time(gain, "t90"), median_time(plan, "t90")
    t80 = median_time(gain, "t80")
    near80 = median_time(groups["nearest"], "t80") if "nearest" in groups else None
    return [
        ("no contact in any seed (gain)", contacts == 0, f"{contacts}/{len(gain)} contacts"),
        (">= 90 % multibeam coverage in every seed (gain)", worst >= 0.9,
         f"worst {100 * worst:.1f} %"),
        (f"median time to 90 % within {SLOWDOWN}x of {plan_mode}", t90 <= SLOWDOWN * plan90,
         f"{_secs(t90)} against {_secs(plan90)}"
         + (f" ({t90 / plan90:.2f}x)" if np.isfinite(t90 / plan90) else "")),
    ] + ([] if near80 is None else [
        ("gain reaches 80 % sooner than nearest (median)", t80 < near80,
         f"{_secs(t80)} against {_secs(near80)}")]) + wreck


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mission", default="boulder_explore", choices=sorted(PLAN_MISSION))
    parser.add_argument("--seeds", default="0:10", help="A:B, seeds A .. B-1 (default 0:10)")
    parser.add_argument("--jobs", type=int, default=1, help="dives at once (1)")
    parser.add_argument("--reuse", action="store_true",
                        help="read back dives whose report.json holds the same configuration")
    parser.add_argument("--out", type=Path, default=Path("out/exploration"))
    parser.add_argument("--markdown", type=Path, default=None,
                        help="default: --out/bench_exploration_<mission>.md")
    parser.add_argument("--json", type=Path, default=None,
                        help="also write the per-dive rows, by mode, to this file")
    parser.add_argument("--figure", type=Path,
                        default=Path("docs/exploration_ablation.png"))
    parser.add_argument("--strategies", default=",".join(STRATEGIES),
                        help="comma-separated, of " + ", ".join(STRATEGIES) + " (all)")
    parser.add_argument("--wreck-seeds", default="0:1",
                        help="A:B, seeds of the wreck site's dive (files, no prior; default "
                             "0:1; empty: none)")
    args = parser.parse_args(argv)
    strategies = tuple(args.strategies.split(","))
    if "gain" not in strategies or not set(strategies) <= set(STRATEGIES):
        parser.error(f"--strategies must name gain and only {', '.join(STRATEGIES)}, got "
                     f"{args.strategies!r}")
    try:
        seeds = parse_seeds(args.seeds)
        wreck_seeds = parse_seeds(args.wreck_seeds) if args.wreck_seeds else []
    except ValueError as err:
        parser.error(str(err))
    if args.jobs < 1:
        parser.error(f"--jobs must be >= 1, got {args.jobs}")
    markdown = args.markdown or args.out / f"bench_exploration_{args.mission}.md"
    outputs = (("--out", args.out), ("--markdown", markdown.parent),
               ("--figure", args.figure.parent)) + \
        ((("--json", args.json.parent),) if args.json is not None else ())
    try:  # before any dive
        for option, folder in outputs:
            output_folder(folder, option, 0)
    except ValueError as err:
        parser.error(str(err))
    plan_mission = PLAN_MISSION[args.mission]
    plan_mode = f"plan + survey ({plan_mission})"
    modes = [(s, args.mission, (strategy_override(args.mission, s),), f"{args.mission}-{s}",
              seeds) for s in strategies] + [(plan_mode, plan_mission, (), plan_mission, seeds)]
    if wreck_seeds:
        wreck = str(write_wreck_mission(args.out / "wreck_site"))
        modes.append((WRECK, wreck, (), "wreck_explore", wreck_seeds))
    tasks = [(mission, seed, extra, args.out / folder / f"seed{seed}", args.reuse)
             for _, mission, extra, folder, mode_seeds in modes for seed in mode_seeds]
    summaries = iter(run_all(tasks, args.jobs))
    by_mode = {mode: [next(summaries) for _ in mode_seeds] for mode, *_, mode_seeds in modes}
    groups = {m: [dive_row(s) for s in runs] for m, runs in by_mode.items()}
    title = f"Exploration ablation: {args.mission}, seeds {args.seeds}"
    figure({m: [s["coverage_vs_time"] for s in runs] for m, runs in by_mode.items()},
           args.figure, title)
    results = checks(groups, plan_mode)
    text = (table(groups, title) + "\n## Acceptance\n\n| check | result | measured |\n"
            "| --- | --- | --- |\n"
            + "".join(f"| {what} | {'pass' if ok else '**FAIL**'} | {measured} |\n"
                      for what, ok, measured in results)
            + f"\n{machine()}\n")
    markdown.write_text(text)
    if args.json is not None:
        args.json.write_text(json.dumps(groups, indent=1) + "\n")
    print(text)
    return 0 if all(ok for _, ok, _ in results) else 1


if __name__ == "__main__":
    sys.exit(main())
