"""`drake-auv demo`: the built-in `boulder` mission (what `make demo` runs).

The reference's combined experiment in one dive: the off-line plan on the boulder's prior map,
horizontal profile following around the boulder, then the plan flown with realtime replanning
against the on-line octree map under prior-map and navigation error. The same as
`drake-auv run boulder -o OUT`.
"""

from __future__ import annotations

from drake_auv.commands import add_recording_options
from drake_auv.commands.run import add_mission_options, run as run_mission

DEFAULT_OUT = "out/demo"


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo", help="the all-together boulder mission: plan, profile following, replanning",
        description="The reference's combined experiment on the boulder site, in one dive "
                    "(`drake-auv run boulder`): off-line plan on the prior map, horizontal "
                    "profile following, then the plan flown with realtime replanning against "
                    "the on-line octree map under prior-map and navigation error.")
    parser.add_argument("-o", "--out", default=DEFAULT_OUT,
                        help=f"output folder (default {DEFAULT_OUT})")
    add_mission_options(parser)
    add_recording_options(parser, playback_speed=20.0, realtime=False)
    parser.set_defaults(func=run, mission="boulder")


def run(args) -> int:
    return run_mission(args)
