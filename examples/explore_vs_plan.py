"""Explore with no prior map against plan + survey with one, at the boulder, on the same seeds.

`boulder_explore` (the `explore` step: next views chosen from the on-line octree, no prior) and
`boulder` (the off-line plan on the shifted prior map, profile following, the survey with
realtime replanning) are flown on each seed of `--seeds` (`A:B`, seeds A .. B-1, as
`drake-auv campaign`). Every dive writes its `report.json` (`summarise`, with the
coverage-against-time curve) to `--out/<mission>[-<strategy>]/seed<N>/` (the layout of
`benchmarks/bench_exploration.py`, which shares these dives); `--reuse` reads a dive back instead
of flying it when that file holds the same mission configuration. Written: `--figure` (default
`docs/explore_vs_plan.png`, multibeam coverage of the true boulder against mission time, each
seed and the median) and `--out/explore_vs_plan.md` (per dive and the medians: time to 80 % and
90 % multibeam coverage, final coverage, minimum clearance, contact).

    .venv/bin/python examples/explore_vs_plan.py [--seeds 0:3] [--jobs 2] [--reuse]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import warnings
from pathlib import Path

import numpy as np

from drake_auv.campaign.grid import parse_seeds
from drake_auv.commands.outputs import output_folder
from drake_auv.mission.config import load_mission, mission_to_dict
from drake_auv.mission.report.summary import rounded, summarise
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.progress import track

PLAN_MISSION = {"boulder_explore": "boulder", "breakwater_explore": "breakwater"}
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red")


def strategy_override(mission: str, strategy: str) -> str:
    """The override setting the strategy of `mission`'s (first) explore step."""
    steps = load_mission(mission).steps
    index = next((i for i, s in enumerate(steps) if s.KIND == "explore"), None)
    if index is None:
        raise ValueError(f"--mission {mission}: has no explore step; allowed: a mission with "
                         "one, e.g. " + ", ".join(PLAN_MISSION))
    return f"steps.{index}.explore.strategy={strategy}"


def run_or_load(task: tuple) -> dict:
    """One dive: (mission, seed, overrides, folder, reuse) -> its summary, written to
    `folder/report.json`; with `reuse`, an existing report of the same configuration is read
    back instead of flying the dive again."""
    mission, seed, overrides, folder, reuse = task
    spec = load_mission(mission, seed=seed, overrides=list(overrides))
    report = Path(folder) / "report.json"
    if reuse and report.is_file():
        summary = json.loads(report.read_text())
        if summary.get("config") == json.loads(json.dumps(rounded(mission_to_dict(spec)))):
            return summary
    with warnings.catch_warnings():  # empty statistics of a phase are reported as null
        warnings.simplefilter("ignore", RuntimeWarning)
        summary = summarise(run_mission(spec, progress=False))
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def run_all(tasks: list[tuple], jobs: int) -> list[dict]:
    """`run_or_load` of every task, `jobs` dives at once (each in its own process and Diagram),
    in the order of `tasks`."""
    if jobs == 1:
        return [run_or_load(t) for t in track(tasks, "dives")]
    with multiprocessing.get_context("spawn").Pool(jobs) as pool:
        return list(track(pool.imap(run_or_load, tasks), "dives", len(tasks)))


def dive_row(summary: dict) -> dict:
    """The comparison's figures of one dive's summary (times in s, None: never reached)."""
    reached = summary["coverage_vs_time"]["time_to_s"]["multibeam"]
    exploration = summary.get("exploration") or {}
    return dict(seed=summary["mission"]["seed"], t80=reached["80"], t90=reached["90"],
                multibeam=summary["coverage"]["multibeam"], camera=summary["coverage"]["camera"],
                believed=exploration.get("believed_coverage"),
                stopped=exploration.get("stopped"),
                clearance=summary["min_clearance_m"], contact=summary["contact"],
                sim_s=summary["timing"]["sim_s"], completed=summary["mission"]["completed"])


def median_time(rows: list[dict], key: str) -> float:
    """Median over dives of a time to coverage; a dive that never reached it counts as
    infinitely late (so the median is inf when half of them never did)."""
    return float(np.median([np.inf if r[key] is None else r[key] for r in rows]))


def _s(value) -> str:
    return "never" if value is None or not np.isfinite(value) else f"{value:.0f}"


def _pct(value) -> str:
    return "n/a" if value is None else f"{100 * value:.1f}"


def table(groups: dict[str, list[dict]], title: str) -> str:
    """Markdown: one row per dive, then the medians (and worst cases) per mode."""
    lines = [f"# {title}", "",
             "Times from the start of the dive to 80 % / 90 % multibeam coverage of the true "
             "target; coverage: share of its area seen over the dive; clearance: true, to "
             f"anything; contact: clearance <= {VEHICLE_RADIUS} m (vehicle radius); believed: "
             "the share of the map's surface the view planner believes covered.", "",
             "| mode | seed | time to 80 % (s) | time to 90 % (s) | multibeam (%) | camera (%) | "
             "believed (%) | stopped | min clearance (m) | contact | dive (s) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for mode, rows in groups.items():
        for r in rows:
            lines.append(f"| {mode} | {r['seed']} | {_s(r['t80'])} | {_s(r['t90'])} | "
                         f"{_pct(r['multibeam'])} | {_pct(r['camera'])} | {_pct(r['believed'])}"
                         f" | {r['stopped'] or '-'} | {r['clearance']:.2f} | "
                         f"{'YES' if r['contact'] else 'no'} | {r['sim_s']:.0f} |")
    lines += ["", "| mode | dives | median time to 80 % (s) | median time to 90 % (s) | "
              "median multibeam (%) | worst multibeam (%) | worst clearance (m) | contacts |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for mode, rows in groups.items():
        cover = [r["multibeam"] for r in rows]
        lines.append(f"| {mode} | {len(rows)} | {_s(median_time(rows, 't80'))} | "
                     f"{_s(median_time(rows, 't90'))} | {_pct(float(np.median(cover)))} | "
                     f"{_pct(min(cover))} | {min(r['clearance'] for r in rows):.2f} | "
                     f"{sum(r['contact'] for r in rows)}/{len(rows)} |")
    return "\n".join(lines) + "\n"


def figure(curves: dict[str, list[dict]], filename, title: str) -> None:
    """Multibeam coverage against mission time per mode: every dive thin, the median over
    dives thick (a dive that ended keeps its final coverage)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 4.8))
    ax = fig.add_subplot(1, 1, 1)
    end = max(c["t_s"][-1] for runs in curves.values() for c in runs)
    t = np.arange(0.0, end + 10.0, 10.0)
    for colour, (mode, runs) in zip(COLOURS, curves.items()):
        shares = np.array([np.interp(t, c["t_s"], c["multibeam"]) for c in runs])
        for share in shares:
            ax.plot(t, 100 * share, color=colour, lw=0.5, alpha=0.4)
        ax.plot(t, 100 * np.median(shares, axis=0), color=colour, lw=2.0,
                label=f"{mode} (median of {len(runs)})")
    for level in (80, 90):
        ax.axhline(level, color="0.6", lw=0.6, ls="--")
    ax.set(xlabel="mission time (s)", ylabel="multibeam coverage of the true target (%)",
           ylim=(0, 101), xlim=(0, end), title=title)
    ax.legend(loc="lower right", fontsize=8)
    fig.savefig(filename, dpi=120, bbox_inches="tight")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0:3",
                        help="A:B, seeds A .. B-1 (default 0:3; the acceptance uses 0:10)")
    parser.add_argument("--jobs", type=int, default=1, help="dives at once (1)")
    parser.add_argument("--reuse", action="store_true",
                        help="read back dives whose report.json holds the same configuration")
    parser.add_argument("--out", type=Path, default=Path("out/exploration"))
    parser.add_argument("--figure", type=Path, default=Path("docs/explore_vs_plan.png"))
    args = parser.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as err:
        parser.error(str(err))
    if args.jobs < 1:
        parser.error(f"--jobs must be >= 1, got {args.jobs}")
    try:  # before any dive
        output_folder(args.out, "--out", 0)
        output_folder(args.figure.parent, "--figure", 0)
    except ValueError as err:
        parser.error(str(err))
    modes = (("explore", "boulder_explore", (strategy_override("boulder_explore", "gain"),),
              "boulder_explore-gain"), ("plan + survey", "boulder", (), "boulder"))
    tasks = [(mission, seed, extra, args.out / folder / f"seed{seed}", args.reuse)
             for _, mission, extra, folder in modes for seed in seeds]
    summaries = iter(run_all(tasks, args.jobs))
    by_mode = {mode: [next(summaries) for _ in seeds] for mode, *_ in modes}
    title = f"Explore (no prior) against plan + survey (prior map), boulder, seeds {args.seeds}"
    figure({m: [s["coverage_vs_time"] for s in runs] for m, runs in by_mode.items()},
           args.figure, title)
    text = table({m: [dive_row(s) for s in runs] for m, runs in by_mode.items()}, title)
    (args.out / "explore_vs_plan.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
