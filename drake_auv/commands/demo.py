"""`drake-auv demo`: the all-together boulder mission (what `make demo` runs).

Plans on the boulder's prior map, simulates horizontal profile following and the nominal plan
with realtime replanning, and writes `<out>/report.md`, `report.json`, `plan.png`,
`coverage.png`, `distance.png` and `mission.html` (a standalone Meshcat recording).
"""

from __future__ import annotations

from drake_auv.commands import add_recording_options

DEFAULT_OUT = "out/demo"


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo", help="the all-together boulder mission: plan, profile following, replanning",
        description="The reference's combined experiment on the boulder site, headless: "
                    "off-line plan on the prior map, horizontal profile following, then the "
                    "plan flown with realtime replanning against the on-line octree map under "
                    "prior-map and navigation error. Writes a report, figures and mission.html.")
    parser.add_argument("--out", default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the prior-map error, navigation drift, noise and STOMP")
    parser.add_argument("--prior-error", type=float, default=3.0,
                        help="horizontal error of the prior map, m in [0, 5] (default 3)")
    parser.add_argument("--follow-loops", type=float, default=1.0,
                        help="loops of horizontal profile following around the boulder "
                             "(default 1)")
    parser.add_argument("--replan-time", type=float, default=None,
                        help="cap on the replanning phase's simulated time, s (default: the "
                             "whole plan)")
    add_recording_options(parser, playback_speed=20.0, realtime=False)
    parser.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path as FilePath

    from drake_auv.mission import MissionConfig, run_mission, write_recording
    from drake_auv.mission_report import write_report

    config = MissionConfig(seed=args.seed, prior_error_m=args.prior_error,
                           follow_loops=args.follow_loops, replan_time=args.replan_time)
    scene = None
    if not args.no_html:
        from drake_auv.visualization import Scene

        scene = Scene()
        scene.start_recording(playback_speed=args.playback_speed, live=False)
    result = run_mission(config, scene=scene, progress=not args.quiet)
    out = FilePath(args.out)
    summary = write_report(result, out)
    if scene is not None:
        write_recording(result, scene, out / "mission.html")
    mission = summary["results"]["mission"]
    print(f"multibeam coverage {100 * mission['multibeam_coverage']:.1f} %, camera "
          f"{100 * mission['camera_coverage']:.1f} %, minimum clearance "
          f"{mission['clearance_min_m']:.2f} m; report in {out / 'report.md'}")
    return 0
